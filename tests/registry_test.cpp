#include "test_support.hpp"

#include <hapsyn/plugin.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include <sys/stat.h>
#include <unistd.h>

using hapsyn::Json;
using hapsyn::Registry;
using hapsyn::test::expect_error;

namespace {
const Registry& broken() {
  static Registry r({HAPSYN_TEST_PLUGIN_DIR});
  return r;
}
}  // namespace

TEST(Registry, FindsEveryBuiltInPluginWithItsKind) {
  const auto records = hapsyn::test::registry().list();
  auto kind_of = [&](const std::string& name) {
    auto it = std::find_if(records.begin(), records.end(), [&](const auto& r) { return r.name == name; });
    return it == records.end() ? std::string("missing") : it->kind;
  };
  EXPECT_EQ(kind_of("fivebar"), "mechanism");
  EXPECT_EQ(kind_of("planar_square"), "scene");
  EXPECT_EQ(kind_of("gii"), "metric");
  EXPECT_EQ(kind_of("gdi"), "metric");
  EXPECT_EQ(kind_of("evaluate"), "solver");
  EXPECT_EQ(kind_of("grid"), "solver");
  for (const auto& r : records) {
    EXPECT_FALSE(r.version.empty()) << r.name;
    EXPECT_NE(r.file.find("hapsyn-" + r.name + ".so"), std::string::npos) << r.file;
  }
}

TEST(Registry, UnknownNameListsTheKnownOnes) {
  expect_error([] { hapsyn::test::registry().find("giii"); },
               {"registry: unknown plugin 'giii'", "did you mean 'gii'?", "known plugins:", "fivebar", "gdi", "grid"});
}

TEST(Registry, VersionMismatchNamesTheFileAndBothVersions) {
  expect_error([] { broken().find("badversion"); },
               {"hapsyn-badversion.so", "plugin API version 999", "API version " + std::to_string(HAPSYN_PLUGIN_API_VERSION)});
}

TEST(Registry, SharedLibraryThatIsNotAPluginIsRefused) {
  expect_error([] { broken().find("notaplugin"); }, {"hapsyn-notaplugin.so", "not a hapsyn plugin"});
}

// Issue 53, cause 8: the entry points exported as data once crashed `hapsyn plugins` when called.
TEST(Registry, EntryPointsThatAreNotCodeAreRefusedBeforeTheCall) {
  expect_error([] { broken().find("datasymbols"); },
               {"hapsyn-datasymbols.so: not a hapsyn plugin: hapsyn_plugin_info does not point to a function in "
                "executable code (plugins export their entry points with HAPSYN_*_PLUGIN)"});
}

TEST(Registry, FactoryThatThrowsIsReportedWithItsMessage) {
  expect_error([] { broken().create_metric("throwing", Json::object(), "objectives[0]"); },
               {"plugin 'throwing'", "hapsyn-throwing.so", "deliberate failure in the factory"});
}

TEST(Registry, MalformedPluginSchemaIsRefused) {
  expect_error([] { broken().find("badschema"); }, {"badschema"});
}

TEST(Registry, KindMismatchIsRefused) {
  expect_error([] { hapsyn::test::registry().create_solver("gii", Json::object(), "solver"); },
               {"solver.plugin = \"gii\"", "'gii' is a metric plugin, not a solver plugin"});
}

TEST(Registry, ListReportsBrokenFilesWithoutThrowing) {
  std::vector<std::string> errors;
  const auto records = broken().list(&errors);
  std::vector<std::string> names;
  for (const auto& r : records) names.push_back(r.name);
  EXPECT_NE(std::find(names.begin(), names.end(), "throwing"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "nanmetric"), names.end());
  std::string all;
  for (const auto& e : errors) all += e + "\n";
  EXPECT_NE(all.find("hapsyn-badversion.so"), std::string::npos) << all;
  EXPECT_NE(all.find("hapsyn-notaplugin.so"), std::string::npos) << all;
  EXPECT_NE(all.find("hapsyn-badschema.so"), std::string::npos) << all;
}

TEST(Registry, SearchPathStartsWithTheEnvironmentThenLibraryRelativeDirectory) {
  ::setenv("HAPSYN_PLUGIN_PATH", "/first/dir:/second/dir", 1);
  const auto path = Registry::default_search_path();
  ::unsetenv("HAPSYN_PLUGIN_PATH");
  ASSERT_EQ(path.size(), 3u);
  EXPECT_EQ(path[0], "/first/dir");
  EXPECT_EQ(path[1], "/second/dir");
  EXPECT_NE(path[2].find("hapsyn/plugins"), std::string::npos);
}

