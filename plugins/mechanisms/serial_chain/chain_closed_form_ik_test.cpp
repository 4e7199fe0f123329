// Tests of serial_chain's closed-form IK (chain_closed_form_ik.hpp) on the shipped 6R chain files
// (haptic6r_dh.json, haptic6r.urdf, ur5_like_dh.json, ur5_like.urdf): thousands of random
// in-limit configurations -> forward kinematics (chain_frames, not the engine's) -> IK; the
// generating configuration among the solutions, the closest-to-home pick against a brute-force
// search written here, proved statuses, the solver choice and its errors.
#include "chain_closed_form_ik.hpp"

#include "haptic6r_comparison.hpp"
#include "test_support.hpp"

#include <hapsyn/error.hpp>

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

using namespace hapsyn;
using namespace hapsyn::plugins;
using namespace hapsyn::plugins::test_support;

namespace {

struct Arm {
  const char* name;
  Json options;
};

Json ur5_urdf_options() { return Json{{"urdf", "serial_chain/ur5_like.urdf"}, {"base_link", "base_link"}, {"tip_link", "tool0"}}; }

std::vector<Arm> shipped_arms() {
  std::vector<Arm> arms = {{"haptic6r_dh.json", haptic6r_dh_options()}, {"ur5_like_dh.json", Json{{"dh_file", "serial_chain/ur5_like_dh.json"}}}};
#ifdef HAPSYN_HAVE_URDFDOM
  arms.push_back({"haptic6r.urdf", haptic6r_urdf_options()});
  arms.push_back({"ur5_like.urdf", ur5_urdf_options()});
#endif
  return arms;
}

double wrap(double x) { return std::remainder(x, 2.0 * kPi); }

double largest_gap(const double* a, const double* b) {
  double m = 0.0;
  for (int i = 0; i < 6; ++i) m = std::max(m, std::abs(wrap(a[i] - b[i])));
  return m;
}

// Brute force: whether some whole-turn shift of every angle lies within the limits (1e-9 rad).
bool admissible(const Chain& chain, const double* q) {
  for (int i = 0; i < 6; ++i) {
    const ChainJoint& j = chain.joints[static_cast<std::size_t>(i)];
    bool inside = false;
    for (int k = -3; k <= 3 && !inside; ++k) {
      const double x = q[i] + 2.0 * kPi * k;
      inside = x >= j.lower - 1e-9 && x <= j.upper + 1e-9;
    }
    if (!inside) return false;
  }
  return true;
}

double distance_to(const double* q, const JointVector& home) {
  double s = 0.0;
  for (int i = 0; i < 6; ++i) s += wrap(q[i] - home(i)) * wrap(q[i] - home(i));
  return s;
}

// A configuration uniform inside the limits (a full turn for a joint whose limits span more).
JointVector random_configuration(const Chain& chain, std::mt19937& rng) {
  JointVector q(6);
  for (int i = 0; i < 6; ++i) {
    const ChainJoint& j = chain.joints[static_cast<std::size_t>(i)];
    std::uniform_real_distribution<double> u(std::max(j.lower, -kPi), std::min(j.upper, kPi));
    q(i) = u(rng);
  }
  return q;
}

double smallest_singular_value(const Chain& chain, const ChainFrames& frames) {
  TaskJointMatrix jacobian;
  chain_jacobian(chain, frames, jacobian);
  const Eigen::JacobiSVD<TaskJointMatrix> svd(jacobian);
  return svd.singularValues()(svd.singularValues().size() - 1);
}

}  // namespace

