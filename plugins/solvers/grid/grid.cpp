#include "grid.hpp"

#include "shared/bounds/ledger.hpp"
#include "shared/bounds/line_bound.hpp"
#include "shared/bounds/run_bounds.hpp"
#include "shared/bounds/rank_support.hpp"
#include "shared/bounds/task_bytes.hpp"
#include "shared/bounds/worst_case_check.hpp"

#include <hapsyn/accel/sample_block.hpp>
#include <hapsyn/cluster.hpp>
#include <hapsyn/checkpoint.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/pareto.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cmath>
#include <iomanip>
#include <limits>
#include <mutex>
#include <optional>
#include <ostream>
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

// The grid of the free design variables: points per variable (last fastest) and in all, and the
// designs per chunk (see below).
struct GridShape {
  std::vector<long long> counts;
  long long total = 1;
  long long chunk = 64;

  explicit GridShape(const DesignSpace& space) : counts(space.grid_counts()) {
    for (long long c : counts) total *= c;
    // Grids of a million designs and more: chunks of whole lines (the smallest multiple of the
    // line length of at least 64 designs), since a chunk's end inside a line splits a group of
    // the line's designs evaluated together (a third of the pruned 10 mm five-bar search's
    // time). Smaller grids keep 64 designs, the finest stop and shard granularity.
    const long long line = line_length();
    if (total >= (1LL << 20)) chunk = line * ((64 + line - 1) / line);
  }
  long long chunks() const { return (total + chunk - 1) / chunk; }
  // Designs per line of the last free variable (1 when no variable is free: one design).
  long long line_length() const { return counts.empty() ? 1 : std::max(1LL, counts.back()); }
};

// How the evaluations of some grid designs ended.
struct Tally {
  long long feasible = 0, constraint_violated = 0, sample_failed = 0, pruned = 0, samples = 0;
  // Block bounds (best mode with pruning): runs tried, and the designs they ruled out (also
  // counted above: as failing at a sample when all fail there, else as pruned).
  long long block_bounds = 0, block_ruled_out = 0;

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
    block_bounds += t.block_bounds;
    block_ruled_out += t.block_ruled_out;
  }
  long long designs() const { return feasible + constraint_violated + sample_failed + pruned; }
  Json to_json() const {
    return {{"feasible", feasible}, {"constraint_violated", constraint_violated}, {"sample_failed", sample_failed},
            {"pruned", pruned}, {"samples", samples}, {"block_bounds", block_bounds},
            {"block_ruled_out", block_ruled_out}};
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
            {"block_bounds", block_bounds},
            {"block_ruled_out", block_ruled_out},
            {"grid_counts", grid.counts}};
  }
};
// ---------------------------------------------------------------------------------------------
// Chunks, checkpoints and the sweep both modes share.

// The grid is visited in chunks of consecutive designs: one chunk is one task of the run's task
// farm (handed out in order to every thread of every rank; the chunks of one --shard share are a
// contiguous slice). A chunk (GridShape::chunk designs) counts as finished only when all its
// designs are, so that a checkpoint can say exactly which designs a resumed run still has to
// visit.

// The designs of the finished chunks (the last chunk may be short).
long long finished_designs(const RangeLedger& ledger, const GridShape& grid) {
  long long n = 0;
  for (const auto& [first, end] : ledger.ranges()) n += std::min(grid.total, end * grid.chunk) - first * grid.chunk;
  return n;
}

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
  RangeLedger ledger;
  Tally tally;
  double seconds = 0.0;
};

Resumed read_common(const SolverContext& context, const Json& state, const GridShape& grid, const char* mode) {
  Resumed r;
  const std::string m = checkpoint_field<std::string>(context, state, "state", "mode");
  if (m != mode) throw bad_checkpoint(context, "state.mode = \"" + m + "\", this run's mode is \"" + mode + "\"");
  if (checkpoint_field<long long>(context, state, "state", "grid_designs") != grid.total ||
      checkpoint_field<long long>(context, state, "state", "chunk_size") != grid.chunk) {
    throw bad_checkpoint(context, "state.grid_designs / state.chunk_size do not match this grid (" +
                                      std::to_string(grid.total) + " designs in chunks of " + std::to_string(grid.chunk) + ")");
  }
  r.ledger = RangeLedger::read(context, state, "finished_chunks", "chunk", grid.chunks());
  const Json tally = checkpoint_field<Json>(context, state, "state", "tally");
  r.tally.feasible = checkpoint_field<long long>(context, tally, "state.tally", "feasible");
  r.tally.constraint_violated = checkpoint_field<long long>(context, tally, "state.tally", "constraint_violated");
  r.tally.sample_failed = checkpoint_field<long long>(context, tally, "state.tally", "sample_failed");
  r.tally.pruned = checkpoint_field<long long>(context, tally, "state.tally", "pruned");
  r.tally.samples = checkpoint_field<long long>(context, tally, "state.tally", "samples");
  r.tally.block_bounds = checkpoint_field<long long>(context, tally, "state.tally", "block_bounds");
  r.tally.block_ruled_out = checkpoint_field<long long>(context, tally, "state.tally", "block_ruled_out");
  r.seconds = checkpoint_field<double>(context, state, "state", "elapsed_seconds");
  return r;
}

