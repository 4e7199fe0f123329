#include <hapsyn/error.hpp>
#include <hapsyn/plugin.hpp>
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/schema.hpp>

#include "serialized_plugins.hpp"

#include <boost/dll/import.hpp>
#include <boost/dll/runtime_symbol_info.hpp>
#include <boost/dll/shared_library.hpp>
#include <boost/filesystem.hpp>

#include <dlfcn.h>
#include <elf.h>
#include <fcntl.h>
#include <link.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <set>
#include <sstream>

namespace hapsyn {

namespace fs = boost::filesystem;

namespace {
constexpr const char* kPrefix = "hapsyn-";
constexpr const char* kSuffix = ".so";

// Plugin names are file-name fragments: nothing that could make a path ('/', "..", '.so').
bool is_plugin_name(const std::string& name) {
  return !name.empty() && name.size() <= 128 && std::all_of(name.begin(), name.end(), [](char c) {
           return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
         });
}

std::string plugin_name_of(const std::string& file) {
  return file.substr(7, file.size() - 10);
}

// hapsyn-<name>.so with a valid name: other files in a plugin directory are not plugins.
bool is_plugin_file_name(const std::string& file) {
  return file.size() > std::string(kPrefix).size() + std::string(kSuffix).size() &&
         file.compare(0, 7, kPrefix) == 0 && file.compare(file.size() - 3, 3, kSuffix) == 0 &&
         is_plugin_name(plugin_name_of(file));
}

std::string join(const std::vector<std::string>& items, const std::string& separator) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? separator : "") + items[i];
  return out;
}

// ---- plugin library files, checked before dlopen ----
// dlopen maps a library's segments as its program headers describe them; a truncated file maps
// past its end and the first touch of those pages is a SIGBUS, not an error dlopen could report.
// So the headers are read with plain reads first and every range they name must lie in the file.

struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

