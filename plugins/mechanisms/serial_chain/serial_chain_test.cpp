// Tests of the serial_chain mechanism: its design variables and constraints, option errors,
// the classification, the frames it maps samples through, and the cross-check against the
// closed-form haptic6r on the human-arm workspace.
#include "serial_chain.hpp"

#include "haptic6r.hpp"
#include "haptic6r_comparison.hpp"
#include "test_support.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/options.hpp>
#include <hapsyn/internal/study.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <random>

using namespace hapsyn;
using namespace hapsyn::plugins;

using namespace hapsyn::plugins::test_support;

TEST(LinearConstraints, ParsesSumsCoefficientsAndChains) {
  const std::vector<std::string> names = {"l1", "l2", "size[0]", "size[1]", "size[2]"};
  const auto g = parse_linear_constraints({"l1 + l2 <= 0.9", "2*l1 - 0.5 * l2 >= -0.1 + 0.2", "size[0] >= size[1] >= size[2]"},
                                          names, "serial_chain", "options.constraints");
  ASSERT_EQ(g.size(), 4u);
  const double p[5] = {0.3, 0.5, 3, 2, 2};
  EXPECT_NEAR(g[0].evaluate(p), 0.3 + 0.5 - 0.9, 1e-15);
  EXPECT_NEAR(g[1].evaluate(p), 0.1 - (2 * 0.3 - 0.5 * 0.5), 1e-15);
  EXPECT_DOUBLE_EQ(g[2].evaluate(p), 2 - 3);  // size[1] - size[0] <= 0
  EXPECT_DOUBLE_EQ(g[3].evaluate(p), 0.0);
  EXPECT_EQ(g[2].name, "constraints[2].0");
  EXPECT_EQ(g[3].description, "size[1] >= size[2]");
}

TEST(LinearConstraints, ErrorsNameTheConstraintTheValueAndTheRule) {
  const std::vector<std::string> names = {"l1", "l2"};
  const auto parse = [&](const std::string& text) {
    return test::error_of([&] { parse_linear_constraints({text}, names, "serial_chain", "options.constraints"); });
  };
  EXPECT_EQ(parse("l1 + l3 <= 1"),
            "serial_chain: options.constraints[0] = \"l1 + l3 <= 1\": unknown design variable 'l3' (did you mean 'l1'?); "
            "the mechanism's design variables are: l1, l2");
  EXPECT_NE(parse("l1 + l2").find("a constraint needs '<=' or '>='"), std::string::npos);
  EXPECT_NE(parse("l1 + l2 < 1").find("expected '<=', '>=' or the end of the constraint (at character 9)"), std::string::npos);
  EXPECT_NE(parse("l1 - l1 <= 1").find("has no design variable left"), std::string::npos);
  EXPECT_NE(parse("l1 * 2 <= 1").find("expected '<=', '>='"), std::string::npos);
  EXPECT_NE(parse("l1 <= 1e999").find("numbers must be finite"), std::string::npos);
  // Issue 53, cause 7: finite numbers whose sum overflows (every design would be infeasible).
  EXPECT_EQ(parse("l1 - 1e308 <= 1e308"),
            "serial_chain: options.constraints[0] = \"l1 - 1e308 <= 1e308\": 'l1 - 1e308 <= 1e308': its constant terms "
            "add up to inf: they must sum to a finite number");
  EXPECT_EQ(parse("1e308*l2 + 1e308*l2 <= 1"),
            "serial_chain: options.constraints[0] = \"1e308*l2 + 1e308*l2 <= 1\": '1e308*l2 + 1e308*l2 <= 1': the "
            "coefficients of 'l2' add up to inf: they must sum to a finite number");
}

