#pragma once
/// \file
/// Running a solver inside a solver (nbi's shadow optima, weighted_sum's weights, sequential's
/// per-value optima): checking the sub-solver the framework created from a
/// `{"plugin", "options"}` option (hapsyn::SubSolver), and making the problems it solves; their
/// checkpoints (finished subproblems by task index) and their task farms over the run's ranks
/// (run_subproblem_farm: results collected on rank 0, then handed to every rank).
/// Shared by the solver plugins; not a plugin itself.
#include <hapsyn/cluster.hpp>
#include <hapsyn/options.hpp>
#include <hapsyn/solver.hpp>

#include <atomic>
#include <functional>
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
// Checkpoints of the solvers that run subproblems (nbi, weighted_sum, sequential): the finished
// subproblems, each with its task index, its statistics record, its design, its objective
// values and its evaluation counts. A resumed run skips them and gives exactly the result of an
// uninterrupted run with the same seed.

/// One finished subproblem (a shadow optimum, a weight vector, a value of the variable, an NBI
/// grid point), as the parent's result and checkpoint keep it.
struct FinishedSubproblem {
  Json record = Json::object();         ///< its entry in the parent's statistics (result.json)
  std::optional<SolutionPoint> point;   ///< the design it found, with all objectives (none: infeasible)
  long long design_evaluations = 0;     ///< what it cost, its final full evaluation included
  long long sample_evaluations = 0;
};

/// A sub-solver's result as a finished subproblem with its counts (the caller fills the record
/// and the point), or nullopt when a stop request interrupted it: its best is not the
/// subproblem's optimum, the subproblem runs again on --resume, and its counts are added to
/// `interrupted_designs` / `interrupted_samples`.
std::optional<FinishedSubproblem> finished_unless_stopped(const SolverResult& result,
                                                          std::atomic<long long>& interrupted_designs,
                                                          std::atomic<long long>& interrupted_samples);

/// The subproblems of one list by task index (0 .. count-1); nullopt: not finished. Tasks
/// finish in any order when they run on several threads or ranks.
using SubproblemSlots = std::vector<std::optional<FinishedSubproblem>>;

/// The finished subproblems of a checkpoint, by list name (e.g. "finished", or nbi's "shadows"
/// and "subproblems"), and the run's elapsed seconds when it was written.
struct SubproblemCheckpoint {
  std::map<std::string, SubproblemSlots> lists;  ///< each sized to its limit
  std::map<std::string, std::map<std::size_t, std::size_t>> positions;  ///< list -> task -> its entry
  double seconds = 0.0;
  long long recheck_samples = 0;  ///< samples spent re-evaluating the claimed points on resume

  /// "<list>[<i>]": the file's entry of task `task` (for messages about it).
  std::string where(const std::string& list, std::size_t task) const;
};

/// Number of finished subproblems in `slots`.
std::size_t finished_count(const SubproblemSlots& slots);

/// Writes the checkpoint of `solver` (nothing without a checkpoint file, nothing on ranks other
/// than 0): for each list, its finished subproblems in task order, each with its "task" index;
/// and `seconds`.
/// \throws Error("output", ...) when it cannot be written.
void write_subproblem_checkpoint(const SolverContext& context, const std::string& solver, const std::string& fingerprint,
                                 const std::map<std::string, const SubproblemSlots*>& lists, double seconds);

/// The checkpoint to resume from (nullopt: start over; a line saying so goes to the progress and
/// the log when context.resume is set). Collective under MPI (read_checkpoint): every rank calls
/// it at the same point and gets the same answer. Every claimed point is re-evaluated on
/// `problem` (one design evaluation per finished subproblem, cheap against a subproblem): a point
/// that is not feasible or whose objective values differ from the claimed ones is refused, as is
/// a list longer than `limits` allows, a task index out of range or out of order, or an entry
/// of the wrong shape. An entry without "task" (checkpoints written before tasks could finish
/// out of order) is task <its position>.
/// \throws Error("checkpoint", "<file>: <what is wrong>; delete it, or run without --resume"):
///         read_checkpoint's checks, then "<list>[<i>].<field>: ..." for a bad entry and
///         "<list>[<i>]: the design re-evaluates to <values>, the checkpoint claims <values>".
std::optional<SubproblemCheckpoint> read_subproblem_checkpoint(const Problem& problem, const SolverContext& context,
                                                               const std::string& solver, const std::string& fingerprint,
                                                               const std::map<std::string, std::size_t>& limits);

// ---------------------------------------------------------------------------------------------
// Subproblems as a task farm over the run's ranks (hapsyn/cluster.hpp).

/// The context of a sub-solver that runs inside one task: context.in_task() (this process
/// alone, no checkpoint), except that a single process (context.cluster().size() == 1) keeps
/// the progress stream and the log, so its sub-solvers still show how far they are.
SolverContext task_context(const SolverContext& context);

/// One farm of subproblems (see run_subproblem_farm).
struct SubproblemFarm {
  /// The slots the farm runs (indices into the slots; empty: every slot). Those already
  /// finished are skipped.
  std::vector<std::size_t> tasks;
  /// Tasks run at a time on each rank: 1 for tasks that run a whole sub-solver on the rank's
  /// threads, context.threads for single-threaded tasks.
  int threads = 1;
  /// Runs slot `index` on any rank and thread: its finished subproblem, or nullopt when it was
  /// interrupted by a stop request (it counts as not finished).
  std::function<std::optional<FinishedSubproblem>(std::size_t index)> run;
  /// Optional, rank 0, one call at a time: slot `index` was just filled (write the checkpoint,
  /// a progress line).
  std::function<void(std::size_t index)> collected;
  /// Optional, rank 0: the job is about to be aborted (a rank stopped answering): write the
  /// checkpoint of the slots filled so far.
  std::function<void()> on_abort;
  /// Optional: the subproblem's name for the line "<what>: <record.status> in <record.seconds> s"
  /// that rank 0 writes when it is collected under MPI (a single process's sub-solver says it
  /// itself through run_sub_solver).
  std::function<std::string(std::size_t index)> what;
};

/// Runs the farm's unfinished slots over the ranks of context.cluster() and fills `slots` with
/// their results, on every rank alike: rank 0 collects them, then broadcasts every slot (the
/// code after the farm is replicated). `slots` must be the same on every rank before the call.
/// Collective. Returns the farm's outcome (stopped: some slots are still empty).
/// The results travel as JSON text, which carries doubles exactly: every rank sees the bits the
/// running rank computed.
FarmOutcome run_subproblem_farm(const Problem& problem, const SolverContext& context, SubproblemSlots& slots,
                                const SubproblemFarm& farm);

/// A finished subproblem as bytes and back (the point's score recomputed by `problem`).
std::string subproblem_bytes(const FinishedSubproblem& finished);
FinishedSubproblem subproblem_from_bytes(const Problem& problem, const std::string& bytes);

/// A line for the progress stream and the run log (either may be null).
void solver_line(const SolverContext& context, const std::string& line);

/// What a stopped parent says about its checkpoint: "; checkpoint <file> written: `hapsyn run
/// --resume` continues from there" or "; no checkpoint (no checkpoint file in this context)".
std::string checkpoint_note(const SolverContext& context);

}  // namespace hapsyn::plugins