TEST(ChainClosedFormIk, FindsEveryGeneratingConfigurationAndTheTrueClosestToHomeOnTheShippedArms) {
  for (const Arm& arm : shipped_arms()) {
    const SerialChain m = serial_chain(arm.options);
    ASSERT_TRUE(m.setup().closed_form) << arm.name << ": " << m.summary();
    const auto model = m.build(nominal_design(m).data());
    ASSERT_TRUE(static_cast<const SerialChainModel&>(*model).closed_form()) << arm.name;
    const Chain& chain = static_cast<const SerialChainModel&>(*model).chain();
    const ChainClosedFormIk ik(chain);
    const JointVector& home = m.setup().home;
    ClosedFormScratch scratch;
    std::mt19937 rng(11);
    constexpr int kPoses = 3000;
    int skipped = 0, checked = 0;
    for (int k = 0; k < kPoses; ++k) {
      const JointVector q = random_configuration(chain, rng);
      ChainFrames f;
      chain_frames(chain, q.data(), f);
      if (smallest_singular_value(chain, f) < 1e-3) {  // near-singular: a continuum may stand for q
        ++skipped;
        continue;
      }
      ++checked;
      JointVector picked(6);
      ASSERT_EQ(ik.solve(chain, f.tip, home.data(), false, picked.data(), scratch), IkStatus::kConverged) << arm.name << " pose " << k;
      const auto& all = ik.all_solutions(f.tip, scratch);
      bool generating = false;
      double closest = INFINITY;
      for (int s = 0; s < all.count; ++s) {
        const double* x = all.q[static_cast<std::size_t>(s)].data();
        generating = generating || largest_gap(x, q.data()) < 1e-6;
        ChainFrames g;
        chain_frames(chain, x, g);
        EXPECT_LT((g.tip.translation() - f.tip.translation()).norm(), 1e-9) << arm.name << " pose " << k;
        EXPECT_LT((g.tip.linear() - f.tip.linear()).norm(), 1e-9) << arm.name << " pose " << k;
        if (admissible(chain, x)) closest = std::min(closest, distance_to(x, home));
      }
      EXPECT_TRUE(generating) << arm.name << " pose " << k;
      EXPECT_NEAR(distance_to(picked.data(), home), closest, 1e-12) << arm.name << " pose " << k;
      for (int i = 0; i < 6; ++i) {
        const ChainJoint& j = chain.joints[static_cast<std::size_t>(i)];
        EXPECT_TRUE(picked(i) >= j.lower && picked(i) <= j.upper) << arm.name << " pose " << k << " joint " << i;
      }
    }
    std::printf("[ %s ] %d poses: %d checked, %d near-singular skipped\n", arm.name, kPoses, checked, skipped);
    EXPECT_GT(checked, kPoses * 8 / 10) << arm.name;
  }
}

TEST(ChainClosedFormIk, FirstFoundIsTheEnginesFirstAdmissibleSolution) {
  const SerialChain m = serial_chain(Json{{"dh_file", "serial_chain/ur5_like_dh.json"}});
  const auto model = m.build(nominal_design(m).data());
  const Chain& chain = static_cast<const SerialChainModel&>(*model).chain();
  const ChainClosedFormIk ik(chain);
  ClosedFormScratch scratch;
  std::mt19937 rng(5);
  for (int k = 0; k < 200; ++k) {
    const JointVector q = random_configuration(chain, rng);
    ChainFrames f;
    chain_frames(chain, q.data(), f);
    JointVector first(6), again(6);
    ASSERT_EQ(ik.solve(chain, f.tip, m.setup().home.data(), true, first.data(), scratch), IkStatus::kConverged);
    ik.all_solutions(f.tip, scratch);
    int expected = -1;
    for (int s = 0; s < scratch.solutions.count && expected < 0; ++s) {
      if (admissible(chain, scratch.solutions.q[static_cast<std::size_t>(s)].data())) expected = s;
    }
    ASSERT_GE(expected, 0);
    EXPECT_LT(largest_gap(first.data(), scratch.solutions.q[static_cast<std::size_t>(expected)].data()), 1e-12) << k;
    ik.solve(chain, f.tip, m.setup().home.data(), true, again.data(), scratch);
    EXPECT_EQ(first, again) << k;
  }
}

