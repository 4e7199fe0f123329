#include "weighted_sum.hpp"

#include "shared/sub_solver.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/pareto.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

namespace hapsyn::plugins {

std::vector<std::vector<double>> WeightedSumSolver::weight_vectors(std::size_t objectives) const {
  if (options_.weights.empty()) return simplex_grid(static_cast<int>(objectives), options_.count - 1);
  return options_.weights;
}

void WeightedSumSolver::check(const Problem& problem) const {
  const std::size_t m = problem.objectives().size();
  if (m < 2) throw Error("weighted_sum", "objectives: " + std::to_string(m) + " objective(s); a Pareto study needs at least 2");
  for (std::size_t k = 0; k < options_.weights.size(); ++k) {
    const std::vector<double>& weights = options_.weights[k];
    const std::string path = "solver.options.weights[" + std::to_string(k) + "]";
    if (weights.size() != m) {
      throw Error("weighted_sum", path + " = " + render_value(Json(weights)) + ": must have " + std::to_string(m) +
                                      " weights (one per objective)");
    }
    double sum = 0.0;
    for (std::size_t i = 0; i < m; ++i) {
      const double w = weights[i];
      if (!std::isfinite(w) || w < 0.0) {
        throw Error("weighted_sum", path + "[" + std::to_string(i) + "] = " + render_value(Json(w)) +
                                        ": must be finite and >= 0");
      }
      sum += w;
    }
    if (!(sum > 0.0)) throw Error("weighted_sum", path + " = " + render_value(Json(weights)) + ": the weights must not all be 0");
  }
  // The simplex grid's size check, then the sub-solver on every problem it will be given.
  for (const std::vector<double>& w : weight_vectors(m)) {
    check_sub_solver(options_.sub_solver, *reweighted_problem(problem, w), "weighted_sum",
                     options_.sub_solver.json_path);
  }
}

SolverResult WeightedSumSolver::solve(const Problem& problem, const SolverContext& context) const {
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();
  SolverResult result;
  const Solver* solver = sub_solver_for_solve(options_.sub_solver, "weighted_sum", "sub-solver", result);
  if (!solver) return result;
  const std::size_t m = problem.objectives().size();
  std::vector<SolutionPoint> points;
  Json runs = Json::array();
  bool stopped = false;
  for (const std::vector<double>& w : weight_vectors(m)) {
    if (context.stop && context.stop->load()) {
      stopped = true;
      break;
    }
    const auto t0 = Clock::now();
    const SolverResult r = run_sub_solver(*solver, *reweighted_problem(problem, w), context);
    result.design_evaluations += r.design_evaluations;
    result.sample_evaluations += r.sample_evaluations;
    Json run = {{"weights", w}, {"status", to_string(r.status)}, {"seconds", 0.0}};
    std::vector<double> values;
    if (r.best && evaluate_full_design(problem, r.best->design, context.threads, values, result.sample_evaluations)) {
      points.push_back({r.best->design, values, problem.score(values)});
      run["design"] = problem.design_to_json(r.best->design);
      run["objectives"] = values;
    }
    run["seconds"] = std::chrono::duration<double>(Clock::now() - t0).count();
    runs.push_back(run);
  }
  std::vector<Sense> senses;
  for (const Objective& o : problem.objectives()) senses.push_back(o.sense);
  std::vector<ObjectivePoint> values;
  for (const SolutionPoint& p : points) values.push_back(p.objectives);
  const std::vector<std::size_t> keep = non_dominated(values, senses);
  for (std::size_t i : keep) result.front.push_back(points[i]);
  std::stable_sort(result.front.begin(), result.front.end(), [&](const SolutionPoint& a, const SolutionPoint& b) {
    return (senses[0] == Sense::kMaximize ? 1.0 : -1.0) * (a.objectives[0] - b.objectives[0]) > 0;
  });
  result.statistics = {{"runs", runs}, {"designs_found", points.size()}, {"distinct_non_dominated", keep.size()},
                       {"sub_solver", sub_solver_json(options_.sub_solver)},
                       {"seconds", std::chrono::duration<double>(Clock::now() - t_start).count()}};
  std::ostringstream message;
  message << "weighted sums: " << runs.size() << " weight vectors gave " << keep.size()
          << " distinct non-dominated points";
  result.message = message.str();
  if (points.empty()) {
    result.status = stopped ? SolverStatus::kStopped : SolverStatus::kInfeasible;
    result.message += " (no weight found a feasible design)";
  } else {
    result.status = stopped ? SolverStatus::kStopped : SolverStatus::kConverged;
  }
  return result;
}

}  // namespace hapsyn::plugins
