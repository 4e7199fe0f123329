// hapsyn compare: runs studies in order into their own folders, one table, CSV/JSON, plots.
#include "test_support.hpp"

#include <hapsyn/compare.hpp>
#include <hapsyn/plot.hpp>

#include <boost/filesystem.hpp>

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
