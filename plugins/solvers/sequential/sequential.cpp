#include "sequential.hpp"

#include "shared/sub_solver.hpp"

#include <hapsyn/checkpoint.hpp>
#include <hapsyn/error.hpp>

#include <atomic>
#include <chrono>
#include <sstream>

namespace hapsyn::plugins {

std::size_t SequentialSolver::free_index(const Problem& problem) const {
  const DesignSpace& space = problem.design_space();
  for (std::size_t k = 0; k < space.free_size(); ++k) {
    if (space.components()[static_cast<std::size_t>(space.free_indices()[k])].name == options_.variable) return k;
  }
  std::string free;
  for (int i : space.free_indices()) free += (free.empty() ? "" : ", ") + space.components()[static_cast<std::size_t>(i)].name;
  throw Error("sequential", "solver.options.variable = \"" + options_.variable + "\": not a free design variable (free: " +
                                (free.empty() ? std::string("none") : free) + ")");
}

void SequentialSolver::check(const Problem& problem) const {
  if (problem.objectives().size() != 2) {
    throw Error("sequential", "objectives: " + std::to_string(problem.objectives().size()) +
                                  " objective(s); sequential optimization takes exactly 2 (first, then second)");
  }
  const std::size_t k = free_index(problem);
  const DesignComponent& c =
      problem.design_space().components()[static_cast<std::size_t>(problem.design_space().free_indices()[k])];
  if (!(c.step > 0.0)) {
    throw Error("sequential", "design." + c.name + " has no step: the independent variable is searched value by value");
  }
  // The sub-solver sees the first objective with the variable fixed (here at its first value).
  check_sub_solver(options_.sub_solver, *fixed_component_problem(*single_objective_problem(problem, 0), k, c.lower),
                   "sequential", options_.sub_solver.json_path);
}

SolverResult SequentialSolver::solve(const Problem& problem, const SolverContext& context) const {
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();
  SolverResult result;
  const Solver* solver = sub_solver_for_solve(options_.sub_solver, "sequential", "sub-solver", result);
  if (!solver) return result;
  const std::size_t k = free_index(problem);
  const auto first = single_objective_problem(problem, 0);
  const std::size_t values = static_cast<std::size_t>(problem.design_space().grid_count(k));
  const std::string fingerprint = study_fingerprint(problem, OptionDeclarations<SequentialOptions>::to_json(options_));

  // The values a checkpoint has finished (their designs re-evaluated on reading).
  SubproblemSlots finished(values);
  double seconds_before = 0.0;
  Json resumed = nullptr;
  if (std::optional<SubproblemCheckpoint> checkpoint =
          read_subproblem_checkpoint(problem, context, "sequential", fingerprint, {{"finished", values}})) {
    finished = std::move(checkpoint->lists["finished"]);
    for (std::size_t i = 0; i < finished.size(); ++i) {
      const double v = problem.design_space().grid_value(k, static_cast<long long>(i));
      if (finished[i] && finished[i]->record.value("value", Json()) != Json(v)) {
        throw bad_checkpoint(context, checkpoint->where("finished", i) + ".record.value = " +
                                          finished[i]->record.value("value", Json()).dump() + ": this study's value " +
                                          std::to_string(i) + " of " + options_.variable + " is " + Json(v).dump());
      }
    }
    seconds_before = checkpoint->seconds;
    resumed = {{"checkpoint", context.checkpoint_file},
               {"finished", finished_count(finished)},
               {"recheck_sample_evaluations", checkpoint->recheck_samples}};
    solver_line(context, "sequential: resuming from " + context.checkpoint_file + ": " +
                             std::to_string(finished_count(finished)) + " of " + std::to_string(values) + " values of " +
                             options_.variable + " finished");
  }
  const auto elapsed = [&] { return seconds_before + std::chrono::duration<double>(Clock::now() - t_start).count(); };
  const auto checkpoint = [&] {
    write_subproblem_checkpoint(context, "sequential", fingerprint, {{"finished", &finished}}, elapsed());
  };

  // One task per value: a whole sub-solver run on one rank's threads. The values are
  // independent (no warm start), so the result does not depend on where each one runs.
  const SolverContext inner = task_context(context);
  std::atomic<long long> interrupted_designs{0}, interrupted_samples{0};
  const auto what = [&](std::size_t i) {
    std::ostringstream name;
    name << "sequential: " << options_.variable << " = "
         << problem.design_space().grid_value(k, static_cast<long long>(i)) << " (" << i + 1 << " of " << values << ")";
    return name.str();
  };
  SubproblemFarm farm;
  farm.what = what;
  farm.run = [&](std::size_t i) -> std::optional<FinishedSubproblem> {
    if (inner.stop_requested()) return std::nullopt;
    const auto t0 = Clock::now();
    const double v = problem.design_space().grid_value(k, static_cast<long long>(i));
    const SolverResult r = run_sub_solver(*solver, *fixed_component_problem(*first, k, v), inner, what(i));
    if (r.status == SolverStatus::kStopped) {
      // Its best is not this value's optimum: the value is run again on --resume.
      interrupted_designs += r.design_evaluations;
      interrupted_samples += r.sample_evaluations;
      return std::nullopt;
    }
    FinishedSubproblem f;
    f.design_evaluations = r.design_evaluations;
    f.sample_evaluations = r.sample_evaluations;
    f.record = {{"value", v}, {"status", to_string(r.status)}};
    std::vector<double> objectives;
    if (r.best && evaluate_full_design(problem, r.best->design, inner.threads, objectives, f.sample_evaluations)) {
      f.point = SolutionPoint{r.best->design, objectives, problem.score(objectives)};
      f.record["design"] = problem.design_to_json(r.best->design);
      f.record["objectives"] = objectives;
    }
    f.record["seconds"] = std::chrono::duration<double>(Clock::now() - t0).count();
    return f;
  };
  farm.collected = [&](std::size_t) { checkpoint(); };
  farm.on_abort = checkpoint;
  // A stop that came after the last value finished changes nothing.
  const bool stopped =
      run_subproblem_farm(problem, context, finished, farm).stopped && finished_count(finished) < finished.size();
  if (stopped) checkpoint();
  result.design_evaluations = interrupted_designs;
  result.sample_evaluations = interrupted_samples;

  // The best second objective among the per-value designs (ties: the better first objective),
  // in value order.
  const double s2 = problem.objectives()[1].sense == Sense::kMaximize ? 1.0 : -1.0;
  const double s1 = problem.objectives()[0].sense == Sense::kMaximize ? 1.0 : -1.0;
  const auto better = [&](const std::vector<double>& a, const std::vector<double>& b) {
    if (s2 * a[1] != s2 * b[1]) return s2 * a[1] > s2 * b[1];
    return s1 * a[0] > s1 * b[0];
  };
  Json per_value = Json::array();
  std::optional<SolutionPoint> chosen;
  for (const std::optional<FinishedSubproblem>& f : finished) {
    if (!f) continue;
    result.design_evaluations += f->design_evaluations;
    result.sample_evaluations += f->sample_evaluations;
    per_value.push_back(f->record);
    if (f->point && (!chosen || better(f->point->objectives, chosen->objectives))) chosen = f->point;
  }
  result.statistics = {{"variable", options_.variable},
                       {"per_value", per_value},
                       {"sub_solver", sub_solver_json(options_.sub_solver)},
                       {"seconds", elapsed()}};
  if (!resumed.is_null()) result.statistics["resumed"] = resumed;
  result.best = chosen;
  std::ostringstream message;
  if (stopped) {
    message << "sequential stopped on request after " << per_value.size() << " of " << values << " values of "
            << options_.variable << "; "
            << (chosen ? "the best is that of the finished values" : "none of the finished values gave a feasible design")
            << checkpoint_note(context);
    result.status = SolverStatus::kStopped;
  } else if (!chosen) {
    message << "no value of " << options_.variable << " gave a feasible design";
    result.status = SolverStatus::kInfeasible;
  } else {
    message << "sequential: best " << problem.objectives()[0].name << " for each of " << per_value.size()
            << " values of " << options_.variable << ", then the best " << problem.objectives()[1].name << " among them";
    result.status = SolverStatus::kConverged;
  }
  result.message = message.str();
  return result;
}

}  // namespace hapsyn::plugins