// The ranked path (polish in the rule's order, stop at the first in-limit solution) picks what
// ranking all polished solutions picks, status and q, for both rules, on the UR5-like arm with
// joint 1 limited to [-0.3, 0.3] rad (many invalid poses) and unlimited.
TEST(ChainClosedFormIk, RankedPathEqualsTheAllSolutionsPath) {
  const SerialChain m = serial_chain(Json{{"dh_file", "serial_chain/ur5_like_dh.json"}});
  const auto model = m.build(nominal_design(m).data());
  Chain chain = static_cast<const SerialChainModel&>(*model).chain();
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-kPi, kPi);
  int invalid = 0;
  for (const bool narrow : {false, true}) {
    if (narrow) {
      chain.joints[0].lower = -0.3;
      chain.joints[0].upper = 0.3;
    }
    const ChainClosedFormIk ik(chain);
    ClosedFormScratch scratch;
    for (int k = 0; k < 1000; ++k) {
      JointVector q(6);
      for (int i = 0; i < 6; ++i) q(i) = u(rng);
      ChainFrames f;
      chain_frames(chain, q.data(), f);
      for (const bool first : {false, true}) {
        JointVector ranked(6), reference(6);
        const IkStatus a = ik.solve(chain, f.tip, m.setup().home.data(), first, ranked.data(), scratch);
        const IkStatus b = ik.solve_from_all(chain, f.tip, m.setup().home.data(), first, reference.data(), scratch);
        ASSERT_EQ(a, b) << k;
        EXPECT_LT(largest_gap(ranked.data(), reference.data()), 1e-12) << k << (first ? " first_found" : " closest");
        invalid += a == IkStatus::kJointLimit;
      }
    }
  }
  EXPECT_GT(invalid, 100);
}

// kJointLimit is proved: solutions exist and all lie outside the limits; kUnreachable: none exist.
TEST(ChainClosedFormIk, InvalidOnlyWhenEverySolutionLiesOutsideTheLimits) {
  const SerialChain m = serial_chain(Json{{"dh_file", "serial_chain/ur5_like_dh.json"}});
  const auto model = m.build(nominal_design(m).data());
  const Chain& chain = static_cast<const SerialChainModel&>(*model).chain();
  JointVector q(6);
  q << 0.2, -1.0, 1.2, -0.5, 0.8, 0.3;
  ChainFrames f;
  chain_frames(chain, q.data(), f);
  ClosedFormScratch scratch;
  JointVector out(6);
  // Joint 1 limited to [0.5, 0.6] rad: every solution's q1 (the generating 0.2 and the shoulder's
  // other branch) lies outside.
  Chain narrow = chain;
  narrow.joints[0].lower = 0.5;
  narrow.joints[0].upper = 0.6;
  EXPECT_EQ(ChainClosedFormIk(narrow).solve(narrow, f.tip, nullptr, false, out.data(), scratch), IkStatus::kJointLimit);
  ChainClosedFormIk(narrow).all_solutions(f.tip, scratch);
  ASSERT_GT(scratch.solutions.count, 0);
  for (int s = 0; s < scratch.solutions.count; ++s) EXPECT_FALSE(admissible(narrow, scratch.solutions.q[static_cast<std::size_t>(s)].data()));
  // [0.1, 0.3] admits the generating configuration's branch.
  narrow.joints[0].lower = 0.1;
  narrow.joints[0].upper = 0.3;
  EXPECT_EQ(ChainClosedFormIk(narrow).solve(narrow, f.tip, nullptr, false, out.data(), scratch), IkStatus::kConverged);
  EXPECT_NEAR(out(0), 0.2, 1e-9);
  // Beyond the reach: no solution at all.
  Eigen::Isometry3d far = f.tip;
  far.translation() << 3.0, 0.0, 0.0;
  EXPECT_EQ(ChainClosedFormIk(chain).solve(chain, far, nullptr, false, out.data(), scratch), IkStatus::kUnreachable);
  EXPECT_EQ(ChainClosedFormIk(chain).all_solutions(far, scratch).count, 0);
}

