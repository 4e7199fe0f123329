#include "culling.hpp"

#include "shared/bounds/ledger.hpp"
#include "shared/bounds/line_bound.hpp"
#include "shared/bounds/run_bounds.hpp"
#include "shared/bounds/rank_support.hpp"
#include "shared/bounds/task_bytes.hpp"
#include "shared/bounds/worst_case_check.hpp"
#include "shared/minmax_sqp.hpp"

#include <hapsyn/accel/sample_block.hpp>
#include <hapsyn/cluster.hpp>
#include <hapsyn/checkpoint.hpp>
#include <hapsyn/error.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <mutex>
#include <optional>
#include <sstream>

namespace hapsyn::plugins {

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kInf = std::numeric_limits<double>::infinity();

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// SQP seed and polish: the shared min-max SQP (plugins/solvers/shared) on the study's score.
// `phase` ("seed", "polish") heads its progress lines, at the study's progress interval.
SqpOutcome run_sqp(const Problem& problem, const std::vector<double>& x, const std::vector<double>& lower,
                   const std::vector<double>& upper, const CullingOptions& options, double xtol,
                   const SolverContext& context, const char* phase) {
  SqpSettings settings;
  settings.xtol = xtol;
  settings.ftol = options.sqp_ftol;
  settings.max_evaluations = options.sqp_max_evaluations;
  settings.report_interval = options.progress_interval;
  if (context.progress) {
    settings.report = [&context, phase](const std::string& line) {
      *context.progress << "culling: SQP " << phase << ", " << line << "\n" << std::flush;
    };
  }
  return run_minmax_sqp(problem, x, lower, upper, settings, score_goal(problem));
}

// ---------------------------------------------------------------------------------------------
// The grid.

struct Grid {
  const DesignSpace* space = nullptr;
  std::vector<long long> counts;
  long long total = 1;

  explicit Grid(const DesignSpace& s) : space(&s), counts(s.grid_counts()) {
    for (long long c : counts) total *= c;
  }
  void decode(long long index, double* x) const { space->grid_point(index, counts, x); }
  long long nearest_cell(std::size_t k, double v) const {
    const DesignComponent& c = space->components()[static_cast<std::size_t>(space->free_indices()[k])];
    const double i = std::floor((v - c.lower) / c.step);
    return std::clamp(static_cast<long long>(i), 0LL, counts[k] - 1);
  }
};

struct Best {
  double score = -kInf;
  long long index = -1;
  bool improves_on(double s, long long i) const { return s > score || (s == score && (index < 0 || i < index)); }
};

// The free variables' bounds, and whether one of them is integer-valued (no SQP then).
struct Bounds {
  std::vector<double> lower, upper;
  bool any_integer = false;

  explicit Bounds(const DesignSpace& space) : lower(space.free_size()), upper(space.free_size()) {
    for (std::size_t k = 0; k < lower.size(); ++k) {
      const DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
      lower[k] = c.lower;
      upper[k] = c.upper;
      any_integer = any_integer || c.integer;
    }
  }
};

struct SweepCounts {
  long long culled = 0, constraint_violated = 0, failed_at_bound = 0, full_searches = 0, full_feasible = 0,
            full_pruned = 0, full_failed = 0, bound_samples = 0, full_samples = 0, block_bounds = 0,
            block_ruled_out = 0;

  void add(const SweepCounts& c) {
    culled += c.culled;
    constraint_violated += c.constraint_violated;
    failed_at_bound += c.failed_at_bound;
    full_searches += c.full_searches;
    full_feasible += c.full_feasible;
    full_pruned += c.full_pruned;
    full_failed += c.full_failed;
    bound_samples += c.bound_samples;
    full_samples += c.full_samples;
    block_bounds += c.block_bounds;
    block_ruled_out += c.block_ruled_out;
  }
  // The counts since `before` (a line's share of a thread's counts).
  SweepCounts since(const SweepCounts& before) const {
    SweepCounts d = *this;
    d.culled -= before.culled;
    d.constraint_violated -= before.constraint_violated;
    d.failed_at_bound -= before.failed_at_bound;
    d.full_searches -= before.full_searches;
    d.full_feasible -= before.full_feasible;
    d.full_pruned -= before.full_pruned;
    d.full_failed -= before.full_failed;
    d.bound_samples -= before.bound_samples;
    d.full_samples -= before.full_samples;
    d.block_bounds -= before.block_bounds;
    d.block_ruled_out -= before.block_ruled_out;
    return d;
  }
  Json to_json() const {
    return {{"culled", culled}, {"constraint_violated", constraint_violated}, {"failed_at_bound", failed_at_bound},
            {"full_searches", full_searches}, {"full_feasible", full_feasible}, {"full_pruned", full_pruned},
            {"full_failed", full_failed}, {"bound_samples", bound_samples}, {"full_samples", full_samples},
            {"block_bounds", block_bounds}, {"block_ruled_out", block_ruled_out}};
  }
};

// What the seed and the sweep share: the reference (the best fully evaluated feasible grid
// design so far) and the global critical samples, in the order found. Each rank has its own,
// fed by its threads and by what the other ranks share (TaskFarm::learn); on rank 0 it is also
// the run's collected state (ledger, counts, breach), which TaskFarm::collect fills.
struct Reference {
  std::mutex mutex;  // guards best, critical, is_critical, iterations, the members below and the progress stream
  Best best;
  std::atomic<double> score{-kInf};  // best.score, readable without the lock
  std::vector<int> critical;
  std::vector<char> is_critical;
  std::atomic<int> critical_count{0};
  long long iterations = 0;  // reference updates
  RangeLedger ledger;         // the sweep's finished lines
  SweepCounts finished;       // the counts of the finished lines (before a resume included)
  std::optional<MonotonicityBreach> breach;
  std::atomic<bool> failed{false};  // a breach is known on this rank: its threads stop

  explicit Reference(int samples) : is_critical(static_cast<std::size_t>(samples), 0) {}

