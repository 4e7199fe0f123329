#include "test_support.hpp"

#include <hapsyn/cluster.hpp>
#include <hapsyn/internal/sweep.hpp>

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

// ---- several processes: a cluster, shards and their merge ----

namespace {
// Three runs and a separate reference: four cases, shares of 1, 1 and 2 under --shard i/3.
hapsyn::SweepOptions sharded_sweep(const fs::path& out) {
  hapsyn::SweepOptions options = small_sweep(out);
  options.reference = {"design.l0.step=0.025", "design.l1.step=0.025"};
  options.threads = 1;
  return options;
}
// What must not depend on how the runs were shared out: everything but times and "reused".
void expect_same_rows(const Json& a, const Json& b) {
  ASSERT_EQ(a["runs"].size(), b["runs"].size());
  for (std::size_t i = 0; i < a["runs"].size(); ++i) {
    for (const char* key : {"values", "objectives", "errors", "status", "evaluations", "case"}) {
      EXPECT_EQ(a["runs"][i][key], b["runs"][i][key]) << "run " << i << " " << key;
    }
  }
  EXPECT_EQ(a["reference"]["best"], b["reference"]["best"]);
  EXPECT_EQ(a["reference"]["overrides"], b["reference"]["overrides"]);
  EXPECT_EQ(a["seed"], b["seed"]);
  EXPECT_EQ(a["status"], b["status"]);
}
void write_json(const fs::path& file, const Json& doc) {
  fs::create_directories(file.parent_path());
  std::ofstream(file.string()) << doc.dump(2);
}
}  // namespace

TEST(Sweep, ALocalClusterRunGivesTheSummaryOfAPlainRunAndRecordsHowToRunItAgain) {
  const fs::path plain = fresh("plain"), local = fresh("local");
  const Json expected = hapsyn::run_sweep(culling_study(), sharded_sweep(plain), hapsyn::test::registry());
  hapsyn::SweepOptions options = sharded_sweep(local);
  options.cluster = &hapsyn::Cluster::local();
  const Json summary = hapsyn::run_sweep(culling_study(), options, hapsyn::test::registry());
  expect_same_rows(summary, expected);
  EXPECT_EQ(summary["status"], "finished");
  EXPECT_FALSE(summary.contains("shard"));
  EXPECT_FALSE(summary.contains("message"));
  ASSERT_EQ(summary["runs"].size(), 3u);
  EXPECT_EQ(summary["runs"][2]["case"], "run-2");
  EXPECT_FALSE(summary["runs"][0]["errors"]["objective_error"].is_null());
  EXPECT_TRUE(fs::exists(local / "reference" / "result.json"));
  // sweep.json holds what a merge needs to run the sweep again.
  const Json written = read_json(local / "sweep.json");
  EXPECT_EQ(written["problem"], culling_study());
  EXPECT_EQ(written["options"]["axes"], Json::parse(R"([{"paths": ["design.l0.step"], "values": [0.1, 0.05, 0.025]}])"));
  EXPECT_EQ(written["options"]["reference"], Json::parse(R"(["design.l0.step=0.025", "design.l1.step=0.025"])"));
  EXPECT_EQ(written["options"]["seed"], 3);
  EXPECT_EQ(written["problem_directory"], "");
  fs::remove_all(plain);
  fs::remove_all(local);
}

