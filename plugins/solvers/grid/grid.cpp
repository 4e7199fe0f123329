#include "grid.hpp"

#include "worst_case_check.hpp"

#include <hapsyn/checkpoint.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/parallel.hpp>
#include <hapsyn/pareto.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <mutex>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>

namespace hapsyn::plugins {

void GridSolver::check(const Problem& problem) const {
  if (options_.pareto && problem.objectives().size() < 2) {
    throw Error("grid", "solver.options.pareto = true: needs two or more objectives (the study has " +
                            std::to_string(problem.objectives().size()) + ")");
  }
  problem.design_space().check_grid("grid", options_.max_designs);
}

SolverResult GridSolver::solve(const Problem& problem, const SolverContext& context) const {
  return options_.pareto ? solve_front(problem, context) : solve_best(problem, context);
}

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kInf = std::numeric_limits<double>::infinity();

// One progress line, "<what>: P% of N designs, <detail>, E s elapsed, ~L s left", at most every
// `interval` seconds (the caller holds the lock that guards last_report and what detail reads).
template <typename Detail>
void report_progress(std::ostream& out, const char* what, long long finished, long long total, Clock::time_point start,
                     Clock::time_point& last_report, double interval, const Detail& detail) {
  const auto now = Clock::now();
  if (std::chrono::duration<double>(now - last_report).count() < interval) return;
  last_report = now;
  const double elapsed = std::chrono::duration<double>(now - start).count();
  const double fraction = static_cast<double>(finished) / static_cast<double>(total);
  out << what << ": " << std::fixed << std::setprecision(1) << 100.0 * fraction << "% of " << total << " designs, ";
  detail(out);
  out << ", " << std::setprecision(1) << elapsed << " s elapsed, ~" << elapsed * (1 - fraction) / fraction
      << " s left\n"
      << std::defaultfloat;
}

void raise_to(std::atomic<double>& target, double value) {
  double current = target.load(std::memory_order_relaxed);
  while (value > current && !target.compare_exchange_weak(current, value, std::memory_order_relaxed)) {
  }
}

// The grid of the free design variables: points per variable (last fastest) and in all.
struct GridShape {
  std::vector<long long> counts;
  long long total = 1;

  explicit GridShape(const DesignSpace& space) : counts(space.grid_counts()) {
    for (long long c : counts) total *= c;
  }
};

// How the evaluations of some grid designs ended.
struct Tally {
  long long feasible = 0, constraint_violated = 0, sample_failed = 0, pruned = 0, samples = 0;

  void count(const Evaluation& e) {
    samples += e.samples_evaluated;
    switch (e.status) {
      case EvalStatus::kFeasible: ++feasible; break;
      case EvalStatus::kConstraintViolated: ++constraint_violated; break;
      case EvalStatus::kSampleFailed: ++sample_failed; break;
      case EvalStatus::kPruned: ++pruned; break;
    }
  }
  void add(const Tally& t) {
    feasible += t.feasible;
    constraint_violated += t.constraint_violated;
    sample_failed += t.sample_failed;
    pruned += t.pruned;
    samples += t.samples;
  }
  long long designs() const { return feasible + constraint_violated + sample_failed + pruned; }
  Json to_json() const {
    return {{"feasible", feasible}, {"constraint_violated", constraint_violated}, {"sample_failed", sample_failed},
            {"pruned", pruned}, {"samples", samples}};
  }
  // The statistics both modes share.
  Json statistics(const GridShape& grid, bool prune) const {
    return {{"grid_designs", grid.total},
            {"feasible", feasible},
            {"constraint_violated", constraint_violated},
            {"sample_failed", sample_failed},
            {"pruned", pruned},
            {"full_workspace_searches", feasible},
            {"prune", prune},
            {"grid_counts", grid.counts}};
  }
};

// ---------------------------------------------------------------------------------------------
// Chunks, checkpoints and the sweep both modes share.

// The grid is visited in chunks of consecutive designs, handed out to the threads in order; a
// chunk counts as finished only when all its designs are, so that a checkpoint can say exactly
// which designs a resumed run still has to visit.
constexpr long long kChunk = 64;

// Which chunks are finished: every chunk below `prefix`, and those in `beyond` (the few that
// other threads finished while an earlier one was still running).
struct Ledger {
  long long chunks = 0;
  long long prefix = 0;
  std::set<long long> beyond;

