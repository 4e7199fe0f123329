// End-to-end: the hapsyn program as a user runs it.
#include "test_support.hpp"

#include <boost/filesystem.hpp>

#include <hapsyn/output_files.hpp>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <sys/wait.h>

namespace fs = boost::filesystem;
using hapsyn::Json;

namespace {
using hapsyn::test::hapsyn_cli;
using hapsyn::test::Output;

// hapsyn under a command that signals it (`timeout`), with the exit status of hapsyn itself.
Output hapsyn_test_stopped(const std::string& wrapper, const std::string& args) {
  const std::string command = wrapper + std::string(HAPSYN_BINARY_DIR) + "/bin/hapsyn " + args + " 2>&1";
  Output o;
  FILE* pipe = ::popen(command.c_str(), "r");
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe)) o.out += buffer.data();
  const int status = ::pclose(pipe);
  o.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

// Runs `hapsyn <args>` in the background and sends it SIGINT once the shell test `condition`
// holds (polled every 50 ms, for at most 60 s): the stop comes at a known point of the run, not
// after a fixed time that a loaded machine may not reach. The exit code is hapsyn's.
Output hapsyn_interrupted_when(const std::string& condition, const std::string& args) {
  const std::string script = std::string(HAPSYN_BINARY_DIR) + "/bin/hapsyn " + args +
                             " & p=$!; i=0; until " + condition +
                             "; do sleep 0.05; i=$((i+1)); [ $i -gt 1200 ] && break; done; kill -INT $p; wait $p";
  Output o;
  FILE* pipe = ::popen(("sh -c '" + script + "' 2>&1").c_str(), "r");
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe)) o.out += buffer.data();
  const int status = ::pclose(pipe);
  o.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

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

std::string read_text(const fs::path& p) {
  std::ifstream in(p.string());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The shipped coarse grid study at a 50 mm design grid: a second or less.
std::string quick_study() {
  return problem("fivebar-gii-coarse.json") +
         " --set design.l0.step=0.05 --set design.l1.step=0.05 --set design.l2.step=0.05 --set design.r.step=0.05"
         " --set design.l1.lower=0.05 --set design.l2.lower=0.05";
}

bool has_staging(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().filename().string().rfind(".staging-", 0) == 0) return true;
  }
  return false;
}
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
  // The phases add up to the wall time; the outputs of a big scene report their progress.
  const Json& phases = result["phases"];
  EXPECT_GT(phases["scene_s"].get<double>(), 0.0);
  EXPECT_NEAR(phases["scene_s"].get<double>() + phases["solve_s"].get<double>() + phases["outputs_s"].get<double>(),
              result["wall_time_s"].get<double>(), 1e-9);
  EXPECT_NE(o.out.find("outputs: writing samples.csv"), std::string::npos) << o.out;
  EXPECT_NE(read_text(out / "run.log").find("outputs: writing samples.csv"), std::string::npos);
  EXPECT_FALSE(has_staging(out));
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

// The rules relating several options are listed after the options, with their fields' paths
// (those of a group under the group's path).
TEST(Cli, DescribeShowsTheRulesBetweenOptions) {
  const Output square = hapsyn_cli("describe planar_square");
  ASSERT_EQ(square.code, 0) << square.out;
  EXPECT_NE(square.out.find("  rule (step, side): step <= side and divides it into whole steps\n"), std::string::npos)
      << square.out;
  const Output ga = hapsyn_cli("describe ga");
  ASSERT_EQ(ga.code, 0) << ga.out;
  EXPECT_NE(ga.out.find("  rule (fidelity.subset_fraction, fidelity.generations): subset_fraction < 1 needs generations >= 1"),
            std::string::npos)
      << ga.out;
  const Output json = hapsyn_cli("describe planar_square --json");
  ASSERT_EQ(json.code, 0) << json.out;
  EXPECT_NE(json.out.find("\"x-rules\""), std::string::npos) << json.out;
}

