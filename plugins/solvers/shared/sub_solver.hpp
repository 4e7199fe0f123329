#pragma once
/// \file
/// Running a solver inside a solver (nbi's shadow optima, weighted_sum's weights, sequential's
/// per-value optima): checking the sub-solver the framework created from a
/// `{"plugin", "options"}` option (hapsyn::SubSolver), and making the problems it solves.
/// Shared by the solver plugins; not a plugin itself.
#include <hapsyn/options.hpp>
#include <hapsyn/solver.hpp>

#include <memory>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// The sub-solver for one solve() call. When the options were made without a registry (tests
/// that build a solver directly with make_options), there is none: it returns null and marks
/// `result` failed: "<component> has no <role> (sub-solvers are created when the study is loaded
/// through the registry)".
const Solver* sub_solver_for_solve(const SubSolver& sub_solver, const std::string& component, const std::string& role,
                                   SolverResult& result);

/// Runs the sub-solver's check() on `problem` (called from the parent's check()); its error is
/// rethrown as Error(component, "<where>: <the sub-solver's message>"). Does nothing when the
/// sub-solver was not created (see sub_solver_for_solve).
void check_sub_solver(const SubSolver& sub_solver, const Problem& problem, const std::string& component,
                      const std::string& where);

/// The option as the problem file gives it, `{"plugin": NAME, "options": {...}}` (for statistics).
Json sub_solver_json(const SubSolver& sub_solver);

/// The problem with only objective `index` (weight 1): a shadow optimum's problem.
std::shared_ptr<const Problem> single_objective_problem(const Problem& problem, std::size_t index);
/// The problem with the same objectives and these weights (one per objective, finite).
std::shared_ptr<const Problem> reweighted_problem(const Problem& problem, const std::vector<double>& weights);
/// The problem with free design component `free_index` fixed at `value` (within its bounds).
std::shared_ptr<const Problem> fixed_component_problem(const Problem& problem, std::size_t free_index, double value);

/// Runs `solver` on `problem` with the parent's threads, seed and stop flag, quietly.
SolverResult run_sub_solver(const Solver& solver, const Problem& problem, const SolverContext& parent);

/// Evaluates a full design over every sample with `problem`'s objectives (all of them).
/// Returns false (and leaves `objectives` empty) when the design is not feasible.
bool evaluate_full_design(const Problem& problem, const Eigen::VectorXd& full_design, int threads,
                          std::vector<double>& objectives, long long& samples);

}  // namespace hapsyn::plugins
