#pragma once
/// \file
/// What a plugin library exports. A plugin is a shared library `hapsyn-<name>.so` (built with the
/// CMake function hapsyn_add_plugin; the file name must equal the registered name) that registers
/// exactly one class with one of:
///
///   HAPSYN_MECHANISM_PLUGIN(MyMechanism, "name", "1.0.0", "one-line description")
///   HAPSYN_SCENE_PLUGIN(...)   HAPSYN_METRIC_PLUGIN(...)   HAPSYN_SOLVER_PLUGIN(...)
///
/// The class may declare
///   - `using Options = MyOptions;` an options struct with a static `declare` function
///     (hapsyn/options.hpp). The class then needs a constructor taking `const MyOptions&`: the
///     framework validates the problem file's options against the declarations, fills the
///     struct (defaults included) and creates declared sub-solvers before the constructor runs.
///     Without an Options type the plugin has no options and is default-constructed.
///   - `static constexpr hapsyn::ThreadSafety thread_safety = hapsyn::ThreadSafety::kSerialized;`
///     when its const methods must not run concurrently (default: kConcurrent).
/// The constructor may throw hapsyn::Error for option combinations the declarations cannot
/// express; the message is reported under the options' JSON path.
#include <hapsyn/json.hpp>
#include <hapsyn/mechanism.hpp>
#include <hapsyn/metric.hpp>
#include <hapsyn/options.hpp>
#include <hapsyn/scene.hpp>
#include <hapsyn/solver.hpp>

#include <boost/dll/alias.hpp>
#include <memory>
#include <string>
#include <type_traits>

/// Bumped whenever an interface in framework/include/hapsyn changes incompatibly.
/// 3: options declared in C++ (hapsyn/options.hpp), sub-solvers created by the framework,
///    declared thread safety; Solver::prepare_sub_solvers and SolverContext::registry removed.
/// 4: two layers: the speed hooks moved to Mechanism::acceleration() and Metric::acceleration()
///    (hapsyn/accel/); capabilities in specs structs (MechanismSpecs, MetricSpecs,
///    SolverSpecs); MechanismModel::solve_block became MechanismAcceleration::solve_block;
///    plugin bases non-copyable; the framework's orchestration headers private.
/// 5: MechanismModel::segments (a mechanism drawn at a sample, for `hapsyn view`): a new virtual,
///    so a model built for API 4 has another vtable.
#define HAPSYN_PLUGIN_API_VERSION 5

// Tests build a plugin with another version to exercise the registry's check.
#ifndef HAPSYN_PLUGIN_BUILT_API_VERSION
#define HAPSYN_PLUGIN_BUILT_API_VERSION HAPSYN_PLUGIN_API_VERSION
#endif

namespace hapsyn {

/// Description every plugin exports under the alias "hapsyn_plugin_info". Its layout and the
/// info function's signature are the same in every API version (api_version first), so the
/// registry can read the version of any plugin before it trusts anything else of it.
struct PluginInfo {
  int api_version;
  const char* name;
  const char* kind;  ///< "mechanism", "scene", "metric" or "solver"
  const char* version;
  const char* description;
  const char* schema;         ///< the options schema derived from the declarations (JSON text)
  const char* thread_safety;  ///< to_string(ThreadSafety) of the class's declaration
};

/// The factory every plugin exports under the alias "hapsyn_plugin_create".
/// \param options   the options, validated against PluginInfo::schema, defaults filled
/// \param arguments the plugin's name and JSON path, and the sub-solvers created at load
template <class Kind>
using PluginFactory = std::unique_ptr<Kind>(const Json& options, const PluginArguments& arguments);

namespace detail {

template <class T, class = void>
struct OptionsOf {
  using type = NoOptions;
};
template <class T>
struct OptionsOf<T, std::void_t<typename T::Options>> {
  using type = typename T::Options;
};

template <class T, class = void>
struct ThreadSafetyOf : std::integral_constant<ThreadSafety, ThreadSafety::kConcurrent> {};
template <class T>
struct ThreadSafetyOf<T, std::void_t<decltype(T::thread_safety)>>
    : std::integral_constant<ThreadSafety, T::thread_safety> {};

template <class Kind, class Class>
std::unique_ptr<Kind> create_plugin(const Json& options, const PluginArguments& arguments) {
  using Options = typename OptionsOf<Class>::type;
  if constexpr (std::is_constructible_v<Class, const Options&>) {
    return std::make_unique<Class>(OptionDeclarations<Options>::fill(options, arguments));
  } else {
    static_assert(std::is_same_v<Options, NoOptions>,
                  "a plugin class with an Options type needs a constructor taking const Options&");
    return std::make_unique<Class>();
  }
}

template <class Class>
PluginInfo plugin_info(const char* name, const char* kind, const char* version, const char* description) {
  // A plugin whose options describe nothing (no options at all) is described by its one line.
  static const std::string schema = [description] {
    Json s = options_schema<typename OptionsOf<Class>::type>();
    if (!s.contains("description")) s["description"] = description;
    return s.dump();
  }();
  return PluginInfo{HAPSYN_PLUGIN_BUILT_API_VERSION, name, kind, version, description, schema.c_str(),
                    to_string(ThreadSafetyOf<Class>::value)};
}

}  // namespace detail
}  // namespace hapsyn

#define HAPSYN_DETAIL_PLUGIN(Kind, KindName, Class, Name, Version, Description)                  \
  namespace {                                                                                    \
  hapsyn::PluginInfo hapsyn_plugin_info_impl() {                                                 \
    return hapsyn::detail::plugin_info<Class>(Name, KindName, Version, Description);             \
  }                                                                                              \
  std::unique_ptr<hapsyn::Kind> hapsyn_plugin_create_impl(const hapsyn::Json& options,          \
                                                          const hapsyn::PluginArguments& args) { \
    return hapsyn::detail::create_plugin<hapsyn::Kind, Class>(options, args);                    \
  }                                                                                              \
  }                                                                                              \
  BOOST_DLL_ALIAS(hapsyn_plugin_info_impl, hapsyn_plugin_info)                                   \
  BOOST_DLL_ALIAS(hapsyn_plugin_create_impl, hapsyn_plugin_create)

#define HAPSYN_MECHANISM_PLUGIN(Class, Name, Version, Description) \
  HAPSYN_DETAIL_PLUGIN(Mechanism, "mechanism", Class, Name, Version, Description)
#define HAPSYN_SCENE_PLUGIN(Class, Name, Version, Description) \
  HAPSYN_DETAIL_PLUGIN(Scene, "scene", Class, Name, Version, Description)
#define HAPSYN_METRIC_PLUGIN(Class, Name, Version, Description) \
  HAPSYN_DETAIL_PLUGIN(Metric, "metric", Class, Name, Version, Description)
#define HAPSYN_SOLVER_PLUGIN(Class, Name, Version, Description) \
  HAPSYN_DETAIL_PLUGIN(Solver, "solver", Class, Name, Version, Description)