// A mechanism whose variables come from its options (serial_chain reads them from the chain
// file) lists them with --options, and says how without.
TEST(Cli, DescribeListsTheDesignVariablesOfGivenOptions) {
  const Output plain = hapsyn_cli("describe serial_chain");
  ASSERT_EQ(plain.code, 0) << plain.out;
  EXPECT_NE(plain.out.find("design variables: depend on the options (with the defaults: problem: mechanism.options: "
                           "serial_chain: options.urdf = \"\": give the chain as options.urdf or options.dh_file); list "
                           "them with: "
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

// Issue 51: a wrong tip_link gave a 3x4 Jacobian with a zero column, unnoticed. The run header,
// result.json and describe now say which joints the chain has, from base to tip.
TEST(Cli, RunHeaderListsAChainsMovingJoints) {
  const fs::path dir = fresh_dir("chain-header");
  const Output o = hapsyn_cli("run " + problem("phantom3r-gii-box.json") + " --set solver.plugin=evaluate --set 'design={}' --out " +
                              (dir / "whole").string());
  ASSERT_EQ(o.code, 0) << o.out;
  const std::string joints = "3 moving joints world -> stylus_tip: yaw_joint (revolute), shoulder_joint (revolute), "
                             "elbow_joint (revolute); folded: stylus_tip -> forearm; task position; IK selection closest_to_home; IK solver numerical (damped "
                             "least squares, 8 restarts; no closed form: 3 moving joints (the closed form is for 6 or 7 "
                             "revolute joints))";
  EXPECT_NE(o.out.find("mechanism serial_chain: " + joints), std::string::npos) << o.out;
  EXPECT_EQ(read_json(dir / "whole" / "result.json")["mechanism_summary"], joints);
  // A tip two links short: a 2-joint chain cannot serve a 3-row position task, and the refusal
  // points at the links rather than at the task it already has.
  const Output short_tip = hapsyn_cli("run " + problem("phantom3r-gii-box.json") +
                                      " --set solver.plugin=evaluate --set 'design={}' --set mechanism.options.tip_link=upper_arm "
                                      "--out " + (dir / "short").string());
  EXPECT_EQ(short_tip.code, 1) << short_tip.out;
  EXPECT_NE(short_tip.out.find("options.task = \"position\": matches 3 task rows, but the chain has only 2 joints (a "
                               "non-redundant task needs at least as many joints as rows; check base_link and tip_link: "
                               "the chain between them has 2 moving joints)"),
            std::string::npos)
      << short_tip.out;
  // A 6R read one link short for a position task: the header shows the joints it got.
  const Output forearm = hapsyn_cli(
      "describe serial_chain --options '{\"urdf\": \"serial_chain/ur5_like.urdf\", \"base_link\": \"base_link\", "
      "\"tip_link\": \"forearm_link\", \"task\": \"position\"}'");
  EXPECT_NE(forearm.out.find("built: 3 moving joints base_link -> forearm_link: shoulder_pan_joint (revolute), "
                             "shoulder_lift_joint (revolute), elbow_joint (revolute); task position"),
            std::string::npos)
      << forearm.out;
  const Output described = hapsyn_cli(
      "describe serial_chain --options '{\"urdf\": \"serial_chain/ur5_like.urdf\", \"base_link\": \"base_link\", "
      "\"tip_link\": \"tool0\"}'");
  EXPECT_NE(described.out.find("built: 6 moving joints base_link -> tool0: shoulder_pan_joint (revolute), "
                               "shoulder_lift_joint (revolute), elbow_joint (revolute), wrist_1_joint (revolute), "
                               "wrist_2_joint (revolute), wrist_3_joint (revolute); folded: gripper_base -> wrist_3_link; "
                               "task pose"),
            std::string::npos)
      << described.out;
  // The five-bar has nothing to add: no line.
  const Output fivebar = hapsyn_cli("run " + problem("fivebar-table2-best-gii.json") + " --out " + (dir / "fb").string());
  EXPECT_EQ(fivebar.out.find("mechanism fivebar"), std::string::npos) << fivebar.out;
  fs::remove_all(dir);
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
  // The GII optimum of this grid has the longest l2 the bounds allow: the run says so.
  const std::string warning = "design.l2 = 0.3 is at its upper bound: the optimum may lie beyond it; widen "
                              "design.l2.upper to check";
  ASSERT_TRUE(result.contains("warnings")) << result.dump(2);
  EXPECT_NE(std::find(result["warnings"].begin(), result["warnings"].end(), warning), result["warnings"].end())
      << result["warnings"].dump();
  EXPECT_NE(o.out.find("warning: " + warning), std::string::npos) << o.out;
  EXPECT_NE(read_text(out / "run.log").find("warning: " + warning), std::string::npos);
  fs::remove_all(out);
}

TEST(Cli, AnOptimumAtTheMechanismsHardLimitIsNoHintToWiden) {
  const fs::path out = fresh_dir("hard-limit");
  // The shipped study (10 mm grid, under a second): its optimum has l0 = 0, the hard limit of a length.
  const Output o = hapsyn_cli("run " + problem("fivebar-gii-coarse.json") + " --quiet --out " + out.string());
  ASSERT_EQ(o.code, 0) << o.out;
  const Json result = read_json(out / "result.json");
  ASSERT_EQ(result["best"]["design"]["l0"], 0.0);
  ASSERT_TRUE(result.contains("warnings"));
  for (const Json& w : result["warnings"]) EXPECT_EQ(w.get<std::string>().find("design.l0"), std::string::npos) << w;
  EXPECT_NE(o.out.find("warning: design.l1 = 0.3 is at its upper bound"), std::string::npos) << o.out;
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

// The arm file's palm position in S at q (standard DH, as share/human_arm/README.md states it),
// computed here from the file alone.
Eigen::Vector3d arm_file_palm(const std::string& file, const std::array<double, 7>& q_degrees) {
  std::ifstream in(file);
  const Json arm = Json::parse(in);
  const auto length = [&](const Json& v) {
    if (v.is_number()) return v.get<double>();
    std::string name = v.get<std::string>();
    const double sign = name[0] == '-' ? -1.0 : 1.0;
    if (sign < 0) name = name.substr(1);
    return sign * arm.at("segments").at(name).get<double>();
  };
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 7; ++i) {
    const Json& r = arm.at("dh")[static_cast<std::size_t>(i)];
    const double theta = (q_degrees[static_cast<std::size_t>(i)] + r.at("theta_offset").get<double>()) * M_PI / 180.0;
    T = T * Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()) * Eigen::Translation3d(0, 0, length(r.at("d"))) *
        Eigen::Translation3d(length(r.at("a")), 0, 0) *
        Eigen::AngleAxisd(r.at("alpha").get<double>() * M_PI / 180.0, Eigen::Vector3d::UnitX());
  }
  return T.translation();
}

// What a user checks with `hapsyn scene PROBLEM --csv F`: the rotation that carries the exported
// shoulder-frame positions onto the base-frame positions (a least-squares fit, Kabsch) hangs the
// arm file's rest pose along -z_B (gravity) and moves it horizontally when the arm is raised
// sideways or forward.
TEST(Cli, ExportedSceneOfTheEvaluateStudyHangsTheRestArmAlongGravity) {
  const fs::path dir = fresh_dir("upright");
  const Output o = hapsyn_cli("scene " + problem("haptic6r-evaluate.json") +
                              " --set scene.options.lattice_step=0.2 --set scene.options.orientations=20 "
                              "--set scene.options.joint3_steps=5 --set scene.options.cache_directory=" +
                              (dir / "cache").string() + " --csv " + (dir / "samples.csv").string());
  ASSERT_EQ(o.code, 0) << o.out;
  std::ifstream csv((dir / "samples.csv").string());
  std::string line;
  std::getline(csv, line);
  std::vector<std::string> header;
  for (std::istringstream h(line); std::getline(h, line, ',');) header.push_back(line);
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  const std::size_t shoulder = column("shoulder_pose[0]");
  ASSERT_LT(shoulder, header.size());
  std::vector<Eigen::Vector3d> in_base, in_shoulder;
  while (std::getline(csv, line)) {
    std::vector<double> v;
    for (std::istringstream r(line); std::getline(r, line, ',');) v.push_back(std::stod(line));
    in_base.emplace_back(v[0], v[1], v[2]);
    in_shoulder.emplace_back(v[shoulder], v[shoulder + 1], v[shoulder + 2]);
  }
  ASSERT_GT(in_base.size(), 100u);
  Eigen::Vector3d mean_b = Eigen::Vector3d::Zero(), mean_s = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < in_base.size(); ++i) {
    mean_b += in_base[i] / static_cast<double>(in_base.size());
    mean_s += in_shoulder[i] / static_cast<double>(in_base.size());
  }
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < in_base.size(); ++i) cross += (in_base[i] - mean_b) * (in_shoulder[i] - mean_s).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d fit = svd.matrixU() * svd.matrixV().transpose();
  ASSERT_GT(fit.determinant(), 0.0);
  const std::string arm = std::string(HAPSYN_SOURCE_DIR) + "/share/human_arm/fennel2022_right_arm.json";
  const Eigen::Vector3d rest = (fit * arm_file_palm(arm, {0, 0, 0, 0, 0, 0, 0})).normalized();
  const Eigen::Vector3d abducted = (fit * arm_file_palm(arm, {90, 0, 0, 0, 0, 0, 0})).normalized();
  const Eigen::Vector3d flexed = (fit * arm_file_palm(arm, {0, 90, 0, 0, 0, 0, 0})).normalized();
  EXPECT_GT(rest.dot(Eigen::Vector3d(0, 0, -1)), 1.0 - 1e-9) << rest.transpose();
  EXPECT_NEAR(abducted.z(), 0.0, 1e-9) << abducted.transpose();
  EXPECT_NEAR(flexed.z(), 0.0, 1e-9) << flexed.transpose();
  EXPECT_GT(flexed.x(), 1.0 - 1e-9) << "the user faces +x_B: " << flexed.transpose();
  EXPECT_GT(-abducted.y(), 1.0 - 1e-9) << "the right arm abducts to -y_B: " << abducted.transpose();
  fs::remove_all(dir);
}

