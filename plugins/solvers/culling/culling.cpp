#include "culling.hpp"

#include "shared/minmax_sqp.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/parallel.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <mutex>
#include <set>
#include <sstream>

namespace hapsyn::plugins {

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kInf = std::numeric_limits<double>::infinity();

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// SQP seed and polish: the shared min-max SQP (plugins/solvers/shared) on the study's score.
SqpOutcome run_sqp(const Problem& problem, const std::vector<double>& x, const std::vector<double>& lower,
                   const std::vector<double>& upper, const CullingOptions& options) {
  SqpSettings settings;
  settings.xtol = options.sqp_xtol;
  settings.ftol = options.sqp_ftol;
  settings.max_evaluations = options.sqp_max_evaluations;
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

// What the seed and the sweep share: the reference (the best fully evaluated feasible grid
// design so far) and the global critical samples, in the order found.
struct Reference {
  std::mutex mutex;  // guards best, critical, is_critical, iterations and the progress stream
  Best best;
  std::atomic<double> score{-kInf};  // best.score, readable without the lock
  std::vector<int> critical;
  std::vector<char> is_critical;
  std::atomic<int> critical_count{0};
  long long iterations = 0;  // reference updates

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
  void offer(long long index, const Evaluation& e) {
    if (!best.improves_on(e.score, index)) return;
    best.score = e.score;
    best.index = index;
    score.store(e.score, std::memory_order_relaxed);
    ++iterations;
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
};

// The best feasible point of a coarse grid of start points (empty if none); at most 1e5 points.
std::vector<double> best_start_point(const Problem& problem, const Bounds& bounds, int start_points,
                                     Problem::EvalScratch& ws, Seed& seed) {
  const std::size_t n = bounds.lower.size();
  int m = start_points;
  while (m > 2 && std::pow(static_cast<double>(m), static_cast<double>(n)) > 1e5) --m;
  long long starts = 1;
  for (std::size_t k = 0; k < n; ++k) starts *= m;
  std::vector<double> x(n), start;
  double start_score = -kInf;
  for (long long i = 0; i < starts && std::pow(2.0, static_cast<double>(n)) <= 1e5; ++i) {
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
                  Problem::EvalScratch& ws, Reference& reference, Seed& seed) {
  const std::size_t n = continuous.size();
  std::vector<double> x(n);
  const long long corners = 1LL << n;
  for (long long c = 0; c < corners && n <= 20; ++c) {
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
      reference.offer(index, e);
      reference.publish(e.critical_samples);
    }
  }
}

Seed seed_reference(const Problem& problem, const Grid& grid, const Bounds& bounds, const CullingOptions& options,
                    Reference& reference) {
  Seed seed;
  const auto t0 = Clock::now();
  auto ws = problem.make_eval_scratch();
  const std::vector<double> start = best_start_point(problem, bounds, options.start_points, *ws, seed);
  if (!start.empty()) {
    std::vector<double> continuous = start;
    if (!bounds.any_integer) {
      const SqpOutcome sqp = run_sqp(problem, start, bounds.lower, bounds.upper, options);
      seed.designs += sqp.evaluations;
      seed.samples += sqp.samples;
      seed.statistics["sqp"] = {{"status", sqp.status}, {"evaluations", sqp.evaluations}, {"score", sqp.merit},
                                {"rounds", sqp.rounds}, {"active_samples", sqp.active_samples},
                                {"seconds", sqp.seconds}};
      if (!sqp.x.empty()) continuous = sqp.x;
    }
    snap_to_grid(problem, grid, continuous, *ws, reference, seed);
  }
  seed.statistics["reference_score"] = reference.best.index >= 0 ? Json(reference.best.score) : Json(nullptr);
  seed.statistics["seconds"] = seconds_since(t0);
  return seed;
}

// ---------------------------------------------------------------------------------------------
// 2. The culling sweep over the grid: lines along the last variable, handed out dynamically.

struct SweepCounts {
  long long culled = 0, constraint_violated = 0, failed_at_bound = 0, full_searches = 0, full_feasible = 0,
            full_pruned = 0, full_failed = 0, bound_samples = 0, full_samples = 0;

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
  }
};

struct SweepThread {
  std::unique_ptr<Problem::EvalScratch> eval_scratch;
  std::vector<int> local;  // critical samples, most recently useful first
  int known = 0;           // global critical samples merged so far
  std::vector<double> x;
  SweepCounts counts;
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

// Bounds the design in s.x at the thread's critical samples. True when that rules it out
// (culled, failed at a critical sample or violating a design constraint).
bool ruled_out_by_bound(const Problem& problem, SweepThread& s, double threshold) {
  if (s.local.empty()) return false;
  EvalOptions bound;
  bound.subset = &s.local;
  bound.prune_below = threshold;
  const Evaluation& e = problem.evaluate(s.x.data(), *s.eval_scratch, bound);
  s.counts.bound_samples += e.samples_evaluated;
  if (e.status == EvalStatus::kConstraintViolated) {
    ++s.counts.constraint_violated;
    return true;
  }
  if (e.status == EvalStatus::kPruned || e.status == EvalStatus::kSampleFailed) {
    // Move the deciding sample to the front: neighbouring designs tend to fail on it too.
    const std::size_t j = static_cast<std::size_t>(e.samples_evaluated - 1);
    std::rotate(s.local.begin(), s.local.begin() + static_cast<std::ptrdiff_t>(j),
                s.local.begin() + static_cast<std::ptrdiff_t>(j) + 1);
    if (e.status == EvalStatus::kPruned) {
      ++s.counts.culled;
    } else {
      ++s.counts.failed_at_bound;
    }
    return true;
  }
  return false;
}

// Searches the whole workspace for the design in s.x (grid `index`) and shares what it found.
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
      reference.offer(index, e);
      reference.publish(e.critical_samples);
      break;
    case EvalStatus::kPruned:
      ++s.counts.full_pruned;
      reference.publish(e.critical_samples);
      break;
    case EvalStatus::kSampleFailed:
      ++s.counts.full_failed;
      reference.publish(std::vector<std::vector<int>>{std::vector<int>{e.failed_sample}});
      break;
    case EvalStatus::kConstraintViolated: break;
  }
}

// Every design of one grid line (the last variable running), bounded first, searched in full
// when the bound cannot rule it out.
void cull_line(const Problem& problem, const Grid& grid, long long line, SweepThread& s, Reference& reference) {
  const std::size_t n = s.x.size();
  const long long line_length = grid.counts[n - 1];
  catch_up(s, reference);
  grid.decode(line * line_length, s.x.data());
  for (long long i = 0; i < line_length; ++i) {
    const long long index = line * line_length + i;
    s.x[n - 1] = grid.space->grid_value(n - 1, i);
    const double threshold = reference.score.load(std::memory_order_relaxed);
    if (ruled_out_by_bound(problem, s, threshold)) continue;
    // The bound cannot rule the design out: search the whole workspace.
    full_search(problem, s, index, threshold, reference);
  }
}

// "culling: P% of N grid designs, ..." (the caller holds the reference's mutex).
std::string progress_line(const Grid& grid, const std::vector<SweepThread>& states, const Reference& reference,
                          long long lines_done, long long lines, double elapsed) {
  const double fraction = static_cast<double>(lines_done) / static_cast<double>(lines);
  long long culled = 0;
  for (const SweepThread& st : states) culled += st.counts.culled;
  std::ostringstream out;
  out << std::fixed << std::setprecision(1) << "culling: " << 100.0 * fraction << "% of " << grid.total
      << " grid designs, " << std::setprecision(3) << static_cast<double>(grid.total) * (1 - fraction) / 1e6
      << "M left, " << std::setprecision(2) << static_cast<double>(culled) / elapsed / 1e6 << "M culled/s, reference "
      << std::setprecision(6) << reference.score.load() << ", " << reference.critical.size() << " critical samples, "
      << std::setprecision(1) << elapsed << " s elapsed, ~" << elapsed * (1 - fraction) / fraction << " s left\n";
  return out.str();
}

// The sweep on the context's threads; returns the counts summed over the threads.
SweepCounts sweep(const Problem& problem, const Grid& grid, const CullingOptions& options,
                  const SolverContext& context, Reference& reference) {
  std::vector<SweepThread> states(static_cast<std::size_t>(std::max(1, context.threads)));
  for (SweepThread& s : states) {
    s.eval_scratch = problem.make_eval_scratch();
    s.x.resize(grid.counts.size());
  }
  const long long lines = grid.total / grid.counts.back();
  std::atomic<long long> lines_done{0};
  auto last_report = Clock::now();
  const auto t_sweep = Clock::now();
  parallel_for_dynamic(lines, static_cast<int>(states.size()), 4, [&](long long line, int t) {
    if (context.stop && context.stop->load(std::memory_order_relaxed)) return;
    cull_line(problem, grid, line, states[static_cast<std::size_t>(t)], reference);
    const long long done = lines_done.fetch_add(1, std::memory_order_relaxed) + 1;
    if (context.progress && t == 0 && seconds_since(last_report) >= options.progress_interval) {
      std::lock_guard<std::mutex> lock(reference.mutex);
      last_report = Clock::now();
      *context.progress << progress_line(grid, states, reference, done, lines, seconds_since(t_sweep)) << std::flush;
    }
  });
  SweepCounts sum;
  for (const SweepThread& s : states) sum.add(s.counts);
  return sum;
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
                 Problem::EvalScratch& ws, SolutionPoint& point, SolverResult& result) {
  const DesignSpace& space = problem.design_space();
  const std::size_t n = x.size();
  std::vector<double> lo(n), hi(n);
  for (std::size_t k = 0; k < n; ++k) {
    const DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
    lo[k] = std::max(c.lower, x[k] - c.step);
    hi[k] = std::min(c.upper, x[k] + c.step);
  }
  const SqpOutcome sqp = run_sqp(problem, x, lo, hi, options);
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
  problem.design_space().check_grid("culling");
}

SolverResult CullingSolver::solve(const Problem& problem, const SolverContext& context) const {
  const auto t_start = Clock::now();
  const DesignSpace& space = problem.design_space();
  if (space.free_size() == 0) return evaluate_fixed_design(problem, context);
  const Grid grid(space);
  const Bounds bounds(space);
  Reference reference(problem.samples().size());

  const Seed seed = options_.seed ? seed_reference(problem, grid, bounds, options_, reference) : Seed{};
  const auto t_sweep = Clock::now();
  const SweepCounts sum = sweep(problem, grid, options_, context, reference);
  const double sweep_seconds = seconds_since(t_sweep);

  SolverResult result;
  result.design_evaluations = seed.designs + grid.total;
  result.sample_evaluations = seed.samples + sum.bound_samples + sum.full_samples;
  Json stats = sweep_statistics(grid, sum, reference, problem.samples().size());
  stats["seed"] = seed.statistics;
  stats["sweep_seconds"] = sweep_seconds;

  const bool stopped = context.stop && context.stop->load();
  if (reference.best.index < 0) {
    result.status = stopped ? SolverStatus::kStopped : SolverStatus::kInfeasible;
    result.message = "no feasible design among " + std::to_string(grid.total) + " grid designs";
    result.statistics = stats;
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
  if (options_.polish && !bounds.any_integer) stats["polish"] = polish_cell(problem, x, options_, *ws, point, result);
  result.best = point;
  stats["seconds"] = seconds_since(t_start);
  result.statistics = stats;
  result.status = stopped ? SolverStatus::kStopped : SolverStatus::kConverged;
  std::ostringstream msg;
  msg << (stopped ? "stopped early; best so far of " : "culling of ") << grid.total << " grid designs: "
      << sum.full_searches << " full workspace searches, " << sum.culled << " culled at critical samples";
  result.message = msg.str();
  return result;
}

}  // namespace hapsyn::plugins
