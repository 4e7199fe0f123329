#pragma once
/// \file
/// Running a solver inside a solver (nbi's shadow optima, weighted_sum's weights, sequential's
/// per-value optima): creating the sub-solver from a `{"plugin", "options"}` option and making
/// the problems it solves. Shared by the solver plugins; not a plugin itself.
#include <hapsyn/registry.hpp>
#include <hapsyn/solver.hpp>

#include <memory>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// Creates the solver a `{"plugin": NAME, "options": {...}}` option names, its options validated
/// against its schema. \throws Error("<component>: <json_path>.plugin = ...") when the option
/// is malformed, names an unknown plugin or a plugin that is not a solver, or names a Pareto
/// solver (a sub-solver must return one best design).
std::shared_ptr<Solver> make_sub_solver(const Registry& registry, const Json& spec, const std::string& component,
                                        const std::string& json_path);

/// The sub-solver for one solve() call. Without a registry in the context it returns null and
/// marks `result` failed: "<component> needs the plugin registry in the solver context (for its
/// <role>)". \throws as make_sub_solver.
std::shared_ptr<Solver> sub_solver_for_solve(const SolverContext& context, const Json& spec, const std::string& component,
                                             const std::string& json_path, const std::string& role, SolverResult& result);

/// Runs the sub-solver's check() on `problem` (from prepare_sub_solvers): its error is rethrown as
/// Error(component, "<where>: <the sub-solver's message>").
void check_sub_solver(const Solver& solver, const Problem& problem, const std::string& component, const std::string& where);

/// The problem with only objective `index` (weight 1): a shadow optimum's problem.
std::shared_ptr<const Problem> single_objective_problem(const Problem& problem, std::size_t index);
/// The problem with the same objectives and these weights (one per objective, finite).
std::shared_ptr<const Problem> reweighted_problem(const Problem& problem, const std::vector<double>& weights);
/// The problem with free design component `free_index` fixed at `value` (within its bounds).
std::shared_ptr<const Problem> fixed_component_problem(const Problem& problem, std::size_t free_index, double value);

/// Runs `solver` on `problem` with the parent's threads, seed, stop flag and registry, quietly.
SolverResult run_sub_solver(const Solver& solver, const Problem& problem, const SolverContext& parent);

/// Evaluates a full design over every sample with `problem`'s objectives (all of them).
/// Returns false (and leaves `objectives` empty) when the design is not feasible.
bool evaluate_full_design(const Problem& problem, const Eigen::VectorXd& full_design, int threads,
                          std::vector<double>& objectives, long long& samples);

}  // namespace hapsyn::plugins