  bool finished(long long chunk) const { return chunk < prefix || beyond.count(chunk) != 0; }
  void finish(long long chunk) {
    beyond.insert(chunk);
    while (!beyond.empty() && *beyond.begin() == prefix) {
      beyond.erase(beyond.begin());
      ++prefix;
    }
  }
  long long designs(long long total) const {
    long long n = std::min(total, prefix * kChunk);
    for (long long c : beyond) n += std::min(kChunk, total - c * kChunk);
    return n;
  }
};

// "1,701,900".
std::string with_commas(long long n) {
  std::string digits = std::to_string(n), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

// The checkpoint's fingerprint: the study and the options that change the result (not the
// progress and checkpoint intervals or the size cap, which a resumed run may change).
std::string fingerprint_of(const Problem& problem, const GridOptions& options) {
  return study_fingerprint(problem, options_to_json(options), {"progress_interval", "checkpoint_interval", "max_designs"});
}

// What a run resumes from: the ledger, the counts and time so far (the mode's own part is read
// by the mode).
struct Resumed {
  Ledger ledger;
  Tally tally;
  double seconds = 0.0;
};

Resumed read_common(const SolverContext& context, const Json& state, const GridShape& grid, const char* mode) {
  Resumed r;
  const std::string m = checkpoint_field<std::string>(context, state, "state", "mode");
  if (m != mode) throw bad_checkpoint(context, "state.mode = \"" + m + "\", this run's mode is \"" + mode + "\"");
  if (checkpoint_field<long long>(context, state, "state", "grid_designs") != grid.total ||
      checkpoint_field<long long>(context, state, "state", "chunk_size") != kChunk) {
    throw bad_checkpoint(context, "state.grid_designs / state.chunk_size do not match this grid (" +
                                      std::to_string(grid.total) + " designs in chunks of " + std::to_string(kChunk) + ")");
  }
  r.ledger.chunks = (grid.total + kChunk - 1) / kChunk;
  r.ledger.prefix = checkpoint_field<long long>(context, state, "state", "finished_prefix");
  if (r.ledger.prefix < 0 || r.ledger.prefix > r.ledger.chunks) {
    throw bad_checkpoint(context, "state.finished_prefix = " + std::to_string(r.ledger.prefix) + ": must lie in [0, " +
                                      std::to_string(r.ledger.chunks) + "]");
  }
  for (long long c : checkpoint_field<std::vector<long long>>(context, state, "state", "finished_chunks")) {
    if (c <= r.ledger.prefix || c >= r.ledger.chunks) {
      throw bad_checkpoint(context, "state.finished_chunks: chunk " + std::to_string(c) + " must lie in (" +
                                        std::to_string(r.ledger.prefix) + ", " + std::to_string(r.ledger.chunks) + ")");
    }
    r.ledger.beyond.insert(c);
  }
  const Json tally = checkpoint_field<Json>(context, state, "state", "tally");
  r.tally.feasible = checkpoint_field<long long>(context, tally, "state.tally", "feasible");
  r.tally.constraint_violated = checkpoint_field<long long>(context, tally, "state.tally", "constraint_violated");
  r.tally.sample_failed = checkpoint_field<long long>(context, tally, "state.tally", "sample_failed");
  r.tally.pruned = checkpoint_field<long long>(context, tally, "state.tally", "pruned");
  r.tally.samples = checkpoint_field<long long>(context, tally, "state.tally", "samples");
  r.seconds = checkpoint_field<double>(context, state, "state", "elapsed_seconds");
  return r;
}

Json common_state(const char* mode, const GridShape& grid, const Ledger& ledger, const Tally& tally, double seconds) {
  return {{"mode", mode},
          {"grid_designs", grid.total},
          {"chunk_size", kChunk},
          {"finished_prefix", ledger.prefix},
          {"finished_chunks", std::vector<long long>(ledger.beyond.begin(), ledger.beyond.end())},
          {"tally", tally.to_json()},
          {"elapsed_seconds", seconds}};
}

// Per-thread state of a sweep; `Extra` holds what the mode keeps besides the tally.
template <class Extra>
struct SweepThread : Extra {
  std::unique_ptr<Problem::EvalScratch> eval_scratch;
  std::vector<double> x;
  std::vector<int> check_subset;  // buffer of the monotonicity spot check
  Tally tally;                    // every evaluation of this run, finished chunks or not
};

template <class Extra>
std::vector<SweepThread<Extra>> make_threads(const Problem& problem, const SolverContext& context) {
  std::vector<SweepThread<Extra>> states(static_cast<std::size_t>(std::max(1, context.threads)));
  for (SweepThread<Extra>& s : states) {
    s.eval_scratch = problem.make_eval_scratch();
    s.x.resize(problem.design_space().free_size());
  }
  return states;
}

// What the threads of a sweep share besides the mode's result so far.
struct SweepControl {
  const SolverContext& context;
  const GridShape& grid;
  const Ledger skip;  // chunks finished before this run (resume)
  std::mutex mutex;   // guards ledger, finished, last_checkpoint, breach and the progress stream
  Ledger ledger;
  Tally finished;     // the evaluations of the finished chunks (before this run included)
  Clock::time_point start = Clock::now();
  Clock::time_point last_checkpoint = start, last_report = start;
  double seconds_before = 0.0;
  std::optional<MonotonicityBreach> breach;
  std::atomic<bool> failed{false};

  SweepControl(const SolverContext& c, const GridShape& g, const Resumed& r)
      : context(c), grid(g), skip(r.ledger), ledger(r.ledger), finished(r.tally), seconds_before(r.seconds) {}
  bool halted() const { return context.stop_requested() || failed.load(std::memory_order_relaxed); }
  double seconds() const { return seconds_before + std::chrono::duration<double>(Clock::now() - start).count(); }
  void record_breach(const MonotonicityBreach& b) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!breach) breach = b;
    failed = true;
  }
};