TEST(Registry, DefaultSearchPathFindsTheBuildTreePlugins) {
  Registry registry;  // library-relative directory: build tree here, install prefix when installed
  EXPECT_EQ(registry.find("fivebar").kind, "mechanism");
}

TEST(Registry, CreatedObjectsKeepTheirLibraryLoaded) {
  std::shared_ptr<hapsyn::Metric> metric;
  {
    Registry registry({HAPSYN_TEST_PLUGIN_DIR});
    metric = registry.create_metric("nanmetric", Json::object(), "objectives[0]");
  }
  hapsyn::SampleQuantities q;
  double out = 0.0;
  metric->local(q, &out);  // would crash if the library had been unloaded with the registry
  EXPECT_TRUE(std::isnan(out));
}

TEST(Registry, OptionsAreValidatedAndDefaultsFilled) {
  const Json options = hapsyn::test::registry().resolve_options("grid", Json::object(), "solver.options");
  EXPECT_EQ(options.at("prune"), true);
  expect_error([] { hapsyn::test::registry().create_solver("grid", Json{{"prun", false}}, "solver"); },
               {"solver.options.prun", "did you mean 'prune'"});
}

TEST(Registry, PluginsOfThePreviousApisAreRefusedNamingBothVersions) {
  static_assert(HAPSYN_PLUGIN_API_VERSION == 5, "plugins built for the previous APIs must be refused");
  expect_error([] { broken().find("version4"); },
               {"hapsyn-version4.so", "plugin API version 4", "this hapsyn has API version 5", "rebuild the plugin"});
  expect_error([] { broken().find("version3"); },
               {"hapsyn-version3.so", "plugin API version 3", "this hapsyn has API version 5", "rebuild the plugin"});
}

TEST(Registry, BadDeclarationNamesTheOptionAndItsRule) {
  expect_error([] { broken().find("badschema"); }, {"hapsyn-badschema.so", "x", "default", ">= 0"});
}

TEST(Registry, ResolvedOptionsAreHandedBackOnce) {
  Json resolved;
  hapsyn::test::registry().create_solver("grid", Json{{"prune", false}}, "solver", &resolved);
  EXPECT_EQ(resolved.at("prune"), false);
  EXPECT_EQ(resolved, hapsyn::test::registry().resolve_options("grid", Json{{"prune", false}}, "solver.options"));
}

namespace {
// Calls local() from two threads at once, 20 times each; the test metric reports whether two
// calls ever overlapped in time (0) or not (1).
double overlap_probe(const std::shared_ptr<hapsyn::Metric>& metric) {
  double results[2] = {1.0, 1.0};
  auto work = [&](int t) {
    hapsyn::SampleQuantities q;
    for (int i = 0; i < 20; ++i) metric->local(q, &results[t]);
  };
  std::thread a(work, 0), b(work, 1);
  a.join();
  b.join();
  return std::min(results[0], results[1]);
}
}  // namespace

TEST(Registry, SerializedPluginIsNeverCalledConcurrently) {
  EXPECT_EQ(broken().find("serialmetric").thread_safety, hapsyn::ThreadSafety::kSerialized);
  EXPECT_EQ(overlap_probe(broken().create_metric("serialmetric", Json::object(), "objectives[0]")), 1.0);
}

TEST(Registry, ConcurrentPluginIsCalledFromSeveralThreadsAtOnce) {
  // The control: the same probe does see overlapping calls when the plugin allows them.
  EXPECT_EQ(broken().find("overlapmetric").thread_safety, hapsyn::ThreadSafety::kConcurrent);
  EXPECT_EQ(overlap_probe(broken().create_metric("overlapmetric", Json::object(), "objectives[0]")), 0.0);
}