// Issue 53, cause 4: a merge never writes over one of its shares, with or without --force.
TEST(Cli, MergeRefusesAnOutputThatIsOneOfItsShares) {
  const fs::path dir = fresh_dir("merge-over-share");
  std::vector<std::string> shares;
  for (int i = 1; i <= 3; ++i) {
    const fs::path share = dir / ("s" + std::to_string(i));
    const Output o = hapsyn_cli("run " + problem("fivebar-gii-coarse.json") + " --quiet --shard " + std::to_string(i) +
                                "/3 --out " + share.string());
    ASSERT_EQ(o.code, 0) << o.out;
    shares.push_back(share.string());
  }
  std::ifstream before_in((dir / "s1" / "result.json").string());
  const std::string before((std::istreambuf_iterator<char>(before_in)), std::istreambuf_iterator<char>());
  const std::string all = shares[0] + " " + shares[1] + " " + shares[2];
  for (const std::string& force : {std::string(""), std::string(" --force")}) {
    const Output same = hapsyn_cli("merge " + all + " --out " + shares[0] + force);
    EXPECT_EQ(same.code, 1) << same.out;
    EXPECT_NE(same.out.find("merge: --out " + shares[0] + " is the share " + shares[0] +
                            " given as input: the merged study would be written over it; choose another directory"),
              std::string::npos)
        << same.out;
    const Output inside = hapsyn_cli("merge " + all + " --out " + shares[1] + "/merged" + force);
    EXPECT_EQ(inside.code, 1) << inside.out;
    EXPECT_NE(inside.out.find("lies inside the share " + shares[1]), std::string::npos) << inside.out;
  }
  // Another spelling of the same directory is the same directory.
  const Output dotted = hapsyn_cli("merge " + all + " --out " + (dir / "s2" / ".." / "s1").string());
  EXPECT_EQ(dotted.code, 1) << dotted.out;
  std::ifstream after_in((dir / "s1" / "result.json").string());
  const std::string after((std::istreambuf_iterator<char>(after_in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(after, before) << "a refused merge changed a share";
  EXPECT_FALSE(fs::exists(dir / "s2" / "merged"));
  const Output merged = hapsyn_cli("merge " + all + " --out " + (dir / "merged").string());
  EXPECT_EQ(merged.code, 0) << merged.out;
  fs::remove_all(dir);
}

// Issue 53, cause 7: a share's result.json with a field of the wrong type once ended merge with
// exit 3 (nlohmann's type_error); every field merge reads is checked and named.
TEST(Cli, MergeNamesAShareFieldOfTheWrongType) {
  const fs::path dir = fresh_dir("merge-wrong-type");
  std::vector<std::string> shares;
  for (int i = 1; i <= 2; ++i) {
    const fs::path share = dir / ("s" + std::to_string(i));
    const Output o = hapsyn_cli("run " + problem("fivebar-gii-coarse.json") + " --quiet --shard " + std::to_string(i) +
                                "/2 --out " + share.string());
    ASSERT_EQ(o.code, 0) << o.out;
    shares.push_back(share.string());
  }
  const fs::path result = dir / "s2" / "result.json";
  const Json pristine = read_json(result);
  struct Tamper {
    std::string pointer;
    Json value;
    std::string expected;
  };
  const std::vector<Tamper> cases = {
      {"/shard/index", "2", "shard.index = \"2\": must be an integer from 1 to shard.count"},
      {"/shard/count", 2.5, "shard.count = 2.5: must be an integer >= 1"},
      {"/shard/index", 7, ": index must lie in 1..count"},
      {"/shard/complete", "yes", "shard.complete = \"yes\": must be true or false"},
      {"/shard/problem_file", Json::array(), "shard.problem_file = []: must be a string"},
      {"/shard/problem_document", 1, "shard.problem_document = 1: must be an object"},
      {"/seed", -1, "seed = -1: must be an integer >= 0"},
      {"/hapsyn", "0.1", "hapsyn = \"0.1\": must be an object"},
      {"/hapsyn/version", 1, "hapsyn.version = 1: must be a string"},
      {"/problem", Json::array(), "problem = []: must be an object"},
  };
  for (const Tamper& t : cases) {
    Json edited = pristine;
    edited[Json::json_pointer(t.pointer)] = t.value;
    std::ofstream(result.string()) << edited.dump();
    const Output o = hapsyn_cli("merge " + shares[0] + " " + shares[1] + " --out " + (dir / "merged").string());
    EXPECT_EQ(o.code, 1) << t.pointer << ": " << o.out;
    EXPECT_NE(o.out.find("hapsyn: error: merge: " + result.string() + ": "), std::string::npos)
        << t.pointer << ": " << o.out;
    EXPECT_NE(o.out.find(t.expected), std::string::npos) << t.pointer << ": " << o.out;
    EXPECT_FALSE(fs::exists(dir / "merged" / "result.json")) << t.pointer;
  }
  Json removed = pristine;
  removed["shard"].erase("complete");
  std::ofstream(result.string()) << removed.dump();
  const Output missing = hapsyn_cli("merge " + shares[0] + " " + shares[1] + " --out " + (dir / "merged").string());
  EXPECT_EQ(missing.code, 1) << missing.out;
  EXPECT_NE(missing.out.find(result.string() + ": no shard.complete (true or false; was the file edited?)"), std::string::npos)
      << missing.out;
  std::ofstream(result.string()) << pristine.dump();
  const Output merged = hapsyn_cli("merge " + shares[0] + " " + shares[1] + " --out " + (dir / "merged").string());
  EXPECT_EQ(merged.code, 0) << merged.out;
  fs::remove_all(dir);
}

// A share that holds every task (a grid of one 64-design chunk split three ways) converges on
// its own; its checkpoint is still what merge combines, and the merge is the plain run.
TEST(Cli, AShareHoldingEveryTaskStillMergesToThePlainRun) {
  const fs::path dir = fresh_dir("merge-one-chunk");
  const std::string small = problem("fivebar-gii-coarse.json") + " --quiet --set design.l0.upper=0.01 --set "
                            "design.l1.lower=0.28 --set design.l2.lower=0.28 --set design.r.lower=0.41 --set design.r.upper=0.43";
  const Output plain = hapsyn_cli("run " + small + " --out " + (dir / "plain").string());
  ASSERT_EQ(plain.code, 0) << plain.out;
  std::string all;
  for (int i = 1; i <= 3; ++i) {
    const fs::path share = dir / ("s" + std::to_string(i));
    const Output o = hapsyn_cli("run " + small + " --shard " + std::to_string(i) + "/3 --out " + share.string());
    ASSERT_EQ(o.code, 0) << o.out;
    EXPECT_TRUE(fs::exists(share / "checkpoint.json")) << share;
    all += " " + share.string();
  }
  const Output merged = hapsyn_cli("merge" + all + " --quiet --out " + (dir / "merged").string());
  ASSERT_EQ(merged.code, 0) << merged.out;
  const Json a = read_json(dir / "plain" / "result.json");
  const Json b = read_json(dir / "merged" / "result.json");
  EXPECT_EQ(b["status"], "converged");
  EXPECT_EQ(b["best"], a["best"]);
  EXPECT_FALSE(fs::exists(dir / "merged" / "checkpoint.json"));
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

// ---- trustworthy outputs: never mixed, locked, logged ----

TEST(Cli, ForceReplacesEveryOutputOfTheEarlierRun) {
  const fs::path out = fresh_dir("force");
  ASSERT_EQ(hapsyn_cli("run " + quick_study() + " --quiet --out " + out.string()).code, 0);
  ASSERT_TRUE(fs::exists(out / "samples.csv"));
  // Without --force a finished study stays, and validate says so as run does.
  const Output again = hapsyn_cli("run " + quick_study() + " --quiet --out " + out.string());
  EXPECT_EQ(again.code, 1);
  const std::string finished = "hapsyn: error: output: " + out.string() + " already holds a finished study (";
  EXPECT_NE(again.out.find(finished), std::string::npos) << again.out;
  const Output validate = hapsyn_cli("validate " + quick_study() + " --out " + out.string());
  EXPECT_EQ(validate.code, 0);
  EXPECT_NE(validate.out.find("note: output: " + out.string() + " already holds a finished study ("), std::string::npos)
      << validate.out;
  const Output forced_validate = hapsyn_cli("validate " + quick_study() + " --out " + out.string() + " --force");
  EXPECT_EQ(forced_validate.code, 0);
  EXPECT_EQ(forced_validate.out.find("note:"), std::string::npos) << forced_validate.out;
  // --force without samples: the earlier samples.csv does not survive beside the new result.json.
  const Output forced = hapsyn_cli("run " + quick_study() + " --quiet --force --out " + out.string() +
                                   " --set output.samples_csv=false --set output.maps=false --seed 9");
  ASSERT_EQ(forced.code, 0) << forced.out;
  EXPECT_EQ(read_json(out / "result.json")["seed"], 9);
  EXPECT_FALSE(fs::exists(out / "samples.csv"));
  EXPECT_FALSE(fs::exists(out / "maps.csv"));
  EXPECT_FALSE(has_staging(out));
  fs::remove_all(out);
}

TEST(Cli, ASecondRunIntoALockedDirectoryFailsAtOnce) {
  const fs::path out = fresh_dir("lock");
  fs::create_directories(out);
  const hapsyn::DirectoryLock held(out.string());
  const Output o = hapsyn_cli("run " + quick_study() + " --quiet --out " + out.string());
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.out.find("hapsyn: error: output: " + out.string() + " is in use by another hapsyn run (pid " +
                       std::to_string(::getpid()) + ")"),
            std::string::npos)
      << o.out;
  EXPECT_FALSE(fs::exists(out / "result.json"));
  fs::remove_all(out);
}

TEST(Cli, ASymbolicLinkRunLogIsRefusedAndItsTargetKept) {
  const fs::path out = fresh_dir("loglink");
  ASSERT_EQ(hapsyn_cli("run " + quick_study() + " --quiet --out " + out.string()).code, 0);
  std::ofstream((out / "precious.txt").string()) << "keep";
  fs::remove(out / "run.log");
  fs::create_symlink(out / "precious.txt", out / "run.log");
  const Output o = hapsyn_cli("run " + quick_study() + " --quiet --force --out " + out.string());
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.out.find("hapsyn: error: output: " + (out / "run.log").string() +
                       " is a symbolic link; a run log is never written through one (remove it)"),
            std::string::npos)
      << o.out;
  EXPECT_EQ(read_text(out / "precious.txt"), "keep");
  EXPECT_TRUE(fs::exists(out / "result.json")) << "the refused run leaves the earlier study as it was";
  EXPECT_TRUE(fs::exists(out / "samples.csv"));
  fs::remove_all(out);
}

TEST(Cli, AnOutputNameTakenByADirectoryIsRefusedBeforeTheSolveAndLogged) {
  const fs::path out = fresh_dir("blocked");
  fs::create_directories(out / "samples.csv" / "in-the-way");
  const Output o = hapsyn_cli("run " + quick_study() + " --quiet --out " + out.string());
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.out.find("output: " + (out / "samples.csv").string() +
                       " is a directory, where a run writes a file; remove it, or choose another --out"),
            std::string::npos)
      << o.out;
  EXPECT_FALSE(fs::exists(out / "result.json"));
  EXPECT_FALSE(fs::exists(out / "maps.csv"));
  EXPECT_FALSE(has_staging(out));
  fs::remove_all(out);
}

TEST(Cli, AStoppedRunKeepsItsCheckpointAndResumes) {
  const fs::path out = fresh_dir("stopped");
  // A GA long enough to be stopped by SIGINT, as Ctrl-C or a job scheduler sends.
  const std::string study = problem("fivebar-gii-ga-coarse.json") +
                            " --set solver.options.generations=1000000 --set solver.options.stall_generations=1000000"
                            " --set solver.options.checkpoint_every=1 --threads 2 --quiet --out " + out.string();
  // SIGINT once the first checkpoint is on disk (after the first generation).
  const Output first = hapsyn_interrupted_when("[ -f " + (out / "checkpoint.json").string() + " ]", "run " + study);
  EXPECT_EQ(first.code, 4) << first.out;
  EXPECT_NE(first.out.find("stopped; resume with: hapsyn run " + problem("fivebar-gii-ga-coarse.json") +
                           " --set solver.options.generations=1000000"),
            std::string::npos)
      << first.out;
  EXPECT_NE(first.out.find(" --resume\n"), std::string::npos) << first.out;
  EXPECT_EQ(read_json(out / "result.json")["status"], "stopped");
  EXPECT_TRUE(fs::exists(out / "checkpoint.json"));
  // A stopped study is not finished: --resume continues it; a plain run must choose.
  const Output plain = hapsyn_cli("run " + study);
  EXPECT_EQ(plain.code, 1);
  EXPECT_NE(plain.out.find("holds a stopped study"), std::string::npos) << plain.out;
  // SIGINT once the resumed run has said so in its log.
  const Output resumed =
      hapsyn_interrupted_when("grep -q \"ga: resuming\" " + (out / "run.log").string(), "run " + study + " --resume");
  EXPECT_EQ(resumed.code, 4) << resumed.out;
  EXPECT_EQ(read_json(out / "result.json")["status"], "stopped");
  EXPECT_NE(read_text(out / "run.log").find("resume"), std::string::npos);
  fs::remove_all(out);
}

TEST(Cli, AParetoRunWritesItsFrontAsCsv) {
  const fs::path out = fresh_dir("front");
  const Output o = hapsyn_cli("run " + problem("fivebar-pareto-weighted-sum.json") + " --quiet --out " + out.string() +
                              " --set solver.options.count=3 --set design.l0.step=0.05 --set design.l1.step=0.05"
                              " --set design.l2.step=0.05 --set design.r.step=0.05 --set design.l1.lower=0.05"
                              " --set design.l2.lower=0.05 --set indicators={}");
  ASSERT_EQ(o.code, 0) << o.out;
  const Json result = read_json(out / "result.json");
  ASSERT_TRUE(result.contains("front"));
  EXPECT_EQ(result["files"]["front"], "front.csv");
  EXPECT_EQ(count_lines(out / "front.csv"), static_cast<long>(result["front"].size()) + 1);
  std::ifstream csv((out / "front.csv").string());
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "design.l0,design.l1,design.l2,design.r,gii,gdi");
  fs::remove_all(out);
}

