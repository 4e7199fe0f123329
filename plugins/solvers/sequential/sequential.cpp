#include "sequential.hpp"

#include "shared/sub_solver.hpp"
#include "shared/sub_solver_sweep.hpp"

#include <hapsyn/checkpoint.hpp>
#include <hapsyn/error.hpp>

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
  SolverResult result;
  const Solver* solver = sub_solver_for_solve(options_.sub_solver, "sequential", "sub-solver", result);
  if (!solver) return result;
  const std::size_t k = free_index(problem);
  const auto first = single_objective_problem(problem, 0);
  const std::size_t values = static_cast<std::size_t>(problem.design_space().grid_count(k));
  const auto value = [&](std::size_t i) { return problem.design_space().grid_value(k, static_cast<long long>(i)); };

  // One subproblem per value: the first objective with the variable fixed there.
  SubSolverSweep sweep;
  sweep.solver = "sequential";
  sweep.fingerprint = study_fingerprint(problem, OptionDeclarations<SequentialOptions>::to_json(options_));
  sweep.count = values;
  sweep.units = "values of " + options_.variable;
  sweep.key = "value";
  sweep.identity = [&](std::size_t i) { return Json(value(i)); };
  sweep.named = [&](std::size_t i) { return "value " + std::to_string(i) + " of " + options_.variable; };
  sweep.what = [&](std::size_t i) {
    std::ostringstream name;
    name << "sequential: " << options_.variable << " = " << value(i) << " (" << i + 1 << " of " << values << ")";
    return name.str();
  };
  sweep.problem = [&](std::size_t i) { return fixed_component_problem(*first, k, value(i)); };
  const SubSolverSweepOutcome outcome = run_sub_solver_sweep(*solver, problem, context, sweep);
  const bool stopped = outcome.stopped;
  result.design_evaluations = outcome.design_evaluations;
  result.sample_evaluations = outcome.sample_evaluations;

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
  for (const std::optional<FinishedSubproblem>& f : outcome.finished) {
    if (!f) continue;
    per_value.push_back(f->record);
    if (f->point && (!chosen || better(f->point->objectives, chosen->objectives))) chosen = f->point;
  }
  result.statistics = {{"variable", options_.variable},
                       {"per_value", per_value},
                       {"sub_solver", sub_solver_json(options_.sub_solver)},
                       {"seconds", outcome.elapsed()}};
  if (!outcome.resumed.is_null()) result.statistics["resumed"] = outcome.resumed;
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
