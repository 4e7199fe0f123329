#pragma once
/// \file
/// Running a solver inside a solver (nbi's shadow optima, weighted_sum's weights, sequential's
/// per-value optima): checking the sub-solver the framework created from a
/// `{"plugin", "options"}` option (hapsyn::SubSolver), and making the problems it solves.
/// Shared by the solver plugins; not a plugin itself.
#include <hapsyn/options.hpp>
#include <hapsyn/solver.hpp>

#include <map>
#include <memory>
#include <optional>
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

/// Runs `solver` on `problem` with the parent's threads, seed, stop flag, progress stream and log
/// (a long subproblem is never silent: its own progress lines show how far it is), and without a
/// checkpoint: the sub-solver's checkpoint_file is empty and resume false, because the parent
/// checkpoints at subproblem granularity (an interrupted subproblem is run again on --resume) and
/// the sub-solver must not overwrite the parent's file.
/// \param what  when not empty, the subproblem as the parent names it ("nbi: shadow optimum 1 of
///              2 (gii)"): a line "<what> ..." before and "<what>: <status> in <t> s" after
///              go to the parent's progress and log (solver_line).
SolverResult run_sub_solver(const Solver& solver, const Problem& problem, const SolverContext& parent,
                            const std::string& what = "");

/// Evaluates a full design over every sample with `problem`'s objectives (all of them), in a
/// fixed number of sample chunks: the values do not depend on `threads`.
/// Returns false (and leaves `objectives` empty) when the design is not feasible.
bool evaluate_full_design(const Problem& problem, const Eigen::VectorXd& full_design, int threads,
                          std::vector<double>& objectives, long long& samples);

// ---------------------------------------------------------------------------------------------
// Checkpoints of the solvers that run subproblems one after the other (nbi, weighted_sum,
// sequential): the finished subproblems, each with its statistics record, its design, its
// objective values and its evaluation counts. A resumed run skips them and gives exactly the
// result of an uninterrupted run with the same seed.

/// One finished subproblem (a shadow optimum, a weight vector, a value of the variable, an NBI
/// grid point), as the parent's result and checkpoint keep it.
struct FinishedSubproblem {
  Json record = Json::object();         ///< its entry in the parent's statistics (result.json)
  std::optional<SolutionPoint> point;   ///< the design it found, with all objectives (none: infeasible)
  long long design_evaluations = 0;     ///< what it cost, its final full evaluation included
  long long sample_evaluations = 0;
};

/// The finished subproblems of a checkpoint, by list name (e.g. "finished", or nbi's "shadows"
/// and "subproblems"), and the run's elapsed seconds when it was written.
struct SubproblemCheckpoint {
  std::map<std::string, std::vector<FinishedSubproblem>> lists;
  double seconds = 0.0;
  long long recheck_samples = 0;  ///< samples spent re-evaluating the claimed points on resume
};

/// Writes the checkpoint of `solver` (nothing without a checkpoint file): `lists` and `seconds`.
/// \throws Error("output", ...) when it cannot be written.
void write_subproblem_checkpoint(const SolverContext& context, const std::string& solver, const std::string& fingerprint,
                                 const std::map<std::string, const std::vector<FinishedSubproblem>*>& lists,
                                 double seconds);

/// The checkpoint to resume from (nullopt: start over; a line saying so goes to the progress and
/// the log when context.resume is set). Every claimed point is re-evaluated on `problem` (one
/// design evaluation per finished subproblem, cheap against a subproblem): a point that is not
/// feasible or whose objective values differ from the claimed ones is refused, as is a list
/// longer than `limits` allows or an entry of the wrong shape.
/// \throws Error("checkpoint", "<file>: <what is wrong>; delete it, or run without --resume"):
///         read_checkpoint's checks, then "<list>[<i>].<field>: ..." for a bad entry and
///         "<list>[<i>]: the design re-evaluates to <values>, the checkpoint claims <values>".
std::optional<SubproblemCheckpoint> read_subproblem_checkpoint(const Problem& problem, const SolverContext& context,
                                                               const std::string& solver, const std::string& fingerprint,
                                                               const std::map<std::string, std::size_t>& limits);

/// A line for the progress stream and the run log (either may be null).
void solver_line(const SolverContext& context, const std::string& line);

/// What a stopped parent says about its checkpoint: "; checkpoint <file> written: `hapsyn run
/// --resume` continues from there" or "; no checkpoint (no checkpoint file in this context)".
std::string checkpoint_note(const SolverContext& context);

}  // namespace hapsyn::plugins
