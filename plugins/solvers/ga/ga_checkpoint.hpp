#pragma once
/// \file
/// Checkpoints of the `ga` solver (internal to the plugin): the state of a run between
/// generations, the fingerprint that ties a checkpoint to its study, and the checkpoint file
/// (README.md, "Checkpoints and --resume").
///
/// The file is one JSON document: "seed" (the study seed, read by the framework), "solver":
/// "ga", "fingerprint", "completed_runs" (the run records of statistics.runs), "run_seconds",
/// "evaluations" {"designs", "samples"}, "elapsed_seconds", and "current" (the run in progress,
/// absent between runs).
#include "ga_options.hpp"

#include <hapsyn/json.hpp>
#include <hapsyn/problem.hpp>

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
  bool switched = false;   ///< on the full scene (or never on a subset)
  double best_score = -std::numeric_limits<double>::infinity();
  pagmo::vector_double best_x;   ///< best full-fidelity individual seen (pagmo order); empty: none
  long long designs_before = 0;  ///< study design evaluations when the run started
  double seconds_before = 0.0;   ///< run time before a resume [s]
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

/// Fingerprint of a study for its checkpoints (hex FNV-1a): every option value, the scene's
/// sample count, the free components' names, bounds and integrality, the objectives' names,
/// weights and senses. A checkpoint is resumed only by a study with the same fingerprint.
std::string study_fingerprint(const Problem& problem, const GaOptions& options);

/// Reads a checkpoint file.
/// \throws Error("ga: <file>: cannot be read as a checkpoint (...)") when it is not JSON, and
///         Error("ga: <file>: written for another study (...); delete it or run without --resume")
///         when its solver is not "ga" or its fingerprint is not `fingerprint`.
Checkpoint read_checkpoint(const std::string& file, const std::string& fingerprint);

/// Writes a checkpoint file atomically (write_file_atomically). \param seed the study seed
void write_checkpoint(const std::string& file, std::uint64_t seed, const std::string& fingerprint,
                      const Checkpoint& checkpoint);

/// The run in progress as the checkpoint's "current": its state, the algorithm with its random
/// engine (pagmo_adapter::save_algorithm), the population's seed, decision and fitness vectors.
Json run_to_json(const RunState& state, const pagmo::algorithm& algorithm, const pagmo::population& population);

/// Restores a run in progress from a checkpoint's "current" (run_to_json): fills `state`
/// (except state.run, which the caller sets), `algorithm` and `population` (on `problem`,
/// nothing evaluated).
void restore_run(const Json& current, const pagmo::problem& problem, RunState& state, pagmo::algorithm& algorithm,
                 pagmo::population& population);

}  // namespace hapsyn::plugins::ga