// Issue 51: front.csv of a URDF study listed all 42 file parameters before the 2 freed ones;
// it lists the free components, and result.json the fixed ones once.
TEST(Cli, FrontCsvListsTheFreeComponentsAndResultJsonTheFixedOnesOnce) {
  const fs::path out = fresh_dir("front-fixed");
  const Output o = hapsyn_cli("run " + problem("fivebar-pareto-weighted-sum.json") + " --quiet --out " + out.string() +
                              " --set solver.options.count=3 --set 'design.l0={\"value\": 0.0}' --set design.l1.step=0.05"
                              " --set design.l2.step=0.05 --set design.r.step=0.05 --set design.l1.lower=0.05"
                              " --set design.l2.lower=0.05 --set indicators={}");
  ASSERT_EQ(o.code, 0) << o.out;
  const Json result = read_json(out / "result.json");
  std::ifstream csv((out / "front.csv").string());
  std::string header, row;
  std::getline(csv, header);
  EXPECT_EQ(header, "design.l1,design.l2,design.r,gii,gdi");
  std::getline(csv, row);
  EXPECT_EQ(std::count(row.begin(), row.end(), ','), 4) << row;
  EXPECT_EQ(result["design_fixed"], (Json{{"l0", 0.0}}));
  // Each point lists the free variables; the fixed one is in design_fixed only.
  for (const Json& point : result["front"]) {
    EXPECT_FALSE(point["design"].contains("l0")) << point.dump();
    EXPECT_TRUE(point["design"].contains("l1") && point["design"].contains("l2") && point["design"].contains("r"))
        << point.dump();
  }
  fs::remove_all(out);
}