  // Adds critical samples not known yet (caller holds the mutex).
  void publish(const std::vector<std::vector<int>>& per_metric) {
    for (const auto& list : per_metric) {
      for (int s : list) {
        if (s >= 0 && !is_critical[static_cast<std::size_t>(s)]) {
          is_critical[static_cast<std::size_t>(s)] = 1;
          critical.push_back(s);
        }
      }
    }
    critical_count.store(static_cast<int>(critical.size()), std::memory_order_release);
  }
  // Offers a fully evaluated feasible grid design as the reference (caller holds the mutex).
  // True when it became the reference.
  bool offer(long long index, double value) {
    if (!best.improves_on(value, index)) return false;
    best.score = value;
    best.index = index;
    score.store(value, std::memory_order_relaxed);
    return true;
  }
  // The same, counted as a reference update (caller holds the mutex).
  void update(long long index, double value) {
    if (offer(index, value)) ++iterations;
  }
};

// No free variable: the fixed design is the whole grid.
SolverResult evaluate_fixed_design(const Problem& problem, const SolverContext& context) {
  SolverResult result;
  const Evaluation e = problem.evaluate_parallel(nullptr, context.threads);
  result.design_evaluations = 1;
  result.sample_evaluations = e.samples_evaluated;
  if (e.status == EvalStatus::kFeasible) {
    result.best = SolutionPoint{problem.full_design(nullptr), e.objectives, e.score};
    result.status = SolverStatus::kConverged;
    result.message = "no free design variable: evaluated the fixed design";
  } else {
    result.status = SolverStatus::kInfeasible;
    result.message = "no free design variable and the fixed design is infeasible";
  }
  return result;
}

// ---------------------------------------------------------------------------------------------
// 1. Seed: the best point of a coarse start grid, SQP from there, snapped to the design grid.

struct Seed {
  Json statistics = Json::object();
  long long designs = 0, samples = 0;
  // False when a stop request cut the seed short: its checkpoint then holds no reference, and a
  // resumed run seeds again (the sweep of a resumed run must start from the seed's reference,
  // or its counts and evaluations would differ from an uninterrupted run's).
  bool complete = false;
};

// The best feasible point of a coarse grid of start points (empty if none); at most 1e5 points.
std::vector<double> best_start_point(const Problem& problem, const Bounds& bounds, int start_points,
                                     Problem::EvalScratch& ws, Seed& seed, const SolverContext& context) {
  const std::size_t n = bounds.lower.size();
  int m = start_points;
  while (m > 2 && std::pow(static_cast<double>(m), static_cast<double>(n)) > 1e5) --m;
  long long starts = 1;
  for (std::size_t k = 0; k < n; ++k) starts *= m;
  std::vector<double> x(n), start;
  double start_score = -kInf;
  for (long long i = 0; i < starts && std::pow(2.0, static_cast<double>(n)) <= 1e5 && !context.stop_requested(); ++i) {
    long long rest = i;
    for (std::size_t k = n; k-- > 0;) {
      x[k] = bounds.lower[k] + (bounds.upper[k] - bounds.lower[k]) * static_cast<double>(rest % m) / (m - 1);
      rest /= m;
    }
    EvalOptions o;
    o.prune_below = start_score;
    const Evaluation& e = problem.evaluate(x.data(), ws, o);
    ++seed.designs;
    seed.samples += e.samples_evaluated;
    if (e.status == EvalStatus::kFeasible && e.score > start_score) {
      start_score = e.score;
      start = x;
    }
  }
  seed.statistics["start_grid_points"] = starts;
  return start;
}

// Offers the feasible corners of the grid cell that holds `continuous` as the reference.
void snap_to_grid(const Problem& problem, const Grid& grid, const std::vector<double>& continuous,
                  Problem::EvalScratch& ws, Reference& reference, Seed& seed, const SolverContext& context) {
  const std::size_t n = continuous.size();
  std::vector<double> x(n);
  const long long corners = 1LL << n;
  for (long long c = 0; c < corners && n <= 20 && !context.stop_requested(); ++c) {
    long long index = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const long long i = std::min(grid.nearest_cell(k, continuous[k]) + ((c >> k) & 1), grid.counts[k] - 1);
      index = index * grid.counts[k] + i;
    }
    grid.decode(index, x.data());
    const Evaluation& e = problem.evaluate(x.data(), ws);
    ++seed.designs;
    seed.samples += e.samples_evaluated;
    if (e.status == EvalStatus::kFeasible) {
      std::lock_guard<std::mutex> lock(reference.mutex);
      reference.update(index, e.score);
      reference.publish(e.critical_samples);
    }
  }
}

// Stops between evaluations (and before the SQP) on request: a resumed run keeps what it found.
Seed seed_reference(const Problem& problem, const Grid& grid, const Bounds& bounds, const CullingOptions& options,
                    Reference& reference, const SolverContext& context) {
  Seed seed;
  const auto t0 = Clock::now();
  auto ws = problem.make_eval_scratch();
  const std::vector<double> start = best_start_point(problem, bounds, options.start_points, *ws, seed, context);
  if (!start.empty() && !context.stop_requested()) {
    std::vector<double> continuous = start;
    if (!bounds.any_integer) {
      const SqpOutcome sqp = run_sqp(problem, start, bounds.lower, bounds.upper, options, options.seed_xtol, context, "seed");
      seed.designs += sqp.evaluations;
      seed.samples += sqp.samples;
      seed.statistics["sqp"] = {{"status", sqp.status}, {"evaluations", sqp.evaluations}, {"score", sqp.merit},
                                {"rounds", sqp.rounds}, {"active_samples", sqp.active_samples},
                                {"seconds", sqp.seconds}};
      if (!sqp.x.empty()) continuous = sqp.x;
    }
    snap_to_grid(problem, grid, continuous, *ws, reference, seed, context);
  }
  seed.statistics["reference_score"] = reference.best.index >= 0 ? Json(reference.best.score) : Json(nullptr);
  seed.statistics["seconds"] = seconds_since(t0);
  seed.complete = !context.stop_requested();
  return seed;
}

// ---------------------------------------------------------------------------------------------
// 2. The culling sweep over the grid: lines along the last variable, the tasks of one task farm
//    (handed out in order to every thread of every rank; a --shard share is a contiguous slice).