Json common_state(const char* mode, const GridShape& grid, const RangeLedger& ledger, const Tally& tally, double seconds) {
  Json state = {{"mode", mode}, {"grid_designs", grid.total}, {"chunk_size", grid.chunk}};
  ledger.write(state, "finished_chunks");
  state["tally"] = tally.to_json();
  state["elapsed_seconds"] = seconds;
  return state;
}

void put_tally(ByteWriter& out, const Tally& t) {
  out.put(t.feasible).put(t.constraint_violated).put(t.sample_failed).put(t.pruned).put(t.samples);
  out.put(t.block_bounds).put(t.block_ruled_out);
}

Tally get_tally(ByteReader& in) {
  Tally t;
  t.feasible = in.get<long long>();
  t.constraint_violated = in.get<long long>();
  t.sample_failed = in.get<long long>();
  t.pruned = in.get<long long>();
  t.samples = in.get<long long>();
  t.block_bounds = in.get<long long>();
  t.block_ruled_out = in.get<long long>();
  return t;
}

// The sample that decided a design's evaluation (the one it failed at, or the one after which
// its bound fell below the incumbent) moves to the front of `hints` (at most kHints samples):
// neighbouring designs tend to be decided by it too, so the block bounds try it first.
constexpr std::size_t kHints = 4;
void note_deciding_sample(const Problem& problem, const Evaluation& e, std::vector<int>& hints) {
  int sample = -1;
  if (e.status == EvalStatus::kSampleFailed) {
    sample = e.failed_sample;
  } else if (e.status == EvalStatus::kPruned && e.samples_evaluated > 0) {
    sample = problem.sample_order()[static_cast<std::size_t>(e.samples_evaluated - 1)];
  }
  if (sample < 0) return;
  auto at = std::find(hints.begin(), hints.end(), sample);
  if (at == hints.end()) {
    if (hints.size() == kHints) hints.pop_back();
    hints.push_back(sample);
    at = hints.end() - 1;
  }
  std::rotate(hints.begin(), at, at + 1);
}

// Per-thread state of a sweep; `Extra` holds what the mode keeps besides the tally.
// Cache-line aligned: each thread writes its own per design, never a line another thread writes.
template <class Extra>
struct alignas(64) SweepThread : Extra {
  std::unique_ptr<Problem::EvalScratch> eval_scratch;
  std::vector<double> x;
  std::optional<LineBound> bound;  // of the line `line` (the last free variable varying)
  long long line = -1;
  std::optional<RunBounds> run_bounds;  // block bounds of runs of the line `run_line`
  long long run_line = -1;
  std::vector<int> hints;  // samples that recently decided a design (failed or pruned it), latest first
  // Designs of the current line waiting to be evaluated together (best mode): grid indices,
  // their free vectors one after the other, and the evaluations' buffer.
  std::vector<long long> pending;
  long long pending_line = -1;
  bool pending_verified = false;           // the line bound verified the pending designs' constraints
  std::vector<double> pending_x;           // kBlockLanes rows of free vectors
  std::vector<long long> row_line;         // the line each row was filled for
  std::vector<Evaluation> outs;
  std::vector<int> check_subset;  // buffer of the monotonicity spot check
  Tally partial;                  // evaluations of chunks this thread left unfinished (a stop)
};

// A thread's sweep state, built on the thread that uses it, at its first chunk (docs/design.md
// section 1.5: built together on the calling thread, the threads' buffers shared cache lines).
template <class Extra>
void prepare_thread(SweepThread<Extra>& s, const Problem& problem, bool line_bounds) {
  if (s.eval_scratch) return;
  s.eval_scratch = problem.make_eval_scratch();
  s.x.resize(problem.design_space().free_size());
  s.bound.emplace(problem, line_bounds, "grid");
  // Lines of a few dozen designs: one sample per try, and the wait carries over (measured on
  // the 10 mm GII grid, BLOCK_BOUNDS.md section 13.6).
  s.run_bounds.emplace(problem, "grid", RunBounds::Policy{1, true});
  s.hints.reserve(kHints + 1);
  s.pending_x.assign(static_cast<std::size_t>(kBlockLanes) * s.x.size(), 0.0);
  s.row_line.assign(static_cast<std::size_t>(kBlockLanes), -1);
}

// What the threads of a sweep share besides the mode's result so far. On rank 0 it is also the
// run's collected state (ledger, counts, breach), which collect() fills.
struct SweepControl {
  const SolverContext& context;
  const GridShape& grid;
  const RangeLedger skip;  // chunks finished before this run (resume)
  std::mutex mutex;        // guards ledger, finished, the clocks, breach, the mode's result and the progress stream
  RangeLedger ledger;
  Tally finished;          // the evaluations of the finished chunks (before this run included)
  Clock::time_point start = Clock::now();
  Clock::time_point last_checkpoint = start, last_report = start;
  double seconds_before = 0.0;
  std::optional<MonotonicityBreach> breach;
  std::atomic<bool> failed{false};  // a breach is known on this rank: its tasks stop

