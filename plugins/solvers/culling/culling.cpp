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
  const std::size_t n = space.free_size();
  const int samples = problem.samples().size();
  SolverResult result;
  Json stats;

  if (n == 0) {  // nothing to search: the fixed design is the grid
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

  const Grid grid(space);
  std::vector<double> lower(n), upper(n);
  bool any_integer = false;
  for (std::size_t k = 0; k < n; ++k) {
    const DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
    lower[k] = c.lower;
    upper[k] = c.upper;
    any_integer = any_integer || c.integer;
  }

  std::mutex mutex;  // guards best, critical, and the progress stream
  Best best;
  std::atomic<double> reference{-kInf};
  std::vector<int> critical;  // global critical samples, in the order found
  std::vector<char> is_critical(static_cast<std::size_t>(samples), 0);
  std::atomic<int> critical_count{0};
  long long iterations = 0;  // reference updates

  auto publish = [&](const std::vector<std::vector<int>>& per_metric) {
    for (const auto& list : per_metric) {
      for (int s : list) {
        if (s >= 0 && !is_critical[static_cast<std::size_t>(s)]) {
          is_critical[static_cast<std::size_t>(s)] = 1;
          critical.push_back(s);
        }
      }
    }
    critical_count.store(static_cast<int>(critical.size()), std::memory_order_release);
  };
  // Offers a fully evaluated feasible grid design as the reference (caller holds the mutex).
  auto offer = [&](long long index, const Evaluation& e) {
    if (!best.improves_on(e.score, index)) return;
    best.score = e.score;
    best.index = index;
    reference.store(e.score, std::memory_order_relaxed);
    ++iterations;
  };

  // 1. Seed: best point of a coarse start grid, SQP from there, snapped to the design grid.
  Json seed_stats = Json::object();
  long long seed_samples = 0, seed_designs = 0;
  if (options_.seed) {
    const auto t0 = Clock::now();
    auto ws = problem.make_workspace();
    int m = options_.start_points;
    while (m > 2 && std::pow(static_cast<double>(m), static_cast<double>(n)) > 1e5) --m;
    long long starts = 1;
    for (std::size_t k = 0; k < n; ++k) starts *= m;
    std::vector<double> x(n), start;
    double start_score = -kInf;
    for (long long i = 0; i < starts && std::pow(2.0, static_cast<double>(n)) <= 1e5; ++i) {
      long long rest = i;
      for (std::size_t k = n; k-- > 0;) {
        x[k] = lower[k] + (upper[k] - lower[k]) * static_cast<double>(rest % m) / (m - 1);
        rest /= m;
      }
      EvalOptions o;
      o.prune_below = start_score;
      const Evaluation& e = problem.evaluate(x.data(), *ws, o);
      ++seed_designs;
      seed_samples += e.samples_evaluated;
      if (e.status == EvalStatus::kFeasible && e.score > start_score) {
        start_score = e.score;
        start = x;
      }
    }
    seed_stats["start_grid_points"] = starts;
    if (!start.empty()) {
      std::vector<double> continuous = start;
      if (!any_integer) {
        const SqpOutcome sqp = run_sqp(problem, start, lower, upper, options_);
        seed_designs += sqp.evaluations;
        seed_samples += sqp.samples;
        seed_stats["sqp"] = {{"status", sqp.status}, {"evaluations", sqp.evaluations}, {"score", sqp.merit},
                             {"rounds", sqp.rounds}, {"active_samples", sqp.active_samples}, {"seconds", sqp.seconds}};
        if (!sqp.x.empty()) continuous = sqp.x;
      }
      // Snap: the best feasible corner of the grid cell holding the continuous optimum.
      const long long corners = 1LL << n;
      for (long long c = 0; c < corners && n <= 20; ++c) {
        long long index = 0;
        for (std::size_t k = 0; k < n; ++k) {
          const long long i = std::min(grid.nearest_cell(k, continuous[k]) + ((c >> k) & 1), grid.counts[k] - 1);
          index = index * grid.counts[k] + i;
        }
        grid.decode(index, x.data());
        const Evaluation& e = problem.evaluate(x.data(), *ws);
        ++seed_designs;
        seed_samples += e.samples_evaluated;
        if (e.status == EvalStatus::kFeasible) {
          std::lock_guard<std::mutex> lock(mutex);
          offer(index, e);
          publish(e.critical_samples);
        }
      }
    }
    seed_stats["reference_score"] = best.index >= 0 ? Json(best.score) : Json(nullptr);
    seed_stats["seconds"] = seconds_since(t0);
  }

  // 2. Culling sweep over the grid: lines along the last variable, handed out dynamically.
  struct ThreadState {
    std::unique_ptr<Problem::Workspace> workspace;
    std::vector<int> local;  // critical samples, most recently useful first
    int known = 0;           // global critical samples merged so far
    std::vector<double> x;
    long long culled = 0, constraint_violated = 0, failed_at_bound = 0, full_searches = 0, full_feasible = 0,
              full_pruned = 0, full_failed = 0, bound_samples = 0, full_samples = 0;
  };
  const int threads = std::max(1, context.threads);
  std::vector<ThreadState> states(static_cast<std::size_t>(threads));
  for (ThreadState& s : states) {
    s.workspace = problem.make_workspace();
    s.x.resize(n);
  }
  const long long line_length = grid.counts[n - 1];
  const long long lines = grid.total / line_length;
  std::atomic<long long> lines_done{0};
  auto last_report = Clock::now();
  const auto t_sweep = Clock::now();

  parallel_for_dynamic(lines, threads, 4, [&](long long line, int t) {
    if (context.stop && context.stop->load(std::memory_order_relaxed)) return;
    ThreadState& s = states[static_cast<std::size_t>(t)];
    const int count = critical_count.load(std::memory_order_acquire);
    if (count > s.known) {
      // New critical samples come from better references: they cull best, so they go first.
      std::lock_guard<std::mutex> lock(mutex);
      s.local.insert(s.local.begin(), critical.begin() + s.known, critical.begin() + count);
      s.known = count;
    }
    grid.decode(line * line_length, s.x.data());
    for (long long i = 0; i < line_length; ++i) {
      const long long index = line * line_length + i;
      s.x[n - 1] = space.grid_value(n - 1, i);
      const double threshold = reference.load(std::memory_order_relaxed);
      if (!s.local.empty()) {
        EvalOptions bound;
        bound.subset = &s.local;
        bound.prune_below = threshold;
        const Evaluation& e = problem.evaluate(s.x.data(), *s.workspace, bound);
        s.bound_samples += e.samples_evaluated;
        if (e.status == EvalStatus::kConstraintViolated) {
          ++s.constraint_violated;
          continue;
        }
        if (e.status == EvalStatus::kPruned || e.status == EvalStatus::kSampleFailed) {
          // Move the deciding sample to the front: neighbouring designs tend to fail on it too.
          const std::size_t j = static_cast<std::size_t>(e.samples_evaluated - 1);
          std::rotate(s.local.begin(), s.local.begin() + static_cast<std::ptrdiff_t>(j),
                      s.local.begin() + static_cast<std::ptrdiff_t>(j) + 1);
          if (e.status == EvalStatus::kPruned) {
            ++s.culled;
          } else {
            ++s.failed_at_bound;
          }
          continue;
        }
      }
      // The bound cannot rule the design out: search the whole workspace.
      EvalOptions full;
      full.prune_below = threshold;
      const Evaluation& e = problem.evaluate(s.x.data(), *s.workspace, full);
      if (e.status == EvalStatus::kConstraintViolated) {
        ++s.constraint_violated;
        continue;
      }
      ++s.full_searches;
      s.full_samples += e.samples_evaluated;
      std::lock_guard<std::mutex> lock(mutex);
      switch (e.status) {
        case EvalStatus::kFeasible:
          ++s.full_feasible;
          offer(index, e);
          publish(e.critical_samples);
          break;
        case EvalStatus::kPruned:
          ++s.full_pruned;
          publish(e.critical_samples);
          break;
        case EvalStatus::kSampleFailed:
          ++s.full_failed;
          publish(std::vector<std::vector<int>>{std::vector<int>{e.failed_sample}});
          break;
        case EvalStatus::kConstraintViolated: break;
      }
    }
    const long long done = lines_done.fetch_add(1, std::memory_order_relaxed) + 1;
    if (context.progress && t == 0 && seconds_since(last_report) >= options_.progress_interval) {
      std::lock_guard<std::mutex> lock(mutex);
      last_report = Clock::now();
      const double elapsed = seconds_since(t_sweep);
      const double fraction = static_cast<double>(done) / static_cast<double>(lines);
      long long culled = 0;
      for (const ThreadState& st : states) culled += st.culled;
      std::ostringstream line_out;
      line_out << std::fixed << std::setprecision(1) << "culling: " << 100.0 * fraction << "% of " << grid.total
               << " grid designs, " << std::setprecision(3) << static_cast<double>(grid.total) * (1 - fraction) / 1e6
               << "M left, " << std::setprecision(2) << static_cast<double>(culled) / elapsed / 1e6 << "M culled/s, reference "
               << std::setprecision(6) << reference.load() << ", " << critical.size() << " critical samples, "
               << std::setprecision(1) << elapsed << " s elapsed, ~" << elapsed * (1 - fraction) / fraction << " s left\n";
      *context.progress << line_out.str() << std::flush;
    }
  });
  const double sweep_seconds = seconds_since(t_sweep);

  ThreadState sum;
  for (const ThreadState& s : states) {
    sum.culled += s.culled;
    sum.constraint_violated += s.constraint_violated;
    sum.failed_at_bound += s.failed_at_bound;
    sum.full_searches += s.full_searches;
    sum.full_feasible += s.full_feasible;
    sum.full_pruned += s.full_pruned;
    sum.full_failed += s.full_failed;
    sum.bound_samples += s.bound_samples;
    sum.full_samples += s.full_samples;
  }
  result.design_evaluations = seed_designs + grid.total;
  result.sample_evaluations = seed_samples + sum.bound_samples + sum.full_samples;
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
  stats["iterations"] = iterations;
  stats["critical_samples"] = critical.size();
  stats["samples_per_full_search"] = samples;
  stats["seed"] = seed_stats;
  stats["sweep_seconds"] = sweep_seconds;

  const bool stopped = context.stop && context.stop->load();
  if (best.index < 0) {
    result.status = stopped ? SolverStatus::kStopped : SolverStatus::kInfeasible;
    result.message = "no feasible design among " + std::to_string(grid.total) + " grid designs";
    result.statistics = stats;
    return result;
  }
  std::vector<double> x(n);
  grid.decode(best.index, x.data());
  auto ws = problem.make_workspace();
  const Evaluation grid_best = problem.evaluate(x.data(), *ws);
  result.sample_evaluations += grid_best.samples_evaluated;
  SolutionPoint point{problem.full_design(x.data()), grid_best.objectives, grid_best.score};
  stats["grid_optimum"] = {{"design", problem.design_to_json(point.design)}, {"objectives", point.objectives},
                           {"score", point.score}, {"index", best.index}};

  // 3. Polish: SQP within the optimum's cell (one step either side), keeping the better point.
  if (options_.polish && !any_integer) {
    std::vector<double> lo(n), hi(n);
    for (std::size_t k = 0; k < n; ++k) {
      const DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
      lo[k] = std::max(c.lower, x[k] - c.step);
      hi[k] = std::min(c.upper, x[k] + c.step);
    }
    const SqpOutcome sqp = run_sqp(problem, x, lo, hi, options_);
    result.design_evaluations += sqp.evaluations;
    result.sample_evaluations += sqp.samples;
    Json polish = {{"status", sqp.status}, {"evaluations", sqp.evaluations}, {"rounds", sqp.rounds},
                   {"active_samples", sqp.active_samples}, {"seconds", sqp.seconds}};
    if (!sqp.x.empty() && sqp.merit > point.score) {
      const Evaluation polished = problem.evaluate(sqp.x.data(), *ws);
      point = SolutionPoint{problem.full_design(sqp.x.data()), polished.objectives, polished.score};
      polish["improved"] = true;
    } else {
      polish["improved"] = false;
    }
    stats["polish"] = polish;
  }
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