// Cache-line aligned: each thread writes its own per design, never a line another thread writes.
struct alignas(64) SweepThread {
  std::unique_ptr<Problem::EvalScratch> eval_scratch;
  std::vector<int> local;  // critical samples, most recently useful first
  int known = 0;           // global critical samples merged so far
  std::vector<double> x;
  std::optional<LineBound> line_bound;  // designs of the current line the constraints rule out
  std::vector<double> group_x;          // kBlockLanes rows: the line's designs bounded together
  std::vector<Evaluation> group_outs;   // their bounds
  std::vector<int> group_order;         // s.local as the group was bounded
  std::optional<RunBounds> run_bounds;  // block bounds of runs of the current line
  SweepCounts counts;         // this run's, lines finished or not
  SweepCounts partial;        // of the lines a stop left unfinished
  std::vector<double> bound;  // the objectives' bound at the critical samples of the current design
  bool has_bound = false;
  // What the current line found, for its task result.
  Best line_best;
  std::vector<int> line_critical;
  std::optional<MonotonicityBreach> breach;
};

// Merges the global critical samples found since the thread last looked.
void catch_up(SweepThread& s, Reference& reference) {
  const int count = reference.critical_count.load(std::memory_order_acquire);
  if (count <= s.known) return;
  // New critical samples come from better references: they cull best, so they go first.
  std::lock_guard<std::mutex> lock(reference.mutex);
  s.local.insert(s.local.begin(), reference.critical.begin() + s.known, reference.critical.begin() + count);
  s.known = count;
}

// Takes the bound of the design in s.x at the thread's critical samples (`e`, evaluated on
// s.group_order, the order s.local had when its group was bounded). True when that rules it
// out (culled, failed at a critical sample or violating a design constraint).
bool ruled_out_by_bound(SweepThread& s, const Evaluation& e) {
  s.has_bound = false;
  s.counts.bound_samples += e.samples_evaluated;
  if (e.status == EvalStatus::kConstraintViolated) {
    ++s.counts.constraint_violated;
    return true;
  }
  if (e.status == EvalStatus::kPruned || e.status == EvalStatus::kSampleFailed) {
    // Move the deciding sample to the front: neighbouring designs tend to fail on it too.
    const int deciding = s.group_order[static_cast<std::size_t>(e.samples_evaluated - 1)];
    if (s.local.front() != deciding) {
      const auto at = std::find(s.local.begin(), s.local.end(), deciding);
      std::rotate(s.local.begin(), at, at + 1);
    }
    if (e.status == EvalStatus::kPruned) {
      ++s.counts.culled;
    } else {
      ++s.counts.failed_at_bound;
    }
    return true;
  }
  // Kept for the monotonicity check, should the full search complete.
  s.bound.assign(e.objectives.begin(), e.objectives.end());
  s.has_bound = e.status == EvalStatus::kFeasible;
  return false;
}

// Adds critical samples to the reference and to the line's result (caller holds reference.mutex).
void publish(SweepThread& s, Reference& reference, const std::vector<std::vector<int>>& per_metric) {
  reference.publish(per_metric);
  for (const auto& list : per_metric) {
    for (int sample : list) {
      if (sample >= 0) s.line_critical.push_back(sample);
    }
  }
}

// Searches the whole workspace for the design in s.x (grid `index`) and shares what it found.
// A feasible result is checked against the design's bound at the critical samples: a bound
// below the full value breaks the rule culling rests on (s.breach; the rank's threads stop).
void full_search(const Problem& problem, SweepThread& s, long long index, double threshold, Reference& reference) {
  EvalOptions full;
  full.prune_below = threshold;
  const Evaluation& e = problem.evaluate(s.x.data(), *s.eval_scratch, full);
  if (e.status == EvalStatus::kConstraintViolated) {
    ++s.counts.constraint_violated;
    return;
  }
  ++s.counts.full_searches;
  s.counts.full_samples += e.samples_evaluated;
  std::lock_guard<std::mutex> lock(reference.mutex);
  switch (e.status) {
    case EvalStatus::kFeasible:
      ++s.counts.full_feasible;
      if (s.has_bound) {
        if (auto breach = compare_bounds(problem, s.x.data(), s.bound, e.objectives,
                                         static_cast<long long>(s.local.size()), false)) {
          if (!s.breach) s.breach = breach;
          reference.failed = true;
          return;
        }
      }
      reference.update(index, e.score);
      if (s.line_best.improves_on(e.score, index)) s.line_best = Best{e.score, index};
      publish(s, reference, e.critical_samples);
      break;
    case EvalStatus::kPruned:
      ++s.counts.full_pruned;
      publish(s, reference, e.critical_samples);
      break;
    case EvalStatus::kSampleFailed:
      ++s.counts.full_failed;
      publish(s, reference, std::vector<std::vector<int>>{std::vector<int>{e.failed_sample}});
      break;
    case EvalStatus::kConstraintViolated: break;
  }
}

// Every design of one grid line (the last variable running), bounded first, searched in full
// when the bound cannot rule it out. False when a stop request (or a breach) left it unfinished.
bool cull_line(const Problem& problem, const Grid& grid, long long line, SweepThread& s, Reference& reference,
               const SolverContext& context, bool block_bounds) {
  const std::size_t n = s.x.size();
  const long long line_length = grid.counts[n - 1];
  catch_up(s, reference);
  grid.decode(line * line_length, s.x.data());
  s.line_bound->update(s.x.data());
  // Block bounds on lines whose run is verified, so that the designs they rule out are known to
  // satisfy the constraints (the counts stay those of a run without them).
  const bool try_blocks = block_bounds && s.line_bound->verified();
  if (try_blocks) s.run_bounds->start_line(s.x.data());
  for (std::size_t row = 0; row < static_cast<std::size_t>(kBlockLanes); ++row) {
    std::copy(s.x.begin(), s.x.end(), s.group_x.begin() + static_cast<std::ptrdiff_t>(row * n));
  }
  // The designs of the line in groups of up to kBlockLanes, bounded together at the critical
  // samples (Problem::evaluate_designs: one vector per sample for the five-bar), then taken one
  // by one in grid order: a design the bound cannot rule out gets its full search at once.
  long long i = 0;
  while (i < line_length) {
    if (context.stop_requested() || reference.failed.load(std::memory_order_relaxed)) return false;
    long long group_index[kBlockLanes];
    const double* designs[kBlockLanes];
    int count = 0;
    for (; i < line_length && count < kBlockLanes; ++i) {
      if (s.line_bound->excludes(i)) {
        // The bound excludes a prefix and a suffix of the line: count each at once.
        const long long end = i < s.line_bound->first() ? std::min(s.line_bound->first(), line_length) : line_length;
        s.counts.constraint_violated += end - i;
        i = end - 1;
        continue;
      }
      if (try_blocks) {
        const RunBounds::Try t = s.run_bounds->try_run(i, s.line_bound->last(), reference.score.load(std::memory_order_relaxed),
                                                       s.local, *s.line_bound, *s.eval_scratch);
        if (t.outcome != RunBounds::Outcome::kNotDue) ++s.counts.block_bounds;
        if (t.ruled_out()) {
          s.counts.block_ruled_out += t.last - i + 1;
          i = t.last;
          continue;
        }
      }
      double* slot = s.group_x.data() + static_cast<std::size_t>(count) * n;
      slot[n - 1] = s.line_bound->value(i);
      designs[count] = slot;
      group_index[count++] = line * line_length + i;
    }
    if (count == 0) break;
    const double threshold = reference.score.load(std::memory_order_relaxed);
    if (s.local.empty()) {
      for (int j = 0; j < count; ++j) {
        std::copy(designs[j], designs[j] + n, s.x.begin());
        s.has_bound = false;
        full_search(problem, s, group_index[j], threshold, reference);
      }
      continue;
    }
    s.group_order.assign(s.local.begin(), s.local.end());
    EvalOptions bound;
    bound.subset = &s.group_order;
    bound.prune_below = threshold;
    bound.constraints_verified = s.line_bound->verified();
    problem.evaluate_designs(designs, count, *s.eval_scratch, bound, s.group_outs);
    for (int j = 0; j < count; ++j) {
      if (ruled_out_by_bound(s, s.group_outs[static_cast<std::size_t>(j)])) continue;
      // The bound cannot rule the design out: search the whole workspace.
      std::copy(designs[j], designs[j] + n, s.x.begin());
      full_search(problem, s, group_index[j], reference.score.load(std::memory_order_relaxed), reference);
    }
  }
  return true;
}

