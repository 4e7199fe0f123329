#pragma once
/// \file
/// Speed against accuracy: run one study across values of some keys and measure each run's
/// error against a reference run, with its time and evaluation count (`hapsyn sweep`).
#include <hapsyn/json.hpp>
#include <hapsyn/pareto.hpp>  // inverted_generational_distance
#include <hapsyn/registry.hpp>

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn {

/// One varied axis: one or more keys set together to each value in turn.
struct SweepAxis {
  std::vector<std::string> paths;  ///< e.g. {"design.l0.step", "design.l1.step"}
  std::vector<Json> values;        ///< e.g. {0.01, 0.005}
};

/// Parses "path[,path...]=v1,v2,..." (values are JSON when they parse, else strings; commas
/// inside brackets, braces or quotes do not split). \throws Error("sweep", ...) when malformed.
SweepAxis parse_sweep_axis(const std::string& spec);

struct SweepOptions {
  std::vector<SweepAxis> axes;
  /// Overrides ("path=value") that make the reference run; empty = the last combination.
  std::vector<std::string> reference;
  std::string output_directory = "results/sweep";
  int threads = 0;
  std::optional<std::uint64_t> seed;
  bool quiet = true;  ///< no solver progress lines
  /// Setting it asks the runs to stop (each run's solver returns "stopped"; no further run
  /// starts). Null: no stop request possible.
  const std::atomic<bool>* stop = nullptr;
  /// Run every combination again, overwriting finished runs (by default a run folder that holds
  /// a finished result.json of the same problem and seed is reused: see run_sweep).
  bool force = false;
};

/// Runs the grid of combinations (and the reference when it is not one of them), writes
/// <out>/sweep.csv, <out>/sweep.json and one sub-directory per run, and returns the summary:
/// per run its values, wall time, evaluations, status, objectives and the errors against the
/// reference (max objective difference, design distance [SI], front IGD for Pareto studies),
/// and "status": "finished" or "stopped".
///
/// Continuing: a run folder that already holds a finished result.json (any status but
/// "stopped") of the same resolved problem (and, when options.seed is set, the same seed) is
/// reused, not run again (its row says "reused": true and keeps the stored times); a run whose
/// result is "stopped", or that left only a checkpoint, is resumed from its checkpoint. So the
/// same `hapsyn sweep` command run again after a stop continues the sweep. options.force runs
/// everything again.
///
/// Stopping (options.stop set): the run in progress stops (its solver returns "stopped" and
/// writes its checkpoint), no further run starts, and sweep.csv and sweep.json are written with
/// the finished runs, "status": "stopped" and a "message" saying how to continue; the errors
/// against the reference are null when the reference did not run.
/// \throws Error for a malformed axis or an invalid study (before any run starts);
///         Error("sweep", "<run folder>: ...; delete it, or choose another --out") when a run
///         folder holds a result of another problem or seed, or an unreadable result.json; a
///         run's own errors as Error("sweep", "<run folder> (<values>): <error>").
Json run_sweep(const Json& problem, const SweepOptions& options, const Registry& registry);

/// The finished result to reuse from a run folder (sweep and compare): the parsed
/// <directory>/result.json when it exists, is not "stopped", and was run with `resolved` as its
/// problem (and `seed` when given); nullopt when there is none or it was stopped (the caller
/// resumes that run). `component` and `what` (e.g. "sweep", "this sweep") name the caller in
/// errors.
/// \throws Error(component, "<directory> holds a result of another problem (first difference
///         at <JSON pointer>: ...)" / "... with seed <s>, ..." / "<file>: not a readable result
///         (...)", each ending "; delete it, or choose another --out").
std::optional<Json> reusable_result(const std::string& directory, const Json& resolved,
                                    const std::optional<std::uint64_t>& seed, const std::string& component,
                                    const std::string& what);

}  // namespace hapsyn