// Through the mechanism: the sample statuses follow the solutions. The UR5-like table with joint 1
// limited to [-10, 10] deg, poses from q1 outside: invalid exactly when no solution fits.
TEST(ChainClosedFormIk, SampleStatusesFollowTheSolutions) {
  Json table = read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/share/serial_chain/ur5_like_dh.json");
  table["joints"][0]["lower"] = -10;
  table["joints"][0]["upper"] = 10;
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "h_ik_ur5_narrow.json";
  std::ofstream(file) << table.dump();
  const SerialChain m = serial_chain(Json{{"dh_file", file.string()}});
  const auto model = m.build(nominal_design(m).data());
  const Chain& chain = static_cast<const SerialChainModel&>(*model).chain();
  const ChainClosedFormIk ik(chain);
  ClosedFormScratch scratch;
  JointVector q(6), out(6);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-kPi, kPi), outside(0.3, kPi - 0.3);
  int invalid = 0, reachable = 0;
  for (int k = 0; k < 300; ++k) {
    q << (k % 2 ? 1 : -1) * outside(rng), u(rng), u(rng), u(rng), u(rng), u(rng);
    ChainFrames f;
    chain_frames(chain, q.data(), f);
    const SampleStatus status = solve_one(*model, m, one_pose_scene(f.tip), 0).status;
    ik.all_solutions(f.tip, scratch);
    bool any_inside = false;
    for (int s = 0; s < scratch.solutions.count; ++s) {
      any_inside = any_inside || admissible(chain, scratch.solutions.q[static_cast<std::size_t>(s)].data());
    }
    ASSERT_GT(scratch.solutions.count, 0);
    if (any_inside) {
      EXPECT_TRUE(status == SampleStatus::kReachable || status == SampleStatus::kSingular) << k;
      ++reachable;
    } else {
      EXPECT_EQ(status, SampleStatus::kInvalid) << k;
      ++invalid;
    }
  }
  std::filesystem::remove(file);
  std::printf("[ ur5_like, q1 in [-10, 10] deg ] %d invalid, %d reachable through another branch\n", invalid, reachable);
  EXPECT_GT(invalid, 0);
  EXPECT_GT(reachable, 0);
}

TEST(ChainClosedFormIk, SummaryNamesTheSolverAChainGot) {
  EXPECT_NE(serial_chain(Json{{"dh_file", "serial_chain/ur5_like_dh.json"}}).summary().find("; IK solver closed form (6R: "), std::string::npos);
  EXPECT_NE(serial_chain(Json{{"dh_file", "serial_chain/ur5_like_dh.json"}}).summary().find("(UR type))"), std::string::npos)
      << serial_chain(Json{{"dh_file", "serial_chain/ur5_like_dh.json"}}).summary();
  EXPECT_NE(serial_chain(haptic6r_dh_options()).summary().find("; IK solver closed form (6R: "), std::string::npos);
  Json numerical = {{"dh_file", "serial_chain/ur5_like_dh.json"}, {"ik", {{"solver", "numerical"}}}};
  EXPECT_NE(serial_chain(numerical).summary().find("; IK solver numerical (damped least squares, 8 restarts)"), std::string::npos);
  EXPECT_FALSE(serial_chain(numerical).setup().closed_form);
  Json position = {{"dh_file", "serial_chain/ur5_like_dh.json"}, {"task", "position"}};
  const std::string s = serial_chain(position).summary();
  EXPECT_NE(s.find("; IK solver numerical (damped least squares, 8 restarts; no closed form: the task is not the full pose"),
            std::string::npos)
      << s;
}