// "culling: P% of N grid designs, ..." (the caller holds the reference's mutex).
std::string progress_line(const Grid& grid, const Reference& reference, double elapsed) {
  const double fraction = static_cast<double>(reference.ledger.count()) / static_cast<double>(reference.ledger.units());
  std::ostringstream out;
  out << std::fixed << std::setprecision(1) << "culling: " << 100.0 * fraction << "% of " << grid.total
      << " grid designs, " << std::setprecision(3) << static_cast<double>(grid.total) * (1 - fraction) / 1e6
      << "M left, " << std::setprecision(2) << static_cast<double>(reference.finished.culled) / elapsed / 1e6
      << "M culled/s, reference " << std::setprecision(6) << reference.score.load() << ", " << reference.critical.size()
      << " critical samples, " << std::setprecision(1) << elapsed << " s elapsed, ~" << elapsed * (1 - fraction) / fraction
      << " s left\n";
  return out.str();
}

void put_counts(ByteWriter& out, const SweepCounts& c) {
  out.put(c.culled).put(c.constraint_violated).put(c.failed_at_bound).put(c.full_searches).put(c.full_feasible);
  out.put(c.full_pruned).put(c.full_failed).put(c.bound_samples).put(c.full_samples).put(c.block_bounds);
  out.put(c.block_ruled_out);
}

SweepCounts get_counts(ByteReader& in) {
  SweepCounts c;
  for (long long* v : {&c.culled, &c.constraint_violated, &c.failed_at_bound, &c.full_searches, &c.full_feasible,
                       &c.full_pruned, &c.full_failed, &c.bound_samples, &c.full_samples, &c.block_bounds,
                       &c.block_ruled_out}) {
    *v = in.get<long long>();
  }
  return c;
}

void put_samples(ByteWriter& out, const std::vector<int>& samples) {
  out.put<std::uint64_t>(samples.size());
  for (int v : samples) out.put(v);
}

std::vector<std::vector<int>> get_samples(ByteReader& in) {
  std::vector<std::vector<int>> samples(1);
  samples[0].resize(static_cast<std::size_t>(in.get<std::uint64_t>()));
  for (int& v : samples[0]) v = in.get<int>();
  return samples;
}

// The result of one task of the sweep (consecutive grid lines), sent to rank 0 as one record:
// the lines finished, their summed counts, each line's best fully searched design (lines
// without one left out), the critical samples they found (in order) and a breach.
struct TaskLines {
  std::vector<long long> lines;
  SweepCounts counts;
  std::vector<std::pair<long long, double>> bests;  // (grid index, score), in line order
  std::vector<int> critical;
  std::optional<MonotonicityBreach> breach;

  void add(long long line, const SweepCounts& line_counts, const Best& best, const std::vector<int>& found) {
    lines.push_back(line);
    counts.add(line_counts);
    if (best.index >= 0) bests.emplace_back(best.index, best.score);
    critical.insert(critical.end(), found.begin(), found.end());
  }
  std::string bytes() const {
    ByteWriter out;
    out.put<std::uint64_t>(lines.size());
    for (long long line : lines) out.put(line);
    put_counts(out, counts);
    out.put<std::uint64_t>(bests.size());
    for (const auto& [index, score] : bests) out.put(index).put(score);
    put_samples(out, critical);
    put_breach(out, breach);
    return out.take();
  }
  static TaskLines from(const std::string& bytes) {
    ByteReader in(bytes);
    TaskLines t;
    t.lines.resize(static_cast<std::size_t>(in.get<std::uint64_t>()));
    for (long long& line : t.lines) line = in.get<long long>();
    t.counts = get_counts(in);
    t.bests.resize(static_cast<std::size_t>(in.get<std::uint64_t>()));
    for (auto& [index, score] : t.bests) {
      index = in.get<long long>();
      score = in.get<double>();
    }
    t.critical = get_samples(in)[0];
    t.breach = get_breach(in);
    return t;
  }
};

