#pragma once
// The framework's own keys of a problem file, declared as a plugin declares its options
// (hapsyn/options.hpp): problem_file_schema() (hapsyn/internal/reference.hpp) is the schema these
// declarations give, so that the file's errors read like the plugins' and the reference page
// (docs/reference/problem-file.md) lists them. The plugins' "options" stay free-form here: each
// plugin's own schema checks them when the plugin is created. "design" has the mechanism's
// variable names as keys and is checked by hand (design_space.hpp) against its declarations.
#include <hapsyn/options.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn {

/// What names a plugin's kind in the descriptions of PluginSection.
struct MechanismSection {
  static constexpr const char* kTitle = "Mechanism";
  static constexpr const char* kKind = "mechanism";
};
struct SceneSection {
  static constexpr const char* kTitle = "Scene";
  static constexpr const char* kKind = "scene";
};
struct SolverSection {
  static constexpr const char* kTitle = "Solver";
  static constexpr const char* kKind = "solver";
};

/// "mechanism", "scene", "solver": a plugin and its options.
template <class Kind>
struct PluginSection {
  std::string plugin;
  Json options;
  static void declare(OptionDeclarations<PluginSection>& d) {
    d.add(&PluginSection::plugin, "plugin", {}, std::string(Kind::kTitle) + " plugin name").required();
    d.add(&PluginSection::options, "options", std::string("Options of the ") + Kind::kKind + " plugin");
  }
};

/// One entry of "objectives".
struct ObjectiveDeclaration {
  std::string metric;
  std::optional<std::string> name;
  std::string sense;
  double weight{};
  Json options;
  static void declare(OptionDeclarations<ObjectiveDeclaration>& d);
};

/// "output".
struct OutputDeclaration {
  std::optional<std::string> directory;
  bool samples_csv{};
  bool maps{};
  bool plots{};
  bool groups{};
  std::optional<std::string> timeline;
  static void declare(OptionDeclarations<OutputDeclaration>& d);
};

/// "indicators".
struct IndicatorsDeclaration {
  std::optional<std::string> reference_front;
  std::optional<std::vector<double>> reference_point;
  static void declare(OptionDeclarations<IndicatorsDeclaration>& d);
};

/// A problem file's top level.
struct ProblemFileDeclaration {
  std::string name;
  std::string description;
  PluginSection<MechanismSection> mechanism;
  PluginSection<SceneSection> scene;
  std::vector<ObjectiveDeclaration> objectives;
  PluginSection<SolverSection> solver;
  OutputDeclaration output;
  std::optional<IndicatorsDeclaration> indicators;
  std::optional<Json> design;
  std::optional<std::uint64_t> seed;
  std::optional<int> threads;
  static void declare(OptionDeclarations<ProblemFileDeclaration>& d);
};

}  // namespace hapsyn