// Every unfinished chunk on the context's threads: visit(index, thread, tally) per design, between
// designs a stop check; after each finished chunk (under control.mutex) on_chunk(), which reports
// progress and writes a checkpoint when due.
template <class Thread, class Visit, class OnChunk>
void run_chunks(SweepControl& control, std::vector<Thread>& states, const Visit& visit, const OnChunk& on_chunk) {
  const long long total = control.grid.total;
  const long long chunks = (total + kChunk - 1) / kChunk;
  parallel_for_dynamic(chunks, static_cast<int>(states.size()), 1, [&](long long chunk, int t) {
    if (control.skip.finished(chunk)) return;
    Thread& s = states[static_cast<std::size_t>(t)];
    Tally chunk_tally;
    const long long end = std::min(total, (chunk + 1) * kChunk);
    for (long long index = chunk * kChunk; index < end; ++index) {
      if (control.halted()) {
        s.tally.add(chunk_tally);  // evaluated, but the chunk is not finished: a resumed run redoes it
        return;
      }
      visit(index, s, chunk_tally);
    }
    s.tally.add(chunk_tally);
    std::lock_guard<std::mutex> lock(control.mutex);
    control.ledger.finish(chunk);
    control.finished.add(chunk_tally);
    on_chunk();
  });
}

// The stop message: "stopped on request after 41.0% of 1,701,900 grid designs; <best>; ...".
std::string stopped_message(const SweepControl& control, const std::string& best) {
  std::ostringstream s;
  s << "stopped on request after " << std::fixed << std::setprecision(1)
    << 100.0 * static_cast<double>(control.ledger.designs(control.grid.total)) / static_cast<double>(control.grid.total)
    << "% of " << with_commas(control.grid.total) << " grid designs; " << best << "; "
    << (control.context.checkpoint_file.empty() ? std::string("no checkpoint file, a new run starts over")
                                                : "checkpoint " + control.context.checkpoint_file +
                                                      " written, resume with --resume");
  return s.str();
}

// ---------------------------------------------------------------------------------------------
// Best design.

struct BestDesign {
  double best_score = -kInf;
  long long best_index = -1;

  // Larger score wins; of equal scores the first in grid order, so neither the thread count
  // nor the order in which a resumed run visits the designs can matter.
  bool improves_on(double score, long long index) const {
    return score > best_score || (score == best_score && index < best_index);
  }
};
using BestThread = SweepThread<BestDesign>;