// The sweep of the lines not finished yet, tasks of consecutive lines on every thread of every
// rank; rank 0 collects each task's lines, counts, best designs and critical samples
// (TaskLines) and, when due, reports
// progress and calls save(); the ranks share their reference and critical samples as they find
// them. Returns the farm's outcome and, in `partial`, this rank's counts of unfinished lines.
template <class Save>
FarmOutcome sweep(const Problem& problem, const Grid& grid, const CullingOptions& options, const SolverContext& context,
                  Reference& reference, const Save& save, SweepCounts& partial) {
  std::vector<SweepThread> states(static_cast<std::size_t>(std::max(1, context.threads)));
  // Each thread builds its own state at its first line, on that thread (docs/design.md section
  // 1.5: built here, the threads' buffers shared cache lines).
  const auto prepare = [&](SweepThread& s) {
    s.eval_scratch = problem.make_eval_scratch();
    s.x.resize(grid.counts.size());
    s.line_bound.emplace(problem, options.line_bounds, "culling");
    s.group_x.assign(static_cast<std::size_t>(kBlockLanes) * grid.counts.size(), 0.0);
    s.run_bounds.emplace(problem, "culling");
  };
  const RangeLedger skip = reference.ledger;  // finished before this run
  auto last_report = Clock::now(), last_checkpoint = Clock::now();
  const auto t_sweep = Clock::now();
  // One line of a task, added to the task's result (TaskLines): its counts, its best fully
  // searched design, the critical samples it found. False when a stop left it unfinished (its
  // counts then go to the thread's partial counts) or a breach ended it (task.breach set).
  const auto run_line = [&](long long line, int thread, TaskLines& task) {
    SweepThread& s = states[static_cast<std::size_t>(thread)];
    if (!s.eval_scratch) prepare(s);
    const SweepCounts before = s.counts;
    s.line_best = Best{};
    s.line_critical.clear();
    s.breach.reset();
    const bool complete = cull_line(problem, grid, line, s, reference, context, options.block_bounds);
    if (!complete && !s.breach) {
      s.partial.add(s.counts.since(before));
      return false;
    }
    if (s.breach) {
      task.breach = s.breach;  // the line stays unfinished
      return false;
    }
    task.add(line, s.counts.since(before), s.line_best, s.line_critical);
    return true;
  };
  // A task's result, collected on rank 0: its finished lines, their counts, bests (in line
  // order, so that the reference updates are counted as line by line) and critical samples.
  const auto collect_task = [&](const TaskLines& task) {
    std::lock_guard<std::mutex> lock(reference.mutex);
    for (long long line : task.lines) reference.ledger.finish(line);
    reference.finished.add(task.counts);
    for (const auto& [index, score] : task.bests) reference.update(index, score);
    reference.publish(std::vector<std::vector<int>>{task.critical});
    if (task.breach) {
      if (!reference.breach) reference.breach = task.breach;
      reference.failed = true;
      return;
    }
    if (context.progress && seconds_since(last_report) >= options.progress_interval) {
      last_report = Clock::now();
      *context.progress << progress_line(grid, reference, seconds_since(t_sweep)) << std::flush;
    }
    if (seconds_since(last_checkpoint) >= options.checkpoint_interval) {
      save();
      last_checkpoint = Clock::now();
    }
  };
  // Each task is units_per_task() consecutive lines (those finished before skipped); its result
  // is its finished lines' results in one record (TaskLines), up to a breach. A stop loses the task's finished lines
  // (a resumed run sweeps them again); their counts stay in the thread's partial counts.
  const long long lines = reference.ledger.units();
  const long long per_task = units_per_task(lines);
  TaskFarm farm;
  farm.count = (lines + per_task - 1) / per_task;
  farm.shardable = true;
  farm.done = [&](long long task) {
    for (long long line = task * per_task; line < std::min(lines, (task + 1) * per_task); ++line) {
      if (!skip.finished(line)) return false;
    }
    return true;
  };
  farm.run = [&](long long task, int thread) -> std::optional<std::string> {
    TaskLines result;
    for (long long line = task * per_task; line < std::min(lines, (task + 1) * per_task); ++line) {
      if (skip.finished(line)) continue;
      if (run_line(line, thread, result)) continue;
      if (result.breach) break;  // this rank's tasks stop; rank 0 learns it from this result
      states[static_cast<std::size_t>(thread)].partial.add(result.counts);
      return std::nullopt;
    }
    return result.bytes();
  };
  farm.collect = [&](long long, std::string&& bytes) { collect_task(TaskLines::from(bytes)); };
  // The reference (a real design's full score: it culls nothing that ties or beats it) and the
  // critical samples (any subset of samples bounds from above), as the ranks find them.
  farm.share = [&] {
    std::lock_guard<std::mutex> lock(reference.mutex);
    ByteWriter out;
    out.put(reference.best.index).put(reference.best.score);
    put_samples(out, reference.critical);
    return out.take();
  };
  farm.learn = [&](const std::string& bytes) {
    ByteReader in(bytes);
    const auto index = in.get<long long>();
    const auto score = in.get<double>();
    const std::vector<std::vector<int>> critical = get_samples(in);
    std::lock_guard<std::mutex> lock(reference.mutex);
    if (index >= 0) reference.offer(index, score);
    reference.publish(critical);
  };
  farm.on_abort = [&] {
    std::lock_guard<std::mutex> lock(reference.mutex);
    save();
  };
  const FarmOutcome outcome = context.cluster().run_tasks(farm, static_cast<int>(states.size()));
  for (const SweepThread& s : states) partial.add(s.partial);
  return outcome;
}

Json sweep_statistics(const Grid& grid, const SweepCounts& sum, const Reference& reference, int samples) {
  Json stats;
  stats["grid_designs"] = grid.total;
  stats["grid_counts"] = grid.counts;
  stats["feasible_designs"] = grid.total - sum.constraint_violated;  // satisfy the design constraints
  stats["constraint_violated"] = sum.constraint_violated;
  stats["culled"] = sum.culled;
  stats["failed_at_critical_sample"] = sum.failed_at_bound;
  stats["full_workspace_searches"] = sum.full_searches;
  stats["full_searches_feasible"] = sum.full_feasible;
  stats["full_searches_pruned"] = sum.full_pruned;
  stats["full_searches_failed"] = sum.full_failed;
  stats["bound_sample_evaluations"] = sum.bound_samples;
  stats["full_search_sample_evaluations"] = sum.full_samples;
  stats["block_bounds"] = sum.block_bounds;        // runs of a line tried at once (section 13.5)
  stats["block_ruled_out"] = sum.block_ruled_out;  // designs those ruled out, not in the counts above
  stats["iterations"] = reference.iterations;
  stats["critical_samples"] = reference.critical.size();
  stats["samples_per_full_search"] = samples;
  return stats;
}

// ---------------------------------------------------------------------------------------------
// 3. Polish: SQP within the optimum's cell (one step either side), keeping the better point.

