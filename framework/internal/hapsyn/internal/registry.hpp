#pragma once
/// \file
/// Finds, loads and checks plugins (Boost.DLL). A plugin is found by name: the file
/// hapsyn-<name>.so in the search path. A name is letters, digits, '_' and '-' only, so it can
/// never make a path that leaves the search-path directories; files hapsyn-*.so whose middle is
/// not such a name are ignored.
///
/// Before a library is handed to dlopen its file is checked cheaply (a truncated library would
/// otherwise be mapped past its end and crash the process with SIGBUS on first touch): it must be
/// a regular file (not a FIFO, device or directory) with an ELF header of this hapsyn's class,
/// byte order and machine, of type ET_DYN, whose program header table, every segment
/// (p_offset + p_filesz) and section header table lie inside the file. Otherwise the error is
/// Error("registry", "<file>: not loaded: <what is wrong>"), e.g. "... segment 2 ends past the
/// end of the file (at byte 81920, the file has 40960 bytes; truncated?)".
#include <hapsyn/json.hpp>
#include <hapsyn/mechanism.hpp>
#include <hapsyn/metric.hpp>
#include <hapsyn/options.hpp>
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
  std::string name, kind, version, description;
  ThreadSafety thread_safety = ThreadSafety::kConcurrent;  ///< as the plugin class declares it
  std::string file;  ///< absolute path of the shared library
  Json schema;       ///< the options schema derived from the plugin's declarations
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
  /// \throws Error "registry: plugin name \"y.so/../x\": not a plugin name (names are letters,
  ///         digits, '_' and '-')"; "registry: unknown plugin 'x' ...; known plugins: a, b, c"; a
  ///         library file that fails the check above ("<file>: not loaded: ..."); a version
  ///         mismatch naming the file and both versions; a library that is not a hapsyn plugin; a
  ///         bad schema.
  const PluginRecord& find(const std::string& name) const;
  /// Every plugin in the search path (loads them all). Files that fail to load, truncated or
  /// damaged libraries included, are reported in `errors` (one message each, naming the file)
  /// instead of throwing; the others are listed.
  std::vector<PluginRecord> list(std::vector<std::string>* errors = nullptr) const;
  /// Names of hapsyn-*.so files in the search path (without loading them), sorted.
  std::vector<std::string> known_names() const;

  /// Validates `options` against the plugin's schema (filling defaults) and returns them.
  /// \param json_path where the options sit in the problem file, for error messages
  Json resolve_options(const std::string& name, const Json& options, const std::string& json_path) const;

  /// Creates a plugin object of the expected kind. The options are validated against the
  /// plugin's declarations once (defaults filled), its declared sub-solvers are created (each
  /// checked the same way, recursively; a Pareto sub-solver is refused), and a plugin that
  /// declares ThreadSafety::kSerialized is wrapped so that its calls never overlap.
  /// \param json_path where the plugin sits in the problem file, e.g. "solver" (its options are
  ///        at "<json_path>.options")
  /// \param resolved_options when not null, receives the validated options with defaults
  /// \throws Error on a kind mismatch ("'gii' is a metric plugin, not a solver plugin"), invalid
  ///         options, or when the plugin's factory throws (its message is kept).
  std::shared_ptr<Mechanism> create_mechanism(const std::string& name, const Json& options,
                                              const std::string& json_path, Json* resolved_options = nullptr) const;
  std::shared_ptr<Scene> create_scene(const std::string& name, const Json& options, const std::string& json_path,
                                      Json* resolved_options = nullptr) const;
  std::shared_ptr<Metric> create_metric(const std::string& name, const Json& options, const std::string& json_path,
                                        Json* resolved_options = nullptr) const;
  std::shared_ptr<Solver> create_solver(const std::string& name, const Json& options, const std::string& json_path,
                                        Json* resolved_options = nullptr) const;

 private:
  struct Loaded;
  const Loaded& load(const std::string& path) const;
  template <class T>
  std::shared_ptr<T> create(const std::string& name, const char* kind, const Json& options,
                            const std::string& json_path, Json* resolved_options) const;
  /// Creates the sub-solvers `schema` declares (properties with "plugin_kind": "solver"),
  /// recursively through option groups, from the resolved options.
  void create_sub_solvers(const Json& schema, const Json& resolved, const std::string& relative,
                          PluginArguments& arguments) const;
  /// Creates one sub-solver from `{"plugin": NAME, "options": {...}}`.
  /// \throws Error(component, "<json_path> = ...") for a malformed value, a plugin that is not a
  ///         solver, or a Pareto solver.
  std::shared_ptr<const Solver> make_sub_solver(const Json& spec, const std::string& component,
                                                const std::string& json_path) const;

  std::vector<std::string> search_path_;
  mutable std::mutex mutex_;
  mutable std::map<std::string, std::unique_ptr<Loaded>> loaded_;  // by file path
};

}  // namespace hapsyn