TEST(Registry, DeclaredDefaultsFillTheOptionsStruct) {
  struct Group {
    double g{};
    static void declare(hapsyn::OptionDeclarations<Group>& d) { d.add(&Group::g, "g", 2.5, "a number").unit("m"); }
  };
  struct Options {
    int n{};
    std::vector<std::string> terms;
    Group group;
    static void declare(hapsyn::OptionDeclarations<Options>& d) {
      d.describe("test options");
      d.add(&Options::n, "n", 3, "a count").range(1, 5);
      d.add(&Options::terms, "terms", {"a"}, "choices").one_of({"a", "b"}).min_size(1);
      d.add(&Options::group, "group", "a group");
    }
  };
  const Options defaults = hapsyn::default_options<Options>();
  EXPECT_EQ(defaults.n, 3);
  EXPECT_EQ(defaults.terms, std::vector<std::string>{"a"});
  EXPECT_EQ(defaults.group.g, 2.5);
  const Options given = hapsyn::make_options<Options>(Json{{"n", 5}, {"group", {{"g", -1.0}}}});
  EXPECT_EQ(given.n, 5);
  EXPECT_EQ(given.group.g, -1.0);
  const Json schema = hapsyn::options_schema<Options>();
  EXPECT_EQ(schema["description"], "test options");
  EXPECT_EQ(schema["properties"]["n"]["maximum"], 5);
  EXPECT_EQ(schema["properties"]["terms"]["items"]["enum"], Json({"a", "b"}));
  EXPECT_EQ(schema["properties"]["group"]["properties"]["g"]["unit"], "m");
  expect_error([] { hapsyn::make_options<Options>(Json{{"n", 6}}, "solver.options"); },
               {"problem: solver.options.n = 6", "<= 5"});
  expect_error([] { hapsyn::make_options<Options>(Json{{"terms", {"c"}}}, "solver.options"); },
               {"solver.options.terms[0] = \"c\""});
  expect_error([] { hapsyn::make_options<Options>(Json{{"group", {{"h", 1}}}}, "solver.options"); },
               {"solver.options.group.h", "did you mean 'g'"});
}

TEST(Registry, OptionsRoundTripThroughJson) {
  struct Local {
    int n{};
    std::vector<std::vector<double>> rotation;
    static void declare(hapsyn::OptionDeclarations<Local>& d) {
      d.add(&Local::n, "n", 4, "a count").minimum(2);
      d.add(&Local::rotation, "rotation", {{1, 0}, {0, 1}}, "rows").size(2).row_size(2);
    }
  };
  const Local l = hapsyn::make_options<Local>(Json{{"n", 7}});
  EXPECT_EQ(hapsyn::options_to_json(l), Json({{"n", 7}, {"rotation", {{1.0, 0.0}, {0.0, 1.0}}}}));
  // Whole-number bounds read as integers in messages and schemas.
  EXPECT_EQ(hapsyn::options_schema<Local>()["properties"]["n"]["minimum"].dump(), "2");
  expect_error([] { hapsyn::make_options<Local>(Json{{"n", 1}}); }, {"options.n = 1: must be >= 2"});
  expect_error([] { hapsyn::make_options<Local>(Json{{"rotation", {{1, 0}, {0}}}}); }, {"options.rotation[1]"});
}

// ---- plugin library files and names (issue 20) ----