TEST(SerialChain, DesignVariablesAreTheChainParametersFixedAtTheirValues) {
  const SerialChain m = serial_chain(haptic6r_dh_options());
  const auto vars = m.variables();
  std::vector<std::string> names;
  for (const auto& v : vars) names.push_back(v.name);
  for (const char* expected : {"l1", "l2", "l3", "l4", "l5", "mass_scale", "size", "gear"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
  }
  for (const auto& v : vars) {
    EXPECT_EQ(v.default_lower, v.default_upper) << v.name << " must be fixed unless the design section frees it";
  }
  const auto l1 = std::find_if(vars.begin(), vars.end(), [](const VariableDecl& v) { return v.name == "l1"; });
  EXPECT_DOUBLE_EQ(l1->default_lower[0], 0.45);
  ASSERT_EQ(l1->hard_lower.size(), 1u);
  EXPECT_EQ(l1->hard_lower[0], 0.0);
  const auto size = std::find_if(vars.begin(), vars.end(), [](const VariableDecl& v) { return v.name == "size"; });
  EXPECT_EQ(size->size, 6);
  EXPECT_TRUE(size->integer);
  EXPECT_EQ(size->default_lower, (std::vector<double>{3, 3, 2, 2, 1, 1}));
}

TEST(SerialChain, StudyErrorsNameTheParameterTheValueAndTheRule) {
  Json study = {{"name", "t"},
                {"mechanism", {{"plugin", "serial_chain"}, {"options", haptic6r_dh_options()}}},
                {"scene", {{"plugin", "human_arm"}, {"options", {{"lattice_step", 0.2}, {"orientations", 30}, {"joint3_steps", 5}, {"cache", false}}}}},
                {"objectives", {{{"metric", "coverage"}}}},
                {"solver", {{"plugin", "evaluate"}}}};
  Json unknown = study;
  unknown["design"] = {{"l7", {{"lower", 0.3}, {"upper", 0.6}}}};
  const std::string m1 = test::error_of([&] { load_study(unknown, test::registry()); });
  EXPECT_NE(m1.find("design.l7: unknown design variable (did you mean 'l1'?); the mechanism's variables are: "), std::string::npos) << m1;
  EXPECT_NE(m1.find("l5"), std::string::npos) << m1;
  Json negative = study;
  negative["design"] = {{"l1", {{"lower", -0.1}, {"upper", 0.6}}}};
  const std::string m2 = test::error_of([&] { load_study(negative, test::registry()); });
  EXPECT_NE(m2.find("design.l1.lower = -0.1: must be >= 0 (the mechanism's limit for l1)"), std::string::npos) << m2;
  Json constraint = study;
  constraint["mechanism"]["options"]["constraints"] = {"l1 + l2 <= 0.9", "siz[0] >= size[1]"};
  const std::string m3 = test::error_of([&] { load_study(constraint, test::registry()); });
  EXPECT_NE(m3.find("options.constraints[1] = \"siz[0] >= size[1]\": unknown design variable 'siz[0]' (did you mean 'size[0]'?)"),
            std::string::npos)
      << m3;
}

TEST(SerialChain, OptionErrorsNameTheOptionTheValueAndTheRule) {
  const auto error = [](Json o) { return test::error_of([&] { serial_chain(o); }); };
  Json both = haptic6r_dh_options();
  both["urdf"] = "serial_chain/haptic6r.urdf";
  EXPECT_NE(error(both).find("give either urdf or dh_file, not both"), std::string::npos);
  EXPECT_NE(error(Json::object()).find("problem: options.urdf = \"\": give the chain as options.urdf or options.dh_file"), std::string::npos);
  Json no_tip = haptic6r_urdf_options();
  no_tip.erase("tip_link");
  EXPECT_NE(error(no_tip).find("options.tip_link = \"\": a URDF chain needs base_link and tip_link"), std::string::npos);
  Json home = haptic6r_dh_options();
  home["home"] = {0, 0, 0};
  EXPECT_NE(error(home).find("options.home has 3 values: the chain has 6 joints"), std::string::npos);
  home["home"] = {0, 90, 0, -90, 90, 0};
  EXPECT_NE(error(home).find("options.home[3] = -90: outside joint"), std::string::npos);
  Json codes = haptic6r_dh_options();
  codes["actuator_size"] = {3, 3, 2, 2, 1, 4};
  EXPECT_NE(error(codes).find("options.actuator_size[5] = 4: must be in 1..3"), std::string::npos);
  Json table = haptic6r_dh_options();
  table["actuator_file"] = "serial_chain/haptic6r_dh.json";  // a file of another format
  EXPECT_NE(error(table).find("serial_chain: options.actuator_file: "), std::string::npos) << error(table);
  EXPECT_NE(error(table).find("haptic6r_dh.json: format = \"hapsyn-dh\": must be"), std::string::npos) << error(table);
  Json missing = haptic6r_dh_options();
  missing["dh_file"] = "no/such.json";
  EXPECT_NE(error(missing).find("options.dh_file = \"no/such.json\": no such file"), std::string::npos);
}

TEST(SerialChain, FoldFixedLinksIsOnlyForAUrdf) {
  Json o = haptic6r_dh_options();
  o["fold_fixed_links"] = false;
  const std::string e = test::error_of([&] { serial_chain(o); });
  EXPECT_NE(e.find("options.fold_fixed_links = false: only for a URDF (a DH table has no fixed links)"), std::string::npos) << e;
}

#ifdef HAPSYN_HAVE_URDFDOM
// The summary (run header, result.json, describe) names what each body carries; switched off,
// nothing is folded and nothing listed.
TEST(SerialChain, SummaryListsTheFoldedLinksPerBody) {
  const std::string path = ::testing::TempDir() + "serial_chain_test_folded.urdf";
  std::ofstream(path) << R"(<?xml version="1.0"?>
<robot name="t">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="5" velocity="2"/></joint>
  <link name="l1"><inertial><origin xyz="0.1 0 0"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="5" velocity="2"/></joint>
  <link name="l2"/>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="5" velocity="2"/></joint>
  <link name="l3"><inertial><origin xyz="0.1 0 0"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="tip_joint" type="fixed"><parent link="l3"/><child link="tip"/><origin xyz="0.2 0 0"/></joint>
  <link name="tip"/>
  <joint name="payload_mount" type="fixed"><parent link="l1"/><child link="payload"/><origin xyz="0.1 0 0.05"/></joint>
  <link name="payload"><inertial><origin xyz="0 0 0"/><mass value="0.5"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>
  <joint name="grip_mount" type="fixed"><parent link="tip"/><child link="gripper"/><origin xyz="0 0 0.01"/></joint>
  <link name="gripper"><inertial><origin xyz="0 0 0.02"/><mass value="0.4"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>
  <joint name="finger_mount" type="fixed"><parent link="gripper"/><child link="finger_left"/><origin xyz="0 0.01 0.04"/></joint>
  <link name="finger_left"><inertial><origin xyz="0 0 0.01"/><mass value="0.05"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial></link>
</robot>
)";
  Json o{{"urdf", path}, {"base_link", "base"}, {"tip_link", "tip"}, {"task", "position"}};
  const std::string on = serial_chain(o).summary();
  EXPECT_NE(on.find("3 moving joints base -> tip: j1 (revolute), j2 (revolute), j3 (revolute); folded: payload -> l1; "
                    "folded: gripper, finger_left -> l3; task position"),
            std::string::npos)
      << on;
  const SerialChain folding = serial_chain(o);
  const auto variables = folding.variables();
  const auto named = [&](const std::string& name) {
    return std::any_of(variables.begin(), variables.end(), [&](const VariableDecl& v) { return v.name == name; });
  };
  EXPECT_TRUE(named("payload:mass") && named("gripper:mass") && named("finger_left:mass"));
  o["fold_fixed_links"] = false;
  const std::string off = serial_chain(o).summary();
  EXPECT_EQ(off.find("folded"), std::string::npos) << off;
  EXPECT_NE(off.find("j3 (revolute); task position"), std::string::npos) << off;
}

