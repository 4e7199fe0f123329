// Tests of serial_chain's closed-form IK on 7R chains (chain_closed_form_ik.hpp: one joint
// discretised over the 6R engine) on the shipped share/serial_chain/iiwa7_like.urdf: thousands of
// random in-limit configurations with the redundant joint on a grid value -> forward kinematics
// (chain_frames, not the engine's) -> IK; the generating configuration among the solutions, the
// closest-to-home pick against a brute-force search written here, first_found, proved statuses,
// the numerical IK (solve_ik) as a cross-check, the options, the summary and the errors; and
// problems/iiwa7like-gii-evaluate.json through the framework against the GII computed here.
#include "chain_closed_form_ik.hpp"

#include "haptic6r_comparison.hpp"
#include "test_support.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/internal/study.hpp>

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

#ifdef HAPSYN_HAVE_URDFDOM

Json iiwa_options() { return Json{{"urdf", "serial_chain/iiwa7_like.urdf"}, {"base_link", "base_link"}, {"tip_link", "tool0"}}; }

double wrap(double x) { return std::remainder(x, 2.0 * kPi); }

double largest_gap(const JointVector& a, const JointVector& b) {
  double m = 0.0;
  for (int i = 0; i < a.size(); ++i) m = std::max(m, std::abs(wrap(a(i) - b(i))));
  return m;
}

// Brute force: whether some whole-turn shift of every angle lies within the limits (1e-9 rad).
bool admissible(const Chain& chain, const JointVector& q) {
  for (int i = 0; i < q.size(); ++i) {
    const ChainJoint& j = chain.joints[static_cast<std::size_t>(i)];
    bool inside = false;
    for (int k = -3; k <= 3 && !inside; ++k) {
      const double x = q(i) + 2.0 * kPi * k;
      inside = x >= j.lower - 1e-9 && x <= j.upper + 1e-9;
    }
    if (!inside) return false;
  }
  return true;
}

// A configuration uniform inside the limits with joint k on a random value of `grid`.
JointVector random_configuration(const Chain& chain, int k, const std::vector<double>& grid, std::mt19937& rng) {
  JointVector q(7);
  for (int i = 0; i < 7; ++i) {
    const ChainJoint& j = chain.joints[static_cast<std::size_t>(i)];
    std::uniform_real_distribution<double> u(std::max(j.lower, -kPi), std::min(j.upper, kPi));
    q(i) = u(rng);
  }
  q(k) = grid[std::uniform_int_distribution<std::size_t>(0, grid.size() - 1)(rng)];
  return q;
}

// The smallest singular value of the Jacobian without joint k's column: the 6R the grid value leaves.
double locked_smallest_singular_value(const Chain& chain, const JointVector& q, int k) {
  ChainFrames f;
  chain_frames(chain, q.data(), f);
  TaskJointMatrix jacobian;
  chain_jacobian(chain, f, jacobian);
  Eigen::Matrix<double, 6, 6> six;
  for (int i = 0, c = 0; i < 7; ++i) {
    if (i != k) six.col(c++) = jacobian.col(i);
  }
  const Eigen::JacobiSVD<Eigen::Matrix<double, 6, 6>> svd(six);
  return svd.singularValues()(5);
}

struct Iiwa {
  SerialChain mechanism = serial_chain(iiwa_options());
  std::unique_ptr<const MechanismModel> model = mechanism.build(nominal_design(mechanism).data());
  const Chain& chain() const { return static_cast<const SerialChainModel&>(*model).chain(); }
};

#endif

}  // namespace

#ifdef HAPSYN_HAVE_URDFDOM

// The locked 6R is the 7R at that joint value: its forward kinematics against chain_frames.
TEST(ChainClosedFormIk7R, LockedChainIsTheChainAtTheLockedValue) {
  const Iiwa arm;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-kPi, kPi);
  for (int k = 0; k < 7; ++k) {
    for (int t = 0; t < 20; ++t) {
      JointVector q(7);
      for (int i = 0; i < 7; ++i) q(i) = u(rng);
      const closed_form_ik::PoeChain locked = locked_poe_chain(arm.chain(), k, q(k));
      double six[6];
      for (int i = 0, c = 0; i < 7; ++i) {
        if (i != k) six[c++] = q(i);
      }
      ChainFrames f;
      chain_frames(arm.chain(), q.data(), f);
      const Eigen::Isometry3d g = locked.forward(six);
      EXPECT_LT((g.translation() - f.tip.translation()).norm(), 1e-12) << "joint " << k;
      EXPECT_LT((g.linear() - f.tip.linear()).norm(), 1e-12) << "joint " << k;
    }
  }
}