TEST(ChainClosedFormIk, ErrorsNameTheOptionTheChainAndTheRule) {
  const auto error = [](const Json& o) { return test::error_of([&] { serial_chain(o); }); };
  const std::string task = error(Json{{"dh_file", "serial_chain/ur5_like_dh.json"}, {"task", "position"}, {"ik", {{"solver", "closed_form"}}}});
  EXPECT_NE(task.find("serial_chain: options.ik.solver = \"closed_form\": the task is not the full pose"), std::string::npos) << task;
  const std::string unknown = error(Json{{"dh_file", "serial_chain/ur5_like_dh.json"}, {"ik", {{"solver", "fast"}}}});
  EXPECT_NE(unknown.find("ik.solver = \"fast\""), std::string::npos) << unknown;
  // A general 6R (no intersecting or parallel consecutive axes): no closed-form family.
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "h_ik_general_6r.json";
  {
    Json rows = Json::array();
    const double alpha[6] = {60, -45, 75, 50, -65, 0}, a[6] = {0.1, 0.3, 0.05, 0.08, 0.06, 0.02}, d[6] = {0.2, 0.04, 0.07, 0.25, 0.03, 0.1};
    for (int i = 0; i < 6; ++i) {
      rows.push_back(Json{{"joint", "j" + std::to_string(i + 1)}, {"theta", 10 * i}, {"d", d[i]}, {"a", a[i]}, {"alpha", alpha[i]}});
    }
    std::ofstream(file) << Json{{"format", "hapsyn-dh"}, {"format_version", 1}, {"name", "general"}, {"convention", "dh"},
                                {"units", {{"length", "m"}, {"angle", "deg"}}}, {"joints", rows}}
                               .dump();
  }
  const std::string general = error(Json{{"dh_file", file.string()}, {"ik", {{"solver", "closed_form"}}}});
  EXPECT_NE(general.find("serial_chain: options.ik.solver = \"closed_form\": no closed-form decomposition for this chain's axes (6R: "),
            std::string::npos)
      << general;
  EXPECT_NE(general.find("use \"auto\" or \"numerical\""), std::string::npos) << general;
  const SerialChain fallback = serial_chain(Json{{"dh_file", file.string()}});
  EXPECT_FALSE(fallback.setup().closed_form);
  EXPECT_NE(fallback.summary().find("IK solver numerical (damped least squares, 8 restarts; no closed form for the axes: 6R: "),
            std::string::npos)
      << fallback.summary();
  std::filesystem::remove(file);
}

// A design that turns an axis out of the nominal family: "auto" solves it numerically,
// "closed_form" refuses it naming the design's geometry.
TEST(ChainClosedFormIk, DesignLeavingTheFamilyFallsBackOrIsRefused) {
  for (const char* solver : {"auto", "closed_form"}) {
    const SerialChain m = serial_chain(Json{{"dh_file", "serial_chain/ur5_like_dh.json"}, {"ik", {{"solver", solver}}}});
    std::vector<double> design = nominal_design(m);
    // Axes 3 and 4 no longer parallel to 2; axes 1 x 2 and 5 x 6 no longer meeting: no family left.
    for (const auto& [name, value] : {std::pair{"elbow_joint:alpha", 10.0}, std::pair{"shoulder_pan_joint:a", 0.05},
                                      std::pair{"wrist_2_joint:a", 0.04}}) {
      int index = 0;
      for (const VariableDecl& v : m.variables()) {
        if (v.name == name) break;
        index += v.size;
      }
      ASSERT_LT(index, static_cast<int>(design.size())) << name;
      design[static_cast<std::size_t>(index)] = value;
    }
    if (std::string(solver) == "auto") {
      const auto model = m.build(design.data());
      EXPECT_FALSE(static_cast<const SerialChainModel&>(*model).closed_form());
      EXPECT_TRUE(static_cast<const SerialChainModel&>(*m.build(nominal_design(m).data())).closed_form());
    } else {
      const std::string e = test::error_of([&] { m.build(design.data()); });
      EXPECT_NE(e.find("serial_chain: options.ik.solver = \"closed_form\": this design's chain has no closed form ("), std::string::npos) << e;
      EXPECT_NE(e.find("(6R: "), std::string::npos) << e;
    }
  }
}
