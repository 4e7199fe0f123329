#pragma once
/// \file
/// A study and how it is loaded: a problem document (read by problem_file.hpp) validated
/// completely and turned into a ready-to-run Problem and Solver. Nothing here runs a study:
/// that is run_study (study_runner.hpp).
#include <hapsyn/json.hpp>
#include <hapsyn/pareto.hpp>
#include <hapsyn/problem.hpp>
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/solver.hpp>

#include <cstddef>
#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

namespace hapsyn {

/// Longest study or plugin name [characters]. Names become parts of paths (results/<name>,
/// libhapsyn_<name>.so), so they are limited to [A-Za-z0-9._-] and may not start with '.'.
constexpr std::size_t kMaxNameLength = 100;

/// Most samples a scene may give a study: beyond it every design evaluation is hopeless, and
/// sample indices are int. A plugin's own limits usually refuse such options first.
constexpr long long kMaxSceneSamples = 100000000;

/// A validated, ready-to-run study.
struct Study {
  Json resolved;                         ///< the problem with defaults and overrides applied
  std::shared_ptr<Problem> problem;
  std::shared_ptr<Solver> solver;
  std::string solver_plugin;
  std::vector<PluginRecord> plugins;     ///< every plugin the study uses
  std::string output_directory;          ///< from the file, or --out
  /// From the optional "indicators" section: the reference front (objective points, loaded from
  /// a result.json) and the hypervolume reference point (natural units, one per objective).
  std::vector<ObjectivePoint> reference_front;
  ObjectivePoint reference_point;
  /// The reference front's path when the file does not exist yet (then no reference indicators;
  /// result.json says why). A file that exists but is not a usable result is an error.
  std::string reference_front_missing;
};

/// A metric made by the caller rather than loaded from a plugin file (hapsyn's Python binding:
/// a metric class written in Python). An objective whose "metric" is `name` gets one from
/// `create`, with the objective's "options" object as given (no schema: the factory checks them,
/// throwing Error) and the objective's path ("objectives[i]") for messages; result.json lists
/// it among the plugins with `file` = `origin`.
struct InProcessMetric {
  std::string name, version, description;
  std::string origin = "in-process";
  std::function<std::shared_ptr<Metric>(const Json& options, const std::string& json_path)> create;
  /// kSerialized: the framework never calls two of its methods at once (see options.hpp).
  ThreadSafety thread_safety = ThreadSafety::kSerialized;
};

/// Validates a problem document completely and builds the study; nothing runs. In order:
/// the framework's own schema of a problem file (defaults filled in), the mechanism and its
/// options, the "design" section against the mechanism's variables (build_design_space), each
/// objective's metric and options, the solver and its options, the scene and its options (the
/// scene is built here, with the attributes the metrics ask for; its SampleLattice, if any, is
/// checked), Solver::check, the "indicators" section and its reference front file.
/// The resolved document (Study::resolved) records every default, "aggregation":
/// "weighted_sum" for several objectives under a single-objective solver, and
/// indicators.reference_front as the absolute path it was resolved to.
/// Beyond the schema: every string valid UTF-8 and nesting at most kMaxJsonDepth
/// (check_json_text_rules); "name" and every plugin name (mechanism.plugin, scene.plugin,
/// solver.plugin, objectives[i].metric) a safe name (kMaxNameLength, [A-Za-z0-9._-], not
/// starting with '.'), an unknown plugin blamed on the key naming it; "threads" 0..1024, "seed" an
/// unsigned 64-bit integer; weights >= 0 and, under a single-objective solver, not all 0; a design
/// grid within build_design_space's caps; at most kMaxSceneSamples samples.
/// Relative paths (indicators.reference_front, plugins' data files through find_data_file) are
/// resolved against the problem file's folder first while the caller holds a
/// ProblemDirectoryScope (data_file.hpp), then against the current directory.
/// \param problem  the parsed (and overridden) problem document
/// \param registry finds and creates the plugins; must outlive the study
/// \throws Error naming the JSON path, the value and the rule (component "problem" for the
///         file's own rules, the plugin's name for its options), or a scene's lattice error.
/// \param in_process metrics known by name besides the registry's plugins (they take
///        precedence over a plugin of the same name)
/// How the scene is built during load_study (the run's settings reach the scene build).
struct LoadSettings {
  /// Threads for the scene build: the run's --threads (already capped by the caller); 0 = the
  /// file's "threads", else all cores. A scene's own `threads` option, when it has one and it is
  /// above 0, wins.
  int threads = 0;
  /// Progress lines of a long scene build (null: quiet).
  std::ostream* progress = nullptr;
};

Study load_study(const Json& problem, const Registry& registry, const std::vector<InProcessMetric>& in_process = {},
                 const LoadSettings& settings = {});

}  // namespace hapsyn
