// hapsyn compare: runs studies in order into their own folders, one table, CSV/JSON, plots.
#include "test_support.hpp"

#include <hapsyn/cluster.hpp>
#include <hapsyn/internal/compare.hpp>
#include <hapsyn/internal/plot.hpp>

#include <boost/filesystem.hpp>

#include <atomic>
#include <fstream>
#include <sstream>

using hapsyn::Json;
namespace fs = boost::filesystem;

namespace {
std::string write_problem(const fs::path& dir, const std::string& name, Json doc) {
  doc["name"] = name;
  const std::string path = (dir / (name + ".json")).string();
  std::ofstream(path) << doc.dump(1);
  return path;
}
}  // namespace

TEST(Compare, RunsStudiesInOrderAndTabulatesTheirFronts) {
  const fs::path dir = fs::temp_directory_path() / fs::unique_path("hapsyn-compare-%%%%%%");
  fs::create_directories(dir);
  Json base = hapsyn::test::fivebar_study("grid");
  base["objectives"] = Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  Json reference = base;
  reference["solver"]["options"] = {{"pareto", true}};
  Json weighted = base;
  weighted["solver"] = {{"plugin", "weighted_sum"}, {"options", {{"count", 3}, {"sub_solver", {{"plugin", "grid"}}}}}};
  // The reference study runs first and writes the front the weighted sum names.
  weighted["indicators"] = {{"reference_front", (dir / "out" / "ref" / "result.json").string()},
                            {"reference_point", {0.0, 0.0}}};
  hapsyn::CompareOptions options;
  options.files = {write_problem(dir, "ref", reference), write_problem(dir, "ws", weighted)};
  options.output_directory = (dir / "out").string();
  options.threads = 2;
  const Json summary = hapsyn::run_compare(options, hapsyn::test::registry());
  ASSERT_EQ(summary["rows"].size(), 2u);
  const Json& ws = summary["rows"][1];
  EXPECT_EQ(ws["solver"], "weighted_sum");
  EXPECT_GE(ws["points"].get<int>(), 1);
  EXPECT_GT(ws["hypervolume"].get<double>(), 0.0);
  // Grid weighted sums find grid designs: on the exact grid front, nothing dominates them.
  EXPECT_NEAR(ws["generational_distance"].get<double>(), 0.0, 1e-12);
  EXPECT_EQ(ws["max_domination_gap"]["gii"].get<double>(), 0.0);
  EXPECT_TRUE(fs::exists(dir / "out" / "compare.csv"));
  EXPECT_TRUE(fs::exists(dir / "out" / "compare.json"));
  EXPECT_TRUE(fs::exists(dir / "out" / "ws" / "result.json"));
  EXPECT_EQ(hapsyn::test::count_lines((dir / "out" / "compare.csv").string()), 3);
  if (hapsyn::gnuplot_available()) {
    EXPECT_TRUE(fs::exists(dir / "out" / "fronts.png"));
    EXPECT_TRUE(fs::exists(dir / "out" / "fronts.svg"));
  }
  std::ostringstream table;
  hapsyn::print_compare(summary, table);
  EXPECT_NE(table.str().find("weighted_sum"), std::string::npos) << table.str();
  fs::remove_all(dir);
}