  SweepControl(const SolverContext& c, const GridShape& g, const Resumed& r)
      : context(c), grid(g), skip(r.ledger), ledger(r.ledger), finished(r.tally), seconds_before(r.seconds) {}
  bool halted() const { return context.stop_requested() || failed.load(std::memory_order_relaxed); }
  double seconds() const { return seconds_before + std::chrono::duration<double>(Clock::now() - start).count(); }
  long long chunks() const { return ledger.units(); }
  // A task's breach, on rank 0 (caller holds mutex).
  void record_breach(const MonotonicityBreach& b) {
    if (!breach) breach = b;
    failed = true;
  }
  // Whether a checkpoint is due (caller holds mutex).
  bool checkpoint_due(double interval) const {
    return std::chrono::duration<double>(Clock::now() - last_checkpoint).count() >= interval;
  }
};

// Visits the designs of `chunk` line by line (a line: the last free variable running). Each
// line is decoded and bounded once (s.bound; s.x holds the line, s.line its number); the designs
// the line bound excludes are counted at once as violating a constraint, and each other one goes
// to visit(index, i, last, tally) with s.x.back() set to its value (i: its index on the line,
// `last`: the last index of the piece of the line in this chunk that the bound leaves), which
// returns the last index it dealt with (i, or up to `last` when it ruled out a run at once).
// Checks for a stop or a breach between the pieces of lines. False when that left the chunk
// unfinished.
template <class Extra, class Visit>
bool visit_chunk(const SweepControl& control, SweepThread<Extra>& s, const DesignSpace& space, long long chunk,
                 Tally& tally, const Visit& visit) {
  const GridShape& grid = control.grid;
  const long long count = grid.line_length();
  const long long end = std::min(grid.total, (chunk + 1) * grid.chunk);
  for (long long index = chunk * grid.chunk; index < end;) {
    if (control.halted()) return false;
    const long long line = index / count, line_start = line * count;
    if (line != s.line) {
      s.line = line;
      space.grid_point(line_start, grid.counts, s.x.data());
      s.bound->update(s.x.data());
    }
    const long long piece_end = std::min(end, line_start + count) - line_start;
    long long i = index - line_start;
    // The bound excludes a prefix and a suffix of the line: count each part of the piece at once.
    const long long first = std::min(std::max(i, s.bound->first()), piece_end);
    const long long last = std::min(piece_end - 1, s.bound->last());
    tally.constraint_violated += (first - i) + (piece_end - 1 - std::max(last, first - 1));
    for (i = first; i <= last; ++i) {
      if (!s.x.empty()) s.x.back() = s.bound->value(i);  // empty: no free variable, one design
      i = visit(line_start + i, i, last, tally);
    }
    index = line_start + piece_end;
  }
  return true;
}

// The farm both modes fill in: each task is units_per_task() consecutive chunks (the chunks
// finished before skipped), the whole grid split by --shard. run_chunk(chunk, thread, breach,
// tally, out) evaluates one chunk, sets its tally and appends its record to `out`, or returns
// false when a stop left it unfinished; a task's result is its chunks' (index, record) pairs, up
// to a breach. On rank 0, under control.mutex, collect_chunk(chunk, in) reads one record and
// returns whether the chunk is finished (false: a breach), and after_task() runs once per task
// (progress, checkpoint): the per-chunk work is the record alone, since a chunk is only 64
// designs. partial(thread, tally) counts the evaluations of chunks whose task a stop left
// unfinished (a resumed run visits them again).
template <class RunChunk, class CollectChunk, class AfterTask, class Partial>
TaskFarm chunk_farm(SweepControl& control, RunChunk run_chunk, CollectChunk collect_chunk, AfterTask after_task,
                    Partial partial) {
  const long long chunks = control.chunks();
  const long long per_task = units_per_task(chunks);
  TaskFarm farm;
  farm.count = (chunks + per_task - 1) / per_task;
  farm.shardable = true;
  farm.done = [&control, chunks, per_task](long long task) {
    for (long long c = task * per_task; c < std::min(chunks, (task + 1) * per_task); ++c) {
      if (!control.skip.finished(c)) return false;
    }
    return true;
  };
  farm.run = [&control, chunks, per_task, run_chunk, partial](long long task, int thread) -> std::optional<std::string> {
    ByteWriter out;
    Tally finished;  // of the chunks of this task finished so far
    for (long long c = task * per_task; c < std::min(chunks, (task + 1) * per_task); ++c) {
      if (control.skip.finished(c)) continue;
      bool breach = false;
      Tally tally;
      out.put(c);
      if (!run_chunk(c, thread, breach, tally, out)) {
        partial(thread, finished);
        return std::nullopt;
      }
      finished.add(tally);
      if (breach) break;  // this rank's tasks stop; rank 0 learns it from this result
    }
    return out.take();
  };
  farm.collect = [&control, collect_chunk, after_task](long long, std::string&& bytes) {
    ByteReader in(bytes);
    std::lock_guard<std::mutex> lock(control.mutex);
    // The task's finished chunks are consecutive but for chunks skipped or breached: the ledger
    // takes each run of them at once.
    long long run_first = -1, run_end = -1;
    while (!in.at_end()) {
      const auto chunk = in.get<long long>();
      if (!collect_chunk(chunk, in)) continue;
      if (chunk != run_end) {
        control.ledger.add(run_first, run_end);
        run_first = chunk;
      }
      run_end = chunk + 1;
    }
    control.ledger.add(run_first, run_end);
    after_task();
  };
  return farm;
}