// Replaces `point` (the grid optimum x) by the polished design when that is better; returns
// the polish statistics.
Json polish_cell(const Problem& problem, const std::vector<double>& x, const CullingOptions& options,
                 Problem::EvalScratch& ws, SolutionPoint& point, SolverResult& result, const SolverContext& context) {
  const DesignSpace& space = problem.design_space();
  const std::size_t n = x.size();
  std::vector<double> lo(n), hi(n);
  for (std::size_t k = 0; k < n; ++k) {
    const DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
    lo[k] = std::max(c.lower, x[k] - c.step);
    hi[k] = std::min(c.upper, x[k] + c.step);
  }
  const SqpOutcome sqp = run_sqp(problem, x, lo, hi, options, options.sqp_xtol, context, "polish");
  result.design_evaluations += sqp.evaluations;
  result.sample_evaluations += sqp.samples;
  Json polish = {{"status", sqp.status}, {"evaluations", sqp.evaluations}, {"rounds", sqp.rounds},
                 {"active_samples", sqp.active_samples}, {"seconds", sqp.seconds}};
  if (!sqp.x.empty() && sqp.merit > point.score) {
    const Evaluation polished = problem.evaluate(sqp.x.data(), ws);
    point = SolutionPoint{problem.full_design(sqp.x.data()), polished.objectives, polished.score};
    polish["improved"] = true;
  } else {
    polish["improved"] = false;
  }
  return polish;
}


// ---------------------------------------------------------------------------------------------
// 4. Checkpoints.

// What a breach means for culling.
constexpr const char* kCullingBreach =
    "culling relies on that rule, so its result could be wrong: solve this study with the grid solver and "
    "prune: false";

// The checkpoint's fingerprint: the study and the options that change the result (not the
// progress and checkpoint intervals or the size cap, which a resumed run may change).
std::string fingerprint_of(const Problem& problem, const CullingOptions& options) {
  return study_fingerprint(problem, options_to_json(options), {"progress_interval", "checkpoint_interval", "max_designs"});
}

// The checkpoint's state (caller holds reference.mutex, or the sweep is not running). A seed cut
// short leaves the state of a run that has not started (see Seed::complete).
Json checkpoint_state(const Reference& reference, const Seed& seed, double seconds) {
  Json state;
  state["lines"] = reference.ledger.units();
  if (!seed.complete) {
    RangeLedger(reference.ledger.units()).write(state, "finished_lines");
    state["reference"] = nullptr;
    state["critical_samples"] = Json::array();
    state["iterations"] = 0;
    state["counts"] = SweepCounts().to_json();
    state["seed"] = {{"statistics", Json::object()}, {"designs", 0}, {"samples", 0}, {"complete", false}};
  } else {
    reference.ledger.write(state, "finished_lines");
    state["reference"] = reference.best.index < 0 ? Json(nullptr)
                                                  : Json{{"index", reference.best.index}, {"score", reference.best.score}};
    state["critical_samples"] = reference.critical;
    state["iterations"] = reference.iterations;
    state["counts"] = reference.finished.to_json();
    state["seed"] = {{"statistics", seed.statistics}, {"designs", seed.designs}, {"samples", seed.samples},
                     {"complete", true}};
  }
  state["elapsed_seconds"] = seconds;
  return state;
}

SweepCounts counts_from(const SolverContext& context, const Json& state) {
  const Json c = checkpoint_field<Json>(context, state, "state", "counts");
  SweepCounts n;
  n.culled = checkpoint_field<long long>(context, c, "state.counts", "culled");
  n.constraint_violated = checkpoint_field<long long>(context, c, "state.counts", "constraint_violated");
  n.failed_at_bound = checkpoint_field<long long>(context, c, "state.counts", "failed_at_bound");
  n.full_searches = checkpoint_field<long long>(context, c, "state.counts", "full_searches");
  n.full_feasible = checkpoint_field<long long>(context, c, "state.counts", "full_feasible");
  n.full_pruned = checkpoint_field<long long>(context, c, "state.counts", "full_pruned");
  n.full_failed = checkpoint_field<long long>(context, c, "state.counts", "full_failed");
  n.bound_samples = checkpoint_field<long long>(context, c, "state.counts", "bound_samples");
  n.full_samples = checkpoint_field<long long>(context, c, "state.counts", "full_samples");
  n.block_bounds = checkpoint_field<long long>(context, c, "state.counts", "block_bounds");
  n.block_ruled_out = checkpoint_field<long long>(context, c, "state.counts", "block_ruled_out");
  return n;
}

// Reads a checkpoint's state into `reference` (the ledger, the counts, the critical samples and
// the reference as claimed) and `seed`. Returns the seconds spent before.
double read_state(const Problem& problem, const Grid& grid, const SolverContext& context, const Json& state,
                  Reference& reference, Seed& seed) {
  const long long lines = reference.ledger.units();
  if (checkpoint_field<long long>(context, state, "state", "lines") != lines) {
    throw bad_checkpoint(context, "state.lines does not match this grid (" + std::to_string(lines) + " lines)");
  }
  reference.ledger = RangeLedger::read(context, state, "finished_lines", "line", lines);
  std::vector<std::vector<int>> critical(1);
  for (int sample : checkpoint_field<std::vector<int>>(context, state, "state", "critical_samples")) {
    if (sample < 0 || sample >= problem.samples().size()) {
      throw bad_checkpoint(context, "state.critical_samples: sample " + std::to_string(sample) + " is not one of the " +
                                        std::to_string(problem.samples().size()) + " samples");
    }
    critical[0].push_back(sample);
  }
  reference.publish(critical);
  reference.iterations = checkpoint_field<long long>(context, state, "state", "iterations");
  reference.finished = counts_from(context, state);
  const Json s = checkpoint_field<Json>(context, state, "state", "seed");
  seed.statistics = checkpoint_field<Json>(context, s, "state.seed", "statistics");
  seed.designs = checkpoint_field<long long>(context, s, "state.seed", "designs");
  seed.samples = checkpoint_field<long long>(context, s, "state.seed", "samples");
  // (older checkpoints lack the field; they are read as before, as complete)
  seed.complete = !s.contains("complete") || checkpoint_field<bool>(context, s, "state.seed", "complete");
  const Json claimed = checkpoint_field<Json>(context, state, "state", "reference");
  if (!claimed.is_null()) {
    const long long index = checkpoint_field<long long>(context, claimed, "state.reference", "index");
    const double score = checkpoint_field<double>(context, claimed, "state.reference", "score");
    if (index < 0 || index >= grid.total) {
      throw bad_checkpoint(context, "state.reference.index = " + std::to_string(index) + ": not a grid design (0.." +
                                        std::to_string(grid.total - 1) + ")");
    }
    reference.best.index = index;
    reference.best.score = score;
    reference.score.store(score);
  }
  return checkpoint_field<double>(context, state, "state", "elapsed_seconds");
}

