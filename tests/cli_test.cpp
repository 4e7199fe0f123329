// End-to-end: the hapsyn program as a user runs it.
#include "test_support.hpp"

#include <boost/filesystem.hpp>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <sys/wait.h>

namespace fs = boost::filesystem;
using hapsyn::Json;

namespace {
using hapsyn::test::hapsyn_cli;
using hapsyn::test::Output;

std::string problem(const std::string& name) { return std::string(HAPSYN_SOURCE_DIR) + "/problems/" + name; }

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("hapsyn-cli-test-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}

Json read_json(const fs::path& p) {
  std::ifstream in(p.string());
  return Json::parse(in);
}

long count_lines(const fs::path& p) { return hapsyn::test::count_lines(p.string()); }
}  // namespace

TEST(Cli, RunWritesResultJsonAndSamplesCsv) {
  const fs::path out = fresh_dir("run");
  const Output o = hapsyn_cli("run " + problem("fivebar-table2-best-gii.json") + " --out " + out.string() + " --threads 2 --seed 5");
  ASSERT_EQ(o.code, 0) << o.out;
  EXPECT_NE(o.out.find("gii = 0.7827"), std::string::npos) << o.out;
  const Json result = read_json(out / "result.json");
  EXPECT_EQ(result["status"], "converged");
  EXPECT_NEAR(result["best"]["objectives"]["gii"].get<double>(), 0.783, 0.0005);
  EXPECT_NEAR(result["best"]["objectives"]["gdi"].get<double>(), 0.622, 0.0005);
  EXPECT_EQ(result["seed"], 5);
  EXPECT_EQ(result["threads"], 2);
  EXPECT_TRUE(result["machine"].contains("cpu"));
  EXPECT_EQ(result["problem"]["scene"]["options"]["step"], 0.001);
  EXPECT_FALSE(result["hapsyn"]["version"].get<std::string>().empty());
  EXPECT_EQ(result["plugins"].size(), 5u);
  EXPECT_EQ(count_lines(out / "samples.csv"), 101 * 101 + 1);
  fs::remove_all(out);
}

TEST(Cli, SetOverridesAnyKey) {
  const fs::path out = fresh_dir("set");
  const Output o = hapsyn_cli("run " + problem("fivebar-table2-best-gii.json") + " --quiet --out " + out.string() +
                              " --set scene.options.step=0.01 --set 'objectives=[{\"metric\":\"gdi\"}]'");
  ASSERT_EQ(o.code, 0) << o.out;
  const Json result = read_json(out / "result.json");
  EXPECT_EQ(result["problem"]["scene"]["options"]["step"], 0.01);
  EXPECT_EQ(result["samples_in_scene"], 121);
  EXPECT_FALSE(result["best"]["objectives"].contains("gii"));
  fs::remove_all(out);
}

TEST(Cli, BadInputGivesPathValueAndRuleWithoutStackTrace) {
  const Output o = hapsyn_cli("validate " + problem("fivebar-gii-coarse.json") + " --set design.l1.upper=-3");
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.out.find("hapsyn: error: problem: design.l1.upper = -3"), std::string::npos) << o.out;
  EXPECT_EQ(o.out.find("terminate"), std::string::npos) << o.out;
  EXPECT_EQ(o.out.find("Aborted"), std::string::npos) << o.out;
}

TEST(Cli, MalformedJsonReportsLineAndColumn) {
  const fs::path dir = fresh_dir("malformed");
  fs::create_directories(dir);
  const fs::path file = dir / "broken.json";
  std::ofstream(file.string()) << "{\n  \"name\": \"x\",\n  \"scene\": {,\n}\n";
  const Output o = hapsyn_cli("validate " + file.string());
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.out.find("broken.json:3:"), std::string::npos) << o.out;
  fs::remove_all(dir);
}

TEST(Cli, ValidateAcceptsEveryShippedProblem) {
  for (const auto& entry : fs::directory_iterator(std::string(HAPSYN_SOURCE_DIR) + "/problems")) {
    if (entry.path().extension() != ".json") continue;
    const Output o = hapsyn_cli("validate " + entry.path().string());
    EXPECT_EQ(o.code, 0) << entry.path() << "\n" << o.out;
    EXPECT_NE(o.out.find("valid"), std::string::npos) << o.out;
  }
}

TEST(Cli, PluginsListsNameKindVersionAndFile) {
  const Output o = hapsyn_cli("plugins");
  ASSERT_EQ(o.code, 0) << o.out;
  for (const char* s : {"fivebar", "planar_square", "gii", "gdi", "evaluate", "grid", "mechanism", "scene", "metric",
                        "solver", "hapsyn-fivebar.so"}) {
    EXPECT_NE(o.out.find(s), std::string::npos) << s << "\n" << o.out;
  }
}