TEST(ChainClosedFormIk7R, GridSpansTheLimitsWithBothEndsOrAFullTurn) {
  ChainJoint j;
  j.lower = -2.5;
  j.upper = 1.5;
  const std::vector<double> g = redundant_grid(j, 17);
  ASSERT_EQ(g.size(), 17u);
  EXPECT_EQ(g.front(), -2.5);
  EXPECT_EQ(g.back(), 1.5);
  for (std::size_t i = 1; i < g.size(); ++i) EXPECT_NEAR(g[i] - g[i - 1], 4.0 / 16, 1e-15);
  const ChainJoint unlimited;  // infinite limits: a full turn, pi left out (it is -pi)
  const std::vector<double> u = redundant_grid(unlimited, 8);
  ASSERT_EQ(u.size(), 8u);
  EXPECT_EQ(u.front(), -kPi);
  EXPECT_NEAR(u.back(), kPi - 2.0 * kPi / 8, 1e-15);
}

// Joint 4 (the elbow between a spherical shoulder and a spherical wrist) keeps the self-motion
// when locked at any value; joints 2 and 6 locked at 0 put axes 1 and 3 (5 and 7) on one line,
// a self-motion again. Auto takes joint 3, the next in its order (4, 3, 5, ...).
TEST(ChainClosedFormIk7R, AutoChoiceSkipsTheJointsThatKeepASelfMotion) {
  const Iiwa arm;
  EXPECT_NE(redundant_joint_unsuitability(arm.chain(), 3).find("joint 4 (joint_4) at 0 rad leaves a 6R whose Jacobian is "
                                                               "rank-deficient everywhere (a self-motion remains"),
            std::string::npos)
      << redundant_joint_unsuitability(arm.chain(), 3);
  for (const int k : {1, 5}) {
    EXPECT_NE(redundant_joint_unsuitability(arm.chain(), k).find(" at 0 rad leaves a 6R whose Jacobian is rank-deficient"), std::string::npos)
        << redundant_joint_unsuitability(arm.chain(), k);
  }
  for (const int k : {0, 2, 4, 6}) EXPECT_EQ(redundant_joint_unsuitability(arm.chain(), k), "") << k;
  EXPECT_EQ(choose_redundant_joint(arm.chain()), 2);
  ASSERT_TRUE(arm.mechanism.setup().closed_form) << arm.mechanism.summary();
  EXPECT_EQ(arm.mechanism.setup().redundancy.joint, 2);
  EXPECT_TRUE(static_cast<const SerialChainModel&>(*arm.model).closed_form());
}

