#include "sequential.hpp"

#include "shared/sub_solver.hpp"

#include <hapsyn/error.hpp>

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
  const long long values = problem.design_space().grid_count(k);
  const bool larger_is_better = problem.objectives()[1].sense == Sense::kMaximize;
  const bool first_larger_is_better = problem.objectives()[0].sense == Sense::kMaximize;
  Json per_value = Json::array();
  std::optional<SolutionPoint> chosen;
  bool stopped = false;
  for (long long i = 0; i < values; ++i) {
    if (context.stop && context.stop->load()) {
      stopped = true;
      break;
    }
    const double v = problem.design_space().grid_value(k, i);
    const SolverResult r = run_sub_solver(*solver, *fixed_component_problem(*first, k, v), context);
    result.design_evaluations += r.design_evaluations;
    result.sample_evaluations += r.sample_evaluations;
    Json record = {{"value", v}, {"status", to_string(r.status)}};
    std::vector<double> objectives;
    if (r.best && evaluate_full_design(problem, r.best->design, context.threads, objectives, result.sample_evaluations)) {
      record["design"] = problem.design_to_json(r.best->design);
      record["objectives"] = objectives;
      const auto better = [&](const std::vector<double>& a, const std::vector<double>& b) {
        const double s2 = larger_is_better ? 1.0 : -1.0, s1 = first_larger_is_better ? 1.0 : -1.0;
        if (s2 * a[1] != s2 * b[1]) return s2 * a[1] > s2 * b[1];
        return s1 * a[0] > s1 * b[0];  // ties on the second: the better first objective
      };
      if (!chosen || better(objectives, chosen->objectives)) {
        chosen = SolutionPoint{r.best->design, objectives, problem.score(objectives)};
      }
    }
    per_value.push_back(record);
  }
  result.statistics = {{"variable", options_.variable},
                       {"per_value", per_value},
                       {"sub_solver", sub_solver_json(options_.sub_solver)},
                       {"seconds", std::chrono::duration<double>(Clock::now() - t_start).count()}};
  if (!chosen) {
    result.status = stopped ? SolverStatus::kStopped : SolverStatus::kInfeasible;
    result.message = "no value of " + options_.variable + " gave a feasible design";
    return result;
  }
  result.best = chosen;
  result.status = stopped ? SolverStatus::kStopped : SolverStatus::kConverged;
  std::ostringstream message;
  message << "sequential: best " << problem.objectives()[0].name << " for each of " << per_value.size()
          << " values of " << options_.variable << ", then the best " << problem.objectives()[1].name << " among them";
  result.message = message.str();
  return result;
}

}  // namespace hapsyn::plugins