TEST(Cli, DescribeShowsOptionsDefaultsUnitsAndVariables) {
  const Output o = hapsyn_cli("describe fivebar");
  ASSERT_EQ(o.code, 0) << o.out;
  for (const char* s : {"mechanism plugin", "rho", "1.08", "kg/m", "design variables", "l0", "reach"}) {
    EXPECT_NE(o.out.find(s), std::string::npos) << s << "\n" << o.out;
  }
  const Output unknown = hapsyn_cli("describe fivebr");
  EXPECT_EQ(unknown.code, 1);
  EXPECT_NE(unknown.out.find("did you mean 'fivebar'"), std::string::npos) << unknown.out;
}

// A mechanism whose variables come from its options (serial_chain reads them from the chain
// file) lists them with --options, and says how without.
TEST(Cli, DescribeListsTheDesignVariablesOfGivenOptions) {
  const Output plain = hapsyn_cli("describe serial_chain");
  ASSERT_EQ(plain.code, 0) << plain.out;
  EXPECT_NE(plain.out.find("design variables: depend on the options (with the defaults: problem: mechanism.options: "
                           "serial_chain: options: give the chain as options.urdf or options.dh_file); list them with: "
                           "hapsyn describe serial_chain --options '{...}'"),
            std::string::npos)
      << plain.out;
  const Output urdf = hapsyn_cli(
      "describe serial_chain --options '{\"urdf\": \"serial_chain/ur5_like.urdf\", \"base_link\": \"base_link\", "
      "\"tip_link\": \"tool0\"}'");
  ASSERT_EQ(urdf.code, 0) << urdf.out;
  for (const char* s : {"elbow_joint:x real [-0.425, -0.425] m; limits [-inf, inf]", "upper_arm_link:mass", "mass_scale"}) {
    EXPECT_NE(urdf.out.find(s), std::string::npos) << s << "\n" << urdf.out;
  }
  const Output bad = hapsyn_cli("describe serial_chain --options '{\"urdf\": \"serial_chain/ur5_like.urdf\"}'");
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.out.find("options.base_link = \"\": a URDF chain needs base_link and tip_link"), std::string::npos) << bad.out;
}

TEST(Cli, UnwritableOutputDirectoryIsRefusedBeforeAnyWork) {
  const Output o = hapsyn_cli("run " + problem("fivebar-table2-best-gii.json") + " --out /proc/hapsyn-cannot-write");
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.out.find("hapsyn: error: output:"), std::string::npos) << o.out;
}

TEST(Cli, FailedRunLeavesNoResultBehind) {
  const fs::path out = fresh_dir("nothing");
  const Output o = hapsyn_cli("run " + problem("fivebar-gii-coarse.json") + " --out " + out.string() +
                              " --set design.l0.step=5");
  EXPECT_EQ(o.code, 1);
  EXPECT_FALSE(fs::exists(out / "result.json"));
  fs::remove_all(out);
}

TEST(Cli, CoarseGridStudyFindsAFeasibleOptimum) {
  const fs::path out = fresh_dir("grid");
  // The shipped study at a 50 mm design grid (a few seconds at most).
  const Output o = hapsyn_cli("run " + problem("fivebar-gii-coarse.json") + " --quiet --out " + out.string() +
                              " --set design.l0.step=0.05 --set design.l1.step=0.05 --set design.l2.step=0.05"
                              " --set design.r.step=0.05 --set design.l1.lower=0.05 --set design.l2.lower=0.05");
  ASSERT_EQ(o.code, 0) << o.out;
  const Json result = read_json(out / "result.json");
  EXPECT_EQ(result["status"], "converged");
  EXPECT_GT(result["best"]["objectives"]["gii"].get<double>(), 0.5);
  EXPECT_LE(result["best"]["objectives"]["gii"].get<double>(), 1.0);
  fs::remove_all(out);
}

TEST(Cli, UsageErrorsExitWithTwo) {
  EXPECT_EQ(hapsyn_cli("").code, 2);
  EXPECT_EQ(hapsyn_cli("run").code, 2);
  EXPECT_EQ(hapsyn_cli("frobnicate").code, 2);
}

// ---- hapsyn scene ----

namespace {
std::string human_arm_scene_args(const fs::path& cache) {
  return std::string(HAPSYN_SOURCE_DIR) + "/share/human_arm/paper_scene.json --set scene.options.lattice_step=0.2 " +
         "--set scene.options.orientations=30 --set scene.options.joint3_steps=5 --set scene.options.cache_directory=" +
         cache.string();
}
}  // namespace