// A front of dozens of points printed every one of them; the console shows 11 spread along it,
// the first and the last included, and says where the rest is.
TEST(Cli, ALongFrontIsSummarisedOnTheConsole) {
  const fs::path out = fresh_dir("long-front");
  const Output o = hapsyn_cli("run " + problem("fivebar-pareto-nsga2.json") + " --out " + out.string() +
                              " --set solver.options.generations=30 --set solver.options.population=40");
  ASSERT_EQ(o.code, 0) << o.out;
  const Json result = read_json(out / "result.json");
  const std::size_t n = result["front"].size();
  ASSERT_GT(n, 11u) << o.out;
  EXPECT_NE(o.out.find("front: " + std::to_string(n) + " non-dominated points (11 shown; all in front.csv)"),
            std::string::npos)
      << o.out;
  std::size_t designs = 0;
  for (std::size_t at = o.out.find("  design:"); at != std::string::npos; at = o.out.find("  design:", at + 1)) ++designs;
  EXPECT_EQ(designs, 11u) << o.out;
  const auto shown = [&](const Json& point) {
    std::ostringstream gii;
    gii << std::setprecision(6) << point["objectives"]["gii"].get<double>();
    return o.out.find("gii = " + gii.str()) != std::string::npos;
  };
  EXPECT_TRUE(shown(result["front"][0])) << o.out;
  EXPECT_TRUE(shown(result["front"][n - 1])) << o.out;
  fs::remove_all(out);
}

