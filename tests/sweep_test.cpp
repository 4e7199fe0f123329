#include "test_support.hpp"

#include <hapsyn/sweep.hpp>

#include <boost/filesystem.hpp>

#include <cmath>
#include <fstream>

using hapsyn::Json;
using hapsyn::test::expect_error;
namespace fs = boost::filesystem;

namespace {
fs::path fresh(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("hapsyn-sweep-test-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}
long lines(const fs::path& p) { return hapsyn::test::count_lines(p.string()); }
}  // namespace

TEST(Sweep, AxisSplitsPathsAndValuesOutsideBrackets) {
  const auto axis = hapsyn::parse_sweep_axis("a.b,c.d=0.1,[1,2],{\"x\":3},text");
  ASSERT_EQ(axis.paths.size(), 2u);
  EXPECT_EQ(axis.paths[1], "c.d");
  ASSERT_EQ(axis.values.size(), 4u);
  EXPECT_EQ(axis.values[0], 0.1);
  EXPECT_EQ(axis.values[1], Json::array({1, 2}));
  EXPECT_EQ(axis.values[2]["x"], 3);
  EXPECT_EQ(axis.values[3], "text");
}

TEST(Sweep, MalformedAxesAreRefused) {
  expect_error([] { hapsyn::parse_sweep_axis("no-equals"); }, {"sweep: --vary 'no-equals'", "expected path"});
  expect_error([] { hapsyn::parse_sweep_axis("=1,2"); }, {"expected path"});
  expect_error([] { hapsyn::parse_sweep_axis("a,,b=1"); }, {"empty path"});
  expect_error([] { hapsyn::parse_sweep_axis("a=1,,2"); }, {"empty value"});
}

TEST(Sweep, InvertedGenerationalDistanceOnHandCheckableFronts) {
  const std::vector<std::vector<double>> reference = {{0, 1}, {1, 0}};
  EXPECT_DOUBLE_EQ(hapsyn::inverted_generational_distance(reference, reference), 0.0);
  // One point at (0, 0): distance 1 to each reference point.
  EXPECT_DOUBLE_EQ(hapsyn::inverted_generational_distance({{0, 0}}, reference), 1.0);
  // (0, 1) exact, (1, 0) at distance 0.5 from (1, 0.5).
  EXPECT_DOUBLE_EQ(hapsyn::inverted_generational_distance({{0, 1}, {1, 0.5}}, reference), 0.25);
  EXPECT_TRUE(std::isinf(hapsyn::inverted_generational_distance({}, reference)));
}

TEST(Sweep, MeasuresEachRunAgainstTheReference) {
  Json doc = hapsyn::test::fivebar_study("culling");
  doc["solver"]["options"] = {{"polish", false}};
  const fs::path out = fresh("runs");
  hapsyn::SweepOptions options;
  options.axes.push_back(hapsyn::parse_sweep_axis("design.l0.step,design.l1.step=0.1,0.05"));
  options.axes.push_back(hapsyn::parse_sweep_axis("scene.options.step=0.05,0.025"));
  options.reference = {"design.l0.step=0.025", "design.l1.step=0.025", "scene.options.step=0.025"};
  options.output_directory = out.string();
  options.threads = 2;
  options.seed = 3;
  const Json summary = hapsyn::run_sweep(doc, options, hapsyn::test::registry());
  ASSERT_EQ(summary["runs"].size(), 4u);
  EXPECT_EQ(lines(out / "sweep.csv"), 5);
  EXPECT_TRUE(fs::exists(out / "reference" / "result.json"));
  EXPECT_TRUE(fs::exists(out / "sweep.json"));
  for (const Json& run : summary["runs"]) {
    EXPECT_EQ(run["values"].size(), 3u);  // both linked paths and the scene step
    EXPECT_GE(run["errors"]["objective_error"].get<double>(), 0.0);
    EXPECT_GT(run["evaluations"]["samples"].get<long long>(), 0);
  }
  // A finer design grid can only come closer to the reference optimum from below: the objective
  // of the reference (finest grid) is at least that of every run at the same scene step.
  const double reference_gii = summary["reference"]["best"]["objectives"]["gii"];
  EXPECT_GE(reference_gii + 1e-12, summary["runs"][3]["objectives"]["gii"].get<double>());
  EXPECT_EQ(summary["seed"], 3);
  fs::remove_all(out);
}

TEST(Sweep, AnInvalidRunIsRefusedBeforeAnyRunStarts) {
  const fs::path out = fresh("invalid");
  hapsyn::SweepOptions options;
  options.axes.push_back(hapsyn::parse_sweep_axis("scene.options.step=0.05,0.03"));
  options.output_directory = out.string();
  expect_error([&] { hapsyn::run_sweep(hapsyn::test::fivebar_study(), options, hapsyn::test::registry()); },
               {"sweep: run with {\"scene.options.step\":0.03}", "step"});
  EXPECT_FALSE(fs::exists(out));
}