TEST(Cli, SceneBuildsSummarizesAndExportsTheHumanArmScene) {
  const fs::path dir = fresh_dir("scene");
  const Output first = hapsyn_cli("scene " + human_arm_scene_args(dir / "cache") + " --threads 2 --csv " +
                                  (dir / "samples.csv").string());
  ASSERT_EQ(first.code, 0) << first.out;
  EXPECT_NE(first.out.find("scene human_arm: "), std::string::npos) << first.out;
  EXPECT_NE(first.out.find("n_reach: "), std::string::npos) << first.out;
  EXPECT_NE(first.out.find("build_time_s: "), std::string::npos) << first.out;
  EXPECT_NE(first.out.find("from_cache: false"), std::string::npos) << first.out;
  EXPECT_NE(first.out.find("cache_file: " + (dir / "cache").string() + "/human_arm-"), std::string::npos) << first.out;
  // n_reach from the summary equals the CSV's rows; the header has the pose columns and the
  // shoulder-frame pose, joint angles and manipulability the issue asks for.
  const std::size_t at = first.out.find("n_reach: ") + 9;
  const long n_reach = std::stol(first.out.substr(at));
  ASSERT_GT(n_reach, 0);
  EXPECT_EQ(count_lines(dir / "samples.csv"), n_reach + 1);
  std::ifstream csv((dir / "samples.csv").string());
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("x,y,z,qw,qx,qy,qz,", 0), 0u) << header;
  for (const char* column : {"human_q[0]", "human_q[6]", "lattice_index", "manipulability", "shoulder_pose[0]",
                             "shoulder_pose[6]"}) {
    EXPECT_NE(header.find(column), std::string::npos) << column << "\n" << header;
  }
  EXPECT_EQ(header.find("M_v"), std::string::npos) << "ellipsoids are built only on request";
  // Second run: from the cache.
  const Output second = hapsyn_cli("scene " + human_arm_scene_args(dir / "cache"));
  ASSERT_EQ(second.code, 0) << second.out;
  EXPECT_NE(second.out.find("from_cache: true"), std::string::npos) << second.out;
  EXPECT_NE(second.out.find("n_reach: " + std::to_string(n_reach)), std::string::npos) << second.out;
  fs::remove_all(dir);
}

TEST(Cli, ScenePlotsReachabilityDensitySlices) {
  const fs::path dir = fresh_dir("scene-plot");
  const Output o = hapsyn_cli("scene " + human_arm_scene_args(dir / "cache") + " --plot " + (dir / "plot").string());
  EXPECT_TRUE(fs::exists(dir / "plot" / "density_slices.dat"));
  EXPECT_TRUE(fs::exists(dir / "plot" / "density_slices.gp"));
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    ASSERT_EQ(o.code, 0) << o.out;
    EXPECT_GT(fs::file_size(dir / "plot" / "density_slices.png"), 1000u);
  } else {
    EXPECT_EQ(o.code, 1) << o.out;
    EXPECT_NE(o.out.find("--plot needs gnuplot, which is not installed"), std::string::npos) << o.out;
  }
  fs::remove_all(dir);
}

TEST(Cli, SceneWorksOnAnyProblemFileAndRefusesBadScenes) {
  // A full study's file: only its scene section is read; a planar scene has no lattice to plot.
  const Output planar = hapsyn_cli("scene " + problem("fivebar-gii-coarse.json"));
  ASSERT_EQ(planar.code, 0) << planar.out;
  EXPECT_NE(planar.out.find("scene planar_square: 441 samples (x, y; unit m)"), std::string::npos) << planar.out;
  const Output no_plot = hapsyn_cli("scene " + problem("fivebar-gii-coarse.json") + " --plot " +
                                    fresh_dir("scene-noplot").string());
  EXPECT_EQ(no_plot.code, 1);
  EXPECT_NE(no_plot.out.find("hapsyn: error: scene: --plot needs a lattice scene"), std::string::npos) << no_plot.out;
  const Output bad_option = hapsyn_cli("scene " + human_arm_scene_args(fresh_dir("scene-bad")) +
                                       " --set scene.options.orientations=0");
  EXPECT_EQ(bad_option.code, 1);
  EXPECT_NE(bad_option.out.find("hapsyn: error: "), std::string::npos) << bad_option.out;
  EXPECT_NE(bad_option.out.find("orientations"), std::string::npos) << bad_option.out;
  const Output missing = hapsyn_cli("scene " + problem("fivebar-gii-coarse.json") + " --set 'scene=3'");
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.out.find("hapsyn: error: problem: scene = 3: must be an object"), std::string::npos) << missing.out;
  const Output attribute = hapsyn_cli("scene " + human_arm_scene_args(fresh_dir("scene-attr")) + " --attribute forces");
  EXPECT_EQ(attribute.code, 1);
  EXPECT_NE(attribute.out.find("human_arm: per-sample attribute 'forces' requested"), std::string::npos) << attribute.out;
}
