// Tests of the serial_chain mechanism: its design variables and constraints, option errors,
// the classification, the frames it maps samples through, and the cross-check against the
// closed-form haptic6r on the human-arm workspace.
#include "serial_chain.hpp"

#include "haptic6r.hpp"
#include "haptic6r_comparison.hpp"
#include "test_support.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/options.hpp>
#include <hapsyn/study.hpp>

#include <gtest/gtest.h>

#include <cmath>
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
  EXPECT_NE(error(Json::object()).find("serial_chain: options: give the chain as options.urdf or options.dh_file"), std::string::npos);
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

#ifdef HAPSYN_HAVE_URDFDOM
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
// closed-form haptic6r, sample by sample, on a human-arm workspace.
class SerialChainHaptic6R : public ::testing::TestWithParam<const char*> {};

TEST_P(SerialChainHaptic6R, AgreesWithTheClosedFormWhereBothPickTheSameConfiguration) {
  const Json options = std::string(GetParam()) == "dh" ? haptic6r_dh_options() : haptic6r_urdf_options();
  EXPECT_GE(compare_with_haptic6r(options, 8, coarse_human_arm(), GetParam()).same_share(), 0.95);
}

// The selection differs only because the numerical IK does not see every solution: with enough
// starts it finds the closed form's closest one on every sample of the workspace.
TEST(SerialChainHaptic6RSelection, EnoughRestartsPickTheClosedFormsConfigurationEverywhere) {
  EXPECT_EQ(compare_with_haptic6r(haptic6r_dh_options(), 24, coarse_human_arm(), "dh, 24 restarts").same_share(), 1.0);
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