// Reads exactly `size` bytes at `offset`; false on a short read.
bool read_at(int fd, void* out, std::size_t size, std::uint64_t offset) {
  auto* bytes = static_cast<char*>(out);
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::pread(fd, bytes + done, size - done, static_cast<off_t>(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

// The ELF header of the running libhapsyn: the class, byte order and machine a plugin must match.
const ElfW(Ehdr)& own_elf_header() {
  static const ElfW(Ehdr) header = [] {
    ElfW(Ehdr) h{};
    Fd self;
    self.fd = ::open(boost::dll::this_line_location().string().c_str(), O_RDONLY | O_CLOEXEC);
    if (self.fd < 0 || !read_at(self.fd, &h, sizeof h, 0)) std::memset(&h, 0, sizeof h);
    return h;
  }();
  return header;
}

// "end of <what> at byte <end> > file size <size>" when [offset, offset + length) leaves the file.
std::string range_problem(std::uint64_t offset, std::uint64_t length, std::uint64_t size, const std::string& what) {
  if (offset <= size && length <= size - offset) return "";
  return what + " ends past the end of the file (at byte " +
         (offset > UINT64_MAX - length ? std::string("> 2^64") : std::to_string(offset + length)) + ", the file has " +
         std::to_string(size) + " bytes; truncated?)";
}

std::string header_problem(const ElfW(Ehdr)& h, std::uint64_t size) {
  if (std::memcmp(h.e_ident, ELFMAG, SELFMAG) != 0) return "not an ELF file (no ELF magic)";
  const ElfW(Ehdr)& own = own_elf_header();
  if (own.e_ident[EI_CLASS] != 0 && h.e_ident[EI_CLASS] != own.e_ident[EI_CLASS]) {
    return h.e_ident[EI_CLASS] == ELFCLASS32 ? "a 32-bit ELF file, this hapsyn is 64-bit" : "an ELF file of another class";
  }
  if (own.e_ident[EI_DATA] != 0 && h.e_ident[EI_DATA] != own.e_ident[EI_DATA]) return "an ELF file of the other byte order";
  if (own.e_machine != 0 && h.e_machine != own.e_machine) {
    return "an ELF file for another machine (e_machine " + std::to_string(h.e_machine) + ", this hapsyn: " +
           std::to_string(own.e_machine) + ")";
  }
  if (h.e_type != ET_DYN) return "not a shared library (ELF type " + std::to_string(h.e_type) + ")";
  if (h.e_phnum > 0 && h.e_phentsize != sizeof(ElfW(Phdr))) return "malformed ELF header (program header entry size)";
  std::string why = range_problem(h.e_phoff, std::uint64_t(h.e_phnum) * h.e_phentsize, size, "the program header table");
  if (why.empty() && h.e_shoff != 0) {
    why = range_problem(h.e_shoff, std::uint64_t(h.e_shnum) * h.e_shentsize, size, "the section header table");
  }
  return why;
}

// Why the file at `path` must not be handed to dlopen, or "" when its headers fit the file.
std::string library_file_problem(const std::string& path) {
  Fd file;
  file.fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);  // a FIFO must not block
  if (file.fd < 0) return std::string("cannot be opened: ") + std::strerror(errno);
  struct stat st {};
  if (::fstat(file.fd, &st) != 0) return std::string("cannot be examined: ") + std::strerror(errno);
  if (!S_ISREG(st.st_mode)) {
    return S_ISDIR(st.st_mode) ? "is a directory, not a shared library" : "is not a regular file (a FIFO, socket or device)";
  }
  const auto size = static_cast<std::uint64_t>(st.st_size);
  ElfW(Ehdr) h{};
  if (size < sizeof h || !read_at(file.fd, &h, sizeof h, 0)) {
    return "is " + std::to_string(size) + " bytes, shorter than an ELF header (truncated?)";
  }
  if (std::string why = header_problem(h, size); !why.empty()) return why;
  for (int i = 0; i < h.e_phnum; ++i) {
    ElfW(Phdr) ph{};
    if (!read_at(file.fd, &ph, sizeof ph, h.e_phoff + std::uint64_t(i) * sizeof ph)) return "program header unreadable";
    std::string why = range_problem(ph.p_offset, ph.p_filesz, size, "segment " + std::to_string(i));
    if (!why.empty()) return why;
  }
  return "";
}

// True when `address` lies in a loaded segment mapped executable (PF_X): a symbol exported as
// data would be called as a function otherwise, a jump into non-executable memory.
bool in_executable_segment(const void* address) {
  struct Search {
    std::uintptr_t address;
    bool executable = false;
  } search{reinterpret_cast<std::uintptr_t>(address)};
  dl_iterate_phdr(
      [](dl_phdr_info* info, std::size_t, void* data) {
        auto* s = static_cast<Search*>(data);
        for (int i = 0; i < info->dlpi_phnum; ++i) {
          const ElfW(Phdr)& ph = info->dlpi_phdr[i];
          if (ph.p_type != PT_LOAD) continue;
          const std::uintptr_t begin = info->dlpi_addr + ph.p_vaddr;
          if (s->address >= begin && s->address < begin + ph.p_memsz) {
            s->executable = (ph.p_flags & PF_X) != 0;
            return 1;
          }
        }
        return 0;
      },
      &search);
  return search.executable;
}

// The entry points are Boost.DLL aliases: data symbols holding a pointer to the function, read
// and called by get_alias. True when `symbol` is such a pointer (an object symbol at least a
// pointer wide) whose value lies in executable code; a symbol of any other shape, called, would
// jump to wherever its bytes point.
bool points_to_code(const void* symbol) {
  Dl_info info{};
  void* found = nullptr;  // the symbol's ElfW(Sym) entry
  if (dladdr1(symbol, &info, &found, RTLD_DL_SYMENT) == 0 || found == nullptr) return false;
  const auto* entry = static_cast<const ElfW(Sym)*>(found);
  if (info.dli_saddr != symbol || entry->st_size < sizeof(void*)) return false;
  const void* target = nullptr;
  std::memcpy(&target, symbol, sizeof target);
  return in_executable_segment(target);
}

void check_plugin_name(const std::string& name) {
  if (is_plugin_name(name)) return;
  throw Error("registry", "plugin name " + Json(name).dump(-1, ' ', false, Json::error_handler_t::replace) +
                              ": not a plugin name (names are letters, digits, '_' and '-')");
}
}  // namespace

struct Registry::Loaded {
  boost::dll::shared_library library;
  PluginRecord record;
};

std::vector<std::string> Registry::default_search_path() {
  std::vector<std::string> path;
  if (const char* env = std::getenv("HAPSYN_PLUGIN_PATH")) {
    std::stringstream ss(env);
    std::string dir;
    while (std::getline(ss, dir, ':')) {
      if (!dir.empty()) path.push_back(dir);
    }
  }
  // Plugins live in <libdir>/hapsyn/plugins next to libhapsyn, in the build tree and in the
  // install prefix alike, so locating this library locates them.
  const fs::path self = boost::dll::this_line_location();
  path.push_back((self.parent_path() / "hapsyn" / "plugins").string());
  return path;
}

Registry::Registry(std::vector<std::string> search_path) : search_path_(std::move(search_path)) {}
Registry::~Registry() = default;

std::vector<std::string> Registry::known_names() const {
  std::set<std::string> names;
  for (const std::string& dir : search_path_) {
    boost::system::error_code ec;
    if (!fs::is_directory(dir, ec)) continue;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string file = it->path().filename().string();
      if (is_plugin_file_name(file)) names.insert(plugin_name_of(file));
    }
  }
  return {names.begin(), names.end()};
}