// How far an unfinished sweep got and where its checkpoint is: "stopped on request after 41.0%
// of 1,701,900 grid designs; <best>; ...", or for a --shard share the cluster's message.
std::string unfinished_message(const SweepControl& control, bool stopped, const std::string& best) {
  if (!stopped) return control.context.cluster().shard_message() + "; " + best;
  std::ostringstream s;
  s << "stopped on request after " << std::fixed << std::setprecision(1)
    << 100.0 * static_cast<double>(finished_designs(control.ledger, control.grid)) /
           static_cast<double>(control.grid.total)
    << "% of " << with_commas(control.grid.total) << " grid designs; " << best << "; "
    << (control.context.checkpoint_file.empty() ? std::string("no checkpoint file, a new run starts over")
                                                : "checkpoint " + control.context.checkpoint_file +
                                                      " written, resume with --resume");
  return s.str();
}


// The ledgers, counts and times of the shards' states, merged; Error("merge", ...) naming the
// first chunk that two shards both claim.
Resumed merge_common(const std::vector<Json>& states, const GridShape& grid, const char* mode) {
  if (states.empty()) throw Error("merge", "no shard states to merge");
  Resumed merged;
  merged.ledger = RangeLedger(grid.chunks());
  std::vector<RangeLedger> ledgers;
  for (std::size_t k = 0; k < states.size(); ++k) {
    const Resumed r = merge_read(k, states.size(), [&](const SolverContext& c) { return read_common(c, states[k], grid, mode); });
    const long long chunk = merged.ledger.first_overlap(r.ledger);
    if (chunk >= 0) {
      std::size_t other = 0;
      while (other < k && !ledgers[other].finished(chunk)) ++other;
      throw Error("merge", "chunk " + std::to_string(chunk) + " (grid designs " + std::to_string(chunk * grid.chunk) + ".." +
                               std::to_string(std::min(grid.total, (chunk + 1) * grid.chunk) - 1) + ") is finished in shard " +
                               std::to_string(other + 1) + " and in shard " + std::to_string(k + 1) + " of " +
                               std::to_string(states.size()) +
                               ": the shares overlap; merge the shards of one --shard i/N split, each once");
    }
    for (const auto& [first, end] : r.ledger.ranges()) merged.ledger.add(first, end);
    merged.tally.add(r.tally);
    // The shards of a job array run side by side: the merged run took as long as the longest.
    merged.seconds = std::max(merged.seconds, r.seconds);
    ledgers.push_back(r.ledger);
  }
  return merged;
}

// ---------------------------------------------------------------------------------------------
// Best design.

struct BestDesign {
  double best_score = -kInf;
  long long best_index = -1;

  // Larger score wins; of equal scores the first in grid order, so neither the thread or rank
  // count nor the order in which the chunks are visited or collected can matter.
  bool improves_on(double score, long long index) const {
    return score > best_score || (score == best_score && index < best_index);
  }
  void take(double score, long long index) {
    if (!improves_on(score, index)) return;
    best_score = score;
    best_index = index;
  }
};
using BestThread = SweepThread<BestDesign>;

// The checkpoint's best as it claims it (index in the grid, or -1 when none).
BestDesign claimed_best(const GridShape& grid, const SolverContext& context, const Json& state) {
  BestDesign best;
  const Json claimed = checkpoint_field<Json>(context, state, "state", "best");
  if (claimed.is_null()) return best;
  best.best_index = checkpoint_field<long long>(context, claimed, "state.best", "index");
  best.best_score = checkpoint_field<double>(context, claimed, "state.best", "score");
  if (best.best_index < 0 || best.best_index >= grid.total) {
    throw bad_checkpoint(context, "state.best.index = " + std::to_string(best.best_index) + ": not a grid design (0.." +
                                      std::to_string(grid.total - 1) + ")");
  }
  return best;
}