TEST(Cli, SeedsMustBeWholeNumbers) {
  for (const std::string& command : {"run " + quick_study() + " --seed", "sweep " + quick_study() + " --vary threads=1 --seed",
                                     "compare " + problem("fivebar-gii-coarse.json") + " --seed"}) {
    for (const std::string seed : {"-1", "1.5", "18446744073709551616"}) {
      const Output o = hapsyn_cli(command + " " + seed);
      EXPECT_EQ(o.code, 2) << command << " " << seed << "\n" << o.out;
      EXPECT_NE(o.out.find("--seed " + seed + ": must be a whole number in [0, 18446744073709551615]"), std::string::npos)
          << o.out;
    }
  }
}

TEST(Cli, TooManyThreadsAreCappedWithAWarning) {
  const fs::path out = fresh_dir("threads");
  const Output o = hapsyn_cli("run " + quick_study() + " --quiet --threads 100000 --out " + out.string());
  ASSERT_EQ(o.code, 0) << o.out;
  EXPECT_NE(o.out.find("hapsyn: warning: --threads 100000: capped to "), std::string::npos) << o.out;
  EXPECT_NE(read_text(out / "run.log").find("warning: --threads 100000: capped to "), std::string::npos);
  EXPECT_LE(read_json(out / "result.json")["threads"].get<int>(), 1024);
  const Output file = hapsyn_cli("validate " + quick_study() + " --set threads=3000000000");
  EXPECT_EQ(file.code, 1);
  EXPECT_NE(file.out.find("threads = 3000000000"), std::string::npos) << file.out;
  fs::remove_all(out);
}

// "--csv export.csv" (no directory part) once failed with "cannot create : No such file or
// directory": the error code of the directory test was reported (found by the csv attack class).
TEST(Cli, SceneCsvWritesToABareRelativeFileName) {
  const fs::path dir = fresh_dir("csv-relative");
  fs::create_directories(dir);
  const std::string hapsyn = std::string(HAPSYN_BINARY_DIR) + "/bin/hapsyn";
  for (const std::string name : {"export.csv", "./dot.csv", "new/dir/nested.csv"}) {
    const std::string command = "cd " + dir.string() + " && " + hapsyn + " scene " + problem("fivebar-gii-coarse.json") +
                                " --csv " + name + " >/dev/null 2>&1";
    EXPECT_EQ(std::system(command.c_str()), 0) << name;
    EXPECT_EQ(count_lines((dir / name).string()), 442) << name;  // a header and the 441 samples
  }
  fs::remove_all(dir);
}

