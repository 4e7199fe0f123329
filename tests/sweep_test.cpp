#include "test_support.hpp"

#include <hapsyn/sweep.hpp>

#include <boost/filesystem.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <thread>

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
  options.axes.push_back(hapsyn::parse_sweep_axis("design.l0.step,design.l1.step=0.05,0.025"));
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

// ---- stopping and continuing ----

namespace {
hapsyn::SweepOptions small_sweep(const fs::path& out) {
  hapsyn::SweepOptions options;
  // Steps that divide both ranges ([0, 0.3] and [0.05, 0.3]) would be 0.05 and 0.025 only: vary l0 alone.
  options.axes.push_back(hapsyn::parse_sweep_axis("design.l0.step=0.1,0.05,0.025"));
  options.output_directory = out.string();
  options.threads = 2;
  options.seed = 3;
  return options;
}
Json culling_study() {
  Json doc = hapsyn::test::fivebar_study("culling");
  doc["solver"]["options"] = {{"polish", false}};
  return doc;
}
Json read_json(const fs::path& file) {
  std::ifstream in(file.string());
  return Json::parse(in);
}
}  // namespace

TEST(Sweep, StopBeforeARunWritesTheTablesWithStatusStopped) {
  const fs::path out = fresh("stop-before");
  hapsyn::SweepOptions options = small_sweep(out);
  const std::atomic<bool> stop{true};
  options.stop = &stop;
  const Json summary = hapsyn::run_sweep(culling_study(), options, hapsyn::test::registry());
  EXPECT_EQ(summary["status"], "stopped");
  EXPECT_EQ(summary["runs"].size(), 0u);
  EXPECT_EQ(summary["message"], "stopped on request at run-0 (not started) after 0 of 3 runs; run the same command again "
                                "to continue (finished runs are reused, a stopped one resumes from its checkpoint)");
  EXPECT_TRUE(summary["reference"]["run_time_s"].is_null());
  const Json written = read_json(out / "sweep.json");
  EXPECT_EQ(written["status"], "stopped");
  EXPECT_EQ(lines(out / "sweep.csv"), 1);  // the header
  EXPECT_FALSE(fs::exists(out / "run-0"));
  fs::remove_all(out);
}

TEST(Sweep, StopDuringARunThenTheSameSweepContinuesToTheUninterruptedResult) {
  const fs::path whole = fresh("uninterrupted"), out = fresh("stop-during");
  const Json uninterrupted = hapsyn::run_sweep(culling_study(), small_sweep(whole), hapsyn::test::registry());
  ASSERT_EQ(uninterrupted["status"], "finished");
  // The stop request comes as soon as the first run has finished (a signal during the second).
  std::atomic<bool> stop{false};
  std::atomic<bool> done{false};
  std::thread requester([&] {
    while (!done && !fs::exists(out / "run-0" / "result.json")) std::this_thread::sleep_for(std::chrono::microseconds(100));
    stop = true;
  });
  hapsyn::SweepOptions options = small_sweep(out);
  options.stop = &stop;
  const Json stopped = hapsyn::run_sweep(culling_study(), options, hapsyn::test::registry());
  done = true;
  requester.join();
  ASSERT_EQ(stopped["status"], "stopped") << stopped.dump(1);
  const std::size_t finished = stopped["runs"].size();
  EXPECT_GE(finished, 1u);
  EXPECT_LT(finished, 3u);
  EXPECT_EQ(read_json(out / "sweep.json")["runs"].size(), finished);
  EXPECT_EQ(lines(out / "sweep.csv"), static_cast<long>(finished) + 1);
  // The same sweep again: the finished runs are reused, the others run; the result is the
  // uninterrupted one.
  const Json continued = hapsyn::run_sweep(culling_study(), small_sweep(out), hapsyn::test::registry());
  ASSERT_EQ(continued["status"], "finished");
  ASSERT_EQ(continued["runs"].size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(continued["runs"][i]["reused"].get<bool>(), i < finished) << i;
    EXPECT_EQ(continued["runs"][i]["objectives"], uninterrupted["runs"][i]["objectives"]) << i;
    // (culling's sample count may differ by a few at two threads: its early exits race)
    EXPECT_EQ(continued["runs"][i]["evaluations"]["designs"], uninterrupted["runs"][i]["evaluations"]["designs"]) << i;
    EXPECT_EQ(continued["runs"][i]["errors"]["objective_error"], uninterrupted["runs"][i]["errors"]["objective_error"]) << i;
  }
  EXPECT_FALSE(continued.contains("message"));
  fs::remove_all(whole);
  fs::remove_all(out);
}

