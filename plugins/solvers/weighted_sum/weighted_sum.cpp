#include "weighted_sum.hpp"

#include "shared/sub_solver.hpp"

#include <hapsyn/checkpoint.hpp>
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
  const std::vector<std::vector<double>> all_weights = weight_vectors(m);
  const std::string fingerprint = study_fingerprint(problem, OptionDeclarations<WeightedSumOptions>::to_json(options_));

  // The weight vectors a checkpoint has finished (their designs re-evaluated on reading).
  std::vector<FinishedSubproblem> finished;
  double seconds_before = 0.0;
  Json resumed = nullptr;
  if (std::optional<SubproblemCheckpoint> checkpoint =
          read_subproblem_checkpoint(problem, context, "weighted_sum", fingerprint, {{"finished", all_weights.size()}})) {
    finished = std::move(checkpoint->lists["finished"]);
    for (std::size_t k = 0; k < finished.size(); ++k) {
      if (finished[k].record.value("weights", Json()) != Json(all_weights[k])) {
        throw bad_checkpoint(context, "finished[" + std::to_string(k) + "].record.weights = " +
                                          finished[k].record.value("weights", Json()).dump() + ": this study's weight vector " +
                                          std::to_string(k) + " is " + Json(all_weights[k]).dump());
      }
    }
    seconds_before = checkpoint->seconds;
    resumed = {{"checkpoint", context.checkpoint_file},
               {"finished", finished.size()},
               {"recheck_sample_evaluations", checkpoint->recheck_samples}};
    solver_line(context, "weighted_sum: resuming from " + context.checkpoint_file + ": " + std::to_string(finished.size()) +
                             " of " + std::to_string(all_weights.size()) + " weight vectors finished");
  }
  const auto elapsed = [&] { return seconds_before + std::chrono::duration<double>(Clock::now() - t_start).count(); };

  bool stopped = false;
  for (std::size_t k = finished.size(); k < all_weights.size(); ++k) {
    if (context.stop_requested()) {
      stopped = true;
      break;
    }
    const std::vector<double>& w = all_weights[k];
    const auto t0 = Clock::now();
    const SolverResult r = run_sub_solver(*solver, *reweighted_problem(problem, w), context,
                                          "weighted_sum: weights " + Json(w).dump() + " (" + std::to_string(k + 1) + " of " +
                                              std::to_string(all_weights.size()) + ")");
    if (r.status == SolverStatus::kStopped) {
      // Its best is not this weight's optimum: the weight is run again on --resume.
      result.design_evaluations += r.design_evaluations;
      result.sample_evaluations += r.sample_evaluations;
      stopped = true;
      break;
    }
    FinishedSubproblem f;
    f.design_evaluations = r.design_evaluations;
    f.sample_evaluations = r.sample_evaluations;
    f.record = {{"weights", w}, {"status", to_string(r.status)}};
    std::vector<double> values;
    if (r.best && evaluate_full_design(problem, r.best->design, context.threads, values, f.sample_evaluations)) {
      f.point = SolutionPoint{r.best->design, values, problem.score(values)};
      f.record["design"] = problem.design_to_json(r.best->design);
      f.record["objectives"] = values;
    }
    f.record["seconds"] = std::chrono::duration<double>(Clock::now() - t0).count();
    finished.push_back(std::move(f));
    write_subproblem_checkpoint(context, "weighted_sum", fingerprint, {{"finished", &finished}}, elapsed());
  }
  if (stopped) write_subproblem_checkpoint(context, "weighted_sum", fingerprint, {{"finished", &finished}}, elapsed());

  std::vector<SolutionPoint> points;
  Json runs = Json::array();
  for (const FinishedSubproblem& f : finished) {
    result.design_evaluations += f.design_evaluations;
    result.sample_evaluations += f.sample_evaluations;
    runs.push_back(f.record);
    if (f.point) points.push_back(*f.point);
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
                       {"sub_solver", sub_solver_json(options_.sub_solver)}, {"seconds", elapsed()}};
  if (!resumed.is_null()) result.statistics["resumed"] = resumed;
  std::ostringstream message;
  if (stopped) {
    message << "weighted sums stopped on request after " << finished.size() << " of " << all_weights.size()
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
