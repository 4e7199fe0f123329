#include "weighted_sum.hpp"

#include "shared/sub_solver.hpp"

#include <hapsyn/checkpoint.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/pareto.hpp>

#include <algorithm>
#include <atomic>
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
  SubproblemSlots finished(all_weights.size());
  double seconds_before = 0.0;
  Json resumed = nullptr;
  if (std::optional<SubproblemCheckpoint> checkpoint =
          read_subproblem_checkpoint(problem, context, "weighted_sum", fingerprint, {{"finished", all_weights.size()}})) {
    finished = std::move(checkpoint->lists["finished"]);
    for (std::size_t k = 0; k < finished.size(); ++k) {
      if (finished[k] && finished[k]->record.value("weights", Json()) != Json(all_weights[k])) {
        throw bad_checkpoint(context, checkpoint->where("finished", k) + ".record.weights = " +
                                          finished[k]->record.value("weights", Json()).dump() +
                                          ": this study's weight vector " + std::to_string(k) + " is " +
                                          Json(all_weights[k]).dump());
      }
    }
    seconds_before = checkpoint->seconds;
    resumed = {{"checkpoint", context.checkpoint_file},
               {"finished", finished_count(finished)},
               {"recheck_sample_evaluations", checkpoint->recheck_samples}};
    solver_line(context, "weighted_sum: resuming from " + context.checkpoint_file + ": " +
                             std::to_string(finished_count(finished)) + " of " + std::to_string(all_weights.size()) +
                             " weight vectors finished");
  }
  const auto elapsed = [&] { return seconds_before + std::chrono::duration<double>(Clock::now() - t_start).count(); };
  const auto checkpoint = [&] {
    write_subproblem_checkpoint(context, "weighted_sum", fingerprint, {{"finished", &finished}}, elapsed());
  };

  // One task per weight vector: a whole sub-solver run on one rank's threads. The weight vectors
  // are independent (no warm start), so the result does not depend on where each one runs.
  const SolverContext inner = task_context(context);
  std::atomic<long long> interrupted_designs{0}, interrupted_samples{0};
  const auto what = [&](std::size_t k) {
    return "weighted_sum: weights " + Json(all_weights[k]).dump() + " (" + std::to_string(k + 1) + " of " +
           std::to_string(all_weights.size()) + ")";
  };
  SubproblemFarm farm;
  farm.what = what;
  farm.run = [&](std::size_t k) -> std::optional<FinishedSubproblem> {
    if (inner.stop_requested()) return std::nullopt;
    const std::vector<double>& w = all_weights[k];
    const auto t0 = Clock::now();
    const SolverResult r = run_sub_solver(*solver, *reweighted_problem(problem, w), inner, what(k));
    if (r.status == SolverStatus::kStopped) {
      // Its best is not this weight's optimum: the weight is run again on --resume.
      interrupted_designs += r.design_evaluations;
      interrupted_samples += r.sample_evaluations;
      return std::nullopt;
    }
    FinishedSubproblem f;
    f.design_evaluations = r.design_evaluations;
    f.sample_evaluations = r.sample_evaluations;
    f.record = {{"weights", w}, {"status", to_string(r.status)}};
    std::vector<double> values;
    if (r.best && evaluate_full_design(problem, r.best->design, inner.threads, values, f.sample_evaluations)) {
      f.point = SolutionPoint{r.best->design, values, problem.score(values)};
      f.record["design"] = problem.design_to_json(r.best->design);
      f.record["objectives"] = values;
    }
    f.record["seconds"] = std::chrono::duration<double>(Clock::now() - t0).count();
    return f;
  };
  farm.collected = [&](std::size_t) { checkpoint(); };
  farm.on_abort = checkpoint;
  // A stop that came after the last weight vector finished changes nothing.
  const bool stopped =
      run_subproblem_farm(problem, context, finished, farm).stopped && finished_count(finished) < finished.size();
  if (stopped) checkpoint();
  result.design_evaluations = interrupted_designs;
  result.sample_evaluations = interrupted_samples;

  std::vector<SolutionPoint> points;
  Json runs = Json::array();
  for (const std::optional<FinishedSubproblem>& f : finished) {
    if (!f) continue;
    result.design_evaluations += f->design_evaluations;
    result.sample_evaluations += f->sample_evaluations;
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
                       {"sub_solver", sub_solver_json(options_.sub_solver)}, {"seconds", elapsed()}};
  if (!resumed.is_null()) result.statistics["resumed"] = resumed;
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