const Registry::Loaded& Registry::load(const std::string& path_in) const {
  boost::system::error_code ec;
  const std::string path = fs::weakly_canonical(path_in, ec).string();
  std::lock_guard<std::mutex> lock(mutex_);
  auto found = loaded_.find(path);
  if (found != loaded_.end()) return *found->second;

  if (const std::string why = library_file_problem(path); !why.empty()) {
    throw Error("registry", path + ": not loaded: " + why);
  }
  auto loaded = std::make_unique<Loaded>();
  try {
    loaded->library.load(path, boost::dll::load_mode::rtld_lazy | boost::dll::load_mode::rtld_local);
  } catch (const std::exception& e) {
    throw Error("registry", path + ": cannot load the shared library: " + e.what());
  }
  if (!loaded->library.has("hapsyn_plugin_info") || !loaded->library.has("hapsyn_plugin_create")) {
    throw Error("registry", path +
                                ": not a hapsyn plugin (the symbols hapsyn_plugin_info and hapsyn_plugin_create "
                                "are missing; register the class with HAPSYN_*_PLUGIN and build it with "
                                "hapsyn_add_plugin)");
  }
  for (const char* symbol : {"hapsyn_plugin_info", "hapsyn_plugin_create"}) {
    if (!points_to_code(&loaded->library.get<const char>(symbol))) {
      throw Error("registry", path + ": not a hapsyn plugin: " + symbol +
                                  " does not point to a function in executable code (plugins export their entry "
                                  "points with HAPSYN_*_PLUGIN)");
    }
  }
  // The info function's signature is the same for every API version: that makes the version
  // check itself safe before anything else of the plugin is trusted.
  const auto& info_fn = loaded->library.get_alias<PluginInfo()>("hapsyn_plugin_info");
  const PluginInfo info = info_fn();
  if (info.api_version != HAPSYN_PLUGIN_API_VERSION) {
    throw Error("registry", path + ": plugin '" + (info.name ? info.name : "?") + "' was built for plugin API version " +
                                std::to_string(info.api_version) + ", this hapsyn has API version " +
                                std::to_string(HAPSYN_PLUGIN_API_VERSION) + "; rebuild the plugin against this hapsyn");
  }
  PluginRecord& r = loaded->record;
  r.name = info.name ? info.name : "";
  r.kind = info.kind ? info.kind : "";
  r.version = info.version ? info.version : "";
  r.description = info.description ? info.description : "";
  r.file = path;
  const std::string safety = info.thread_safety ? info.thread_safety : "";
  if (safety == to_string(ThreadSafety::kConcurrent)) {
    r.thread_safety = ThreadSafety::kConcurrent;
  } else if (safety == to_string(ThreadSafety::kSerialized)) {
    r.thread_safety = ThreadSafety::kSerialized;
  } else {
    throw Error("registry", path + ": plugin '" + r.name + "' declares thread safety '" + safety +
                                "' (known: concurrent, serialized)");
  }
  static const std::set<std::string> kinds = {"mechanism", "scene", "metric", "solver"};
  if (!kinds.count(r.kind)) {
    throw Error("registry", path + ": plugin '" + r.name + "' has unknown kind '" + r.kind +
                                "' (known: mechanism, scene, metric, solver)");
  }
  const std::string file = fs::path(path).filename().string();
  if (is_plugin_file_name(file) && plugin_name_of(file) != r.name) {
    throw Error("registry", path + ": the file is named for plugin '" + plugin_name_of(file) +
                                "' but the plugin registers itself as '" + r.name + "'");
  }
  try {
    r.schema = Json::parse(info.schema ? info.schema : "");
  } catch (const Json::parse_error& e) {
    throw Error("registry", path + ": plugin '" + r.name + "' exports a malformed options schema: " + e.what());
  }
  try {
    check_schema(r.schema, "plugin '" + r.name + "' options");
  } catch (const Error& e) {
    throw Error("registry", path + ": " + e.what());
  }
  auto& slot = loaded_[path];
  slot = std::move(loaded);
  return *slot;
}

