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
};

/// Runs the grid of combinations (and the reference when it is not one of them), writes
/// <out>/sweep.csv, <out>/sweep.json and one sub-directory per run, and returns the summary:
/// per run its values, wall time, evaluations, status, objectives and the errors against the
/// reference (max objective difference, design distance [SI], front IGD for Pareto studies).
/// \throws Error for a malformed axis or an invalid study (before any run starts).
Json run_sweep(const Json& problem, const SweepOptions& options, const Registry& registry);

}  // namespace hapsyn