TEST(Sweep, ShardsMergedGiveTheSummaryOfASingleRun) {
  const fs::path whole = fresh("whole"), merged = fresh("merged");
  const Json expected = hapsyn::run_sweep(culling_study(), sharded_sweep(whole), hapsyn::test::registry());
  ASSERT_EQ(expected["runs"].size(), 3u);
  std::vector<std::string> shards;
  const std::vector<std::vector<std::string>> shares = {{"run-0"}, {"run-1"}, {"run-2", "reference"}};
  for (int i = 0; i < 3; ++i) {
    const fs::path out = fresh("shard" + std::to_string(i + 1));
    hapsyn::ShardCluster cluster(i, 3);
    hapsyn::SweepOptions options = sharded_sweep(out);
    options.cluster = &cluster;
    const Json summary = hapsyn::run_sweep(culling_study(), options, hapsyn::test::registry());
    EXPECT_EQ(summary["status"], "finished") << i;
    EXPECT_EQ(summary["message"], cluster.shard_message()) << i;
    EXPECT_EQ(summary["shard"], Json({{"index", i + 1}, {"count", 3}, {"cases", shares[static_cast<std::size_t>(i)]}})) << i;
    // Only this share ran: one run each (the last share's reference is not a row).
    ASSERT_EQ(summary["runs"].size(), 1u) << i;
    EXPECT_EQ(summary["runs"][0]["case"], shares[static_cast<std::size_t>(i)][0]);
    EXPECT_EQ(summary["runs"][0]["objectives"], expected["runs"][static_cast<std::size_t>(i)]["objectives"]);
    for (int j = 0; j < 3; ++j) EXPECT_EQ(fs::exists(out / ("run-" + std::to_string(j))), i == j) << i << " " << j;
    EXPECT_EQ(fs::exists(out / "reference"), i == 2);
    // The reference is in the last share alone: the errors are known there only.
    EXPECT_EQ(summary["runs"][0]["errors"]["objective_error"].is_null(), i < 2) << i;
    shards.push_back(out.string());
  }
  // Given in any order; every run is reused (none runs again), the summary is the single run's.
  const Json summary = hapsyn::merge_sweep_shards({shards[2], shards[0], shards[1]}, merged.string(),
                                                  hapsyn::test::registry(), 1);
  expect_same_rows(summary, expected);
  for (const Json& run : summary["runs"]) EXPECT_TRUE(run["reused"].get<bool>());
  EXPECT_FALSE(summary.contains("shard"));
  EXPECT_TRUE(hapsyn::is_sweep_output(merged.string()));
  EXPECT_FALSE(hapsyn::is_sweep_output((merged / "run-0").string()));
  expect_same_rows(read_json(merged / "sweep.json"), expected);
  EXPECT_EQ(lines(merged / "sweep.csv"), 4);
  // The shares' folders are untouched by the merge.
  EXPECT_EQ(read_json(fs::path(shards[0]) / "sweep.json")["runs"].size(), 1u);
  for (const std::string& s : shards) fs::remove_all(s);
  fs::remove_all(whole);
  fs::remove_all(merged);
}

TEST(Sweep, MergeRefusesMissingDuplicateForeignAndUnfinishedShares) {
  const fs::path root = fresh("merge-errors");
  std::vector<std::string> shards;
  for (int i = 0; i < 3; ++i) {
    // Summaries alone are enough for the checks, which come before any folder is touched.
    Json summary = {{"status", "finished"},
                    {"problem", culling_study()},
                    {"options", {{"axes", Json::array()}, {"reference", Json::array()}, {"seed", 3}}},
                    {"hapsyn", {{"version", "1"}}},
                    {"shard", {{"index", i + 1}, {"count", 3}, {"cases", Json::array()}}}};
    write_json(root / ("s" + std::to_string(i + 1)) / "sweep.json", summary);
    shards.push_back((root / ("s" + std::to_string(i + 1))).string());
  }
  const std::string out = (root / "out").string();
  const auto& registry = hapsyn::test::registry();
  expect_error([&] { hapsyn::merge_sweep_shards({}, out, registry, 1); }, {"merge: no shard directory given"});
  expect_error([&] { hapsyn::merge_sweep_shards({shards[0], shards[2]}, out, registry, 1); },
               {"merge: shard 2/3 is missing (given: 1/3, 3/3)"});
  expect_error([&] { hapsyn::merge_sweep_shards({shards[0], shards[1], shards[0], shards[2]}, out, registry, 1); },
               {"merge: shard 1/3 is given twice (" + shards[0] + ", " + shards[0] + ")"});
  expect_error([&] { hapsyn::merge_sweep_shards({shards[0], (root / "none").string()}, out, registry, 1); },
               {"merge: " + (root / "none" / "sweep.json").string() + ": not a readable sweep summary ("});
  // A share of another sweep: another seed, another problem, another share count.
  const fs::path foreign = root / "foreign";
  Json other = read_json(fs::path(shards[1]) / "sweep.json");
  other["options"]["seed"] = 4;
  write_json(foreign / "sweep.json", other);
  expect_error([&] { hapsyn::merge_sweep_shards({shards[0], foreign.string(), shards[2]}, out, registry, 1); },
               {"merge: " + foreign.string() + " (shard 2/3) is not of the same sweep as " + shards[0] +
                " (shard 1/3): its seed differs (4 there, 3 in " + shards[0] + ")"});
  other = read_json(fs::path(shards[1]) / "sweep.json");
  other["problem"]["solver"]["options"]["polish"] = true;
  write_json(foreign / "sweep.json", other);
  expect_error([&] { hapsyn::merge_sweep_shards({shards[0], foreign.string(), shards[2]}, out, registry, 1); },
               {"(shard 2/3) is not of the same sweep as ", "its problem differs"});
  other = read_json(fs::path(shards[1]) / "sweep.json");
  other["shard"]["count"] = 2;
  write_json(foreign / "sweep.json", other);
  expect_error([&] { hapsyn::merge_sweep_shards({shards[0], foreign.string(), shards[2]}, out, registry, 1); },
               {"merge: " + foreign.string() + " (shard 2/2) is not of the same sweep as " + shards[0] +
                " (shard 1/3): its shard count differs"});
  // A plain sweep, a stopped share, the output in a share's folder, a share without its runs.
  other.erase("shard");
  write_json(foreign / "sweep.json", other);
  expect_error([&] { hapsyn::merge_sweep_shards({foreign.string()}, out, registry, 1); },
               {"merge: " + foreign.string() + " is not a shard of a sweep (its sweep.json has no \"shard\" entry"});
  other = read_json(fs::path(shards[1]) / "sweep.json");
  other["status"] = "stopped";
  write_json(foreign / "sweep.json", other);
  expect_error([&] { hapsyn::merge_sweep_shards({shards[0], foreign.string(), shards[2]}, out, registry, 1); },
               {"merge: " + foreign.string() + " (shard 2/3) stopped before its runs finished (status \"stopped\"): run "
                "its command again to finish it, then merge"});
  expect_error([&] { hapsyn::merge_sweep_shards(shards, shards[1], registry, 1); },
               {"merge: " + shards[1] + " is shard 2/3's directory: merge into another directory"});
  other = read_json(fs::path(shards[1]) / "sweep.json");
  other["shard"]["cases"] = {"run-1"};
  write_json(foreign / "sweep.json", other);
  expect_error([&] { hapsyn::merge_sweep_shards({shards[0], foreign.string(), shards[2]}, out, registry, 1); },
               {"merge: " + (foreign / "run-1").string() + ": missing, or without result.json (shard 2/3's sweep.json "
                "lists it as finished)"});
  fs::remove_all(root);
}