const PluginRecord& Registry::find(const std::string& name) const {
  check_plugin_name(name);
  for (const std::string& dir : search_path_) {
    const fs::path candidate = fs::path(dir) / (kPrefix + name + kSuffix);
    boost::system::error_code ec;
    if (fs::exists(candidate, ec)) return load(candidate.string()).record;
  }
  const std::vector<std::string> known = known_names();
  std::string message = "unknown plugin '" + name + "'";
  const std::string near = nearest_name(name, known);
  if (!near.empty()) message += " (did you mean '" + near + "'?)";
  message += known.empty() ? "; no plugins found in " + join(search_path_, ":") : "; known plugins: " + join(known, ", ");
  throw Error("registry", message);
}

std::vector<PluginRecord> Registry::list(std::vector<std::string>* errors) const {
  std::vector<PluginRecord> out;
  std::set<std::string> seen;
  for (const std::string& dir : search_path_) {
    boost::system::error_code ec;
    if (!fs::is_directory(dir, ec)) continue;
    std::vector<std::string> files;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
      if (is_plugin_file_name(it->path().filename().string())) files.push_back(it->path().string());
    }
    std::sort(files.begin(), files.end());
    for (const std::string& f : files) {
      const std::string name = plugin_name_of(fs::path(f).filename().string());
      if (seen.count(name)) continue;  // shadowed by an earlier directory
      try {
        out.push_back(load(f).record);
        seen.insert(name);
      } catch (const Error& e) {
        if (errors) errors->push_back(e.what());
      }
    }
  }
  std::sort(out.begin(), out.end(), [](const PluginRecord& a, const PluginRecord& b) {
    return a.kind != b.kind ? a.kind < b.kind : a.name < b.name;
  });
  return out;
}

Json Registry::resolve_options(const std::string& name, const Json& options, const std::string& json_path) const {
  const PluginRecord& r = find(name);
  return validate_and_fill(r.schema, options.is_null() ? Json::object() : options, json_path);
}

void Registry::create_sub_solvers(const Json& schema, const Json& resolved, const std::string& relative,
                                  PluginArguments& arguments) const {
  const auto properties = schema.find("properties");
  if (properties == schema.end()) return;
  for (auto it = properties->begin(); it != properties->end(); ++it) {
    const std::string path = relative.empty() ? it.key() : relative + "." + it.key();
    const auto found = resolved.find(it.key());
    if (found == resolved.end()) continue;  // an optional option left out (no default)
    const Json& value = *found;
    if (it->value("plugin_kind", "") == "solver") {
      arguments.sub_solvers[path] = make_sub_solver(value, arguments.plugin, arguments.json_path + "." + path);
    } else if (it->value("type", "") == "object") {
      create_sub_solvers(*it, value, path, arguments);
    }
  }
}

