#pragma once
/// \file
/// Finds, loads and checks plugins (Boost.DLL). A plugin is found by name: the file
/// hapsyn-<name>.so in the search path.
#include <hapsyn/json.hpp>
#include <hapsyn/mechanism.hpp>
#include <hapsyn/metric.hpp>
#include <hapsyn/scene.hpp>
#include <hapsyn/solver.hpp>

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace hapsyn {

/// What the registry knows of a loaded plugin.
struct PluginRecord {
  std::string name, kind, version, description, thread_safety;
  std::string file;  ///< absolute path of the shared library
  Json schema;       ///< parsed schema.json
};

class Registry {
 public:
  /// Directories searched in order: each entry of HAPSYN_PLUGIN_PATH (':'-separated), then
  /// <directory of libhapsyn>/hapsyn/plugins (the build tree and the install prefix alike).
  static std::vector<std::string> default_search_path();

  /// \param search_path directories to search, in order (first match of a name wins)
  explicit Registry(std::vector<std::string> search_path = default_search_path());
  ~Registry();
  Registry(const Registry&) = delete;
  Registry& operator=(const Registry&) = delete;

  const std::vector<std::string>& search_path() const { return search_path_; }

  /// Loads and checks the plugin called `name`.
  /// \throws Error "registry: unknown plugin 'x' (known: a, b, c)"; a version mismatch naming
  ///         the file and both versions; a library that is not a hapsyn plugin; a bad schema.
  const PluginRecord& find(const std::string& name) const;
  /// Loads a plugin from an explicit file (same checks as find).
  const PluginRecord& load_file(const std::string& path) const;
  /// Every plugin in the search path (loads them all). Files that fail to load are reported
  /// in `errors` (one message each) instead of throwing.
  std::vector<PluginRecord> list(std::vector<std::string>* errors = nullptr) const;
  /// Names of hapsyn-*.so files in the search path (without loading them), sorted.
  std::vector<std::string> known_names() const;

  /// Validates `options` against the plugin's schema (filling defaults) and returns them.
  /// \param json_path where the options sit in the problem file, for error messages
  Json resolve_options(const std::string& name, const Json& options, const std::string& json_path) const;

  /// Creates a plugin object of the expected kind. Options are resolved first.
  /// \throws Error on a kind mismatch ("'gii' is a metric, not a solver"), invalid options, or
  ///         when the plugin's factory throws (its message is kept).
  std::shared_ptr<Mechanism> create_mechanism(const std::string& name, const Json& options,
                                              const std::string& json_path) const;
  std::shared_ptr<Scene> create_scene(const std::string& name, const Json& options,
                                      const std::string& json_path) const;
  std::shared_ptr<Metric> create_metric(const std::string& name, const Json& options,
                                        const std::string& json_path) const;
  std::shared_ptr<Solver> create_solver(const std::string& name, const Json& options,
                                        const std::string& json_path) const;

 private:
  struct Loaded;
  const Loaded& load(const std::string& path) const;
  template <class T>
  std::shared_ptr<T> create(const std::string& name, const char* kind, const Json& options,
                            const std::string& json_path) const;

  std::vector<std::string> search_path_;
  mutable std::mutex mutex_;
  mutable std::map<std::string, std::unique_ptr<Loaded>> loaded_;  // by file path
};

}  // namespace hapsyn