// Restores the sweep from a checkpoint's state; the reference is re-evaluated in full and the
// checkpoint refused when it does not score what it claims (a hand-edited score must never
// become the reference, let alone the optimum). Returns the seconds spent before.
double restore(const Problem& problem, const Grid& grid, const SolverContext& context, const Json& state,
               Reference& reference, Seed& seed) {
  const double seconds = read_state(problem, grid, context, state, reference, seed);
  if (reference.best.index < 0) return seconds;
  std::vector<double> x(grid.counts.size());
  grid.decode(reference.best.index, x.data());
  auto ws = problem.make_eval_scratch();
  const Evaluation& e = problem.evaluate(x.data(), *ws);
  if (e.status != EvalStatus::kFeasible || e.score != reference.best.score) {
    std::ostringstream m;
    m.precision(17);
    m << "state.reference: grid design " << reference.best.index << " scores " << e.score << " ("
      << to_string(e.status) << ") on re-evaluation, the checkpoint claims " << reference.best.score;
    throw bad_checkpoint(context, m.str());
  }
  return seconds;
}

// "stopped on request after 41.0% of 1,701,900 grid designs; <best>; checkpoint ... written, ...",
// or when a --shard share is done (not `stopped`), the cluster's message.
std::string stopped_message(const Grid& grid, const Reference& reference, const SolverContext& context, bool stopped,
                            const std::string& best) {
  if (!stopped) return context.cluster().shard_message() + "; " + best;
  std::string total = std::to_string(grid.total), commas;
  for (std::size_t i = 0; i < total.size(); ++i) {
    if (i > 0 && (total.size() - i) % 3 == 0) commas += ',';
    commas += total[i];
  }
  std::ostringstream s;
  s << "stopped on request after " << std::fixed << std::setprecision(1)
    << 100.0 * static_cast<double>(reference.ledger.count()) / static_cast<double>(reference.ledger.units()) << "% of "
    << commas << " grid designs; " << best << "; "
    << (context.checkpoint_file.empty() ? std::string("no checkpoint file, a new run starts over")
                                        : "checkpoint " + context.checkpoint_file + " written, resume with --resume");
  return s.str();
}

// The result of a run stopped before its seed (the start grid and the SQP) was complete.
SolverResult stopped_in_seed(const SolverContext& context, double seconds) {
  SolverResult result;
  result.status = SolverStatus::kStopped;
  result.message = "stopped on request during the seed (the start grid and the SQP), before the sweep; " +
                   (context.checkpoint_file.empty()
                        ? std::string("no checkpoint file, a new run starts over")
                        : "checkpoint " + context.checkpoint_file + " written, resume with --resume (the seed runs again)");
  result.statistics = {{"seconds", seconds}};
  return result;
}

// What ranks other than 0 need of the seed that rank 0 ran: the reference, the critical samples
// and the seed's figures (doubles survive JSON text exactly).
Json seed_message(const Reference& reference, const Seed& seed) {
  return {{"index", reference.best.index}, {"score", reference.best.index < 0 ? Json(nullptr) : Json(reference.best.score)},
          {"critical", reference.critical}, {"iterations", reference.iterations},
          {"statistics", seed.statistics}, {"designs", seed.designs}, {"samples", seed.samples},
          {"complete", seed.complete}};
}

void adopt_seed(const Json& message, Reference& reference, Seed& seed) {
  reference.best.index = message["index"].get<long long>();
  if (reference.best.index >= 0) {
    reference.best.score = message["score"].get<double>();
    reference.score.store(reference.best.score);
  }
  reference.publish({message["critical"].get<std::vector<int>>()});
  reference.iterations = message["iterations"].get<long long>();
  seed.statistics = message["statistics"];
  seed.designs = message["designs"].get<long long>();
  seed.samples = message["samples"].get<long long>();
  seed.complete = message["complete"].get<bool>();
}


}  // namespace

void CullingSolver::check(const Problem& problem) const {
  for (const Objective& o : problem.objectives()) {
    const MetricEntry& m = problem.metrics()[static_cast<std::size_t>(o.metric)];
    if (m.metric->aggregation() != Aggregation::kWorstCase) {
      throw Error("culling", "metric '" + m.plugin + "' (objective '" + o.name +
                                 "') is not worst-case (it sums over samples): culling needs worst-case metrics, "
                                 "whose value on a subset of samples bounds the whole");
    }
    if (o.sense != Sense::kMaximize) {
      throw Error("culling", "objective '" + o.name + "' (metric '" + m.plugin +
                                 "') is minimized: the per-sample bound of a worst-case metric bounds it from above, "
                                 "so culling maximizes only");
    }
    if (o.weight < 0.0) {
      throw Error("culling", "objective '" + o.name + "' has weight " + std::to_string(o.weight) +
                                 ": a weighted sum keeps the per-sample bound only with non-negative weights");
    }
  }
  problem.design_space().check_grid("culling", options_.max_designs);
}

