#include "sub_solver.hpp"

#include <hapsyn/error.hpp>

namespace hapsyn::plugins {

std::shared_ptr<Solver> make_sub_solver(const Registry& registry, const Json& spec, const std::string& component,
                                        const std::string& json_path) {
  if (!spec.is_object() || !spec.contains("plugin") || !spec["plugin"].is_string()) {
    throw Error(component, json_path + " = " + render_value(spec) + ": must be {\"plugin\": NAME, \"options\": {...}}");
  }
  const std::string name = spec["plugin"];
  const PluginRecord& record = registry.find(name);
  if (record.kind != "solver") {
    throw Error(component, json_path + ".plugin = \"" + name + "\": '" + name + "' is a " + record.kind +
                               " plugin, not a solver plugin");
  }
  const Json options = spec.contains("options") ? spec["options"] : Json::object();
  std::shared_ptr<Solver> solver = registry.create_solver(name, options, json_path);
  if (solver->pareto()) {
    throw Error(component, json_path + ".plugin = \"" + name +
                               "\": a Pareto solver; the sub-solver must be single-objective (it returns one best design)");
  }
  return solver;
}

std::shared_ptr<Solver> sub_solver_for_solve(const SolverContext& context, const Json& spec, const std::string& component,
                                             const std::string& json_path, const std::string& role, SolverResult& result) {
  if (!context.registry) {
    result.status = SolverStatus::kFailed;
    result.message = component + " needs the plugin registry in the solver context (for its " + role + ")";
    return nullptr;
  }
  return make_sub_solver(*context.registry, spec, component, json_path);
}

void check_sub_solver(const Solver& solver, const Problem& problem, const std::string& component, const std::string& where) {
  try {
    solver.check(problem);
  } catch (const Error& e) {
    throw Error(component, where + ": " + e.what());
  }
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