TEST(ChainClosedFormIk7R, FindsEveryGeneratingConfigurationAndTheTrueClosestToHome) {
  const Iiwa arm;
  const Chain& chain = arm.chain();
  const ChainClosedFormIk ik(chain, arm.mechanism.setup().redundancy);
  const int k = ik.redundant_joint();
  ASSERT_EQ(k, 2);
  ASSERT_EQ(ik.grid().size(), 17u);
  const JointVector& home = arm.mechanism.setup().home;
  ClosedFormScratch scratch;
  std::mt19937 rng(11);
  constexpr int kPoses = 3000;
  int skipped = 0, checked = 0;
  long solutions = 0;
  for (int p = 0; p < kPoses; ++p) {
    const JointVector q = random_configuration(chain, k, ik.grid(), rng);
    if (locked_smallest_singular_value(chain, q, k) < 1e-3) {  // near-singular 6R: a continuum may stand for q
      ++skipped;
      continue;
    }
    ++checked;
    ChainFrames f;
    chain_frames(chain, q.data(), f);
    JointVector picked(7), first(7);
    ASSERT_EQ(ik.solve(chain, f.tip, home.data(), false, picked.data(), scratch), IkStatus::kConverged) << "pose " << p;
    ASSERT_EQ(ik.solve(chain, f.tip, home.data(), true, first.data(), scratch), IkStatus::kConverged) << "pose " << p;
    const std::vector<JointVector> all = ik.every_solution(f.tip, scratch);
    solutions += static_cast<long>(all.size());
    bool generating = false, first_seen = false;
    double closest = INFINITY;
    for (const JointVector& x : all) {
      generating = generating || largest_gap(x, q) < 1e-6;
      ChainFrames g;
      chain_frames(chain, x.data(), g);
      EXPECT_LT((g.tip.translation() - f.tip.translation()).norm(), 1e-9) << "pose " << p;
      EXPECT_LT((g.tip.linear() - f.tip.linear()).norm(), 1e-9) << "pose " << p;
      if (!admissible(chain, x)) continue;
      closest = std::min(closest, home_distance(x, home));
      if (!first_seen) {
        EXPECT_LT(largest_gap(first, x), 1e-12) << "pose " << p << ": first_found is the first admissible";
      }
      first_seen = true;
    }
    EXPECT_TRUE(generating) << "pose " << p;
    EXPECT_NEAR(home_distance(picked, home), closest, 1e-12) << "pose " << p;
    for (int i = 0; i < 7; ++i) {
      const ChainJoint& j = chain.joints[static_cast<std::size_t>(i)];
      EXPECT_TRUE(picked(i) >= j.lower && picked(i) <= j.upper) << "pose " << p << " joint " << i;
    }
  }
  std::printf("[ iiwa7_like.urdf, joint 3 in 17 steps ] %d poses: %d checked, %d near-singular skipped, %.1f solutions per pose\n",
              kPoses, checked, skipped, static_cast<double>(solutions) / std::max(checked, 1));
  EXPECT_GT(checked, kPoses * 8 / 10);
}

// kJointLimit is proved: solutions exist and all lie outside the limits; kUnreachable: none exist.
TEST(ChainClosedFormIk7R, InvalidOnlyWhenEverySolutionLiesOutsideTheLimits) {
  const Iiwa arm;
  JointVector q(7);
  q << 0.2, 0.7, 0.0, -1.1, 0.4, 0.9, -0.3;  // joint 3 at 0: a grid value of [-170, 170] deg in 17 steps
  ChainFrames f;
  chain_frames(arm.chain(), q.data(), f);
  ClosedFormScratch scratch;
  JointVector out(7);
  // Axes 1-2-3 meet at the shoulder and 5-6-7 at the wrist: |q4| alone sets the shoulder-wrist
  // distance, so every solution, on every grid value of joint 3, has q4 = -1.1 or +1.1.
  Chain narrow = arm.chain();
  narrow.joints[3].lower = 0.2;
  narrow.joints[3].upper = 0.3;
  const ChainClosedFormIk ik(narrow);
  const std::vector<JointVector> all = ik.every_solution(f.tip, scratch);
  ASSERT_GT(all.size(), 0u);
  for (const JointVector& x : all) {
    EXPECT_NEAR(std::abs(x(3)), 1.1, 1e-9);
    EXPECT_FALSE(admissible(narrow, x));
  }
  EXPECT_EQ(ik.solve(narrow, f.tip, nullptr, false, out.data(), scratch), IkStatus::kJointLimit);
  EXPECT_LT(largest_gap(out, all.front()), 1e-12);  // the first solution found
  narrow.joints[3].lower = -1.2;  // admits the generating configuration's elbow
  narrow.joints[3].upper = -1.0;
  EXPECT_EQ(ChainClosedFormIk(narrow).solve(narrow, f.tip, nullptr, false, out.data(), scratch), IkStatus::kConverged);
  EXPECT_NEAR(out(3), -1.1, 1e-9);
  Eigen::Isometry3d far = f.tip;
  far.translation() << 3.0, 0.0, 0.5;
  EXPECT_EQ(ik.solve(narrow, far, nullptr, false, out.data(), scratch), IkStatus::kUnreachable);
  EXPECT_TRUE(ik.every_solution(far, scratch).empty());
  EXPECT_NE(test::error_of([&] { ik.all_solutions(f.tip, scratch); }).find("closed_form_ik: all_solutions() is for 6R chains"),
            std::string::npos);
  for (const int steps : {1, kMaxRedundantSteps + 1}) {
    const std::string e = test::error_of([&] { ChainClosedFormIk(narrow, {2, steps}); });
    EXPECT_NE(e.find("closed_form_ik: redundant joint steps = " + std::to_string(steps) + ": must be in 2..1000"), std::string::npos) << e;
  }
}