// Issue 53, cause 7: a box centred at the edge of the doubles once exported samples at inf with
// exit 0; a scene's samples are checked for finite values before anything uses or writes them.
TEST(Cli, SceneSamplesBeyondTheDoublesAreRefusedBeforeTheyAreWritten) {
  const fs::path dir = fresh_dir("scene-inf");
  fs::create_directories(dir);
  const fs::path problem_file = dir / "inf.json";
  std::ofstream(problem_file.string()) << R"({"scene": {"plugin": "box", "options": {"dimension": 2,
      "center": [1.7e308, 0], "size": [1e308, 1e308], "step": 1e307}}})";
  const Output scene = hapsyn_cli("scene " + problem_file.string() + " --csv " + (dir / "inf.csv").string());
  EXPECT_EQ(scene.code, 1) << scene.out;
  EXPECT_NE(scene.out.find("hapsyn: error: box: sample 6: x = inf: every pose coordinate must be finite"), std::string::npos)
      << scene.out;
  EXPECT_FALSE(fs::exists(dir / "inf.csv"));
  const Output validate = hapsyn_cli("validate " + problem("fivebar-gii-coarse.json") +
                                     " --set 'scene={\"plugin\": \"box\", \"options\": {\"dimension\": 2, \"center\": "
                                     "[1.7e308, 0], \"size\": [1e308, 1e308], \"step\": 1e307}}'");
  EXPECT_EQ(validate.code, 1) << validate.out;
  EXPECT_NE(validate.out.find("box: sample 6: x = inf"), std::string::npos) << validate.out;
  fs::remove_all(dir);
}

// Issue 51: designs printed as "0.30000000000000004 m"; the console shows ten significant digits,
// result.json keeps every one.
TEST(Cli, ConsoleShowsDesignValuesAtTenDigitsAndResultJsonKeepsThemAll) {
  const fs::path dir = fresh_dir("design-digits");
  const Output o = hapsyn_cli("run " + problem("fivebar-table2-best-gii.json") +
                              " --set design.l2.value=0.29000000000000004 --out " + dir.string());
  ASSERT_EQ(o.code, 0) << o.out;
  EXPECT_NE(o.out.find("l2 = 0.29 m"), std::string::npos) << o.out;
  EXPECT_EQ(o.out.find("0.29000000000000004"), std::string::npos) << o.out;
  EXPECT_EQ(read_json(dir / "result.json")["best"]["design"]["l2"].get<double>(), 0.29000000000000004);
  // A refusal that turns on the last digit shows it: 0.30000000000000004 is beyond 0.3.
  const Output beyond = hapsyn_cli("validate " + problem("fivebar-table2-best-gii.json") +
                                   " --set design.l2.value=0.30000000000000004");
  EXPECT_EQ(beyond.code, 1) << beyond.out;
  EXPECT_NE(beyond.out.find("design.l2.value = 0.30000000000000004: must lie within the bounds [0.01, 0.3]"),
            std::string::npos)
      << beyond.out;
  fs::remove_all(dir);
}

// Issue 51: fixing a URDF parameter to a new value was refused unless bounds were given too (its
// default bounds are [nominal, nominal]); the value now moves it, as widened bounds do.
TEST(Cli, AFixedValueMovesAFileParameter) {
  const fs::path dir = fresh_dir("fixed-value");
  const auto gii = [&](const std::string& design, const std::string& name) {
    const Output o = hapsyn_cli("run " + problem("phantom3r-gii-box.json") + " --quiet --set solver.plugin=evaluate " +
                                "--set 'design=" + design + "' --out " + (dir / name).string());
    EXPECT_EQ(o.code, 0) << o.out;
    return read_json(dir / name / "result.json")["best"]["objectives"]["gii"].get<double>();
  };
  const double nominal = gii("{}", "nominal");
  const double moved = gii(R"({"elbow_joint:x": {"value": 0.2}})", "moved");
  const double widened = gii(R"({"elbow_joint:x": {"value": 0.2, "lower": 0.0, "upper": 1.0}})", "widened");
  EXPECT_EQ(moved, widened);
  EXPECT_NE(moved, nominal);
  const Output result = hapsyn_cli("validate " + problem("phantom3r-gii-box.json") +
                                   " --set 'design={\"mass_scale\": {\"value\": -1}}'");
  EXPECT_EQ(result.code, 1) << result.out;
  EXPECT_NE(result.out.find("design.mass_scale.value = -1: must lie within the mechanism's limits ["), std::string::npos)
      << result.out;
  fs::remove_all(dir);
}

