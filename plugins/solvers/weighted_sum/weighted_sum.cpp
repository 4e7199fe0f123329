#include "weighted_sum.hpp"

#include "shared/sub_solver.hpp"
#include "shared/sub_solver_sweep.hpp"

#include <hapsyn/checkpoint.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/pareto.hpp>

#include <algorithm>
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
  SolverResult result;
  const Solver* solver = sub_solver_for_solve(options_.sub_solver, "weighted_sum", "sub-solver", result);
  if (!solver) return result;
  const std::size_t m = problem.objectives().size();
  const std::vector<std::vector<double>> all_weights = weight_vectors(m);

  // One subproblem per weight vector: the study's objectives with those weights.
  SubSolverSweep sweep;
  sweep.solver = "weighted_sum";
  sweep.fingerprint = study_fingerprint(problem, OptionDeclarations<WeightedSumOptions>::to_json(options_));
  sweep.count = all_weights.size();
  sweep.units = "weight vectors";
  sweep.key = "weights";
  sweep.identity = [&](std::size_t k) { return Json(all_weights[k]); };
  sweep.named = [&](std::size_t k) { return "weight vector " + std::to_string(k); };
  sweep.what = [&](std::size_t k) {
    return "weighted_sum: weights " + Json(all_weights[k]).dump() + " (" + std::to_string(k + 1) + " of " +
           std::to_string(all_weights.size()) + ")";
  };
  sweep.problem = [&](std::size_t k) { return reweighted_problem(problem, all_weights[k]); };
  const SubSolverSweepOutcome outcome = run_sub_solver_sweep(*solver, problem, context, sweep);
  const bool stopped = outcome.stopped;
  result.design_evaluations = outcome.design_evaluations;
  result.sample_evaluations = outcome.sample_evaluations;

  std::vector<SolutionPoint> points;
  Json runs = Json::array();
  for (const std::optional<FinishedSubproblem>& f : outcome.finished) {
    if (!f) continue;
    runs.push_back(f->record);
    if (f->point) points.push_back(*f->point);
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
                       {"sub_solver", sub_solver_json(options_.sub_solver)}, {"seconds", outcome.elapsed()}};
  if (!outcome.resumed.is_null()) result.statistics["resumed"] = outcome.resumed;
  std::ostringstream message;
  if (stopped) {
    message << "weighted sums stopped on request after " << runs.size() << " of " << all_weights.size()
            << " weight vectors; the front is that of the finished ones (" << keep.size() << " distinct non-dominated points)"
            << checkpoint_note(context);
    result.status = SolverStatus::kStopped;
  } else {
    message << "weighted sums: " << runs.size() << " weight vectors gave " << keep.size()
            << " distinct non-dominated points";
    if (points.empty()) message << " (no weight found a feasible design)";
    result.status = points.empty() ? SolverStatus::kInfeasible : SolverStatus::kConverged;
  }
  result.message = message.str();
  return result;
}

}  // namespace hapsyn::plugins
