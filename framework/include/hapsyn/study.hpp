#pragma once
/// \file
/// Problem files: loading (with clear errors), --set overrides, and running a study.
#include <hapsyn/json.hpp>
#include <hapsyn/pareto.hpp>
#include <hapsyn/problem.hpp>
#include <hapsyn/registry.hpp>
#include <hapsyn/solver.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn {

/// A validated, ready-to-run study.
struct Study {
  Json resolved;                         ///< the problem with defaults and overrides applied
  std::shared_ptr<Problem> problem;
  std::shared_ptr<Solver> solver;
  std::string solver_plugin;
  std::vector<PluginRecord> plugins;     ///< every plugin the study uses
  std::string output_directory;          ///< from the file, or --out
  const Registry* registry = nullptr;    ///< the registry that loaded it (sub-solvers use it)
  /// From the optional "indicators" section: the reference front (objective points, loaded from
  /// a result.json) and the hypervolume reference point (natural units, one per objective).
  std::vector<ObjectivePoint> reference_front;
  ObjectivePoint reference_point;
  /// The reference front's path when the file does not exist yet (then no reference indicators;
  /// result.json says why). A file that exists but is not a usable result is an error.
  std::string reference_front_missing;
};

/// Validates a problem document completely (framework rules, each plugin's schema, design
/// bounds against the mechanism's limits, the "indicators" section and its reference front
/// file) and builds the scene and problem. Nothing runs. The registry must outlive the study.
/// \throws Error naming the JSON path, the value and the rule.
Study load_study(const Json& problem, const Registry& registry);

struct RunOptions {
  std::string output_directory;  ///< overrides output.directory when not empty
  int threads = 0;               ///< 0 = hardware concurrency
  std::optional<std::uint64_t> seed;
  bool quiet = false;
  bool write_samples = true;     ///< per-sample CSV of the best design
  /// Overwrite a finished study (an existing result.json in the output directory).
  bool force = false;
  /// Continue from the output directory's checkpoint.json (solvers that checkpoint); the seed
  /// is the checkpoint's unless given.
  bool resume = false;
};

/// Runs a loaded study: solves, then writes result.json (atomically) and samples.csv into the
/// output directory. Returns the result document. The solver's outcome is in "status".
/// Studies with a front (or a reference front) get "indicators" (see front_indicators).
/// Progress lines also go to run.log in the output directory (appended on --resume); the
/// solver's checkpoint is <output>/checkpoint.json and is removed once result.json is written.
/// \throws Error("output", ...) when the output directory holds a finished study
///         (result.json) and `force` is not set, when `resume` finds a finished
///         study, or when the checkpoint's seed contradicts options.seed.
Json run_study(Study& study, const RunOptions& options);

}  // namespace hapsyn