// The numerical IK (damped least squares, 7 joints, self-motion toward home) as the cross-check:
// each of its solutions, locked at its own q_k, is among the 6R engine's solutions of that lock
// (the lock and the engine agree with an independent solver); and the closed form's pick, which
// has q_k on the grid, is at most one half grid step in q_k from some solution of the same pose.
TEST(ChainClosedFormIk7R, NumericalSolutionsAreAmongTheLockedEnginesSolutions) {
  const Iiwa arm;
  const Chain& chain = arm.chain();
  const ChainClosedFormIk ik(chain, arm.mechanism.setup().redundancy);
  const int k = ik.redundant_joint();
  const JointVector& home = arm.mechanism.setup().home;
  IkTask task;
  task.position = true;
  task.orientation = IkTask::Orientation::kFull;
  IkSettings settings;
  IkScratch numerical_scratch;
  ClosedFormScratch scratch;
  closed_form_ik::IkScratch engine_scratch;
  closed_form_ik::IkSolutions engine_solutions;
  std::mt19937 rng(5);
  int compared = 0, closer = 0;
  double worst_excess = 0.0;
  for (int p = 0; p < 200; ++p) {
    const JointVector q = random_configuration(chain, k, ik.grid(), rng);
    if (locked_smallest_singular_value(chain, q, k) < 1e-3) continue;
    ChainFrames f;
    chain_frames(chain, q.data(), f);
    JointVector numerical(7), closed(7);
    const double* starts[1] = {home.data()};
    if (solve_ik(chain, task, settings, f.tip, starts, 1, home.data(), false, numerical.data(), numerical_scratch) != IkStatus::kConverged) {
      continue;
    }
    ASSERT_EQ(ik.solve(chain, f.tip, home.data(), false, closed.data(), scratch), IkStatus::kConverged);
    ++compared;
    const closed_form_ik::ClosedFormIk6R engine(locked_poe_chain(chain, k, numerical(k)));
    engine.solve(f.tip, engine_scratch, engine_solutions);
    bool found = false;
    for (int s = 0; s < engine_solutions.count; ++s) {
      double gap = 0.0;
      for (int i = 0, c = 0; i < 7; ++i) {
        if (i != k) gap = std::max(gap, std::abs(wrap(engine_solutions.q[static_cast<std::size_t>(s)](c++) - numerical(i))));
      }
      found = found || gap < 1e-6;
    }
    EXPECT_TRUE(found) << "pose " << p;
    const double excess = home_distance(closed, home) - home_distance(numerical, home);
    if (excess > 0.0) ++closer;
    worst_excess = std::max(worst_excess, excess);
  }
  std::printf("[ iiwa7_like.urdf ] %d poses compared with solve_ik: its pick closer to home on %d (its q3 off the grid), "
              "largest excess of the closed form's distance %.3g rad^2\n",
              compared, closer, worst_excess);
  EXPECT_GT(compared, 150);
}

