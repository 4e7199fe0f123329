#pragma once
/// \file
/// Checkpoints of the `ga` solver (internal to the plugin): the state of a run between
/// generations, the fingerprint that ties a checkpoint to its study, and the checkpoint file
/// (README.md, "Checkpoints and --resume").
///
/// The file is the framework's checkpoint (hapsyn/checkpoint.hpp: format, seed, solver "ga",
/// fingerprint, checksum); its "state" holds "completed_runs" (the run records of
/// statistics.runs), "run_seconds", "evaluations" {"designs", "samples"}, "elapsed_seconds", and
/// "current" (the run in progress, absent between runs). "completed_runs" are by run index but
/// need not be consecutive: a shard (`--shard i/N`) holds its share of the runs.
#include "ga_options.hpp"

#include <hapsyn/json.hpp>
#include <hapsyn/convergence.hpp>
#include <hapsyn/problem.hpp>
#include <hapsyn/solver.hpp>

#include <pagmo/algorithm.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#include <pagmo/types.hpp>

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn::plugins::ga {

/// The state of one run between generations (with the pagmo algorithm and population, all a
/// resumed run needs to continue exactly as an uninterrupted one).
struct RunState {
  int run = 0;             ///< 0-based index of the run
  int generation = 0;      ///< generations done
  int stall = 0;           ///< generations at full fidelity without an improvement > ftol
  bool switched = false;   ///< past the subset generations (or never on a subset): stalling is counted
  bool refining = false;   ///< switched to the refine subset (fidelity.refine_fraction < 1), not the full scene
  double best_score = -std::numeric_limits<double>::infinity();
  pagmo::vector_double best_x;   ///< best individual seen since the switch, at its fidelity (pagmo order); empty: none
  long long designs = 0;         ///< the run's design evaluations before a resume
  double seconds_before = 0.0;   ///< run time before a resume [s]
  /// Per generation: generation, evaluations (the run's designs so far), best and mean score of
  /// the population's feasible individuals, fidelity with a subset (statistics.runs[i].history).
  ConvergenceHistory history;
};

/// A checkpoint's content besides the seed, the solver and the fingerprint.
struct Checkpoint {
  Json completed_runs = Json::array();  ///< records of the finished runs
  std::vector<double> run_seconds;      ///< their times [s], one per record
  long long designs = 0;                ///< design evaluations so far (all runs)
  long long samples = 0;                ///< sample evaluations so far (all runs)
  double elapsed_seconds = 0.0;         ///< solve time so far [s]
  std::optional<Json> current;          ///< the run in progress (run_to_json)
};

/// The checkpoint's "state" (the framework's checkpoint file, hapsyn/checkpoint.hpp, written
/// with solver "ga" and study_fingerprint(problem, options_to_json(options))).
Json checkpoint_to_state(const Checkpoint& checkpoint);

/// The checkpoint from its "state" (read_checkpoint).
/// \throws Error("checkpoint", "<file>: state.<field> ...; delete it, or run without --resume")
///         (bad_checkpoint) when a field is missing or of another type.
Checkpoint checkpoint_from_state(const SolverContext& context, const Json& state);

/// The run in progress as the checkpoint's "current": its state, the algorithm with its random
/// engine (pagmo_adapter::save_algorithm), the population's seed, decision and fitness vectors
/// and its champion (the best individual it ever held: gaco's stall count compares champions).
Json run_to_json(const RunState& state, const pagmo::algorithm& algorithm, const pagmo::population& population);

/// Restores a run in progress from a checkpoint's "current" (run_to_json): fills `state`
/// (except state.run, which the caller sets), `algorithm` and `population` (on `problem`,
/// nothing evaluated). A checkpoint of an earlier version without "history" gives an empty one
/// (the resumed run's history starts at the resume).
/// \throws Error("checkpoint", "<file>: state.current...") (bad_checkpoint) when a field is
///         missing, of another type or of another size, or the algorithm archive is damaged.
void restore_run(const SolverContext& context, const Json& current, const pagmo::problem& problem, RunState& state,
                 pagmo::algorithm& algorithm, pagmo::population& population);

}  // namespace hapsyn::plugins::ga
