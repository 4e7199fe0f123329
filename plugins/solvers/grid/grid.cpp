#include "grid.hpp"

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
#include <ostream>

namespace hapsyn::plugins {

void GridSolver::check(const Problem& problem) const {
  if (options_.pareto && problem.objectives().size() < 2) {
    throw Error("grid", "solver.options.pareto = true: needs two or more objectives (the study has " +
                            std::to_string(problem.objectives().size()) + ")");
  }
  problem.design_space().check_grid("grid");
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

bool stop_requested(const SolverContext& context) {
  return context.stop && context.stop->load(std::memory_order_relaxed);
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

// Per-thread state of a sweep; `Extra` holds what the mode keeps besides the tally.
template <class Extra>
struct SweepThread : Extra {
  std::unique_ptr<Problem::EvalScratch> eval_scratch;
  std::vector<double> x;
  Tally tally;
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

template <class Extra>
Tally total_tally(const std::vector<SweepThread<Extra>>& states) {
  Tally sum;
  for (const SweepThread<Extra>& s : states) sum.add(s.tally);
  return sum;
}

// ---------------------------------------------------------------------------------------------
// Best design.

struct BestDesign {
  double best_score = -kInf;
  long long best_index = -1;

  // Larger score wins; of equal scores the first in grid order, so the thread count cannot matter.
  bool improves_on(double score, long long index) const {
    return score > best_score || (score == best_score && index < best_index);
  }
};
using BestThread = SweepThread<BestDesign>;

// Every grid design, on the context's threads; each thread keeps its own best.
std::vector<BestThread> sweep_for_best(const Problem& problem, const GridShape& grid, bool prune,
                                       double progress_interval, const SolverContext& context) {
  std::vector<BestThread> states = make_threads<BestDesign>(problem, context);
  const DesignSpace& space = problem.design_space();
  std::atomic<double> incumbent{-kInf};
  std::atomic<long long> done{0};
  std::mutex progress_mutex;
  const auto start = Clock::now();
  auto last_report = start;
  const long long block = 64;
  parallel_for_dynamic(grid.total, static_cast<int>(states.size()), block, [&](long long index, int t) {
    BestThread& s = states[static_cast<std::size_t>(t)];
    if (stop_requested(context)) return;
    space.grid_point(index, grid.counts, s.x.data());
    EvalOptions options;
    if (prune) options.prune_below = incumbent.load(std::memory_order_relaxed);
    const Evaluation& e = problem.evaluate(s.x.data(), *s.eval_scratch, options);
    s.tally.count(e);
    if (e.status == EvalStatus::kFeasible && s.improves_on(e.score, index)) {
      s.best_score = e.score;
      s.best_index = index;
      raise_to(incumbent, e.score);
    }
    const long long finished = done.fetch_add(1, std::memory_order_relaxed) + 1;
    if (context.progress && (finished & 4095) == 0) {
      std::lock_guard<std::mutex> lock(progress_mutex);
      report_progress(*context.progress, "grid", finished, grid.total, start, last_report, progress_interval,
                      [&](std::ostream& out) { out << "best score " << std::setprecision(6) << incumbent.load(); });
    }
  });
  return states;
}

BestDesign overall_best(const std::vector<BestThread>& states) {
  BestDesign best;
  for (const BestThread& s : states) {
    if (s.best_index >= 0 && best.improves_on(s.best_score, s.best_index)) {
      best.best_score = s.best_score;
      best.best_index = s.best_index;
    }
  }
  return best;
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
  std::mutex mutex;                   // guards front, flat and the progress stream
  std::vector<FrontPoint> front;
  std::vector<double> flat;           // the front as EvalOptions wants it (natural units)
  std::atomic<long long> version{0};  // bumped when the front changes

  // Offers a feasible design's objectives (natural units) at grid `index`.
  void offer(const std::vector<double>& objectives, long long index) {
    const std::size_t m = sign.size();
    FrontPoint p{std::vector<double>(m), index};
    for (std::size_t o = 0; o < m; ++o) p.values[o] = sign[o] * objectives[o];
    std::lock_guard<std::mutex> lock(mutex);
    if (!insert_point(front, p)) return;
    flat.clear();
    for (const FrontPoint& q : front) {
      for (std::size_t o = 0; o < m; ++o) flat.push_back(sign[o] * q.values[o]);
    }
    version.fetch_add(1, std::memory_order_release);
  }
};

// A thread's copy of the front it prunes against, and the front version it was taken at.
struct FrontSnapshot {
  std::vector<double> snapshot;
  long long seen = -1;
};
using FrontThread = SweepThread<FrontSnapshot>;

// Every grid design, on the context's threads, offered to `shared`.
std::vector<FrontThread> sweep_for_front(const Problem& problem, const GridShape& grid, bool prune,
                                         double progress_interval, const SolverContext& context,
                                         Clock::time_point start, SharedFront& shared) {
  std::vector<FrontThread> states = make_threads<FrontSnapshot>(problem, context);
  const DesignSpace& space = problem.design_space();
  std::atomic<long long> done{0};
  auto last_report = start;
  parallel_for_dynamic(grid.total, static_cast<int>(states.size()), 64, [&](long long index, int t) {
    FrontThread& s = states[static_cast<std::size_t>(t)];
    if (stop_requested(context)) return;
    if (prune && shared.version.load(std::memory_order_acquire) != s.seen) {
      std::lock_guard<std::mutex> lock(shared.mutex);
      s.snapshot.assign(shared.flat.begin(), shared.flat.end());
      s.seen = shared.version.load(std::memory_order_relaxed);
    }
    space.grid_point(index, grid.counts, s.x.data());
    EvalOptions options;
    if (prune) options.prune_dominated_by = &s.snapshot;
    const Evaluation& e = problem.evaluate(s.x.data(), *s.eval_scratch, options);
    s.tally.count(e);
    if (e.status == EvalStatus::kFeasible) shared.offer(e.objectives, index);
    const long long finished = done.fetch_add(1, std::memory_order_relaxed) + 1;
    if (context.progress && (finished & 65535) == 0) {
      std::lock_guard<std::mutex> lock(shared.mutex);
      report_progress(*context.progress, "grid (pareto)", finished, grid.total, start, last_report, progress_interval,
                      [&](std::ostream& out) { out << "front " << shared.front.size() << " points"; });
    }
  });
  return states;
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

}  // namespace

SolverResult GridSolver::solve_best(const Problem& problem, const SolverContext& context) const {
  const DesignSpace& space = problem.design_space();
  const GridShape grid(space);
  const bool prune = options_.prune && problem.worst_case();
  const std::vector<BestThread> states = sweep_for_best(problem, grid, prune, options_.progress_interval, context);
  const Tally sum = total_tally(states);
  const BestDesign best = overall_best(states);

  SolverResult result;
  result.design_evaluations = sum.designs();
  result.sample_evaluations = sum.samples;
  result.statistics = sum.statistics(grid, prune);
  const bool stopped = context.stop && context.stop->load();
  if (best.best_index < 0) {
    result.status = stopped ? SolverStatus::kStopped : SolverStatus::kInfeasible;
    result.message = "no feasible design among " + std::to_string(result.design_evaluations) + " grid designs (" +
                     std::to_string(sum.constraint_violated) + " violate a design constraint, " +
                     std::to_string(sum.sample_failed) + " fail at a sample)";
    return result;
  }
  // Re-evaluate the winner in full (its running evaluation may have been bounded).
  std::vector<double> x(space.free_size());
  space.grid_point(best.best_index, grid.counts, x.data());
  auto ws = problem.make_eval_scratch();
  const Evaluation& e = problem.evaluate(x.data(), *ws);
  result.sample_evaluations += e.samples_evaluated;
  result.best = SolutionPoint{problem.full_design(x.data()), e.objectives, e.score};
  result.status = stopped ? SolverStatus::kStopped : SolverStatus::kConverged;
  result.message = (stopped ? "stopped early; best of the designs searched, " : "exhaustive search of ") +
                   std::to_string(grid.total) + " grid designs, " + std::to_string(sum.feasible) + " fully evaluated";
  return result;
}

SolverResult GridSolver::solve_front(const Problem& problem, const SolverContext& context) const {
  const auto start = Clock::now();
  const GridShape grid(problem.design_space());
  SharedFront shared;
  for (const Objective& o : problem.objectives()) shared.sign.push_back(o.sense == Sense::kMaximize ? 1.0 : -1.0);
  // Pruning needs upper bounds of maximized worst-case objectives (the evaluator checks too).
  const bool prune = options_.prune && problem.worst_case() &&
                     std::all_of(shared.sign.begin(), shared.sign.end(), [](double s) { return s > 0; });
  const std::vector<FrontThread> states =
      sweep_for_front(problem, grid, prune, options_.progress_interval, context, start, shared);
  const Tally sum = total_tally(states);

  SolverResult result;
  result.design_evaluations = sum.designs();
  result.sample_evaluations = sum.samples;
  result.front = front_solutions(problem, grid, shared);
  result.statistics = sum.statistics(grid, prune);
  result.statistics["pareto"] = true;
  result.statistics["front_points"] = shared.front.size();
  result.statistics["seconds"] = std::chrono::duration<double>(Clock::now() - start).count();
  const bool stopped = context.stop && context.stop->load();
  if (shared.front.empty()) {
    result.status = stopped ? SolverStatus::kStopped : SolverStatus::kInfeasible;
    result.message = "no feasible design among " + std::to_string(grid.total) + " grid designs";
    return result;
  }
  result.status = stopped ? SolverStatus::kStopped : SolverStatus::kConverged;
  result.message = (stopped ? "stopped early; front of the designs searched: " : "exact Pareto front of ") +
                   std::to_string(grid.total) + " grid designs: " + std::to_string(shared.front.size()) + " points, " +
                   std::to_string(sum.feasible) + " designs fully evaluated";
  return result;
}

}  // namespace hapsyn::plugins
