#include "sub_solver.hpp"

#include <hapsyn/error.hpp>

namespace hapsyn::plugins {

const Solver* sub_solver_for_solve(const SubSolver& sub_solver, const std::string& component, const std::string& role,
                                   SolverResult& result) {
  if (!sub_solver.solver) {
    result.status = SolverStatus::kFailed;
    result.message = component + " has no " + role +
                     " (sub-solvers are created when the study is loaded through the registry)";
    return nullptr;
  }
  return sub_solver.solver.get();
}

void check_sub_solver(const SubSolver& sub_solver, const Problem& problem, const std::string& component,
                      const std::string& where) {
  if (!sub_solver.solver) return;
  try {
    sub_solver.solver->check(problem);
  } catch (const Error& e) {
    throw Error(component, where + ": " + e.what());
  }
}

Json sub_solver_json(const SubSolver& sub_solver) {
  return {{"plugin", sub_solver.plugin}, {"options", sub_solver.options}};
}

std::shared_ptr<const Problem> single_objective_problem(const Problem& problem, std::size_t index) {
  Objective o = problem.objectives().at(index);
  o.weight = 1.0;
  return problem.with_objectives({o});
}

std::shared_ptr<const Problem> reweighted_problem(const Problem& problem, const std::vector<double>& weights) {
  std::vector<Objective> objectives = problem.objectives();
  for (std::size_t i = 0; i < objectives.size() && i < weights.size(); ++i) objectives[i].weight = weights[i];
  return problem.with_objectives(std::move(objectives));
}

std::shared_ptr<const Problem> fixed_component_problem(const Problem& problem, std::size_t free_index, double value) {
  std::vector<DesignComponent> components = problem.design_space().components();
  DesignComponent& c = components.at(static_cast<std::size_t>(problem.design_space().free_indices().at(free_index)));
  c.lower = c.upper = value;
  c.step = 0.0;
  c.fixed = true;
  return problem.with_design_space(DesignSpace(std::move(components)));
}

SolverResult run_sub_solver(const Solver& solver, const Problem& problem, const SolverContext& parent) {
  SolverContext context = parent;
  context.progress = nullptr;
  return solver.solve(problem, context);
}

bool evaluate_full_design(const Problem& problem, const Eigen::VectorXd& full, int threads,
                          std::vector<double>& objectives, long long& samples) {
  const DesignSpace& space = problem.design_space();
  std::vector<double> x(space.free_size());
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = full[space.free_indices()[k]];
  const Evaluation e = problem.evaluate_parallel(x.data(), threads);
  samples += e.samples_evaluated;
  objectives.clear();
  if (e.status != EvalStatus::kFeasible) return false;
  objectives = e.objectives;
  return true;
}

}  // namespace hapsyn::plugins