// The checkpoint's best: re-evaluated in full; refused when it does not score what it claims
// (a hand-edited score must never become the study's best).
BestDesign read_best(const Problem& problem, const GridShape& grid, const SolverContext& context, const Json& state) {
  BestDesign best;
  const Json claimed = checkpoint_field<Json>(context, state, "state", "best");
  if (claimed.is_null()) return best;
  best.best_index = checkpoint_field<long long>(context, claimed, "state.best", "index");
  best.best_score = checkpoint_field<double>(context, claimed, "state.best", "score");
  if (best.best_index < 0 || best.best_index >= grid.total) {
    throw bad_checkpoint(context, "state.best.index = " + std::to_string(best.best_index) + ": not a grid design (0.." +
                                      std::to_string(grid.total - 1) + ")");
  }
  std::vector<double> x(problem.design_space().free_size());
  problem.design_space().grid_point(best.best_index, grid.counts, x.data());
  auto ws = problem.make_eval_scratch();
  const Evaluation& e = problem.evaluate(x.data(), *ws);
  if (e.status != EvalStatus::kFeasible || e.score != best.best_score) {
    std::ostringstream s;
    s.precision(17);
    s << "state.best: grid design " << best.best_index << " scores " << e.score << " (" << to_string(e.status)
      << ") on re-evaluation, the checkpoint claims " << best.best_score;
    throw bad_checkpoint(context, s.str());
  }
  return best;
}

Json best_to_json(const BestDesign& best) {
  if (best.best_index < 0) return nullptr;
  return {{"index", best.best_index}, {"score", best.best_score}};
}

// ---------------------------------------------------------------------------------------------
// Pareto front.

// A point of the front found so far: its objective vector, sense-signed so that larger is
// better, and its grid index.
struct FrontPoint {
  std::vector<double> values;  // sense-signed
  long long index;
};

// Inserts p into `front` (non-dominated points sorted by the first value, descending) unless a
// point dominates it (or equals it with a lower index); removes the points it dominates.
// Returns true when the front changed.
bool insert_point(std::vector<FrontPoint>& front, const FrontPoint& p) {
  const std::vector<Sense> max(p.values.size(), Sense::kMaximize);
  for (FrontPoint& q : front) {
    if (dominates(q.values, p.values, max)) return false;
    if (q.values == p.values) {
      if (q.index <= p.index) return false;
      q.index = p.index;
      return true;
    }
  }
  front.erase(std::remove_if(front.begin(), front.end(), [&](const FrontPoint& q) { return dominates(p.values, q.values, max); }),
              front.end());
  const auto at = std::lower_bound(front.begin(), front.end(), p, [](const FrontPoint& a, const FrontPoint& b) {
    return a.values[0] > b.values[0] || (a.values[0] == b.values[0] && a.values < b.values);
  });
  front.insert(at, p);
  return true;
}

// The front the sweep's threads share.
struct SharedFront {
  std::vector<double> sign;           // +1 maximized, -1 minimized objective
  std::mutex mutex;                   // guards front and flat
  std::vector<FrontPoint> front;
  std::vector<double> flat;           // the front as EvalOptions wants it (natural units)
  std::atomic<long long> version{0};  // bumped when the front changes

  // Offers a feasible design's objectives (natural units) at grid `index`; true when the front
  // changed.
  bool offer(const std::vector<double>& objectives, long long index) {
    const std::size_t m = sign.size();
    FrontPoint p{std::vector<double>(m), index};
    for (std::size_t o = 0; o < m; ++o) p.values[o] = sign[o] * objectives[o];
    std::lock_guard<std::mutex> lock(mutex);
    if (!insert_point(front, p)) return false;
    flat.clear();
    for (const FrontPoint& q : front) {
      for (std::size_t o = 0; o < m; ++o) flat.push_back(sign[o] * q.values[o]);
    }
    version.fetch_add(1, std::memory_order_release);
    return true;
  }
  // The front as the checkpoint holds it: grid index and natural objective values per point.
  Json to_json() {
    std::lock_guard<std::mutex> lock(mutex);
    Json points = Json::array();
    for (const FrontPoint& q : front) {
      std::vector<double> natural(sign.size());
      for (std::size_t o = 0; o < sign.size(); ++o) natural[o] = sign[o] * q.values[o];
      points.push_back({{"index", q.index}, {"objectives", natural}});
    }
    return points;
  }
};