TEST(Sweep, FinishedRunsAreReusedAndForeignResultsRefusedNamingTheFolder) {
  const fs::path out = fresh("reuse");
  hapsyn::SweepOptions options = small_sweep(out);
  options.axes[0] = hapsyn::parse_sweep_axis("design.l0.step,design.l1.step=0.05,0.025");
  const Json first = hapsyn::run_sweep(culling_study(), options, hapsyn::test::registry());
  const Json again = hapsyn::run_sweep(culling_study(), options, hapsyn::test::registry());
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_FALSE(first["runs"][i]["reused"].get<bool>());
    EXPECT_TRUE(again["runs"][i]["reused"].get<bool>());
    EXPECT_EQ(again["runs"][i]["run_time_s"], first["runs"][i]["run_time_s"]);  // the stored time
    EXPECT_EQ(again["runs"][i]["objectives"], first["runs"][i]["objectives"]);
  }
  const std::string run0 = (out / "run-0").string();
  // Another problem in the same folders.
  Json other = culling_study();
  other["solver"]["options"]["polish"] = true;
  expect_error([&] { hapsyn::run_sweep(other, options, hapsyn::test::registry()); },
               {"sweep: " + run0 + " holds a result of another problem (first difference at /solver/options/polish: "
                                   "false there, true in this sweep); delete it, or choose another --out"});
  // Another seed.
  hapsyn::SweepOptions reseeded = options;
  reseeded.seed = 4;
  expect_error([&] { hapsyn::run_sweep(culling_study(), reseeded, hapsyn::test::registry()); },
               {"sweep: " + run0 + " holds a result run with seed 3, this sweep has seed 4; delete it, or choose another --out"});
  // force runs everything again.
  hapsyn::SweepOptions forced = options;
  forced.force = true;
  const Json rerun = hapsyn::run_sweep(other, forced, hapsyn::test::registry());
  EXPECT_FALSE(rerun["runs"][0]["reused"].get<bool>());
  // A damaged or foreign result.json.
  std::ofstream((out / "run-0" / "result.json").string()) << "{\"problem\": ";
  expect_error([&] { hapsyn::run_sweep(other, options, hapsyn::test::registry()); },
               {"sweep: " + run0 + "/result.json: not a readable result (", "); delete it, or choose another --out"});
  std::ofstream((out / "run-0" / "result.json").string()) << "{\"front\": []}";
  expect_error([&] { hapsyn::run_sweep(other, options, hapsyn::test::registry()); },
               {"sweep: " + run0 + "/result.json: not a hapsyn result (no \"problem\" or \"status\"); delete it"});
  fs::remove_all(out);
}

TEST(Sweep, ARunThatFailsIsReportedWithItsFolderAndValues) {
  const fs::path out = fresh("run-error");
  fs::create_directories(out);
  std::ofstream((out / "run-0").string()) << "a file where the run's folder goes";
  hapsyn::SweepOptions options = small_sweep(out);
  expect_error([&] { hapsyn::run_sweep(culling_study(), options, hapsyn::test::registry()); },
               {"sweep: " + (out / "run-0").string() + " ({\"design.l0.step\":0.1}): output: ",
                "is not a directory"});
  fs::remove_all(out);
}