// Issue 51: coverage on a point_list scene failed with "per-sample attribute 'M_v' requested" and
// no word of who requested it; the objective and where to read what it needs are named.
TEST(Cli, ASceneAttributeAMetricNeedsNamesTheObjective) {
  const Output o = hapsyn_cli("validate " + problem("haptic6r-evaluate.json") +
                              " --set 'scene={\"plugin\": \"point_list\", \"options\": {\"file\": "
                              "\"point_list/example_planar.csv\"}}'");
  EXPECT_EQ(o.code, 1) << o.out;
  EXPECT_NE(o.out.find("point_list: per-sample attribute 'M_v' requested"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("; 'M_v' is needed by objectives[1], objectives[4] (metric 'coverage': `hapsyn describe "
                       "coverage` names the scene it needs)"),
            std::string::npos)
      << o.out;
}

// An objective named with a comma or a quote once wrote a maps.csv whose header had one column
// more than its rows (a red-team finding).
TEST(Cli, ObjectiveNamesThatWouldBreakCsvColumnsAreRefused) {
  for (const std::string name : {"g,ii", "g\\\"ii"}) {
    const Output o = hapsyn_cli("validate " + problem("fivebar-gii-coarse.json") + " --set 'objectives[0].name=\"" + name + "\"'");
    EXPECT_EQ(o.code, 1) << o.out;
    EXPECT_NE(o.out.find(": may not contain a comma, a double quote or a line break (it names CSV columns)"),
              std::string::npos)
        << o.out;
  }
}

// Issue 51: `run` of a Pareto study with plots: true wrote only front.csv; it draws the front.
TEST(Cli, AParetoRunWithPlotsDrawsItsFront) {
  const fs::path dir = fresh_dir("front-plot");
  const Output o = hapsyn_cli("run " + problem("fivebar-pareto-nbi.json") + " --quiet --set output.plots=true --out " +
                              dir.string());
  ASSERT_EQ(o.code, 0) << o.out;
  const Json result = read_json(dir / "result.json");
  EXPECT_EQ(count_lines((dir / "front.dat").string()), static_cast<long>(result["front"].size()) + 1);
  std::ifstream script_in((dir / "front.gp").string());
  const std::string script((std::istreambuf_iterator<char>(script_in)), std::istreambuf_iterator<char>());
  EXPECT_NE(script.find("set xlabel 'gii (maximize)'"), std::string::npos) << script;
  EXPECT_NE(script.find("set ylabel 'gdi (maximize)'"), std::string::npos) << script;
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    EXPECT_EQ(result["files"]["front_plot"], "front.png, front.svg");
    EXPECT_GT(fs::file_size(dir / "front.png"), 1000u);
  }
  fs::remove_all(dir);
}

TEST(Cli, PathsTheFileSystemRefusesAreClearErrors) {
  const fs::path dir = fresh_dir("paths");
  fs::create_directories(dir);
  const Output csv = hapsyn_cli("scene " + problem("fivebar-gii-coarse.json") + " --csv " + dir.string());
  EXPECT_EQ(csv.code, 1);
  EXPECT_NE(csv.out.find("hapsyn: error: scene: --csv " + dir.string() + " is a directory; give a file name, e.g. " +
                         (dir / "samples.csv").string()),
            std::string::npos)
      << csv.out;
  const std::string too_long = (dir / std::string(300, 'x')).string();
  const Output out = hapsyn_cli("run " + quick_study() + " --quiet --out " + too_long);
  EXPECT_EQ(out.code, 1) << out.out;
  EXPECT_NE(out.out.find("hapsyn: error: output: the output directory " + too_long + ": File name too long"),
            std::string::npos)
      << out.out;
  const Output deep = hapsyn_cli("validate " + quick_study() + " --out " + (dir / "new" / std::string(300, 'y')).string());
  EXPECT_EQ(deep.code, 1) << deep.out;
  EXPECT_NE(deep.out.find("characters, more than the 255 its file system allows"), std::string::npos) << deep.out;
  const Output unwritable = hapsyn_cli("validate " + quick_study() + " --out /proc/hapsyn-cannot-write");
  EXPECT_EQ(unwritable.code, 1) << unwritable.out;
  EXPECT_NE(unwritable.out.find("hapsyn: error: output: cannot create the output directory /proc/hapsyn-cannot-write: "
                                "/proc is not writable"),
            std::string::npos)
      << unwritable.out;
  fs::remove_all(dir);
}

TEST(Cli, AKilledForcedRunLeavesNoResultOfEitherRun) {
  const fs::path out = fresh_dir("killed");
  ASSERT_EQ(hapsyn_cli("run " + quick_study() + " --quiet --out " + out.string()).code, 0);
  // SIGKILL while the forced run solves: no handler, no cleanup.
  hapsyn_test_stopped("timeout -s KILL 2 ", "run " + problem("fivebar-gii-ga-coarse.json") +
                                                " --set solver.options.generations=1000000"
                                                " --set solver.options.stall_generations=1000000 --threads 2 --quiet"
                                                " --force --out " + out.string());
  EXPECT_FALSE(fs::exists(out / "result.json"));
  EXPECT_FALSE(fs::exists(out / "samples.csv")) << "no file of the earlier run beside a later one";
  EXPECT_FALSE(fs::exists(out / "maps.csv"));
  EXPECT_TRUE(fs::exists(out / "run.log"));
  // Nothing finished is there: the next run needs no --force and leaves no staging behind.
  const Output next = hapsyn_cli("run " + quick_study() + " --quiet --out " + out.string());
  EXPECT_EQ(next.code, 0) << next.out;
  EXPECT_TRUE(fs::exists(out / "samples.csv"));
  EXPECT_FALSE(has_staging(out));
  fs::remove_all(out);
}

#ifdef HAPSYN_TEST_NO_MPI
// A build without MPI (HAPSYN_WITH_MPI=OFF, as the sanitizer build is): started by mpirun (the
// launcher's environment says so), `hapsyn run` refuses instead of running the whole study on
// every rank into the same directory.
TEST(Cli, RunStartedByMpirunInABuildWithoutMpiSaysSo) {
  const fs::path out = fresh_dir("no-mpi");
  const Output o = hapsyn_test_stopped("OMPI_COMM_WORLD_SIZE=3 ", "run " + problem("fivebar-gii-coarse.json") +
                                                                      " --out " + out.string() + " --quiet");
  EXPECT_EQ(o.code, 1) << o.out;
  EXPECT_NE(o.out.find("mpi: this hapsyn was built without MPI (HAPSYN_WITH_MPI=OFF)"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("--shard i/N"), std::string::npos) << o.out;
  EXPECT_FALSE(fs::exists(out / "result.json"));
}
#endif