// A thread's copy of the front it prunes against, and the front version it was taken at.
struct FrontSnapshot {
  std::vector<double> snapshot;
  long long seen = -1;
};
using FrontThread = SweepThread<FrontSnapshot>;

// The checkpoint's front, every point re-evaluated in full and refused when its objective
// values differ from the claimed ones, offered to `shared`.
void read_front(const Problem& problem, const GridShape& grid, const SolverContext& context, const Json& state,
                SharedFront& shared) {
  const Json points = checkpoint_field<Json>(context, state, "state", "front");
  if (!points.is_array()) throw bad_checkpoint(context, "state.front is not an array");
  auto ws = problem.make_eval_scratch();
  std::vector<double> x(problem.design_space().free_size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::string path = "state.front[" + std::to_string(i) + "]";
    const long long index = checkpoint_field<long long>(context, points[i], path, "index");
    const std::vector<double> claimed = checkpoint_field<std::vector<double>>(context, points[i], path, "objectives");
    if (index < 0 || index >= grid.total || claimed.size() != shared.sign.size()) {
      throw bad_checkpoint(context, path + ": index " + std::to_string(index) + " or " + std::to_string(claimed.size()) +
                                        " objective values do not fit this grid and study");
    }
    problem.design_space().grid_point(index, grid.counts, x.data());
    const Evaluation& e = problem.evaluate(x.data(), *ws);
    if (e.status != EvalStatus::kFeasible || e.objectives != claimed) {
      std::ostringstream s;
      s.precision(17);
      s << path << ": grid design " << index << " has objectives " << Json(e.objectives).dump() << " ("
        << to_string(e.status) << ") on re-evaluation, the checkpoint claims " << Json(claimed).dump();
      throw bad_checkpoint(context, s.str());
    }
    shared.offer(claimed, index);
  }
}

// The front's designs with their natural objective values, in the front's order.
std::vector<SolutionPoint> front_solutions(const Problem& problem, const GridShape& grid, const SharedFront& shared) {
  const std::size_t m = shared.sign.size();
  std::vector<SolutionPoint> solutions;
  std::vector<double> x(problem.design_space().free_size());
  for (const FrontPoint& q : shared.front) {
    problem.design_space().grid_point(q.index, grid.counts, x.data());
    std::vector<double> natural(m);
    for (std::size_t o = 0; o < m; ++o) natural[o] = shared.sign[o] * q.values[o];
    solutions.push_back({problem.full_design(x.data()), natural, problem.score(natural)});
  }
  return solutions;
}

template <class Extra>
Tally run_tally(const std::vector<SweepThread<Extra>>& states, const Tally& before) {
  Tally sum = before;
  for (const SweepThread<Extra>& s : states) sum.add(s.tally);
  return sum;
}

// What a breach means for the grid.
constexpr const char* kGridBreach =
    "grid pruning relies on that rule, so its result could be wrong: run this study with the grid option "
    "prune: false";

}  // namespace