std::shared_ptr<const Solver> Registry::make_sub_solver(const Json& spec, const std::string& component,
                                                        const std::string& json_path) const {
  if (!spec.is_object() || !spec.contains("plugin") || !spec["plugin"].is_string()) {
    throw Error(component, json_path + " = " + render_value(spec) + ": must be {\"plugin\": NAME, \"options\": {...}}");
  }
  const std::string name = spec["plugin"];
  const PluginRecord& record = find(name);
  if (record.kind != "solver") {
    throw Error(component, json_path + ".plugin = \"" + name + "\": '" + name + "' is a " + record.kind +
                               " plugin, not a solver plugin");
  }
  const Json options = spec.contains("options") ? spec["options"] : Json::object();
  std::shared_ptr<Solver> solver = create_solver(name, options, json_path);
  if (solver->specs().pareto) {
    throw Error(component, json_path + ".plugin = \"" + name +
                               "\": a Pareto solver; the sub-solver must be single-objective (it returns one best design)");
  }
  return solver;
}

template <class T>
std::shared_ptr<T> Registry::create(const std::string& name, const char* kind, const Json& options,
                                    const std::string& json_path, Json* resolved_options) const {
  const PluginRecord& record = find(name);
  if (record.kind != kind) {
    throw Error("problem", json_path + ".plugin = \"" + name + "\": '" + name + "' is a " + record.kind +
                               " plugin, not a " + kind + " plugin");
  }
  PluginArguments arguments;
  arguments.plugin = name;
  arguments.json_path = json_path + ".options";
  const Json resolved = validate_and_fill(record.schema, options.is_null() ? Json::object() : options, arguments.json_path);
  create_sub_solvers(record.schema, resolved, "", arguments);
  const Loaded* loaded = nullptr;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    loaded = loaded_.at(record.file).get();
  }
  const auto& factory = loaded->library.get_alias<PluginFactory<T>>("hapsyn_plugin_create");
  std::unique_ptr<T> object;
  try {
    object = factory(resolved, arguments);
  } catch (const Error& e) {
    throw Error("problem", arguments.json_path + ": " + e.what());
  } catch (const std::exception& e) {
    throw Error("registry", "plugin '" + name + "' (" + record.file + ") failed to create its " + kind + ": " + e.what());
  } catch (...) {
    throw Error("registry", "plugin '" + name + "' (" + record.file + ") failed to create its " + kind +
                                ": unknown exception");
  }
  if (!object) {
    throw Error("registry", "plugin '" + name + "' (" + record.file + ") returned no " + kind);
  }
  if (resolved_options) *resolved_options = resolved;
  // The deleter holds its own reference to the library, so an object never outlives its code.
  boost::dll::shared_library library = loaded->library;
  std::shared_ptr<T> shared(object.release(), [library](T* p) { delete p; });
  if (record.thread_safety == ThreadSafety::kSerialized) return serialized(std::move(shared));
  return shared;
}

std::shared_ptr<Mechanism> Registry::create_mechanism(const std::string& name, const Json& options,
                                                      const std::string& json_path, Json* resolved_options) const {
  return create<Mechanism>(name, "mechanism", options, json_path, resolved_options);
}
std::shared_ptr<Scene> Registry::create_scene(const std::string& name, const Json& options,
                                              const std::string& json_path, Json* resolved_options) const {
  return create<Scene>(name, "scene", options, json_path, resolved_options);
}
std::shared_ptr<Metric> Registry::create_metric(const std::string& name, const Json& options,
                                                const std::string& json_path, Json* resolved_options) const {
  return create<Metric>(name, "metric", options, json_path, resolved_options);
}
std::shared_ptr<Solver> Registry::create_solver(const std::string& name, const Json& options,
                                                const std::string& json_path, Json* resolved_options) const {
  return create<Solver>(name, "solver", options, json_path, resolved_options);
}

}  // namespace hapsyn