SolverResult CullingSolver::solve(const Problem& problem, const SolverContext& context) const {
  const auto t_start = Clock::now();
  const DesignSpace& space = problem.design_space();
  if (space.free_size() == 0) return evaluate_fixed_design(problem, context);
  Cluster& cluster = context.cluster();
  const Grid grid(space);
  const Bounds bounds(space);
  Reference reference(problem.samples().size());
  reference.ledger = RangeLedger(grid.total / grid.counts.back());
  const std::string fingerprint = fingerprint_of(problem, options_);

  Seed seed;
  double seconds_before = 0.0;
  // Every rank reads the checkpoint (a collective) and re-evaluates its reference alike.
  const std::optional<Json> state = read_checkpoint(context, "culling", fingerprint);
  if (state) seconds_before = restore(problem, grid, context, *state, reference, seed);
  const bool seeded_before = state && seed.complete;
  if (!seeded_before && !options_.seed) {
    seed.complete = true;
  } else if (!seeded_before) {
    // Rank 0 seeds (the SQP is one sequential run) and the other ranks take its outcome, so that
    // every rank starts the sweep from the same reference whatever its floating point.
    if (cluster.root()) seed = seed_reference(problem, grid, bounds, options_, reference, context);
    if (cluster.size() > 1) {
      std::string message = cluster.root() ? seed_message(reference, seed).dump() : std::string();
      cluster.broadcast(message);
      if (!cluster.root()) adopt_seed(Json::parse(message), reference, seed);
    }
  }
  auto save = [&] {  // caller holds reference.mutex, or the sweep is not running
    write_checkpoint(context, "culling", fingerprint,
                     checkpoint_state(reference, seed, seconds_before + seconds_since(t_start)));
  };
  if (!seed.complete) {
    save();  // a resumed run seeds again
    return cluster.root() ? stopped_in_seed(context, seconds_before + seconds_since(t_start)) : result_of_rank_0(context);
  }
  if (!seeded_before) save();  // the seed is done: a resumed run skips it
  const auto t_sweep = Clock::now();
  SweepCounts partial;
  const FarmOutcome outcome = sweep(problem, grid, options_, context, reference, save, partial);
  if (!cluster.root()) return result_of_rank_0(context);
  const double sweep_seconds = seconds_since(t_sweep);
  // The collected lines' counts (before a resume included) and this rank's unfinished lines'.
  SweepCounts sum = reference.finished;
  sum.add(partial);

  SolverResult result;
  result.design_evaluations = seed.designs + grid.total;
  result.sample_evaluations = seed.samples + sum.bound_samples + sum.full_samples;
  Json stats = sweep_statistics(grid, sum, reference, problem.samples().size());
  stats["seed"] = seed.statistics;
  stats["sweep_seconds"] = sweep_seconds;
  stats["seconds"] = seconds_before + seconds_since(t_start);
  result.statistics = stats;
  if (reference.breach) {
    result.status = SolverStatus::kFailed;
    result.message = breach_message(problem, *reference.breach, kCullingBreach);
    return result;
  }
  const bool unfinished = !reference.ledger.complete();
  const bool stopped = unfinished && (outcome.stopped || context.stop_requested());
  save();
  if (reference.best.index < 0) {
    result.status = unfinished ? SolverStatus::kStopped : SolverStatus::kInfeasible;
    result.message = unfinished ? stopped_message(grid, reference, context, stopped, "no feasible design yet")
                                : "no feasible design among " + std::to_string(grid.total) + " grid designs";
    return result;
  }
  std::vector<double> x(space.free_size());
  grid.decode(reference.best.index, x.data());
  auto ws = problem.make_eval_scratch();
  const Evaluation grid_best = problem.evaluate(x.data(), *ws);
  result.sample_evaluations += grid_best.samples_evaluated;
  SolutionPoint point{problem.full_design(x.data()), grid_best.objectives, grid_best.score};
  stats["grid_optimum"] = {{"design", problem.design_to_json(point.design)}, {"objectives", point.objectives},
                           {"score", point.score}, {"index", reference.best.index}};
  std::vector<int> subset;
  if (auto breach = spot_check(problem, x.data(), *ws, subset, false)) {
    result.status = SolverStatus::kFailed;
    result.message = breach_message(problem, *breach, kCullingBreach);
    return result;
  }
  if (unfinished) {
    result.best = point;
    result.statistics = stats;
    std::ostringstream best;
    best.precision(10);
    best << "best so far: score " << point.score << " (grid design " << reference.best.index << ", not polished)";
    result.status = SolverStatus::kStopped;
    result.message = stopped_message(grid, reference, context, stopped, best.str());
    return result;
  }
  if (options_.polish && !bounds.any_integer) stats["polish"] = polish_cell(problem, x, options_, *ws, point, result, context);
  result.best = point;
  stats["seconds"] = seconds_before + seconds_since(t_start);
  result.statistics = stats;
  result.status = SolverStatus::kConverged;
  std::ostringstream msg;
  msg << "culling of " << grid.total << " grid designs: " << sum.full_searches << " full workspace searches, "
      << sum.culled << " culled at critical samples";
  result.message = msg.str();
  return result;
}

Json CullingSolver::merge_shards(const Problem& problem, const std::vector<Json>& states) const {
  if (states.empty()) throw Error("merge", "no shard states to merge");
  const DesignSpace& space = problem.design_space();
  if (space.free_size() == 0) throw Error("merge", "the study has no free design variable: there is nothing to merge");
  const Grid grid(space);
  Reference merged(problem.samples().size());
  merged.ledger = RangeLedger(grid.total / grid.counts.back());
  std::vector<RangeLedger> ledgers;
  Seed seed;
  double seconds = 0.0;
  for (std::size_t k = 0; k < states.size(); ++k) {
    Reference shard(problem.samples().size());
    shard.ledger = RangeLedger(merged.ledger.units());
    Seed shard_seed;
    // The claimed reference is re-evaluated by the resume that follows the merge, not here.
    const double shard_seconds = merge_read(k, states.size(), [&](const SolverContext& c) {
      return read_state(problem, grid, c, states[k], shard, shard_seed);
    });
    const long long line = merged.ledger.first_overlap(shard.ledger);
    if (line >= 0) {
      std::size_t other = 0;
      while (other < k && !ledgers[other].finished(line)) ++other;
      throw Error("merge", "line " + std::to_string(line) + " (grid designs " +
                               std::to_string(line * grid.counts.back()) + ".." +
                               std::to_string((line + 1) * grid.counts.back() - 1) + ") is finished in shard " +
                               std::to_string(other + 1) + " and in shard " + std::to_string(k + 1) + " of " +
                               std::to_string(states.size()) +
                               ": the shares overlap; merge the shards of one --shard i/N split, each once");
    }
    for (const auto& [first, end] : shard.ledger.ranges()) merged.ledger.add(first, end);
    merged.finished.add(shard.finished);
    if (shard.best.index >= 0) merged.offer(shard.best.index, shard.best.score);
    merged.publish({shard.critical});
    merged.iterations += shard.iterations;
    // Every shard ran the same seed (the same study and options): the first complete one's stands.
    if (!seed.complete && shard_seed.complete) seed = shard_seed;
    // The shards of a job array run side by side: the merged run took as long as the longest.
    seconds = std::max(seconds, shard_seconds);
    ledgers.push_back(shard.ledger);
  }
  return checkpoint_state(merged, seed, seconds);
}

}  // namespace hapsyn::plugins