TEST(SerialChain, ThreeJointChainRefusesThePoseTask) {
  const std::string m = test::error_of([] {
    serial_chain(Json{{"urdf", "serial_chain/phantom_3r.urdf"}, {"base_link", "base_link"}, {"tip_link", "stylus_tip"}});
  });
  EXPECT_NE(m.find("options.task = \"pose\": matches 6 task rows, but the chain has only 3 joints"), std::string::npos) << m;
}
#endif  // HAPSYN_HAVE_URDFDOM

TEST(SerialChain, SolvedSamplesReproduceTheTargetThroughBaseAndToolFrames) {
  Json o = haptic6r_dh_options();
  o["base_xyz"] = {0.1, -0.2, 0.3};
  o["base_rpy"] = {10, -20, 30};
  o["tool_xyz"] = {0.0, 0.0, 0.05};
  o["tool_rpy"] = {0, 0, 45};
  const SerialChain m = serial_chain(o);
  const auto design = nominal_design(m);
  const auto model = m.build(design.data());
  const auto& chain = static_cast<const SerialChainModel&>(*model).chain();
  // A target made from a configuration: T_S^P = T_S^B T_B^E(q) T_E^P, computed independently.
  const auto rpy = [](double r, double p, double y) {
    return (Eigen::AngleAxisd(y * kPi / 180, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(p * kPi / 180, Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(r * kPi / 180, Eigen::Vector3d::UnitX()))
        .toRotationMatrix();
  };
  Eigen::Isometry3d scene_base = Eigen::Isometry3d::Identity(), tip_tool = Eigen::Isometry3d::Identity();
  scene_base.linear() = rpy(10, -20, 30);
  scene_base.translation() << 0.1, -0.2, 0.3;
  tip_tool.linear() = rpy(0, 0, 45);
  tip_tool.translation() << 0, 0, 0.05;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-2.5, 2.5);
  int reached = 0;
  for (int k = 0; k < 50; ++k) {
    JointVector q(6);
    q << u(rng), u(rng), u(rng), 0.3 + 0.1 * std::abs(u(rng)), u(rng), u(rng);
    ChainFrames f;
    chain_frames(chain, q.data(), f);
    const SampleSet scene = one_pose_scene(scene_base * f.tip * tip_tool);
    const SampleQuantities out = solve_one(*model, m, scene, 0);
    ASSERT_TRUE(out.status == SampleStatus::kReachable || out.status == SampleStatus::kSingular) << k;
    ChainFrames g;
    chain_frames(chain, out.q.data(), g);
    const Eigen::Isometry3d reached_pose = scene_base * g.tip * tip_tool;
    EXPECT_LT((reached_pose.translation() - scene.poses.row(0).head<3>().transpose()).norm(), 1e-9);
    EXPECT_LT((reached_pose.linear() - (scene_base * f.tip * tip_tool).linear()).norm(), 1e-9);
    reached += out.status == SampleStatus::kReachable;
  }
  EXPECT_GE(reached, 45);
}

TEST(SerialChain, SegmentsRunFromTheBaseThroughTheJointsToTheToolPoint) {
  Json o = haptic6r_dh_options();
  o["base_xyz"] = {0.1, -0.2, 0.3};
  o["tool_xyz"] = {0.0, 0.0, 0.05};
  const SerialChain m = serial_chain(o);
  const auto design = nominal_design(m);
  const auto model = m.build(design.data());
  const auto& chain = static_cast<const SerialChainModel&>(*model).chain();
  auto scratch = m.make_scratch();
  JointVector q(6);
  q << 0.3, -0.7, 1.1, 0.9, -0.4, 0.6;
  ChainFrames f;
  chain_frames(chain, q.data(), f);
  Eigen::Isometry3d scene_base = Eigen::Isometry3d::Identity(), tip_tool = Eigen::Isometry3d::Identity();
  scene_base.translation() << 0.1, -0.2, 0.3;
  tip_tool.translation() << 0, 0, 0.05;
  const SampleSet scene = one_pose_scene(scene_base * f.tip * tip_tool);
  const std::vector<Segment> drawn = model->segments(scene, 0, *scratch);
  ASSERT_EQ(drawn.size(), 1u);
  const auto& p = drawn[0].points;
  ASSERT_EQ(p.size(), 9u);  // base, 6 joints, tip, tool point
  EXPECT_LT((p.front() - Eigen::Vector3d(0.1, -0.2, 0.3)).norm(), 1e-12);
  EXPECT_LT((p.back() - scene.poses.row(0).head<3>().transpose()).norm(), 1e-9);
  EXPECT_NEAR((p[8] - p[7]).norm(), 0.05, 1e-9);  // the tool offset
  const SampleSet far = one_pose_scene(Eigen::Isometry3d(Eigen::Translation3d(10.0, 10.0, 10.0)));
  EXPECT_TRUE(model->segments(far, 0, *scratch).empty());
}

TEST(SerialChain, ClassifiesUnreachableSingularAndLimitSamplesNeverNaN) {
  const SerialChain m = serial_chain(haptic6r_dh_options());
  const auto design = nominal_design(m);
  const auto model = m.build(design.data());
  const auto& chain = static_cast<const SerialChainModel&>(*model).chain();
  // Far beyond the reach.
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() << 10, 0, 0;
  EXPECT_EQ(solve_one(*model, m, one_pose_scene(far), 0).status, SampleStatus::kUnreachable);
  // SCARA stretched (q2 = 0) is a singular configuration of the haptic 6R.
  JointVector q(6);
  q << 0.3, 0.0, 0.2, 1.0, 0.5, 0.1;
  ChainFrames f;
  chain_frames(chain, q.data(), f);
  const SampleQuantities s = solve_one(*model, m, one_pose_scene(f.tip), 0);
  EXPECT_EQ(s.status, SampleStatus::kSingular);
  for (int i = 0; i < s.q.size(); ++i) EXPECT_TRUE(std::isfinite(s.q(i)));
  // Only reachable with q4 < 0, outside joint 4's limits [0, 180] deg: every mirror solution of
  // this pose has q4 < 0 or violates nothing else, so it is kInvalid (joint limit).
  q << 0.3, 1.0, 0.2, -0.8, 0.5, 0.1;
  chain_frames(chain, q.data(), f);
  const SampleStatus limit = solve_one(*model, m, one_pose_scene(f.tip), 0).status;
  EXPECT_TRUE(limit == SampleStatus::kInvalid || limit == SampleStatus::kReachable);
}

// The acceptance cross-check: the haptic 6R as a serial_chain (DH table and URDF) against the
// closed-form haptic6r, sample by sample, on a human-arm workspace. serial_chain's own closed form
// (ik.solver auto) sees every solution too, so both pick the same configuration on every sample.
class SerialChainHaptic6R : public ::testing::TestWithParam<const char*> {};

TEST_P(SerialChainHaptic6R, ClosedFormPicksTheSameConfigurationOnEverySample) {
  const Json options = std::string(GetParam()) == "dh" ? haptic6r_dh_options() : haptic6r_urdf_options();
  const Haptic6RComparison r = compare_with_haptic6r(options, "auto", 8, coarse_human_arm(), GetParam());
  EXPECT_EQ(r.same_share(), 1.0);
  EXPECT_EQ(r.farther, 0);
  EXPECT_EQ(r.missed, 0);
}

// The numerical IK: where it picks another configuration, it is because it did not see every
// solution (never a closer one).
TEST_P(SerialChainHaptic6R, NumericalAgreesWhereBothPickTheSameConfiguration) {
  const Json options = std::string(GetParam()) == "dh" ? haptic6r_dh_options() : haptic6r_urdf_options();
  EXPECT_GE(compare_with_haptic6r(options, "numerical", 8, coarse_human_arm(), GetParam()).same_share(), 0.95);
}

// With enough starts the numerical IK finds the closed form's closest one on every sample of the workspace.
TEST(SerialChainHaptic6RSelection, EnoughRestartsPickTheClosedFormsConfigurationEverywhere) {
  EXPECT_EQ(compare_with_haptic6r(haptic6r_dh_options(), "numerical", 24, coarse_human_arm(), "dh, 24 restarts").same_share(), 1.0);
}

// problems/haptic6r-urdf-evaluate.json (serial_chain, closed form) against
// problems/haptic6r-evaluate.json (haptic6r) through the framework: the same objective values.
TEST(SerialChainHaptic6RStudy, UrdfStudyGivesHaptic6RsObjectivesTo1e9) {
#ifdef HAPSYN_HAVE_URDFDOM
  const auto run = [](const std::string& file) {
    const Json doc = read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/problems/" + file);
    const Study study = load_study(doc, test::registry());
    SolverContext context;
    context.threads = 2;
    return study.solver->solve(*study.problem, context);
  };
  const SolverResult urdf = run("haptic6r-urdf-evaluate.json"), closed = run("haptic6r-evaluate.json");
  ASSERT_TRUE(urdf.best.has_value()) << urdf.message;
  ASSERT_TRUE(closed.best.has_value()) << closed.message;
  ASSERT_EQ(urdf.best->objectives.size(), 5u);
  ASSERT_EQ(closed.best->objectives.size(), 5u);
  for (std::size_t k = 0; k < 5; ++k) {  // J_x, J_v, J_a, J_f, J
    EXPECT_NEAR(urdf.best->objectives[k], closed.best->objectives[k], 1e-9) << "objective " << k;
    std::printf("[ objective %zu ] serial_chain %.17g, haptic6r %.17g\n", k, urdf.best->objectives[k], closed.best->objectives[k]);
  }
#else
  GTEST_SKIP() << "built without urdfdom";
#endif
}

#ifdef HAPSYN_HAVE_URDFDOM
INSTANTIATE_TEST_SUITE_P(Forms, SerialChainHaptic6R, ::testing::Values("dh", "urdf"));
#else
INSTANTIATE_TEST_SUITE_P(Forms, SerialChainHaptic6R, ::testing::Values("dh"));
#endif

#ifdef HAPSYN_HAVE_URDFDOM
// position_axis: a 5 x n task Jacobian (two angular rows orthogonal to the tip axis, then v), and
// the IK matches the position and the axis direction but leaves the rotation about it free.
TEST(SerialChain, PositionAxisTaskMatchesPositionAndAxisWithFiveRows) {
  const SerialChain m = serial_chain(Json{{"urdf", "serial_chain/ur5_like.urdf"}, {"base_link", "base_link"},
                                          {"tip_link", "tool0"}, {"task", "position_axis"}, {"task_axis", "z"}});
  const auto design = nominal_design(m);
  const auto model = m.build(design.data());
  const auto& chain = static_cast<const SerialChainModel&>(*model).chain();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  int reached = 0;
  for (int k = 0; k < 20; ++k) {
    JointVector q(6);
    for (int i = 0; i < 6; ++i) q(i) = u(rng);
    ChainFrames f;
    chain_frames(chain, q.data(), f);
    Eigen::Isometry3d target = f.tip;
    target.linear() = target.linear() * Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();  // roll about z: free
    const SampleSet scene = one_pose_scene(target);
    const SampleQuantities out = solve_one(*model, m, scene, 0, kNeedJacobian);
    if (out.status != SampleStatus::kReachable) continue;
    ++reached;
    EXPECT_EQ(out.jacobian.rows(), 5);
    EXPECT_EQ(out.jacobian.cols(), 6);
    ChainFrames g;
    chain_frames(chain, out.q.data(), g);
    EXPECT_LT((g.tip.translation() - target.translation()).norm(), 1e-9);
    EXPECT_LT((g.tip.linear().col(2) - target.linear().col(2)).norm(), 1e-9);
  }
  EXPECT_GE(reached, 18);
}
#endif  // HAPSYN_HAVE_URDFDOM

// M = (J H^-1 J^T)^-1 equals J^-T H J^-1 for the square Jacobian of a 6-joint chain.
TEST(SerialChain, EffectiveMassIsTheInverseOfJHinvJt) {
  const SerialChain m = serial_chain(haptic6r_dh_options());
  const auto design = nominal_design(m);
  const auto model = m.build(design.data());
  const auto& chain = static_cast<const SerialChainModel&>(*model).chain();
  JointVector q(6);
  q << 0.3, 1.2, -0.4, 1.0, 0.6, 0.2;
  ChainFrames f;
  chain_frames(chain, q.data(), f);
  const SampleQuantities out = solve_one(*model, m, one_pose_scene(f.tip), 0, kNeedJacobian | kNeedInertia | kNeedEffectiveMass);
  ASSERT_EQ(out.status, SampleStatus::kReachable);
  const Eigen::MatrixXd j = out.jacobian, h = out.inertia;
  const Eigen::MatrixXd expected = j.transpose().inverse() * h * j.inverse();
  EXPECT_LT((Eigen::MatrixXd(out.effective_mass) - expected).norm(), 1e-9 * expected.norm());
}

// ---- The demanded motion: joint rates, accelerations and the velocity torque ----

namespace {

Eigen::Matrix3d rotation_exp(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  return angle > 0.0 ? Eigen::AngleAxisd(angle, v / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
}

Eigen::Vector3d vee_of_skew(const Eigen::Matrix3d& m) {
  const Eigen::Matrix3d s = 0.5 * (m - m.transpose());
  return Eigen::Vector3d(s(2, 1), s(0, 2), s(1, 0));
}

// First and second time derivatives at t = 0 of a pose trajectory, by central differences:
// (omega, v) and (d omega/dt, a) of its origin, and of its unit axis `axis` (a_dot, a_ddot).
struct PoseDerivatives {
  Vector6d twist, twist_rate;
  Eigen::Vector3d axis_rate, axis_acceleration;
};

template <class Trajectory>
PoseDerivatives differentiate(const Trajectory& at, int axis, double h) {
  const Eigen::Isometry3d p = at(h), o = at(0.0), m = at(-h);
  const Eigen::Matrix3d rdot = (p.linear() - m.linear()) / (2.0 * h);
  const Eigen::Matrix3d rddot = (p.linear() - 2.0 * o.linear() + m.linear()) / (h * h);
  PoseDerivatives d;
  d.twist << vee_of_skew(rdot * o.linear().transpose()), (p.translation() - m.translation()) / (2.0 * h);
  // d/dt (Rdot R^T) = Rddot R^T + Rdot Rdot^T, whose second term is symmetric.
  d.twist_rate << vee_of_skew(rddot * o.linear().transpose()),
      (p.translation() - 2.0 * o.translation() + m.translation()) / (h * h);
  d.axis_rate = rdot.col(axis);
  d.axis_acceleration = rddot.col(axis);
  return d;
}

struct MotionCase {
  const char* name;
  Json options;
  int dimension;
};

std::vector<MotionCase> motion_cases() {
  const auto with_frames = [](Json o) {
    o["base_xyz"] = {0.1, -0.2, 0.3};
    o["base_rpy"] = {10, -20, 30};
    o["tool_xyz"] = {0.02, -0.01, 0.05};
    o["tool_rpy"] = {15, 30, 45};
    return o;
  };
  Json pose = haptic6r_dh_options();
  Json ur5{{"dh_file", "serial_chain/ur5_like_dh.json"}};
  Json position = ur5, axis = ur5;
  position["task"] = "position";
  axis["task"] = "position_axis";
  axis["task_axis"] = "y";
  return {{"pose", with_frames(pose), 7},
          {"pose without frames", pose, 7},
          {"position (redundant), poses", with_frames(position), 7},
          {"position (redundant), positions", with_frames(position), 3},
          {"position_axis", with_frames(axis), 7}};
}

}  // namespace

// The joint rates realise the twist in the task rows (J qdot = the demanded twist carried to E
// in B), and along q(t) = q + qdot t + qddot t^2 / 2 the tip follows the target of the demanded
// scene motion P(t) (origin p + v t + a t^2 / 2, rotation exp(omega t + domega t^2 / 2) R) to
// second order in every row the task matches: both differentiated numerically, the chain's
// from the forward kinematics, the target's from SerialChainModel::target(). This checks the
// frames (base, tool), the Jdot qdot term, and position_axis's spin term.
TEST(SerialChain, JointRatesAndAccelerationsRealiseTheDemandedMotionInEveryTask) {
  for (const MotionCase& c : motion_cases()) {
    SCOPED_TRACE(c.name);
    const SerialChain m = serial_chain(c.options);
    const auto design = nominal_design(m);
    const auto model_ptr = m.build(design.data());
    const auto& model = static_cast<const SerialChainModel&>(*model_ptr);
    const Chain& chain = model.chain();
    const SerialChainSetup& setup = m.setup();
    const auto scratch = m.make_scratch();
    const Eigen::Isometry3d scene_from_base = setup.base_from_scene.inverse();
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int checked = 0;
    double worst_rate = 0.0, worst_acceleration = 0.0;
    for (int k = 0; k < 40; ++k) {
      JointVector q0(chain.dof());
      for (int i = 0; i < chain.dof(); ++i) q0(i) = 2.5 * u(rng);
      ChainFrames f;
      chain_frames(chain, q0.data(), f);
      // The sample whose target is this tip pose.
      Eigen::Isometry3d p0 = scene_from_base * f.tip * setup.sample_to_tip.inverse();
      if (c.dimension == 3) {
        p0.translation() = scene_from_base * f.tip.translation() - setup.sample_to_tip.translation();
        p0.linear().setIdentity();
      }
      Vector6d twist, twist_rate;
      for (int r = 0; r < 6; ++r) {
        twist(r) = 0.4 * u(rng);
        twist_rate(r) = u(rng);
      }
      const auto sample_at = [&](double t) {
        Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
        p.linear() = rotation_exp(twist.head<3>() * t + 0.5 * twist_rate.head<3>() * t * t) * p0.linear();
        p.translation() = p0.translation() + twist.tail<3>() * t + 0.5 * twist_rate.tail<3>() * t * t;
        return p;
      };
      const auto row_of = [&](const Eigen::Isometry3d& p) {
        const Eigen::Quaterniond r(p.linear());
        return std::array<double, 7>{p.translation().x(), p.translation().y(), p.translation().z(), r.w(), r.x(), r.y(), r.z()};
      };
      const auto row = row_of(p0);
      SampleSet scene;
      scene.coordinates = c.dimension == 7 ? std::vector<std::string>{"x", "y", "z", "qw", "qx", "qy", "qz"}
                                           : std::vector<std::string>{"x", "y", "z"};
      scene.poses = Eigen::Map<const Eigen::RowVectorXd>(row.data(), c.dimension);
      SampleQuantities out;
      out.scene = &scene;
      out.sample = 0;
      out.twist = twist.data();
      out.twist_rate = twist_rate.data();
      model.solve(row.data(), kNeedJacobian | kNeedJointVelocity | kNeedJointAcceleration, *scratch, out);
      if (out.status != SampleStatus::kReachable) continue;
      // J qdot = the task rows of the demanded twist at E in B.
      const DemandedMotion demand = model.demanded_motion(row.data(), c.dimension, model.target(row.data(), c.dimension),
                                                          twist.data(), twist_rate.data());
      TaskJointMatrix demanded_rows;
      task_jacobian(setup.task, model.target(row.data(), c.dimension), TaskJointMatrix(demand.twist), demanded_rows);
      const double rate_error = (out.jacobian * out.joint_velocity - demanded_rows).norm();
      worst_rate = std::max(worst_rate, rate_error);
      EXPECT_LT(rate_error, 1e-10);
      // Near a singularity the rates are large and the differences inaccurate: skip those.
      if (out.joint_velocity.norm() > 5.0 || out.joint_acceleration.norm() > 50.0) continue;
      ++checked;
      const double h = 1e-4;
      const PoseDerivatives chain_motion = differentiate(
          [&](double t) {
            JointVector q = out.q + out.joint_velocity * t + 0.5 * out.joint_acceleration * t * t;
            ChainFrames g;
            chain_frames(chain, q.data(), g);
            return g.tip;
          },
          setup.task.axis, h);
      const PoseDerivatives target_motion = differentiate(
          [&](double t) { return model.target(row_of(sample_at(t)).data(), c.dimension); }, setup.task.axis, h);
      // The rows the task matches: v and a always; omega and d omega/dt for pose; the axis's
      // first and second derivatives for position_axis.
      double rate = (chain_motion.twist.tail<3>() - target_motion.twist.tail<3>()).norm();
      double acceleration = (chain_motion.twist_rate.tail<3>() - target_motion.twist_rate.tail<3>()).norm();
      if (setup.task.orientation == IkTask::Orientation::kFull) {
        rate += (chain_motion.twist.head<3>() - target_motion.twist.head<3>()).norm();
        acceleration += (chain_motion.twist_rate.head<3>() - target_motion.twist_rate.head<3>()).norm();
      } else if (setup.task.orientation == IkTask::Orientation::kAxis) {
        rate += (chain_motion.axis_rate - target_motion.axis_rate).norm();
        acceleration += (chain_motion.axis_acceleration - target_motion.axis_acceleration).norm();
        // Not vacuous: the spin about the axis is free, and differs.
        EXPECT_GT((chain_motion.twist.head<3>() - target_motion.twist.head<3>()).norm(), 1e-6);
      }
      worst_acceleration = std::max(worst_acceleration, acceleration / (1.0 + target_motion.twist_rate.norm()));
      EXPECT_LT(rate, 1e-6 * (1.0 + target_motion.twist.norm())) << chain_motion.twist.transpose() << "\n"
                                                                << target_motion.twist.transpose();
      EXPECT_LT(acceleration, 1e-5 * (1.0 + target_motion.twist_rate.norm()))
          << chain_motion.twist_rate.transpose() << "\n" << target_motion.twist_rate.transpose();
    }
    EXPECT_GE(checked, 15);
    std::printf("serial_chain %s: |J qdot - twist rows| <= %.3g; FD acceleration worst relative %.3g (%d samples)\n", c.name,
                worst_rate, worst_acceleration, checked);
  }
}

// The demanded-motion outputs only when asked for, each on its own flag; NaN without a twist.
TEST(SerialChain, DemandedMotionOnlyWhenAskedFor) {
  const SerialChain m = serial_chain(haptic6r_dh_options());
  EXPECT_TRUE(m.provides() & kNeedJointVelocity);
  EXPECT_TRUE(m.provides() & kNeedJointAcceleration);
  EXPECT_TRUE(m.provides() & kNeedVelocityTorque);
  const auto design = nominal_design(m);
  const auto model = m.build(design.data());
  const auto& chain = static_cast<const SerialChainModel&>(*model).chain();
  JointVector q(6);
  q << 0.3, 1.2, -0.4, 1.0, 0.6, 0.2;
  ChainFrames f;
  chain_frames(chain, q.data(), f);
  const SampleSet scene = one_pose_scene(f.tip);
  const double twist[6] = {0.1, -0.2, 0.3, 0.05, 0.1, -0.1}, twist_rate[6] = {0.5, 0.2, -0.1, 0.3, -0.2, 0.4};
  SampleQuantities out;
  out.scene = &scene;
  out.sample = 0;
  out.twist = twist;
  out.twist_rate = twist_rate;
  out.joint_velocity.setConstant(6, 7.0);
  out.joint_acceleration.setConstant(6, 7.0);
  out.velocity_torque.setConstant(6, 7.0);
  const auto scratch = m.make_scratch();
  model->solve(scene.pose(0), kNeedJacobian | kNeedInertia | kNeedEffectiveMass | kNeedGravity | kNeedActuatorLimits,
               *scratch, out);
  ASSERT_EQ(out.status, SampleStatus::kReachable);
  EXPECT_EQ(out.joint_velocity(0), 7.0);
  EXPECT_EQ(out.joint_acceleration(0), 7.0);
  EXPECT_EQ(out.velocity_torque(0), 7.0);
  model->solve(scene.pose(0), kNeedJointVelocity, *scratch, out);
  EXPECT_NE(out.joint_velocity(0), 7.0);
  EXPECT_EQ(out.joint_acceleration(0), 7.0);
  EXPECT_EQ(out.velocity_torque(0), 7.0);
  model->solve(scene.pose(0), kNeedJointVelocity | kNeedVelocityTorque, *scratch, out);
  EXPECT_EQ(out.joint_acceleration(0), 7.0);
  EXPECT_NE(out.velocity_torque(0), 7.0);
  EXPECT_TRUE(out.velocity_torque.allFinite());
  out.twist = nullptr;
  model->solve(scene.pose(0), kNeedJointVelocity, *scratch, out);
  EXPECT_TRUE(std::isnan(out.joint_velocity(0)));
}