SolverResult GridSolver::solve_best(const Problem& problem, const SolverContext& context) const {
  const DesignSpace& space = problem.design_space();
  const GridShape grid(space);
  const bool prune = options_.prune && problem.worst_case();
  // The evaluator prunes a weighted sum only when every objective is maximized with weight >= 0.
  const bool prunes = prune && std::all_of(problem.objectives().begin(), problem.objectives().end(),
                                           [](const Objective& o) { return o.sense == Sense::kMaximize && o.weight >= 0.0; });
  const std::string fingerprint = fingerprint_of(problem, options_);

  Resumed resumed;
  resumed.ledger.chunks = (grid.total + kChunk - 1) / kChunk;
  BestDesign shared_best;
  if (const std::optional<Json> state = read_checkpoint(context, "grid", fingerprint)) {
    resumed = read_common(context, *state, grid, "best");
    shared_best = read_best(problem, grid, context, *state);
  }
  SweepControl control(context, grid, resumed);
  std::atomic<double> incumbent{shared_best.best_score};
  std::vector<BestThread> states = make_threads<BestDesign>(problem, context);

  auto save = [&] {  // caller holds control.mutex
    Json state = common_state("best", grid, control.ledger, control.finished, control.seconds());
    state["best"] = best_to_json(shared_best);
    write_checkpoint(context, "grid", fingerprint, state);
    control.last_checkpoint = Clock::now();
  };
  run_chunks(
      control, states,
      [&](long long index, BestThread& s, Tally& tally) {
        space.grid_point(index, grid.counts, s.x.data());
        EvalOptions options;
        if (prune) options.prune_below = incumbent.load(std::memory_order_relaxed);
        const Evaluation& e = problem.evaluate(s.x.data(), *s.eval_scratch, options);
        tally.count(e);
        if (e.status != EvalStatus::kFeasible || !s.improves_on(e.score, index)) return;
        s.best_score = e.score;
        s.best_index = index;
        raise_to(incumbent, e.score);
        {
          std::lock_guard<std::mutex> lock(control.mutex);
          if (shared_best.improves_on(s.best_score, index)) {
            shared_best.best_score = s.best_score;
            shared_best.best_index = index;
          }
        }
        // A thread's improvements are few (each raises its best): the spot check is cheap there.
        if (prunes) {
          if (auto breach = spot_check(problem, s.x.data(), *s.eval_scratch, s.check_subset, false)) {
            control.record_breach(*breach);
          }
        }
      },
      [&] {
        if (context.progress) {
          report_progress(*context.progress, "grid", control.ledger.designs(grid.total), grid.total, control.start,
                          control.last_report, options_.progress_interval, [&](std::ostream& out) {
                            out << "best score " << std::setprecision(6) << incumbent.load();
                          });
        }
        if (std::chrono::duration<double>(Clock::now() - control.last_checkpoint).count() >= options_.checkpoint_interval) {
          save();
        }
      });
  const Tally sum = run_tally(states, resumed.tally);

  SolverResult result;
  result.design_evaluations = sum.designs();
  result.sample_evaluations = sum.samples;
  result.statistics = sum.statistics(grid, prune);
  result.statistics["seconds"] = control.seconds();
  if (control.breach) {
    result.status = SolverStatus::kFailed;
    result.message = breach_message(problem, *control.breach, kGridBreach);
    return result;
  }
  const bool stopped = context.stop_requested() && control.ledger.prefix < control.ledger.chunks;
  save();
  if (shared_best.best_index < 0) {
    const std::string none = "no feasible design among " + std::to_string(sum.designs()) + " grid designs (" +
                             std::to_string(sum.constraint_violated) + " violate a design constraint, " +
                             std::to_string(sum.sample_failed) + " fail at a sample)";
    result.status = stopped ? SolverStatus::kStopped : SolverStatus::kInfeasible;
    result.message = stopped ? stopped_message(control, "no feasible design yet") : none;
    return result;
  }
  // Re-evaluate the winner in full (its running evaluation may have been bounded).
  std::vector<double> x(space.free_size());
  space.grid_point(shared_best.best_index, grid.counts, x.data());
  auto ws = problem.make_eval_scratch();
  const Evaluation& e = problem.evaluate(x.data(), *ws);
  result.sample_evaluations += e.samples_evaluated;
  result.best = SolutionPoint{problem.full_design(x.data()), e.objectives, e.score};
  if (prunes) {
    std::vector<int> subset;
    if (auto breach = spot_check(problem, x.data(), *ws, subset, false)) {
      result.best.reset();
      result.status = SolverStatus::kFailed;
      result.message = breach_message(problem, *breach, kGridBreach);
      return result;
    }
  }
  std::ostringstream best;
  best.precision(10);
  best << "best so far: score " << result.best->score << " (grid design " << shared_best.best_index << ")";
  result.status = stopped ? SolverStatus::kStopped : SolverStatus::kConverged;
  result.message = stopped ? stopped_message(control, best.str())
                           : "exhaustive search of " + std::to_string(grid.total) + " grid designs, " +
                                 std::to_string(sum.feasible) + " fully evaluated";
  return result;
}

