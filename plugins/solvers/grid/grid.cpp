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

GridSolver::GridSolver(const Json& options)
    : prune_(options.value("prune", true)),
      pareto_(options.value("pareto", false)),
      progress_interval_(options.value("progress_interval", 2.0)) {}

void GridSolver::check(const Problem& problem) const {
  if (pareto_ && problem.objectives().size() < 2) {
    throw Error("grid", "solver.options.pareto = true: needs two or more objectives (the study has " +
                            std::to_string(problem.objectives().size()) + ")");
  }
  problem.design_space().check_grid("grid");
}

namespace {
// One progress line, "<what>: P% of N designs, <detail>, E s elapsed, ~L s left", at most every
// `interval` seconds (the caller holds the lock that guards last_report and what detail reads).
template <typename Detail>
void report_progress(std::ostream& out, const char* what, long long finished, long long total,
                     std::chrono::steady_clock::time_point start, std::chrono::steady_clock::time_point& last_report,
                     double interval, const Detail& detail) {
  const auto now = std::chrono::steady_clock::now();
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
}  // namespace

SolverResult GridSolver::solve(const Problem& problem, const SolverContext& context) const {
  if (pareto_) return solve_front(problem, context);
  using clock = std::chrono::steady_clock;
  const DesignSpace& space = problem.design_space();
  const std::size_t n = space.free_size();
  const std::vector<long long> counts = space.grid_counts();
  long long total = 1;
  for (long long c : counts) total *= c;
  const bool prune = prune_ && problem.worst_case();
  const int threads = std::max(1, context.threads);

  struct ThreadState {
    std::unique_ptr<Problem::Workspace> workspace;
    std::vector<double> x;
    double best_score = -std::numeric_limits<double>::infinity();
    long long best_index = -1;
    long long feasible = 0, constraint_violated = 0, sample_failed = 0, pruned = 0, samples = 0;
  };
  std::vector<ThreadState> states(static_cast<std::size_t>(threads));
  for (ThreadState& s : states) {
    s.workspace = problem.make_workspace();
    s.x.resize(n);
  }
  std::atomic<double> incumbent{-std::numeric_limits<double>::infinity()};
  std::atomic<long long> done{0};
  std::mutex progress_mutex;
  const auto start = clock::now();
  auto last_report = start;

  const long long block = 64;
  parallel_for_dynamic(total, threads, block, [&](long long index, int t) {
    ThreadState& s = states[static_cast<std::size_t>(t)];
    if (context.stop && context.stop->load(std::memory_order_relaxed)) return;
    space.grid_point(index, counts, s.x.data());
    EvalOptions options;
    if (prune) options.prune_below = incumbent.load(std::memory_order_relaxed);
    const Evaluation& e = problem.evaluate(s.x.data(), *s.workspace, options);
    s.samples += e.samples_evaluated;
    switch (e.status) {
      case EvalStatus::kFeasible:
        ++s.feasible;
        if (e.score > s.best_score || (e.score == s.best_score && index < s.best_index)) {
          s.best_score = e.score;
          s.best_index = index;
          raise_to(incumbent, e.score);
        }
        break;
      case EvalStatus::kConstraintViolated: ++s.constraint_violated; break;
      case EvalStatus::kSampleFailed: ++s.sample_failed; break;
      case EvalStatus::kPruned: ++s.pruned; break;
    }
    const long long finished = done.fetch_add(1, std::memory_order_relaxed) + 1;
    if (context.progress && (finished & 4095) == 0) {
      std::lock_guard<std::mutex> lock(progress_mutex);
      report_progress(*context.progress, "grid", finished, total, start, last_report, progress_interval_,
                      [&](std::ostream& out) { out << "best score " << std::setprecision(6) << incumbent.load(); });
    }
  });

  SolverResult result;
  ThreadState sum;
  for (const ThreadState& s : states) {
    sum.feasible += s.feasible;
    sum.constraint_violated += s.constraint_violated;
    sum.sample_failed += s.sample_failed;
    sum.pruned += s.pruned;
    sum.samples += s.samples;
    if (s.best_index >= 0 && (s.best_score > sum.best_score || (s.best_score == sum.best_score && s.best_index < sum.best_index))) {
      sum.best_score = s.best_score;
      sum.best_index = s.best_index;
    }
  }
  result.design_evaluations = sum.feasible + sum.constraint_violated + sum.sample_failed + sum.pruned;
  result.sample_evaluations = sum.samples;
  result.statistics = {{"grid_designs", total},
                       {"feasible", sum.feasible},
                       {"constraint_violated", sum.constraint_violated},
                       {"sample_failed", sum.sample_failed},
                       {"pruned", sum.pruned},
                       {"full_workspace_searches", sum.feasible},
                       {"prune", prune},
                       {"grid_counts", counts}};
  const bool stopped = context.stop && context.stop->load();
  if (sum.best_index < 0) {
    result.status = stopped ? SolverStatus::kStopped : SolverStatus::kInfeasible;
    result.message = "no feasible design among " + std::to_string(result.design_evaluations) + " grid designs (" +
                     std::to_string(sum.constraint_violated) + " violate a design constraint, " +
                     std::to_string(sum.sample_failed) + " fail at a sample)";
    return result;
  }
  // Re-evaluate the winner in full (its running evaluation may have been bounded).
  std::vector<double> x(n);
  space.grid_point(sum.best_index, counts, x.data());
  auto ws = problem.make_workspace();
  const Evaluation& e = problem.evaluate(x.data(), *ws);
  result.sample_evaluations += e.samples_evaluated;
  result.best = SolutionPoint{problem.full_design(x.data()), e.objectives, e.score};
  result.status = stopped ? SolverStatus::kStopped : SolverStatus::kConverged;
  result.message = (stopped ? "stopped early; best of the designs searched, " : "exhaustive search of ") +
                   std::to_string(total) + " grid designs, " + std::to_string(sum.feasible) + " fully evaluated";
  return result;
}

namespace {
// The front found so far: non-dominated objective vectors (sense-signed so that larger is
// better), sorted by the first objective descending, each with its grid index.
struct FrontPoint {
  std::vector<double> values;  // sense-signed
  long long index;
};

// Inserts p unless a point dominates it (or equals it with a lower index); removes the points
// it dominates. Returns true when the front changed.
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
}  // namespace

SolverResult GridSolver::solve_front(const Problem& problem, const SolverContext& context) const {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  const DesignSpace& space = problem.design_space();
  const std::size_t n = space.free_size();
  const std::size_t m = problem.objectives().size();
  const std::vector<long long> counts = space.grid_counts();
  long long total = 1;
  for (long long c : counts) total *= c;
  std::vector<double> sign(m);
  for (std::size_t o = 0; o < m; ++o) sign[o] = problem.objectives()[o].sense == Sense::kMaximize ? 1.0 : -1.0;
  // Pruning needs upper bounds of maximized worst-case objectives (the evaluator checks too).
  const bool prune = prune_ && problem.worst_case() &&
                     std::all_of(sign.begin(), sign.end(), [](double s) { return s > 0; });
  const int threads = std::max(1, context.threads);

  std::mutex mutex;
  std::vector<FrontPoint> front;
  std::vector<double> flat;           // the front as EvalOptions wants it (natural units)
  std::atomic<long long> version{0};  // bumped when the front changes
  struct ThreadState {
    std::unique_ptr<Problem::Workspace> workspace;
    std::vector<double> x, snapshot;
    long long seen = -1;
    long long feasible = 0, constraint_violated = 0, sample_failed = 0, pruned = 0, samples = 0;
  };
  std::vector<ThreadState> states(static_cast<std::size_t>(threads));
  for (ThreadState& s : states) {
    s.workspace = problem.make_workspace();
    s.x.resize(n);
  }
  std::atomic<long long> done{0};
  auto last_report = start;
  parallel_for_dynamic(total, threads, 64, [&](long long index, int t) {
    ThreadState& s = states[static_cast<std::size_t>(t)];
    if (context.stop && context.stop->load(std::memory_order_relaxed)) return;
    if (prune && version.load(std::memory_order_acquire) != s.seen) {
      std::lock_guard<std::mutex> lock(mutex);
      s.snapshot.assign(flat.begin(), flat.end());
      s.seen = version.load(std::memory_order_relaxed);
    }
    space.grid_point(index, counts, s.x.data());
    EvalOptions options;
    if (prune) options.prune_dominated_by = &s.snapshot;
    const Evaluation& e = problem.evaluate(s.x.data(), *s.workspace, options);
    s.samples += e.samples_evaluated;
    switch (e.status) {
      case EvalStatus::kFeasible: {
        ++s.feasible;
        FrontPoint p{std::vector<double>(m), index};
        for (std::size_t o = 0; o < m; ++o) p.values[o] = sign[o] * e.objectives[o];
        std::lock_guard<std::mutex> lock(mutex);
        if (insert_point(front, p)) {
          flat.clear();
          for (const FrontPoint& q : front) {
            for (std::size_t o = 0; o < m; ++o) flat.push_back(sign[o] * q.values[o]);
          }
          version.fetch_add(1, std::memory_order_release);
        }
        break;
      }
      case EvalStatus::kConstraintViolated: ++s.constraint_violated; break;
      case EvalStatus::kSampleFailed: ++s.sample_failed; break;
      case EvalStatus::kPruned: ++s.pruned; break;
    }
    const long long finished = done.fetch_add(1, std::memory_order_relaxed) + 1;
    if (context.progress && (finished & 65535) == 0) {
      std::lock_guard<std::mutex> lock(mutex);
      report_progress(*context.progress, "grid (pareto)", finished, total, start, last_report, progress_interval_,
                      [&](std::ostream& out) { out << "front " << front.size() << " points"; });
    }
  });

  SolverResult result;
  ThreadState sum;
  for (const ThreadState& s : states) {
    sum.feasible += s.feasible;
    sum.constraint_violated += s.constraint_violated;
    sum.sample_failed += s.sample_failed;
    sum.pruned += s.pruned;
    sum.samples += s.samples;
  }
  result.design_evaluations = sum.feasible + sum.constraint_violated + sum.sample_failed + sum.pruned;
  result.sample_evaluations = sum.samples;
  std::vector<double> x(n);
  for (const FrontPoint& q : front) {
    space.grid_point(q.index, counts, x.data());
    std::vector<double> natural(m);
    for (std::size_t o = 0; o < m; ++o) natural[o] = sign[o] * q.values[o];
    result.front.push_back({problem.full_design(x.data()), natural, problem.score(natural)});
  }
  result.statistics = {{"grid_designs", total},
                       {"feasible", sum.feasible},
                       {"constraint_violated", sum.constraint_violated},
                       {"sample_failed", sum.sample_failed},
                       {"pruned", sum.pruned},
                       {"full_workspace_searches", sum.feasible},
                       {"prune", prune},
                       {"pareto", true},
                       {"front_points", front.size()},
                       {"grid_counts", counts},
                       {"seconds", std::chrono::duration<double>(clock::now() - start).count()}};
  const bool stopped = context.stop && context.stop->load();
  if (front.empty()) {
    result.status = stopped ? SolverStatus::kStopped : SolverStatus::kInfeasible;
    result.message = "no feasible design among " + std::to_string(total) + " grid designs";
    return result;
  }
  result.status = stopped ? SolverStatus::kStopped : SolverStatus::kConverged;
  result.message = (stopped ? "stopped early; front of the designs searched: " : "exact Pareto front of ") +
                   std::to_string(total) + " grid designs: " + std::to_string(front.size()) + " points, " +
                   std::to_string(sum.feasible) + " designs fully evaluated";
  return result;
}

}  // namespace hapsyn::plugins