// The checkpoint's best: re-evaluated in full; refused when it does not score what it claims
// (a hand-edited score must never become the study's best).
BestDesign read_best(const Problem& problem, const GridShape& grid, const SolverContext& context, const Json& state) {
  const BestDesign best = claimed_best(grid, context, state);
  if (best.best_index < 0) return best;
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
// Returns true when the front changed. The front of a set of points does not depend on the order
// they are inserted in: chunks, threads and ranks may offer theirs in any order.
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

void put_points(ByteWriter& out, const std::vector<FrontPoint>& points, std::size_t m) {
  out.put<std::uint64_t>(points.size());
  for (const FrontPoint& p : points) {
    out.put(p.index);
    for (std::size_t o = 0; o < m; ++o) out.put(p.values[o]);
  }
}

std::vector<FrontPoint> get_points(ByteReader& in, std::size_t m) {
  std::vector<FrontPoint> points(static_cast<std::size_t>(in.get<std::uint64_t>()));
  for (FrontPoint& p : points) {
    p.index = in.get<long long>();
    p.values.resize(m);
    for (std::size_t o = 0; o < m; ++o) p.values[o] = in.get<double>();
  }
  return points;
}

// The front of a rank's threads (and on rank 0, the collected front).
struct SharedFront {
  std::vector<double> sign;           // +1 maximized, -1 minimized objective
  std::mutex mutex;                   // guards front and flat
  std::vector<FrontPoint> front;
  std::vector<double> flat;           // the front as EvalOptions wants it (natural units)
  std::atomic<long long> version{0};  // bumped when the front changes

  // Inserts a sense-signed point; true when the front changed.
  bool insert(const FrontPoint& p) {
    const std::size_t m = sign.size();
    std::lock_guard<std::mutex> lock(mutex);
    if (!insert_point(front, p)) return false;
    flat.clear();
    for (const FrontPoint& q : front) {
      for (std::size_t o = 0; o < m; ++o) flat.push_back(sign[o] * q.values[o]);
    }
    version.fetch_add(1, std::memory_order_release);
    return true;
  }
  FrontPoint signed_point(const std::vector<double>& objectives, long long index) const {
    FrontPoint p{std::vector<double>(sign.size()), index};
    for (std::size_t o = 0; o < sign.size(); ++o) p.values[o] = sign[o] * objectives[o];
    return p;
  }
  // Offers a feasible design's objectives (natural units) at grid `index`; true when the front
  // changed.
  bool offer(const std::vector<double>& objectives, long long index) { return insert(signed_point(objectives, index)); }
  // The front as the checkpoint holds it: grid index and natural objective values per point.
  Json to_json() {
    std::lock_guard<std::mutex> lock(mutex);
    return points_to_json(front, sign);
  }
  static Json points_to_json(const std::vector<FrontPoint>& points, const std::vector<double>& sign) {
    Json out = Json::array();
    for (const FrontPoint& q : points) {
      std::vector<double> natural(sign.size());
      for (std::size_t o = 0; o < sign.size(); ++o) natural[o] = sign[o] * q.values[o];
      out.push_back({{"index", q.index}, {"objectives", natural}});
    }
    return out;
  }
  std::string bytes() {
    std::lock_guard<std::mutex> lock(mutex);
    ByteWriter out;
    put_points(out, front, sign.size());
    return out.take();
  }
};

// A thread's copy of the front it prunes against, and the front version it was taken at.
struct FrontSnapshot {
  std::vector<double> snapshot;
  long long seen = -1;
};
using FrontThread = SweepThread<FrontSnapshot>;

std::vector<double> front_signs(const Problem& problem) {
  std::vector<double> sign;
  for (const Objective& o : problem.objectives()) sign.push_back(o.sense == Sense::kMaximize ? 1.0 : -1.0);
  return sign;
}

// The checkpoint's front as it claims it: grid index and natural objective values per point.
std::vector<std::pair<long long, std::vector<double>>> claimed_front(const GridShape& grid, const SolverContext& context,
                                                                     const Json& state, std::size_t objectives) {
  const Json points = checkpoint_field<Json>(context, state, "state", "front");
  if (!points.is_array()) throw bad_checkpoint(context, "state.front is not an array");
  std::vector<std::pair<long long, std::vector<double>>> claimed;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::string path = "state.front[" + std::to_string(i) + "]";
    const long long index = checkpoint_field<long long>(context, points[i], path, "index");
    std::vector<double> values = checkpoint_field<std::vector<double>>(context, points[i], path, "objectives");
    if (index < 0 || index >= grid.total || values.size() != objectives) {
      throw bad_checkpoint(context, path + ": index " + std::to_string(index) + " or " + std::to_string(values.size()) +
                                        " objective values do not fit this grid and study");
    }
    claimed.emplace_back(index, std::move(values));
  }
  return claimed;
}