TEST(Sweep, AMergeRunsNothingAgain) {
  // A share whose run folder holds a stopped result: the merge refuses instead of running it.
  const fs::path root = fresh("merge-nothing"), merged = root / "merged";
  std::vector<std::string> shards;
  for (int i = 0; i < 2; ++i) {
    hapsyn::ShardCluster cluster(i, 2);
    hapsyn::SweepOptions options = small_sweep(root / ("s" + std::to_string(i + 1)));
    options.axes[0] = hapsyn::parse_sweep_axis("design.l0.step=0.1,0.05");
    options.cluster = &cluster;
    const Json summary = hapsyn::run_sweep(culling_study(), options, hapsyn::test::registry());
    ASSERT_EQ(summary["shard"]["cases"], Json::array({"run-" + std::to_string(i)}));
    shards.push_back(options.output_directory);
  }
  Json stored = read_json(root / "s1" / "run-0" / "result.json");
  stored["status"] = "stopped";
  write_json(root / "s1" / "run-0" / "result.json", stored);
  expect_error([&] { hapsyn::merge_sweep_shards(shards, merged.string(), hapsyn::test::registry(), 1); },
               {"merge: " + (merged / "run-0").string() + " ({\"design.l0.step\":0.1}): no finished result of this run "
                "to reuse (a merge runs nothing again)"});
  EXPECT_FALSE(fs::exists(merged / "run-0" / "checkpoint.json"));
  fs::remove_all(root);
}

TEST(Sweep, TheCommandRunsOneShareAndRefusesAMalformedShard) {
  const fs::path root = fresh("cli-shard");
  write_json(root / "study.json", culling_study());
  const std::string command = "sweep " + (root / "study.json").string() +
                              " --vary design.l0.step=0.1,0.05 --threads 1 --seed 3 --out " + (root / "out").string();
  const hapsyn::test::Output bad = hapsyn::test::hapsyn_cli(command + " --shard 3/2");
  EXPECT_EQ(bad.code, 1) << bad.out;
  EXPECT_NE(bad.out.find("hapsyn: error: shard: --shard 3/2: the share i must lie in 1..N (N = 2)"), std::string::npos)
      << bad.out;
  EXPECT_FALSE(fs::exists(root / "out"));
  const hapsyn::test::Output share = hapsyn::test::hapsyn_cli(command + " --shard 2/2");
  EXPECT_EQ(share.code, 0) << share.out;
  EXPECT_NE(share.out.find("shard 2/2 done; when every share is, combine them: hapsyn merge"), std::string::npos)
      << share.out;
  const Json summary = read_json(root / "out" / "sweep.json");
  EXPECT_EQ(summary["shard"], Json({{"index", 2}, {"count", 2}, {"cases", {"run-1"}}}));
  EXPECT_EQ(summary["problem_directory"], fs::absolute(root).lexically_normal().string());
  EXPECT_FALSE(fs::exists(root / "out" / "run-0"));
  fs::remove_all(root);
}