// The settings reach the model: a forced joint and steps give that ik's picks.
TEST(ChainClosedFormIk7R, ForcedJointAndStepsReachTheModelAndTheSummary) {
  Json o = iiwa_options();
  o["ik"] = Json{{"redundant_joint", "joint_1"}, {"redundant_steps", 9}};
  const SerialChain forced = serial_chain(o);
  EXPECT_EQ(forced.setup().redundancy.joint, 0);
  EXPECT_EQ(forced.setup().redundancy.steps, 9);
  const std::string s = forced.summary();
  EXPECT_NE(s.find("; IK solver closed form (7R: joint 1 (joint_1) discretised in 9 steps over [-170, 170] deg, each a 6R of "
                   "the other joints numbered 1-6: 6R: "),
            std::string::npos)
      << s;
  const std::string a = serial_chain(iiwa_options()).summary();
  EXPECT_NE(a.find("(7R: joint 3 (joint_3) discretised in 17 steps over [-170, 170] deg"), std::string::npos) << a;
  const auto model = forced.build(nominal_design(forced).data());
  const Chain& chain = static_cast<const SerialChainModel&>(*model).chain();
  const ChainClosedFormIk expected(chain, {0, 9}), automatic(chain);
  EXPECT_EQ(expected.grid().size(), 9u);
  ClosedFormScratch scratch;
  std::mt19937 rng(2);
  int differ = 0;
  for (int p = 0; p < 30; ++p) {
    const JointVector q = random_configuration(chain, 0, expected.grid(), rng);
    ChainFrames f;
    chain_frames(chain, q.data(), f);
    const SampleSet scene = one_pose_scene(f.tip);
    const SampleQuantities out = solve_one(*model, forced, scene, 0, kNeedJacobian);
    const Eigen::Isometry3d goal = static_cast<const SerialChainModel&>(*model).target(scene.pose(0), 7);  // as the model sees it
    JointVector want(7), other(7);
    const IkStatus status = expected.solve(chain, goal, forced.setup().home.data(), false, want.data(), scratch);
    if (status != IkStatus::kConverged) continue;
    ASSERT_TRUE(out.status == SampleStatus::kReachable || out.status == SampleStatus::kSingular) << p;
    EXPECT_LT(largest_gap(out.q, want), 1e-9) << p;
    if (automatic.solve(chain, goal, forced.setup().home.data(), false, other.data(), scratch) != IkStatus::kConverged ||
        largest_gap(other, want) > 1e-6) {
      ++differ;
    }
  }
  EXPECT_GT(differ, 0);  // the model did not fall back on the automatic choice
}

TEST(ChainClosedFormIk7R, ErrorsNameTheOptionTheValueAndTheRule) {
  const auto error = [](Json ik) {
    Json o = iiwa_options();
    o["ik"] = std::move(ik);
    return test::error_of([&] { serial_chain(o); });
  };
  const std::string unknown = error(Json{{"redundant_joint", "elbow"}});
  EXPECT_NE(unknown.find("serial_chain: options.ik.redundant_joint = \"elbow\": not a moving joint of the chain (its joints: "
                         "joint_1, joint_2, joint_3, joint_4, joint_5, joint_6, joint_7; or \"auto\")"),
            std::string::npos)
      << unknown;
  const std::string elbow = error(Json{{"redundant_joint", "joint_4"}});
  EXPECT_NE(elbow.find("serial_chain: options.ik.redundant_joint = \"joint_4\": locking joint 4 (joint_4) at 0 rad leaves a "
                       "6R whose Jacobian is rank-deficient everywhere (a self-motion remains"),
            std::string::npos)
      << elbow;
  EXPECT_NE(elbow.find("use another joint or \"auto\""), std::string::npos) << elbow;
  const std::string numerical = error(Json{{"solver", "numerical"}, {"redundant_joint", "joint_3"}});
  EXPECT_NE(numerical.find("ik.redundant_joint = \"joint_3\": only for the closed form (solver is \"numerical\")"), std::string::npos)
      << numerical;
  const std::string steps_numerical = error(Json{{"solver", "numerical"}, {"redundant_steps", 9}});
  EXPECT_NE(steps_numerical.find("ik.redundant_steps = 9: only for the closed form (solver is \"numerical\")"), std::string::npos)
      << steps_numerical;
  const std::string steps = error(Json{{"redundant_steps", 1}});
  EXPECT_NE(steps.find("ik.redundant_steps = 1"), std::string::npos) << steps;
  EXPECT_NE(steps.find("2"), std::string::npos) << steps;
  const std::string six = test::error_of(
      [] { serial_chain(Json{{"dh_file", "serial_chain/ur5_like_dh.json"}, {"ik", {{"redundant_joint", "elbow_joint"}}}}); });
  EXPECT_NE(six.find("serial_chain: options.ik.redundant_joint = \"elbow_joint\": the chain has 6 moving joints (a redundant "
                     "joint is for 7 revolute joints)"),
            std::string::npos)
      << six;
}

