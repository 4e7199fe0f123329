#include "test_support.hpp"

#include <hapsyn/plugin.hpp>

#include <algorithm>
#include <cstdlib>

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