namespace {

namespace fs = std::filesystem;

// A fresh directory under the test's temporary directory, removed at the end.
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name) : path(fs::temp_directory_path() / ("hapsyn-registry-" + name + "-" + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

// A copy of the built gii plugin, cut to `length` bytes, as `dir`/hapsyn-gii.so.
void truncated_copy(const fs::path& dir, std::uintmax_t length) {
  const fs::path target = dir / "hapsyn-gii.so";
  fs::copy_file(fs::path(HAPSYN_PLUGIN_DIR) / "hapsyn-gii.so", target, fs::copy_options::overwrite_existing);
  fs::resize_file(target, length);
}

}  // namespace

TEST(Registry, TruncatedLibraryIsSkippedWithAWarningNamingTheFile) {
  const std::uintmax_t full = fs::file_size(fs::path(HAPSYN_PLUGIN_DIR) / "hapsyn-gii.so");
  for (const std::uintmax_t length : {std::uintmax_t(0), std::uintmax_t(20), std::uintmax_t(64), full / 2, full - 1}) {
    TempDir dir("truncated");
    truncated_copy(dir.path, length);
    fs::copy_file(fs::path(HAPSYN_PLUGIN_DIR) / "hapsyn-gdi.so", dir.path / "hapsyn-gdi.so");
    const Registry registry({dir.path.string()});
    std::vector<std::string> errors;
    const auto records = registry.list(&errors);  // a SIGBUS here would end the test binary
    ASSERT_EQ(records.size(), 1u) << "length " << length;
    EXPECT_EQ(records[0].name, "gdi");
    ASSERT_EQ(errors.size(), 1u) << "length " << length;
    const std::string& e = errors[0];
    EXPECT_NE(e.find("registry: " + (dir.path / "hapsyn-gii.so").string() + ": not loaded: "), std::string::npos) << e;
    EXPECT_TRUE(e.find("truncated?") != std::string::npos || e.find("not an ELF file") != std::string::npos) << e;
    // A study that names the plugin gets the same error.
    expect_error([&] { registry.find("gii"); }, {"hapsyn-gii.so", "not loaded"});
  }
}

TEST(Registry, TruncatedLibraryMessageSaysWhatEndsPastTheFile) {
  TempDir dir("truncated-message");
  const std::uintmax_t full = fs::file_size(fs::path(HAPSYN_PLUGIN_DIR) / "hapsyn-gii.so");
  truncated_copy(dir.path, full - 1);
  expect_error([&] { Registry({dir.path.string()}).find("gii"); },
               {"hapsyn-gii.so: not loaded: ", "ends past the end of the file", "the file has " + std::to_string(full - 1) +
                                                                                    " bytes; truncated?"});
  truncated_copy(dir.path, 10);
  expect_error([&] { Registry({dir.path.string()}).find("gii"); },
               {"hapsyn-gii.so: not loaded: is 10 bytes, shorter than an ELF header (truncated?)"});
}

TEST(Registry, CliListsTheOtherPluginsBesideATruncatedOne) {
  TempDir dir("cli");
  const std::uintmax_t full = fs::file_size(fs::path(HAPSYN_PLUGIN_DIR) / "hapsyn-gii.so");
  truncated_copy(dir.path, full / 2);
  ::setenv("HAPSYN_PLUGIN_PATH", dir.path.c_str(), 1);  // popen's shell inherits it
  const auto o = hapsyn::test::hapsyn_cli("plugins");
  ::unsetenv("HAPSYN_PLUGIN_PATH");
  EXPECT_EQ(o.code, 0) << o.out;
  EXPECT_NE(o.out.find("hapsyn: warning: registry: " + (dir.path / "hapsyn-gii.so").string() + ": not loaded: "),
            std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("fivebar"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("gdi"), std::string::npos) << o.out;
}

TEST(Registry, NonRegularPluginFilesAreRefusedWithoutBlocking) {
  TempDir dir("fifo");
  ASSERT_EQ(::mkfifo((dir.path / "hapsyn-gii.so").c_str(), 0600), 0);
  fs::create_directories(dir.path / "hapsyn-gdi.so");
  const Registry registry({dir.path.string()});
  expect_error([&] { registry.find("gii"); }, {"hapsyn-gii.so: not loaded: is not a regular file (a FIFO, socket or device)"});
  expect_error([&] { registry.find("gdi"); }, {"hapsyn-gdi.so: not loaded: is a directory, not a shared library"});
}

TEST(Registry, TextFileNamedLikeAPluginIsNotAnElfFile) {
  TempDir dir("text");
  std::ofstream(dir.path / "hapsyn-gii.so") << std::string(200, 'x');
  expect_error([&] { Registry({dir.path.string()}).find("gii"); }, {"hapsyn-gii.so: not loaded: not an ELF file (no ELF magic)"});
}

TEST(Registry, PluginNameThatCouldBeAPathIsRefused) {
  for (const std::string name : {"y.so/../payload", "../hapsyn-gii", "/tmp/x", "gii.so", "a b", ""}) {
    expect_error([&] { hapsyn::test::registry().find(name); },
                 {"registry: plugin name " + Json(name).dump() + ": not a plugin name (names are letters, digits, '_' and '-')"});
  }
  expect_error([] { hapsyn::test::registry().create_scene("../../x", Json::object(), "scene"); },
               {"plugin name \"../../x\"", "names are letters, digits, '_' and '-'"});
  EXPECT_EQ(hapsyn::test::registry().find("motion_feasibility").kind, "metric");  // '_' is a name character
}

TEST(Registry, FilesWhoseNameIsNotAPluginNameAreIgnored) {
  TempDir dir("names");
  fs::copy_file(fs::path(HAPSYN_PLUGIN_DIR) / "hapsyn-gdi.so", dir.path / "hapsyn-gdi.so");
  fs::copy_file(fs::path(HAPSYN_PLUGIN_DIR) / "hapsyn-gii.so", dir.path / "hapsyn-g.ii.so");
  const Registry registry({dir.path.string()});
  EXPECT_EQ(registry.known_names(), std::vector<std::string>{"gdi"});
  std::vector<std::string> errors;
  EXPECT_EQ(registry.list(&errors).size(), 1u);
  EXPECT_TRUE(errors.empty());
}