// The checkpoint's front, every point re-evaluated in full and refused when its objective
// values differ from the claimed ones, offered to `shared`.
void read_front(const Problem& problem, const GridShape& grid, const SolverContext& context, const Json& state,
                SharedFront& shared) {
  const auto claimed = claimed_front(grid, context, state, shared.sign.size());
  auto ws = problem.make_eval_scratch();
  std::vector<double> x(problem.design_space().free_size());
  for (std::size_t i = 0; i < claimed.size(); ++i) {
    const auto& [index, values] = claimed[i];
    problem.design_space().grid_point(index, grid.counts, x.data());
    const Evaluation& e = problem.evaluate(x.data(), *ws);
    if (e.status != EvalStatus::kFeasible || e.objectives != values) {
      std::ostringstream s;
      s.precision(17);
      s << "state.front[" << i << "]: grid design " << index << " has objectives " << Json(e.objectives).dump() << " ("
        << to_string(e.status) << ") on re-evaluation, the checkpoint claims " << Json(values).dump();
      throw bad_checkpoint(context, s.str());
    }
    shared.offer(values, index);
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

// The collected counts plus what this rank's threads evaluated in chunks a stop left unfinished.
template <class Extra>
Tally run_tally(const std::vector<SweepThread<Extra>>& states, const Tally& finished) {
  Tally sum = finished;
  for (const SweepThread<Extra>& s : states) sum.add(s.partial);
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
  // Block bounds rule out runs against the incumbent, so only where the evaluator prunes.
  const bool try_blocks = prunes && options_.block_bounds;
  const std::string fingerprint = fingerprint_of(problem, options_);

  // Every rank reads the checkpoint (a collective) and re-evaluates its best alike.
  Resumed resumed;
  resumed.ledger = RangeLedger(grid.chunks());
  BestDesign shared_best;  // guarded by control.mutex: this rank's best, and on rank 0 the collected one
  if (const std::optional<Json> state = read_checkpoint(context, "grid", fingerprint)) {
    resumed = read_common(context, *state, grid, "best");
    shared_best = read_best(problem, grid, context, *state);
  }
  SweepControl control(context, grid, resumed);
  // The pruning threshold: the best score known on this rank, its own or another rank's. Read
  // by every thread at every group of designs: on a cache line of its own, so that writes to
  // its neighbours on this stack do not evict it (coarse pruned grid, 2 threads: 11.9 ms to 11.4 ms).
  alignas(64) std::atomic<double> incumbent{shared_best.best_score};
  std::vector<BestThread> states(static_cast<std::size_t>(std::max(1, context.threads)));

  auto save = [&] {  // caller holds control.mutex
    Json state = common_state("best", grid, control.ledger, control.finished, control.seconds());
    state["best"] = best_to_json(shared_best);
    write_checkpoint(context, "grid", fingerprint, state);
    control.last_checkpoint = Clock::now();
  };
  // A chunk's record: its tally, its best feasible design (index -1: none) and a breach.
  const auto run_chunk = [&](long long chunk, int thread, bool& breach_found, Tally& tally, ByteWriter& out) {
    BestThread& s = states[static_cast<std::size_t>(thread)];
    prepare_thread(s, problem, options_.line_bounds);
    BestDesign chunk_best;
    std::optional<MonotonicityBreach> breach;
    // One design's outcome (`design` its free vector).
    const auto take = [&](long long index, const double* design, const Evaluation& e, Tally& t) {
      t.count(e);
      if (try_blocks) note_deciding_sample(problem, e, s.hints);
      if (e.status != EvalStatus::kFeasible) return;
      chunk_best.take(e.score, index);
      if (!s.improves_on(e.score, index)) return;
      s.take(e.score, index);
      raise_to(incumbent, e.score);
      {
        std::lock_guard<std::mutex> lock(control.mutex);
        shared_best.take(e.score, index);
      }
      // A thread's improvements are few (each raises its best): the spot check is cheap there.
      // It compares with the design's full evaluation, which must be the scratch's last one
      // (e came from a group of designs): evaluate it again, alone.
      if (prunes && !breach) {
        (void)problem.evaluate(design, *s.eval_scratch);
        breach = spot_check(problem, design, *s.eval_scratch, s.check_subset, false);
        if (breach) control.failed = true;  // this rank's tasks stop; rank 0 learns it from the result
      }
    };
    // Designs of one line are evaluated kBlockLanes at a time (Problem::evaluate_designs: the
    // five-bar solves them in one vector per sample), with the incumbent at the group's start.
    const auto flush = [&](Tally& t) {
      if (s.pending.empty()) return;
      const std::size_t dim = s.x.size();
      const double* designs[kBlockLanes];
      for (std::size_t i = 0; i < s.pending.size(); ++i) designs[i] = s.pending_x.data() + i * dim;
      EvalOptions options;
      if (prune) options.prune_below = incumbent.load(std::memory_order_relaxed);
      options.constraints_verified = s.pending_verified;
      problem.evaluate_designs(designs, static_cast<int>(s.pending.size()), *s.eval_scratch, options, s.outs);
      for (std::size_t i = 0; i < s.pending.size(); ++i) take(s.pending[i], designs[i], s.outs[i], t);
      s.pending.clear();
    };
    const bool complete = visit_chunk(control, s, space, chunk, tally, [&](long long index, long long i, long long last, Tally& t) {
      if (try_blocks && s.bound->verified()) {
        if (s.run_line != s.line) {
          s.run_bounds->start_line(s.x.data());
          s.run_line = s.line;
        }
        const RunBounds::Try run = s.run_bounds->try_run(i, last, incumbent.load(std::memory_order_relaxed), s.hints,
                                                         *s.bound, *s.eval_scratch);
        if (run.outcome != RunBounds::Outcome::kNotDue) ++t.block_bounds;
        if (run.ruled_out()) {
          const long long n = run.last - i + 1;
          t.block_ruled_out += n;
          (run.outcome == RunBounds::Outcome::kAllFail ? t.sample_failed : t.pruned) += n;
          return run.last;
        }
      }
      if (s.pending_line != s.line || s.pending.size() == static_cast<std::size_t>(kBlockLanes)) flush(t);
      s.pending_line = s.line;
      // After the flush: the bound already describes this design's line (its update came first).
      if (s.pending.empty()) s.pending_verified = s.bound->verified();
      // Row `row` of pending_x holds the line's design once per line; then only r changes.
      const std::size_t dim = s.x.size(), row = s.pending.size();
      double* slot = s.pending_x.data() + row * dim;
      if (s.row_line[row] != s.line) {
        for (std::size_t k = 0; k < dim; ++k) slot[k] = s.x[k];
        s.row_line[row] = s.line;
      }
      if (dim > 0) slot[dim - 1] = s.x[dim - 1];
      s.pending.push_back(index);
      return i;
    });
    if (complete) flush(tally);
    s.pending.clear();
    if (!complete && !breach) {
      s.partial.add(tally);
      return false;
    }
    breach_found = breach.has_value();
    put_tally(out, tally);
    out.put(chunk_best.best_index).put(chunk_best.best_score);
    put_breach(out, breach);
    return true;
  };
  const auto collect_chunk = [&](long long, ByteReader& in) {  // caller holds control.mutex
    const Tally tally = get_tally(in);
    const auto index = in.get<long long>();
    const auto score = in.get<double>();
    const std::optional<MonotonicityBreach> breach = get_breach(in);
    if (breach) {
      control.record_breach(*breach);  // the chunk stays unfinished
      return false;
    }
    control.finished.add(tally);
    if (index >= 0) {
      shared_best.take(score, index);
      raise_to(incumbent, score);
    }
    return true;
  };
  const auto after_task = [&] {  // caller holds control.mutex
    if (context.progress) {
      report_progress(*context.progress, "grid", finished_designs(control.ledger, grid), grid.total, control.start,
                      control.last_report, options_.progress_interval, [&](std::ostream& out) {
                        out << "best score " << std::setprecision(6) << incumbent.load();
                      });
    }
    if (control.checkpoint_due(options_.checkpoint_interval)) save();
  };
  const auto partial = [&](int thread, const Tally& t) { states[static_cast<std::size_t>(thread)].partial.add(t); };
  TaskFarm farm = chunk_farm(control, run_chunk, collect_chunk, after_task, partial);
  if (prune) {
    farm.share = [&] {
      ByteWriter out;
      out.put(incumbent.load(std::memory_order_relaxed));
      return out.take();
    };
    farm.learn = [&](const std::string& bytes) {
      ByteReader in(bytes);
      raise_to(incumbent, in.get<double>());  // another rank's real design: cuts nothing that ties or beats it
    };
  }
  farm.on_abort = [&] {
    std::lock_guard<std::mutex> lock(control.mutex);
    save();
  };
  const FarmOutcome outcome = context.cluster().run_tasks(farm, static_cast<int>(states.size()));
  if (!context.cluster().root()) return result_of_rank_0(context);
  const Tally sum = run_tally(states, control.finished);

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
  const bool unfinished = !control.ledger.complete();
  const bool stopped = unfinished && (outcome.stopped || context.stop_requested());
  save();
  if (shared_best.best_index < 0) {
    const std::string none = "no feasible design among " + std::to_string(sum.designs()) + " grid designs (" +
                             std::to_string(sum.constraint_violated) + " violate a design constraint, " +
                             std::to_string(sum.sample_failed) + " fail at a sample)";
    result.status = unfinished ? SolverStatus::kStopped : SolverStatus::kInfeasible;
    result.message = unfinished ? unfinished_message(control, stopped, "no feasible design yet") : none;
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
  result.status = unfinished ? SolverStatus::kStopped : SolverStatus::kConverged;
  result.message = unfinished ? unfinished_message(control, stopped, best.str())
                              : "exhaustive search of " + std::to_string(grid.total) + " grid designs, " +
                                    std::to_string(sum.feasible) + " fully evaluated";
  return result;
}

SolverResult GridSolver::solve_front(const Problem& problem, const SolverContext& context) const {
  const GridShape grid(problem.design_space());
  const DesignSpace& space = problem.design_space();
  SharedFront shared;  // this rank's front, and on rank 0 the collected one
  shared.sign = front_signs(problem);
  const std::size_t m = shared.sign.size();
  // Pruning needs upper bounds of maximized worst-case objectives (the evaluator checks too).
  const bool prune = options_.prune && problem.worst_case() &&
                     std::all_of(shared.sign.begin(), shared.sign.end(), [](double s) { return s > 0; });
  const std::string fingerprint = fingerprint_of(problem, options_);

  Resumed resumed;
  resumed.ledger = RangeLedger(grid.chunks());
  if (const std::optional<Json> state = read_checkpoint(context, "grid", fingerprint)) {
    resumed = read_common(context, *state, grid, "front");
    read_front(problem, grid, context, *state, shared);
  }
  SweepControl control(context, grid, resumed);
  std::vector<FrontThread> states(static_cast<std::size_t>(std::max(1, context.threads)));

  auto save = [&] {  // caller holds control.mutex
    Json state = common_state("front", grid, control.ledger, control.finished, control.seconds());
    state["front"] = shared.to_json();
    write_checkpoint(context, "grid", fingerprint, state);
    control.last_checkpoint = Clock::now();
  };
  // A chunk's record: its tally, the front of its feasible designs and a breach.
  const auto run_chunk = [&](long long chunk, int thread, bool& breach_found, Tally& tally, ByteWriter& out) {
    FrontThread& s = states[static_cast<std::size_t>(thread)];
    prepare_thread(s, problem, options_.line_bounds);
    std::vector<FrontPoint> chunk_front;
    std::optional<MonotonicityBreach> breach;
    const bool complete = visit_chunk(control, s, space, chunk, tally, [&](long long index, long long i, long long, Tally& t) {
      if (prune && shared.version.load(std::memory_order_acquire) != s.seen) {
        std::lock_guard<std::mutex> lock(shared.mutex);
        s.snapshot.assign(shared.flat.begin(), shared.flat.end());
        s.seen = shared.version.load(std::memory_order_relaxed);
      }
      EvalOptions options;
      if (prune) options.prune_dominated_by = &s.snapshot;
      const Evaluation& e = problem.evaluate(s.x.data(), *s.eval_scratch, options);
      t.count(e);
      if (e.status != EvalStatus::kFeasible) return i;
      const FrontPoint p = shared.signed_point(e.objectives, index);
      insert_point(chunk_front, p);
      if (!shared.insert(p)) return i;
      // Designs that enter the front are few compared with the grid: the spot check is cheap there.
      if (prune && !breach) {
        breach = spot_check(problem, s.x.data(), *s.eval_scratch, s.check_subset, true);
        if (breach) control.failed = true;
      }
      return i;
    });
    if (!complete && !breach) {
      s.partial.add(tally);
      return false;
    }
    breach_found = breach.has_value();
    put_tally(out, tally);
    put_points(out, chunk_front, m);
    put_breach(out, breach);
    return true;
  };
  const auto collect_chunk = [&](long long, ByteReader& in) {  // caller holds control.mutex
    const Tally tally = get_tally(in);
    const std::vector<FrontPoint> points = get_points(in, m);
    const std::optional<MonotonicityBreach> breach = get_breach(in);
    if (breach) {
      control.record_breach(*breach);  // the chunk stays unfinished
      return false;
    }
    control.finished.add(tally);
    for (const FrontPoint& p : points) shared.insert(p);
    return true;
  };
  const auto after_task = [&] {  // caller holds control.mutex
    if (context.progress) {
      report_progress(*context.progress, "grid (pareto)", finished_designs(control.ledger, grid), grid.total,
                      control.start, control.last_report, options_.progress_interval, [&](std::ostream& out) {
                        std::lock_guard<std::mutex> front_lock(shared.mutex);
                        out << "front " << shared.front.size() << " points";
                      });
    }
    if (control.checkpoint_due(options_.checkpoint_interval)) save();
  };
  const auto partial = [&](int thread, const Tally& t) { states[static_cast<std::size_t>(thread)].partial.add(t); };
  TaskFarm farm = chunk_farm(control, run_chunk, collect_chunk, after_task, partial);
  if (prune) {
    farm.share = [&] { return shared.bytes(); };
    farm.learn = [&](const std::string& bytes) {
      ByteReader in(bytes);
      // Other ranks' points are real designs: pruning against them cuts no point of the final front.
      for (const FrontPoint& p : get_points(in, m)) shared.insert(p);
    };
  }
  farm.on_abort = [&] {
    std::lock_guard<std::mutex> lock(control.mutex);
    save();
  };
  const FarmOutcome outcome = context.cluster().run_tasks(farm, static_cast<int>(states.size()));
  if (!context.cluster().root()) return result_of_rank_0(context);
  const Tally sum = run_tally(states, control.finished);

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
  const bool unfinished = !control.ledger.complete();
  const bool stopped = unfinished && (outcome.stopped || context.stop_requested());
  save();
  result.front = front_solutions(problem, grid, shared);
  if (shared.front.empty()) {
    result.status = unfinished ? SolverStatus::kStopped : SolverStatus::kInfeasible;
    result.message = unfinished ? unfinished_message(control, stopped, "no feasible design yet")
                                : "no feasible design among " + std::to_string(grid.total) + " grid designs";
    return result;
  }
  result.status = unfinished ? SolverStatus::kStopped : SolverStatus::kConverged;
  result.message = unfinished
                       ? unfinished_message(control, stopped, "front so far: " + std::to_string(shared.front.size()) + " points")
                       : "exact Pareto front of " + std::to_string(grid.total) + " grid designs: " +
                             std::to_string(shared.front.size()) + " points, " + std::to_string(sum.feasible) +
                             " designs fully evaluated";
  return result;
}

Json GridSolver::merge_shards(const Problem& problem, const std::vector<Json>& states) const {
  const GridShape grid(problem.design_space());
  const char* mode = options_.pareto ? "front" : "best";
  const Resumed merged = merge_common(states, grid, mode);
  Json state = common_state(mode, grid, merged.ledger, merged.tally, merged.seconds);
  if (options_.pareto) {
    // Each shard's front is the front of its designs: the front of their union is the front of
    // the grid's finished part, whatever the order (ties to the first grid index).
    const std::vector<double> sign = front_signs(problem);
    std::vector<FrontPoint> front;
    for (std::size_t k = 0; k < states.size(); ++k) {
      const auto claimed = merge_read(k, states.size(), [&](const SolverContext& c) {
        return claimed_front(grid, c, states[k], sign.size());
      });
      for (const auto& [index, values] : claimed) {
        FrontPoint p{std::vector<double>(sign.size()), index};
        for (std::size_t o = 0; o < sign.size(); ++o) p.values[o] = sign[o] * values[o];
        insert_point(front, p);
      }
    }
    state["front"] = SharedFront::points_to_json(front, sign);
  } else {
    BestDesign best;
    for (std::size_t k = 0; k < states.size(); ++k) {
      const BestDesign b = merge_read(k, states.size(), [&](const SolverContext& c) { return claimed_best(grid, c, states[k]); });
      if (b.best_index >= 0) best.take(b.best_score, b.best_index);
    }
    state["best"] = best_to_json(best);
  }
  return state;
}

}  // namespace hapsyn::plugins