// Issue 51: the README's `hapsyn compare ... --out DIR` showed "-" for GD, IGD and the gap: the
// reference study was written under DIR while the others read its default directory. A
// reference_front naming another study's default output is read where the comparison writes it;
// one that is missing is a warning in the table.
TEST(Compare, AReferenceStudyOfTheComparisonIsReadWhereTheComparisonWritesIt) {
  const fs::path dir = fs::temp_directory_path() / fs::unique_path("hapsyn-compare-ref-%%%%%%");
  fs::create_directories(dir);
  Json base = hapsyn::test::fivebar_study("grid");
  base["objectives"] = Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  Json reference = base;
  reference["solver"]["options"] = {{"pareto", true}};
  reference["output"] = {{"directory", (dir / "default" / "ref").string()}};
  Json weighted = base;
  weighted["solver"] = {{"plugin", "weighted_sum"}, {"options", {{"count", 3}, {"sub_solver", {{"plugin", "grid"}}}}}};
  weighted["indicators"] = {{"reference_front", (dir / "default" / "ref" / "result.json").string()}};
  hapsyn::CompareOptions options;
  options.files = {write_problem(dir, "ref", reference), write_problem(dir, "ws", weighted)};
  options.output_directory = (dir / "out").string();
  options.threads = 2;
  const Json summary = hapsyn::run_compare(options, hapsyn::test::registry());
  const Json& ws = summary["rows"][1];
  EXPECT_EQ(ws["reference"], "ref");
  EXPECT_TRUE(ws["reference_front_missing"].is_null()) << ws;
  EXPECT_NEAR(ws["generational_distance"].get<double>(), 0.0, 1e-12);
  EXPECT_GT(ws["inverted_generational_distance"].get<double>(), 0.0);
  EXPECT_FALSE(fs::exists(dir / "default"));  // nothing read or written at the default place

  // Alone, the weighted sum's reference does not exist: said in the row and on the console.
  options.files = {options.files[1]};
  options.output_directory = (dir / "alone").string();
  const Json alone = hapsyn::run_compare(options, hapsyn::test::registry());
  EXPECT_TRUE(alone["rows"][0]["generational_distance"].is_null());
  ASSERT_TRUE(alone["rows"][0]["reference_front_missing"].is_string()) << alone["rows"][0];
  std::ostringstream table;
  hapsyn::print_compare(alone, table);
  EXPECT_NE(table.str().find("warning: ws: GD, IGD and the domination gap are not computed (\"-\"): " +
                             (dir / "default" / "ref" / "result.json").string() + " does not exist"),
            std::string::npos)
      << table.str();
  fs::remove_all(dir);
}

TEST(Compare, RefusesNoFilesAndDuplicateStudyNames) {
  hapsyn::test::expect_error([] { hapsyn::run_compare({}, hapsyn::test::registry()); },
                             {"compare: at least one problem file is required"});
  const fs::path dir = fs::temp_directory_path() / fs::unique_path("hapsyn-compare-%%%%%%");
  fs::create_directories(dir);
  const std::string file = write_problem(dir, "same", hapsyn::test::fivebar_study("grid"));
  hapsyn::CompareOptions options;
  options.files = {file, file};
  options.output_directory = (dir / "out").string();
  options.plots = false;
  hapsyn::test::expect_error([&] { hapsyn::run_compare(options, hapsyn::test::registry()); },
                             {"compare: ", "a study named 'same' is already in this comparison"});
  fs::remove_all(dir);
}

// ---- continuing, stopping ----

namespace {
hapsyn::CompareOptions two_grid_studies(const fs::path& dir) {
  fs::create_directories(dir);
  Json a = hapsyn::test::fivebar_study("grid");
  Json b = a;
  b["design"]["r"]["step"] = 0.2;
  hapsyn::CompareOptions options;
  options.files = {write_problem(dir, "fine", a), write_problem(dir, "coarse", b)};
  options.output_directory = (dir / "out").string();
  options.threads = 2;
  options.seed = 7;
  options.plots = false;
  return options;
}
}  // namespace

TEST(Compare, FinishedStudiesAreReusedAndAnotherProblemIsRefusedWithAWorkingRemedy) {
  const fs::path dir = fs::temp_directory_path() / fs::unique_path("hapsyn-compare-%%%%%%");
  hapsyn::CompareOptions options = two_grid_studies(dir);
  const Json first = hapsyn::run_compare(options, hapsyn::test::registry());
  EXPECT_EQ(first["status"], "finished");
  const Json again = hapsyn::run_compare(options, hapsyn::test::registry());
  ASSERT_EQ(again["rows"].size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_FALSE(first["rows"][i]["reused"].get<bool>());
    EXPECT_TRUE(again["rows"][i]["reused"].get<bool>());
    EXPECT_EQ(again["rows"][i]["wall_time_s"], first["rows"][i]["wall_time_s"]);
    EXPECT_EQ(again["rows"][i]["samples"], first["rows"][i]["samples"]);
  }
  // Another problem under the same study name: refused with what works (no --force, which
  // `hapsyn compare` does not take).
  options.overrides = {"scene.options.step=0.05"};
  const std::string message = hapsyn::test::error_of([&] { hapsyn::run_compare(options, hapsyn::test::registry()); });
  EXPECT_NE(message.find("compare: " + (dir / "out" / "fine").string() +
                         " holds a result of another problem (first difference at /scene/options/step: 0.025 there, "
                         "0.05 in this comparison's " + options.files[0] + "); delete it, or choose another --out"),
            std::string::npos)
      << message;
  EXPECT_EQ(message.find("--force"), std::string::npos) << message;
  // force (CompareOptions::force) runs the studies again.
  options.force = true;
  const Json forced = hapsyn::run_compare(options, hapsyn::test::registry());
  EXPECT_FALSE(forced["rows"][0]["reused"].get<bool>());
  fs::remove_all(dir);
}

