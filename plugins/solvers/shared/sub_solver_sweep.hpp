#pragma once
/// \file
/// A sweep of independent subproblems, each one whole sub-solver run: the body `sequential`
/// (one subproblem per value of its variable) and `weighted_sum` (one per weight vector) share.
/// The subproblems run as a task farm over the run's ranks (run_subproblem_farm, one at a time
/// per rank on its threads); the checkpoint (one list, "finished") is written after each one
/// finishes and on a stop; on --resume the finished ones are read back (read_subproblem_checkpoint
/// re-evaluates their designs) and each is checked to be the same subproblem as this study's.
/// The parent says how it builds and names subproblem i, and assembles its result from the
/// finished slots. Shared by the solver plugins; not a plugin itself.
#include "shared/sub_solver.hpp"

#include <chrono>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>

namespace hapsyn::plugins {

/// The subproblems of a sweep, as the parent defines them.
struct SubSolverSweep {
  std::string solver;       ///< the parent's name: its checkpoint's owner and its lines' prefix ("sequential")
  std::string fingerprint;  ///< study_fingerprint of the study's problem and the parent's options
  std::size_t count = 0;    ///< subproblems 0 .. count-1
  /// The subproblems in the resume line "<solver>: resuming from <file>: <n> of <count> <units>
  /// finished", e.g. "values of r" or "weight vectors".
  std::string units;
  /// The record field that identifies a subproblem, e.g. "value" or "weights": the first field
  /// of its record (then "status", "design" and "objectives" when feasible, "seconds").
  std::string key;
  /// Subproblem i's identity, its record's `key` field; a resumed entry must carry the same.
  std::function<Json(std::size_t i)> identity;
  /// Subproblem i in the resume's error, e.g. "value 3 of r" or "weight vector 3".
  std::function<std::string(std::size_t i)> named;
  /// Subproblem i's name for run_sub_solver's progress lines, e.g. "sequential: r = 0.5 (4 of 9)".
  std::function<std::string(std::size_t i)> what;
  /// Subproblem i's problem for the sub-solver (called on the rank and thread that runs it).
  std::function<std::shared_ptr<const Problem>(std::size_t i)> problem;
};

/// What a sweep leaves for the parent to assemble.
struct SubSolverSweepOutcome {
  using Clock = std::chrono::steady_clock;

  /// The finished subproblems by index, resumed ones included; each point holds the design the
  /// sub-solver found, re-evaluated with all the study's objectives (none: infeasible).
  SubproblemSlots finished;
  /// A stop request left some subproblems unfinished (the checkpoint was written).
  bool stopped = false;
  /// What the sweep cost: the finished subproblems' counts and those of interrupted runs.
  long long design_evaluations = 0;
  long long sample_evaluations = 0;
  /// The statistics' "resumed" entry ({checkpoint, finished, recheck_sample_evaluations}); null
  /// when the run did not resume.
  Json resumed = nullptr;
  /// Seconds the run took so far, the time before a resume included.
  double elapsed() const { return seconds_before + std::chrono::duration<double>(Clock::now() - start).count(); }
  Clock::time_point start = Clock::now();  ///< when this run's sweep began
  double seconds_before = 0.0;             ///< the checkpoint's seconds (0: not resumed)
};

/// Runs the sweep's unfinished subproblems with `solver` (after resuming from the checkpoint
/// when context.resume is set). A sub-solver run that stops on request is not a finished
/// subproblem (its best is not that subproblem's optimum): it runs again on --resume, and only
/// its evaluation counts are kept. Collective under MPI: every rank gets the same outcome.
/// \throws Error("checkpoint", ...) as read_subproblem_checkpoint, and "<file>: finished[<i>].
///         record.<key> = <value>: this study's <named(i)> is <identity(i)>; delete it, or run
///         without --resume" when an entry is another subproblem.
SubSolverSweepOutcome run_sub_solver_sweep(const Solver& solver, const Problem& problem, const SolverContext& context,
                                           const SubSolverSweep& sweep);

}  // namespace hapsyn::plugins