// The shipped study through the framework: every pose of its box reachable, and its GII equal to
// min sigma_min / max sigma_max of the 6 x 7 Jacobian (angular rows x 0.5 m) computed here at the
// closed form's picks over the same 125 poses (built here from the box's numbers).
TEST(ChainClosedFormIk7R, ShippedStudyGivesTheGiiComputedFromThePicks) {
  const Json doc = read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/problems/iiwa7like-gii-evaluate.json");
  const Study study = load_study(doc, test::registry());
  SolverContext context;
  context.threads = 2;
  const SolverResult result = study.solver->solve(*study.problem, context);
  ASSERT_TRUE(result.best.has_value()) << result.message;
  const Iiwa arm;
  const ChainClosedFormIk ik(arm.chain(), arm.mechanism.setup().redundancy);
  ClosedFormScratch scratch;
  double smallest = INFINITY, largest = 0.0;
  int poses = 0;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) {
      for (int k = 0; k < 5; ++k) {
        Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
        target.linear() = Eigen::Quaterniond(0, 1, 0, 0).toRotationMatrix();  // the tool pointing down
        target.translation() << 0.4 + 0.05 * i, -0.1 + 0.05 * j, 0.25 + 0.05 * k;
        JointVector q(7);
        ASSERT_EQ(ik.solve(arm.chain(), target, arm.mechanism.setup().home.data(), false, q.data(), scratch), IkStatus::kConverged);
        ChainFrames f;
        chain_frames(arm.chain(), q.data(), f);
        TaskJointMatrix jacobian;
        chain_jacobian(arm.chain(), f, jacobian);
        jacobian.topRows(3) *= 0.5;
        const Eigen::JacobiSVD<TaskJointMatrix> svd(jacobian);
        smallest = std::min(smallest, svd.singularValues()(5));
        largest = std::max(largest, svd.singularValues()(0));
        ++poses;
      }
    }
  }
  ASSERT_EQ(poses, 125);
  ASSERT_EQ(result.best->objectives.size(), 1u);
  EXPECT_NEAR(result.best->objectives[0], smallest / largest, 1e-12);
  std::printf("[ iiwa7like-gii-evaluate ] gii %.9g (here %.9g)\n", result.best->objectives[0], smallest / largest);
}

// A 7R without any joint whose lock leaves a family: auto falls back to the numerical IK,
// closed_form refuses it naming every joint's reason.
TEST(ChainClosedFormIk7R, GeneralSevenRFallsBackOrIsRefused) {
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "h_ik_general_7r.json";
  {
    Json rows = Json::array();
    const double alpha[7] = {60, -45, 75, 50, -65, 35, 0}, a[7] = {0.1, 0.3, 0.05, 0.08, 0.06, 0.07, 0.02},
                 d[7] = {0.2, 0.04, 0.07, 0.25, 0.03, 0.05, 0.1};
    for (int i = 0; i < 7; ++i) {
      rows.push_back(Json{{"joint", "j" + std::to_string(i + 1)}, {"theta", 10 * i}, {"d", d[i]}, {"a", a[i]}, {"alpha", alpha[i]}});
    }
    std::ofstream(file) << Json{{"format", "hapsyn-dh"}, {"format_version", 1}, {"name", "general7"}, {"convention", "dh"},
                                {"units", {{"length", "m"}, {"angle", "deg"}}}, {"joints", rows}}
                               .dump();
  }
  const std::string refused = test::error_of([&] { serial_chain(Json{{"dh_file", file.string()}, {"ik", {{"solver", "closed_form"}}}}); });
  EXPECT_NE(refused.find("serial_chain: options.ik.solver = \"closed_form\": 7R: no joint whose locking leaves a 6R with a closed form "
                         "(locking joint 1 (j1) at 0 rad leaves a 6R without a closed-form family (6R: "),
            std::string::npos)
      << refused;
  const SerialChain fallback = serial_chain(Json{{"dh_file", file.string()}});
  EXPECT_FALSE(fallback.setup().closed_form);
  EXPECT_NE(fallback.summary().find("IK solver numerical (damped least squares, 8 restarts; no closed form: 7R, no joint whose"),
            std::string::npos)
      << fallback.summary();
  std::filesystem::remove(file);
}

#endif