TEST(Compare, StopWritesTheFinishedStudiesWithStatusStopped) {
  const fs::path dir = fs::temp_directory_path() / fs::unique_path("hapsyn-compare-%%%%%%");
  hapsyn::CompareOptions options = two_grid_studies(dir);
  const std::atomic<bool> stop{true};
  options.stop = &stop;
  const Json summary = hapsyn::run_compare(options, hapsyn::test::registry());
  EXPECT_EQ(summary["status"], "stopped");
  EXPECT_EQ(summary["rows"].size(), 0u);
  EXPECT_EQ(summary["message"], "stopped on request at fine (not started) after 0 of 2 studies; run the same command "
                                "again to continue (finished studies are reused, a stopped one resumes from its checkpoint)");
  std::ifstream in((dir / "out" / "compare.json").string());
  EXPECT_EQ(Json::parse(in)["status"], "stopped");
  std::ostringstream table;
  hapsyn::print_compare(summary, table);
  EXPECT_NE(table.str().find("stopped: stopped on request at fine"), std::string::npos) << table.str();
  fs::remove_all(dir);
}

// ---- several processes: a cluster, shards and their merge ----

TEST(Compare, ShardsMergedGiveTheTableOfASingleRunAndALocalClusterChangesNothing) {
  const fs::path dir = fs::temp_directory_path() / fs::unique_path("hapsyn-compare-%%%%%%");
  hapsyn::CompareOptions options = two_grid_studies(dir);
  options.threads = 1;
  const Json single = hapsyn::run_compare(options, hapsyn::test::registry());
  ASSERT_EQ(single["rows"].size(), 2u);
  const auto same_rows = [&](const Json& summary) {
    ASSERT_EQ(summary["rows"].size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
      for (const char* key : {"study", "file", "solver", "status", "points", "hypervolume", "spacing", "designs", "samples"}) {
        EXPECT_EQ(summary["rows"][i][key], single["rows"][i][key]) << i << " " << key;
      }
    }
  };
  hapsyn::CompareOptions local = options;
  local.output_directory = (dir / "local").string();
  local.cluster = &hapsyn::Cluster::local();
  const Json on_local = hapsyn::run_compare(local, hapsyn::test::registry());
  same_rows(on_local);
  EXPECT_FALSE(on_local.contains("shard"));
  EXPECT_EQ(on_local["options"]["files"], Json(options.files));
  EXPECT_EQ(on_local["options"]["seed"], 7);

  std::vector<std::string> shards;
  for (int i = 0; i < 2; ++i) {
    hapsyn::ShardCluster cluster(i, 2);
    hapsyn::CompareOptions share = options;
    share.output_directory = (dir / ("share" + std::to_string(i + 1))).string();
    share.cluster = &cluster;
    const Json summary = hapsyn::run_compare(share, hapsyn::test::registry());
    EXPECT_EQ(summary["status"], "finished");
    EXPECT_EQ(summary["message"], cluster.shard_message());
    ASSERT_EQ(summary["rows"].size(), 1u);
    EXPECT_EQ(summary["rows"][0]["study"], single["rows"][static_cast<std::size_t>(i)]["study"]);
    EXPECT_EQ(summary["shard"]["cases"], Json::array({single["rows"][static_cast<std::size_t>(i)]["study"]}));
    shards.push_back(share.output_directory);
  }
  const std::string merged = (dir / "merged").string();
  hapsyn::test::expect_error(
      [&] { hapsyn::merge_compare_shards({shards[1]}, merged, hapsyn::test::registry(), 1); },
      {"merge: shard 1/2 is missing (given: 2/2)"});
  hapsyn::test::expect_error(
      [&] { hapsyn::merge_compare_shards({(dir / "local").string()}, merged, hapsyn::test::registry(), 1); },
      {"merge: " + (dir / "local").string() + " is not a shard of a comparison (its compare.json has no \"shard\" entry"});
  const Json summary = hapsyn::merge_compare_shards({shards[1], shards[0]}, merged, hapsyn::test::registry(), 1);
  same_rows(summary);
  for (const Json& row : summary["rows"]) EXPECT_TRUE(row["reused"].get<bool>());
  EXPECT_EQ(summary["status"], "finished");
  EXPECT_TRUE(hapsyn::is_compare_output(merged));
  EXPECT_FALSE(hapsyn::is_compare_output(shards[0] + "/fine"));
  fs::remove_all(dir);
}
