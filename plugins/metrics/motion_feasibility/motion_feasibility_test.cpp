// The motion_feasibility metric on hand-made quantities: the shares, the limits (a value exactly
// at a limit passes), the full inverse dynamics written out independently, and the needs.
#include "motion_feasibility.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/options.hpp>

#include <gtest/gtest.h>

#include <random>

namespace hapsyn::plugins {
namespace {

MotionFeasibility make(const std::string& share) {
  MotionFeasibilityOptions o;
  o.share = share;
  return MotionFeasibility(o);
}

// A reachable 3-joint sample with random dynamics, every torque and rate within its limit.
SampleQuantities random_sample(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  SampleQuantities q;
  q.status = SampleStatus::kReachable;
  const int n = 3;
  q.joint_velocity.resize(n);
  q.joint_acceleration.resize(n);
  q.velocity_torque.resize(n);
  q.gravity.resize(n);
  q.max_velocity.resize(n);
  q.max_torque.resize(n);
  q.inertia.resize(n, n);
  for (int i = 0; i < n; ++i) {
    q.joint_velocity(i) = u(rng);
    q.joint_acceleration(i) = u(rng);
    q.velocity_torque(i) = u(rng);
    q.gravity(i) = u(rng);
    for (int j = 0; j < n; ++j) q.inertia(i, j) = u(rng);
  }
  q.max_velocity.setConstant(10.0);
  q.max_torque.setConstant(100.0);
  return q;
}

// tau = H qddot + c + g, computed with Eigen products (the metric loops by hand).
Eigen::VectorXd torque(const SampleQuantities& q) {
  const Eigen::MatrixXd h = q.inertia;
  const Eigen::VectorXd qdd = q.joint_acceleration, c = q.velocity_torque, g = q.gravity;
  return h * qdd + c + g;
}

TEST(MotionFeasibility, LocalsFollowTheShare) {
  EXPECT_EQ(make("reachable").locals().size(), 1u);
  EXPECT_EQ(make("velocity").locals().size(), 2u);
  EXPECT_EQ(make("acceleration").locals().size(), 2u);
  const std::vector<LocalValue> all = make("all").locals();
  ASSERT_EQ(all.size(), 4u);
  EXPECT_EQ(all[0].name, "reachable");
  EXPECT_EQ(all[1].name, "velocity_feasible");
  EXPECT_EQ(all[2].name, "acceleration_feasible");
  EXPECT_EQ(all[3].name, "feasible");
  for (const LocalValue& l : all) EXPECT_EQ(l.reduction, Reduction::kSum);
  EXPECT_EQ(make("all").aggregation(), Aggregation::kAveraging);
}

TEST(MotionFeasibility, NeedsOnlyWhatTheShareUses) {
  EXPECT_EQ(make("reachable").needs(), kNeedPose);
  EXPECT_EQ(make("velocity").needs(), kNeedJointVelocity | kNeedActuatorLimits);
  const Needs acceleration = make("acceleration").needs();
  EXPECT_TRUE(acceleration & kNeedJointAcceleration);
  EXPECT_TRUE(acceleration & kNeedVelocityTorque);
  EXPECT_TRUE(acceleration & kNeedInertia);
  EXPECT_TRUE(acceleration & kNeedGravity);
  EXPECT_FALSE(acceleration & kNeedJacobian);
}

TEST(MotionFeasibility, UnreachableSamplesFailEveryShare) {
  std::mt19937_64 rng(1);
  SampleQuantities q = random_sample(rng);
  for (SampleStatus s : {SampleStatus::kUnreachable, SampleStatus::kSingular, SampleStatus::kInvalid}) {
    q.status = s;
    double out[4] = {-1, -1, -1, -1};
    make("all").local(q, out);
    for (double v : out) EXPECT_EQ(v, 0.0) << to_string(s);
  }
}

TEST(MotionFeasibility, VelocityLimitIsInclusivePerJoint) {
  std::mt19937_64 rng(2);
  SampleQuantities q = random_sample(rng);
  const MotionFeasibility m = make("velocity");
  double out[2];
  q.joint_velocity(1) = -q.max_velocity(1);  // exactly at the limit: feasible
  m.local(q, out);
  EXPECT_EQ(out[0], 1.0);
  EXPECT_EQ(out[1], 1.0);
  q.joint_velocity(1) = std::nextafter(-q.max_velocity(1), -1e9);  // one ulp beyond
  m.local(q, out);
  EXPECT_EQ(out[1], 0.0);
}

TEST(MotionFeasibility, TorqueIsTheFullInverseDynamics) {
  std::mt19937_64 rng(3);
  const MotionFeasibility m = make("acceleration");
  int feasible = 0, infeasible = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    SampleQuantities q = random_sample(rng);
    // Limits straddle the torques so that both outcomes occur.
    const Eigen::VectorXd tau = torque(q);
    std::uniform_real_distribution<double> scale(0.6, 1.4);
    for (int i = 0; i < 3; ++i) q.max_torque(i) = std::abs(tau(i)) * scale(rng) + 1e-12;
    const bool expected = (tau.array().abs() <= q.max_torque.head(3).array()).all();
    double out[2];
    m.local(q, out);
    EXPECT_EQ(out[1], expected ? 1.0 : 0.0) << "trial " << trial;
    (expected ? feasible : infeasible) += 1;
  }
  EXPECT_GT(feasible, 100);
  EXPECT_GT(infeasible, 100);
}

TEST(MotionFeasibility, VelocityTorqueTermMatters) {
  // A sample whose torque is within the limit only without C qdot: the metric must see it.
  std::mt19937_64 rng(4);
  SampleQuantities q = random_sample(rng);
  q.velocity_torque.setZero();
  const Eigen::VectorXd without = torque(q);
  q.max_torque = without.cwiseAbs().array() + 0.01;
  q.velocity_torque(0) = without(0) >= 0 ? 0.02 : -0.02;
  double out[2];
  make("acceleration").local(q, out);
  EXPECT_EQ(out[1], 0.0);
}

TEST(MotionFeasibility, CombineIsTheChosenShare) {
  const double reduced[4] = {9, 7, 5, 4};
  EXPECT_DOUBLE_EQ(make("all").combine(reduced, 10), 0.4);
  EXPECT_DOUBLE_EQ(make("velocity").combine(reduced, 10), 0.7);
  EXPECT_DOUBLE_EQ(make("acceleration").combine(reduced, 10), 0.7);  // its locals: reachable, acceleration
  EXPECT_DOUBLE_EQ(make("reachable").combine(reduced, 10), 0.9);
  EXPECT_EQ(make("all").combine(reduced, 0), 0.0);
}

TEST(MotionFeasibility, UnknownShareIsRefusedWithTheChoices) {
  Json options = {{"share", "speed"}};
  try {
    make_options<MotionFeasibilityOptions>(options, "objectives[0].options");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("speed"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("acceleration"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hapsyn::plugins