SolverResult GridSolver::solve_front(const Problem& problem, const SolverContext& context) const {
  const GridShape grid(problem.design_space());
  const DesignSpace& space = problem.design_space();
  SharedFront shared;
  for (const Objective& o : problem.objectives()) shared.sign.push_back(o.sense == Sense::kMaximize ? 1.0 : -1.0);
  // Pruning needs upper bounds of maximized worst-case objectives (the evaluator checks too).
  const bool prune = options_.prune && problem.worst_case() &&
                     std::all_of(shared.sign.begin(), shared.sign.end(), [](double s) { return s > 0; });
  const std::string fingerprint = fingerprint_of(problem, options_);

  Resumed resumed;
  resumed.ledger.chunks = (grid.total + kChunk - 1) / kChunk;
  if (const std::optional<Json> state = read_checkpoint(context, "grid", fingerprint)) {
    resumed = read_common(context, *state, grid, "front");
    read_front(problem, grid, context, *state, shared);
  }
  SweepControl control(context, grid, resumed);
  std::vector<FrontThread> states = make_threads<FrontSnapshot>(problem, context);

  auto save = [&] {  // caller holds control.mutex
    Json state = common_state("front", grid, control.ledger, control.finished, control.seconds());
    state["front"] = shared.to_json();
    write_checkpoint(context, "grid", fingerprint, state);
    control.last_checkpoint = Clock::now();
  };
  run_chunks(
      control, states,
      [&](long long index, FrontThread& s, Tally& tally) {
        if (prune && shared.version.load(std::memory_order_acquire) != s.seen) {
          std::lock_guard<std::mutex> lock(shared.mutex);
          s.snapshot.assign(shared.flat.begin(), shared.flat.end());
          s.seen = shared.version.load(std::memory_order_relaxed);
        }
        space.grid_point(index, grid.counts, s.x.data());
        EvalOptions options;
        if (prune) options.prune_dominated_by = &s.snapshot;
        const Evaluation& e = problem.evaluate(s.x.data(), *s.eval_scratch, options);
        tally.count(e);
        if (e.status != EvalStatus::kFeasible || !shared.offer(e.objectives, index)) return;
        // Designs that enter the front are few compared with the grid: the spot check is cheap there.
        if (prune) {
          if (auto breach = spot_check(problem, s.x.data(), *s.eval_scratch, s.check_subset, true)) {
            control.record_breach(*breach);
          }
        }
      },
      [&] {
        if (context.progress) {
          report_progress(*context.progress, "grid (pareto)", control.ledger.designs(grid.total), grid.total,
                          control.start, control.last_report, options_.progress_interval, [&](std::ostream& out) {
                            std::lock_guard<std::mutex> lock(shared.mutex);
                            out << "front " << shared.front.size() << " points";
                          });
        }
        if (std::chrono::duration<double>(Clock::now() - control.last_checkpoint).count() >= options_.checkpoint_interval) {
          save();
        }
      });
  const Tally sum = run_tally(states, resumed.tally);

  SolverResult result;
  result.design_evaluations = sum.designs();
  result.sample_evaluations = sum.samples;
  result.statistics = sum.statistics(grid, prune);
  result.statistics["pareto"] = true;
  result.statistics["front_points"] = shared.front.size();
  result.statistics["seconds"] = control.seconds();
  if (control.breach) {
    result.status = SolverStatus::kFailed;
    result.message = breach_message(problem, *control.breach, kGridBreach);
    return result;
  }
  const bool stopped = context.stop_requested() && control.ledger.prefix < control.ledger.chunks;
  save();
  result.front = front_solutions(problem, grid, shared);
  if (shared.front.empty()) {
    result.status = stopped ? SolverStatus::kStopped : SolverStatus::kInfeasible;
    result.message = stopped ? stopped_message(control, "no feasible design yet")
                             : "no feasible design among " + std::to_string(grid.total) + " grid designs";
    return result;
  }
  result.status = stopped ? SolverStatus::kStopped : SolverStatus::kConverged;
  result.message = stopped ? stopped_message(control, "front so far: " + std::to_string(shared.front.size()) + " points")
                           : "exact Pareto front of " + std::to_string(grid.total) + " grid designs: " +
                                 std::to_string(shared.front.size()) + " points, " + std::to_string(sum.feasible) +
                                 " designs fully evaluated";
  return result;
}

}  // namespace hapsyn::plugins
