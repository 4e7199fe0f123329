// Tests of the haptic6r mechanism: IK/FK round trips, Jacobian vs finite differences, inertia
// and gravity vs KDL and vs an independent energy computation, extremes, selection, errors.
#include "haptic6r.hpp"
#include "haptic6r_ik.hpp"

#include "test_support.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/options.hpp>

#include <gtest/gtest.h>

#include "vector_targets.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>
#include <iomanip>
#include <cstring>
#include <fstream>
#include <map>
#include <random>

#ifdef HAPSYN_HAVE_KDL
#include <kdl/chain.hpp>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#endif

using namespace hapsyn;
using namespace hapsyn::plugins;

namespace {

constexpr double kPi = 3.14159265358979323846;

std::vector<double> paper_like_design() {
  // l1..l5 [m], s, r: a plausible design inside the paper's bounds.
  return {0.45, 0.45, 0.65, 0.55, 0.15, 3, 3, 2, 2, 1, 1, 2, 2, 3, 2, 3, 3};
}

std::vector<double> random_design(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double lo[5] = {0.3, 0.3, 0.3, 0.3, 0.12}, hi[5] = {1.0, 1.0, 1.5, 1.0, 0.3};
  std::vector<double> d(17);
  for (int i = 0; i < 5; ++i) d[static_cast<std::size_t>(i)] = lo[i] + (hi[i] - lo[i]) * u(rng);
  int s = 3;
  for (int i = 0; i < 6; ++i) {
    if (i >= 2) s = std::max(1, s - static_cast<int>(u(rng) * 1.5));
    d[static_cast<std::size_t>(5 + i)] = s;
    d[static_cast<std::size_t>(11 + i)] = 1 + static_cast<int>(u(rng) * 6) % 6;
  }
  return d;
}

// The mechanism as the registry builds it from a problem file's options (validated, defaults filled).
Haptic6R haptic6r(const Json& options = Json::object()) { return Haptic6R(make_options<Haptic6ROptions>(options)); }

struct Fixture {
  Haptic6RSetup setup;
  Haptic6RModel model;
  explicit Fixture(const std::vector<double>& design, const Json& json = Json::object())
      : setup(Haptic6RSetup::from_options(make_options<Haptic6ROptions>(json))) {
    model.rebuild(design.data(), setup);
  }
};

double pose_error(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm() + (a.linear() - b.linear()).norm();
}

std::array<double, 7> pose_row(const Eigen::Isometry3d& t) {
  Eigen::Quaterniond q(t.linear());
  if (q.w() < 0) q.coeffs() *= -1.0;
  return {t.translation().x(), t.translation().y(), t.translation().z(), q.w(), q.x(), q.y(), q.z()};
}

Vector6d random_q(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-kPi, kPi), u4(0.05, kPi - 0.05);
  Vector6d q;
  q << u(rng), u(rng), u(rng), u4(rng), u(rng), u(rng);
  return q;
}

double angle_distance(const Vector6d& a, const Vector6d& b) {
  double m = 0.0;
  for (int i = 0; i < 6; ++i) m = std::max(m, std::abs(std::remainder(a(i) - b(i), 2.0 * kPi)));
  return m;
}

}  // namespace

TEST(Haptic6R, InverseKinematicsTrigAgreesWithItsAngles) {
  // solve() builds the chosen configuration's frames from these cosines and sines.
  std::mt19937 rng(7);
  for (int d = 0; d < 10; ++d) {
    Fixture f(random_design(rng));
    for (int k = 0; k < 200; ++k) {
      std::array<Vector6d, 8> solutions;
      std::array<hapsyn::plugins::JointTrig, 8> trig;
      const int count = f.model.inverse_kinematics(f.model.forward(random_q(rng)), solutions, &trig);
      for (int s = 0; s < count; ++s) {
        for (int i = 0; i < 6; ++i) {
          const double theta = solutions[static_cast<std::size_t>(s)](i) + f.model.dh_row(i)(0);
          EXPECT_NEAR(trig[static_cast<std::size_t>(s)].c[static_cast<std::size_t>(i)], std::cos(theta), 1e-9) << s << " " << i;
          EXPECT_NEAR(trig[static_cast<std::size_t>(s)].s[static_cast<std::size_t>(i)], std::sin(theta), 1e-9) << s << " " << i;
        }
      }
    }
  }
}

TEST(Haptic6R, InverseThenForwardReproducesEveryPoseForRandomConfigurations) {
  std::mt19937 rng(42);
  int checked = 0;
  for (int d = 0; d < 20; ++d) {
    Fixture f(random_design(rng));
    for (int k = 0; k < 200; ++k) {
      const Vector6d q = random_q(rng);
      const Eigen::Isometry3d target = f.model.forward(q);
      std::array<Vector6d, 8> solutions;
      const int count = f.model.inverse_kinematics(target, solutions);
      ASSERT_GE(count, 1);
      bool found_original = false;
      for (int s = 0; s < count; ++s) {
        const Vector6d& qs = solutions[static_cast<std::size_t>(s)];
        ASSERT_TRUE(qs.allFinite());
        EXPECT_LT(pose_error(f.model.forward(qs), target), 1e-9) << "solution " << s << " of " << count;
        found_original = found_original || angle_distance(qs, q) < 1e-7;
      }
      EXPECT_TRUE(found_original) << "the configuration that made the pose is among the solutions";
      // The wrist point fixes joint 3's axis up to the two values of L4 cos(theta4) (each shared by
      // the mirror pair (h, theta4), (-h, pi - theta4)), each with two SCARA elbows: 4 or 8.
      EXPECT_TRUE(count == 4 || count == 8) << count;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 4000);
}

TEST(Haptic6R, SolveClassifiesAndReproducesThePose) {
  std::mt19937 rng(7);
  Fixture f(paper_like_design());
  auto scratch = std::make_unique<MechanismScratch>();
  int reachable = 0;
  for (int k = 0; k < 500; ++k) {
    const Vector6d q = random_q(rng);
    const auto row = pose_row(f.model.forward(q));
    SampleQuantities out;
    f.model.solve(row.data(), kNeedJacobian, *scratch, out);
    ASSERT_NE(out.status, SampleStatus::kUnreachable);
    ASSERT_TRUE(out.q.allFinite());
    if (out.status != SampleStatus::kReachable) continue;
    ++reachable;
    EXPECT_GE(out.q(3), -1e-12);
    EXPECT_LE(out.q(3), kPi + 1e-12);
    EXPECT_LT(pose_error(f.model.forward(Vector6d(out.q)), f.model.forward(q)), 1e-9);
  }
  EXPECT_GT(reachable, 450);
}

TEST(Haptic6R, SegmentsFollowTheDhRowsFromTheBaseToTheTarget) {
  std::mt19937 rng(11);
  Fixture f(paper_like_design());
  auto scratch = std::make_unique<MechanismScratch>();
  // Independently: the polyline's length is the sum of every row's |d| and |a| (d along z_{i-1},
  // then a along x_i, at right angles).
  double length = 0.0;
  for (int i = 0; i < 6; ++i) length += std::abs(f.model.dh_row(i)(1)) + std::abs(f.model.dh_row(i)(2));
  int drawn = 0;
  for (int k = 0; k < 50; ++k) {
    const Vector6d q = random_q(rng);
    const auto row = pose_row(f.model.forward(q));
    SampleSet scene;
    scene.poses = Eigen::Map<const SampleSet::RowMatrix>(row.data(), 1, 7);
    SampleQuantities out;
    f.model.solve(row.data(), kNeedPose, *scratch, out);
    const std::vector<Segment> segments = f.model.segments(scene, 0, *scratch);
    if (out.status != SampleStatus::kReachable && out.status != SampleStatus::kSingular) {
      EXPECT_TRUE(segments.empty());
      continue;
    }
    ++drawn;
    ASSERT_EQ(segments.size(), 1u);
    const auto& p = segments[0].points;
    EXPECT_LT(p.front().norm(), 1e-12);
    EXPECT_LT((p.back() - Eigen::Vector3d(row[0], row[1], row[2])).norm(), 1e-9);
    double sum = 0.0;
    for (std::size_t i = 1; i < p.size(); ++i) sum += (p[i] - p[i - 1]).norm();
    EXPECT_NEAR(sum, length, 1e-9);
  }
  EXPECT_GT(drawn, 40);
  SampleSet far;
  far.poses.resize(1, 7);
  far.poses << 10, 10, 10, 1, 0, 0, 0;
  EXPECT_TRUE(f.model.segments(far, 0, *scratch).empty());
}

TEST(Haptic6R, JacobianMatchesFiniteDifferences) {
  std::mt19937 rng(3);
  for (int d = 0; d < 5; ++d) {
    Fixture f(random_design(rng));
    for (int k = 0; k < 20; ++k) {
      const Vector6d q = random_q(rng);
      const Matrix6d j = f.model.jacobian(q);
      const double h = 1e-6;
      for (int i = 0; i < 6; ++i) {
        Vector6d qp = q, qm = q;
        qp(i) += h;
        qm(i) -= h;
        const Eigen::Isometry3d tp = f.model.forward(qp), tm = f.model.forward(qm);
        const Eigen::Vector3d v = (tp.translation() - tm.translation()) / (2 * h);
        const Eigen::AngleAxisd w(tp.linear() * tm.linear().transpose());
        const Eigen::Vector3d omega = w.axis() * w.angle() / (2 * h);
        EXPECT_LT((j.block<3, 1>(0, i) - omega).norm(), 1e-6) << "omega column " << i;
        EXPECT_LT((j.block<3, 1>(3, i) - v).norm(), 1e-6) << "v column " << i;
      }
    }
  }
}

// Kinetic energy 1/2 qdot^T H qdot computed body by body from finite-difference velocities of
// each body's centre and frame, and the potential energy's gradient: independent of the
// composite-body algorithm.
TEST(Haptic6R, InertiaAndGravityMatchIndependentEnergy) {
  std::mt19937 rng(11);
  Fixture f(paper_like_design());
  for (int k = 0; k < 10; ++k) {
    const Vector6d q = random_q(rng);
    Matrix6d hm;
    Vector6d g;
    f.model.dynamics(q, &hm, &g);
    const auto potential = [&](const Vector6d& x) {
      std::array<Eigen::Isometry3d, 7> fr;
      f.model.frames(x, fr);
      double e = 0.0;
      for (std::size_t b = 0; b < 6; ++b) e += f.model.bodies()[b].mass * 9.81 * (fr[b + 1] * f.model.bodies()[b].com).z();
      return e;
    };
    for (int i = 0; i < 6; ++i) {
      Vector6d qp = q, qm = q;
      qp(i) += 1e-6;
      qm(i) -= 1e-6;
      EXPECT_NEAR(g(i), (potential(qp) - potential(qm)) / 2e-6, 1e-5) << "gravity " << i;
    }
    const Vector6d qdot = Vector6d::Random();
    const double h = 1e-6;
    std::array<Eigen::Isometry3d, 7> fp, fm;
    f.model.frames(q + h * qdot, fp);
    f.model.frames(q - h * qdot, fm);
    double kinetic = 0.0;
    for (std::size_t b = 0; b < 6; ++b) {
      const Haptic6RBody& body = f.model.bodies()[b];
      const Eigen::Vector3d v = (fp[b + 1] * body.com - fm[b + 1] * body.com) / (2 * h);
      const Eigen::AngleAxisd w(fp[b + 1].linear() * fm[b + 1].linear().transpose());
      const Eigen::Vector3d omega = w.axis() * w.angle() / (2 * h);
      std::array<Eigen::Isometry3d, 7> f0;
      f.model.frames(q, f0);
      const Eigen::Matrix3d inertia = f0[b + 1].linear() * body.inertia * f0[b + 1].linear().transpose();
      kinetic += 0.5 * body.mass * v.squaredNorm() + 0.5 * omega.dot(inertia * omega);
    }
    EXPECT_NEAR(0.5 * qdot.dot(hm * qdot), kinetic, 1e-6 * std::max(1.0, kinetic));
    EXPECT_LT((hm - hm.transpose()).norm(), 1e-12);
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix6d>(hm).eigenvalues().minCoeff(), 0.0);
  }
}

#ifdef HAPSYN_HAVE_KDL
namespace {
// The same chain and mass model for KDL: one RotZ segment per DH row, body i in DH frame i + 1
// (KDL's segment tip frame); KDL's joint angle is q_i + theta_offset_i.
KDL::Chain kdl_chain(const Haptic6RModel& model) {
  KDL::Chain chain;
  for (int i = 0; i < 6; ++i) {
    const Eigen::Vector4d row = model.dh_row(i);  // offset, d, a, alpha
    const Haptic6RBody& b = model.bodies()[static_cast<std::size_t>(i)];
    const KDL::RotationalInertia ic(b.inertia(0, 0), b.inertia(1, 1), b.inertia(2, 2), b.inertia(0, 1),
                                    b.inertia(0, 2), b.inertia(1, 2));
    chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotZ), KDL::Frame::DH(row(2), row(3), row(1), 0.0),
                                  KDL::RigidBodyInertia(b.mass, KDL::Vector(b.com.x(), b.com.y(), b.com.z()), ic)));
  }
  return chain;
}
}  // namespace

TEST(Haptic6R, JacobianInertiaAndGravityMatchKdl) {
  std::mt19937 rng(5);
  for (int d = 0; d < 5; ++d) {
    Fixture f(d == 0 ? paper_like_design() : random_design(rng));
    const KDL::Chain chain = kdl_chain(f.model);
    KDL::ChainDynParam dyn(chain, KDL::Vector(0, 0, -9.81));
    KDL::ChainJntToJacSolver jac_solver(chain);
    for (int k = 0; k < 20; ++k) {
      const Vector6d q = random_q(rng);
      KDL::JntArray kq(6);
      for (int i = 0; i < 6; ++i) kq(static_cast<unsigned>(i)) = q(i) + f.model.dh_row(i)(0);
      KDL::JntSpaceInertiaMatrix kh(6);
      KDL::JntArray kg(6);
      KDL::Jacobian kj(6);
      ASSERT_EQ(dyn.JntToMass(kq, kh), 0);
      ASSERT_EQ(dyn.JntToGravity(kq, kg), 0);
      ASSERT_EQ(jac_solver.JntToJac(kq, kj), 0);
      Matrix6d hm;
      Vector6d g;
      f.model.dynamics(q, &hm, &g);
      const Matrix6d j = f.model.jacobian(q);
      for (int r = 0; r < 6; ++r) {
        EXPECT_NEAR(g(r), kg(static_cast<unsigned>(r)), 1e-9 * std::max(1.0, std::abs(g(r)))) << "gravity " << r;
        for (int c = 0; c < 6; ++c) {
          EXPECT_NEAR(hm(r, c), kh(static_cast<unsigned>(r), static_cast<unsigned>(c)), 1e-9) << "H " << r << "," << c;
          // KDL's Jacobian rows are (v, omega); ours (omega, v).
          EXPECT_NEAR(j(r, c), kj(static_cast<unsigned>((r + 3) % 6), static_cast<unsigned>(c)), 1e-12) << "J " << r << "," << c;
        }
      }
    }
  }
}
#endif

#ifdef HAPSYN_HAVE_KDL
// The full inverse dynamics of solve()'s demanded motion, tau = H qddot + c + g, against KDL's
// recursive Newton-Euler on the same chain with gravity, at random reachable configurations,
// joint rates and accelerations.
TEST(Haptic6R, FullInverseDynamicsMatchesKdlRecursiveNewtonEuler) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto scratch = std::make_unique<MechanismScratch>();
  double worst = 0.0;
  int checked = 0;
  for (int d = 0; d < 5; ++d) {
    Fixture f(d == 0 ? paper_like_design() : random_design(rng));
    const KDL::Chain chain = kdl_chain(f.model);
    KDL::ChainIdSolver_RNE rne(chain, KDL::Vector(0, 0, -f.setup.options.gravity));
    for (int k = 0; k < 40; ++k) {
      const auto row = pose_row(f.model.forward(random_q(rng)));
      Vector6d twist, twist_rate;
      for (int r = 0; r < 6; ++r) {
        twist(r) = u(rng);
        twist_rate(r) = 3.0 * u(rng);
      }
      SampleQuantities out;
      out.twist = twist.data();
      out.twist_rate = twist_rate.data();
      f.model.solve(row.data(),
                    kNeedInertia | kNeedGravity | kNeedJointVelocity | kNeedJointAcceleration | kNeedVelocityTorque,
                    *scratch, out);
      if (out.status != SampleStatus::kReachable) continue;
      ++checked;
      const Vector6d tau = out.inertia * out.joint_acceleration + out.velocity_torque + out.gravity;
      KDL::JntArray kq(6), kqd(6), kqdd(6), ktau(6);
      for (unsigned i = 0; i < 6; ++i) {
        kq(i) = out.q(i) + f.model.dh_row(static_cast<int>(i))(0);
        kqd(i) = out.joint_velocity(i);
        kqdd(i) = out.joint_acceleration(i);
      }
      KDL::Wrenches wrenches(chain.getNrOfSegments(), KDL::Wrench::Zero());
      ASSERT_EQ(rne.CartToJnt(kq, kqd, kqdd, wrenches, ktau), 0);
      Vector6d expected;
      for (int i = 0; i < 6; ++i) expected(i) = ktau(static_cast<unsigned>(i));
      const double error = (tau - expected).norm() / expected.norm();
      worst = std::max(worst, error);
      EXPECT_LT(error, 1e-9) << tau.transpose() << "\n" << expected.transpose();
    }
  }
  EXPECT_GT(checked, 150);
  std::printf("haptic6r tau = H qddot + c + g vs KDL RNE: worst relative error %.3g over %d samples\n", worst, checked);
}
#endif

namespace {
// The end-effector acceleration (d omega/dt, dv/dt) in B at t = 0 along q(t) = q + qdot t +
// qddot t^2 / 2 from the forward kinematics alone, by second central differences: dv/dt from
// the position, d omega/dt = vee(skew(Rddot R^T)) (Rdot Rdot^T, the rest of d/dt (Rdot R^T), is
// symmetric).
Vector6d acceleration_by_differences(const Haptic6RModel& model, const Vector6d& q, const Vector6d& qdot,
                                     const Vector6d& qddot, double h) {
  const auto at = [&](double t) { return model.forward(Vector6d(q + qdot * t + 0.5 * qddot * t * t)); };
  const Eigen::Isometry3d p = at(h), o = at(0.0), m = at(-h);
  const Eigen::Matrix3d a = (p.linear() - 2.0 * o.linear() + m.linear()) / (h * h) * o.linear().transpose();
  const Eigen::Matrix3d skew = 0.5 * (a - a.transpose());
  Vector6d out;
  out << skew(2, 1), skew(0, 2), skew(1, 0), (p.translation() - 2.0 * o.translation() + m.translation()) / (h * h);
  return out;
}
}  // namespace

// solve()'s joint rates realise the twist (J qdot = twist) and its accelerations the twist
// rate: the end-effector acceleration along the joint trajectory, differentiated numerically
// from the forward kinematics, is twist_rate (so the Jdot qdot term is right).
TEST(Haptic6R, JointRatesAndAccelerationsRealiseTheDemandedMotion) {
  std::mt19937 rng(22);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto scratch = std::make_unique<MechanismScratch>();
  double worst_rate = 0.0, worst_acceleration = 0.0;
  int checked = 0;
  for (int d = 0; d < 5; ++d) {
    Fixture f(d == 0 ? paper_like_design() : random_design(rng));
    for (int k = 0; k < 40; ++k) {
      const auto row = pose_row(f.model.forward(random_q(rng)));
      Vector6d twist, twist_rate;
      for (int r = 0; r < 6; ++r) {
        twist(r) = 0.5 * u(rng);
        twist_rate(r) = u(rng);
      }
      SampleQuantities out;
      out.twist = twist.data();
      out.twist_rate = twist_rate.data();
      f.model.solve(row.data(), kNeedJacobian | kNeedJointVelocity | kNeedJointAcceleration, *scratch, out);
      if (out.status != SampleStatus::kReachable) continue;
      const double rate_error = (out.jacobian * out.joint_velocity - twist).norm();
      worst_rate = std::max(worst_rate, rate_error);
      EXPECT_LT(rate_error, 1e-10);
      // Near a singularity the rates are large and the differences inaccurate: skip those.
      if (out.joint_velocity.norm() > 5.0 || out.joint_acceleration.norm() > 50.0) continue;
      ++checked;
      const Vector6d numeric = acceleration_by_differences(f.model, Vector6d(out.q), Vector6d(out.joint_velocity),
                                                           Vector6d(out.joint_acceleration), 1e-4);
      const double error = (numeric - twist_rate).norm() / twist_rate.norm();
      worst_acceleration = std::max(worst_acceleration, error);
      EXPECT_LT(error, 1e-5) << numeric.transpose() << "\n" << twist_rate.transpose();
    }
  }
  EXPECT_GT(checked, 100);
  std::printf("haptic6r: |J qdot - twist| <= %.3g; FK acceleration vs twist_rate: worst relative %.3g (%d samples)\n",
              worst_rate, worst_acceleration, checked);
}

// The demanded-motion outputs are computed only when asked for, each on its own flag.
TEST(Haptic6R, DemandedMotionOnlyWhenAskedFor) {
  Fixture f(paper_like_design());
  auto scratch = std::make_unique<MechanismScratch>();
  Vector6d q;
  q << 0.3, 1.0, -0.5, 1.2, 1.0, 0.2;
  const auto row = pose_row(f.model.forward(q));
  Vector6d twist, twist_rate;
  twist << 0.1, -0.2, 0.3, 0.05, 0.1, -0.1;
  twist_rate << 0.5, 0.2, -0.1, 0.3, -0.2, 0.4;
  SampleQuantities out;
  out.twist = twist.data();
  out.twist_rate = twist_rate.data();
  out.joint_velocity.setConstant(6, 7.0);
  out.joint_acceleration.setConstant(6, 7.0);
  out.velocity_torque.setConstant(6, 7.0);
  f.model.solve(row.data(), kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits, *scratch, out);
  ASSERT_EQ(out.status, SampleStatus::kReachable);
  EXPECT_EQ(out.joint_velocity(0), 7.0);
  EXPECT_EQ(out.joint_acceleration(0), 7.0);
  EXPECT_EQ(out.velocity_torque(0), 7.0);
  f.model.solve(row.data(), kNeedJointVelocity, *scratch, out);
  EXPECT_NE(out.joint_velocity(0), 7.0);
  EXPECT_EQ(out.joint_acceleration(0), 7.0);
  EXPECT_EQ(out.velocity_torque(0), 7.0);
  f.model.solve(row.data(), kNeedJointVelocity | kNeedVelocityTorque, *scratch, out);
  EXPECT_EQ(out.joint_acceleration(0), 7.0);
  EXPECT_NE(out.velocity_torque(0), 7.0);
  EXPECT_TRUE(out.velocity_torque.allFinite());
  // Without a twist (outside the evaluator) the rates are NaN, not silently zero.
  out.twist = nullptr;
  f.model.solve(row.data(), kNeedJointVelocity, *scratch, out);
  EXPECT_TRUE(std::isnan(out.joint_velocity(0)));
  EXPECT_TRUE(haptic6r().provides() & kNeedVelocityTorque);
}

TEST(Haptic6R, ExtremesAreFiniteOrClassifiedNeverNaN) {
  auto scratch = std::make_unique<MechanismScratch>();
  const Needs all = kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits;
  // Links at their lower and upper bounds.
  for (const std::vector<double>& design :
       {std::vector<double>{0.3, 0.3, 0.3, 0.3, 0.12, 3, 3, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1},
        std::vector<double>{1.0, 1.0, 1.5, 1.0, 0.3, 3, 3, 3, 3, 3, 3, 6, 6, 6, 6, 6, 6}, paper_like_design()}) {
    Fixture f(design);
    std::vector<Vector6d> configurations;
    Vector6d q;
    q << 0.3, 1.0, -0.5, 0.0, 1.0, 0.2;  // q4 = 0: l4 vertical (down)
    configurations.push_back(q);
    q(3) = kPi;  // l4 vertical (up)
    configurations.push_back(q);
    q(3) = 1e-9;
    configurations.push_back(q);
    q << 0.3, 1.0, -0.5, 1.2, 0.0, 0.2;  // wrist axis vertical: z_5 = -y_4, vertical when q4 = 90 deg
    q(3) = kPi / 2;
    configurations.push_back(q);
    q << 0.3, 0.0, -0.5, 1.2, 1.0, 0.2;  // SCARA stretched: pose on the horizontal reach boundary
    configurations.push_back(q);
    q << 0.3, 0.0, -0.5, 0.0, 1.0, 0.2;  // stretched and l4 vertical: a corner of the reach
    configurations.push_back(q);
    for (const Vector6d& c : configurations) {
      const auto row = pose_row(f.model.forward(c));
      SampleQuantities out;
      f.model.solve(row.data(), all, *scratch, out);
      EXPECT_TRUE(out.q.allFinite());
      EXPECT_NE(out.status, SampleStatus::kReachable) << "q = " << c.transpose();
      EXPECT_NE(out.status, SampleStatus::kUnreachable) << "a boundary pose is reached (singular), q = " << c.transpose();
      std::array<Vector6d, 8> sol;
      const int n = f.model.inverse_kinematics(f.model.forward(c), sol);
      for (int s = 0; s < n; ++s) EXPECT_TRUE(sol[static_cast<std::size_t>(s)].allFinite());
    }
    // Just past the reach: unreachable, never NaN.
    Vector6d c;
    c << 0.3, 1.0, -0.5, 0.0, kPi / 2, 0.2;
    Eigen::Isometry3d t = f.model.forward(c);
    t.translation().z() -= 1e-6;
    const auto row = pose_row(t);
    SampleQuantities out;
    f.model.solve(row.data(), all, *scratch, out);
    EXPECT_EQ(out.status, SampleStatus::kUnreachable);
    EXPECT_TRUE(out.q.allFinite());
    // Degenerate quaternion.
    const double zero[7] = {0.1, 0.1, -0.5, 0, 0, 0, 0};
    f.model.solve(zero, all, *scratch, out);
    EXPECT_EQ(out.status, SampleStatus::kUnreachable);
  }
}

TEST(Haptic6R, SelectionRulesAndJointLimits) {
  std::mt19937 rng(9);
  Fixture left(paper_like_design(), Json{{"selection", "elbow_left"}});
  Fixture right(paper_like_design(), Json{{"selection", "elbow_right"}});
  Fixture home(paper_like_design(), Json{{"home", {10, -60, 20, 45, 30, 0}}});
  Fixture narrow(paper_like_design(), Json{{"joint_lower", {-180, -180, -180, 80, -180, -180}},
                                           {"joint_upper", {180, 180, 180, 100, 180, 180}}});
  auto scratch = std::make_unique<MechanismScratch>();
  int invalid = 0;
  for (int k = 0; k < 200; ++k) {
    const Vector6d q = random_q(rng);
    const auto row = pose_row(left.model.forward(q));
    SampleQuantities a, b, c, n;
    left.model.solve(row.data(), kNeedPose, *scratch, a);
    right.model.solve(row.data(), kNeedPose, *scratch, b);
    home.model.solve(row.data(), kNeedPose, *scratch, c);
    narrow.model.solve(row.data(), kNeedPose, *scratch, n);
    if (a.status == SampleStatus::kReachable) {
      EXPECT_GE(a.q(1), 0.0);
    }
    if (b.status == SampleStatus::kReachable) {
      EXPECT_LE(b.q(1), 0.0);
    }
    if (c.status == SampleStatus::kReachable) {
      // The chosen solution is the admissible one closest to home.
      std::array<Vector6d, 8> sol;
      const int count = home.model.inverse_kinematics(home.model.forward(q), sol);
      const auto dist = [&](const Vector6d& x) {
        double s = 0;
        for (int i = 0; i < 6; ++i) s += std::pow(std::remainder(x(i) - home.setup.home(i), 2 * kPi), 2);
        return s;
      };
      for (int s = 0; s < count; ++s) {
        const Vector6d& x = sol[static_cast<std::size_t>(s)];
        if (x(3) < -1e-9 || x(3) > kPi + 1e-9) continue;
        EXPECT_LE(dist(Vector6d(c.q)), dist(x) + 1e-12);
      }
    }
    if (n.status == SampleStatus::kInvalid) ++invalid;
    if (n.status == SampleStatus::kReachable) {
      EXPECT_GE(n.q(3), 80 * kPi / 180 - 1e-9);
      EXPECT_LE(n.q(3), 100 * kPi / 180 + 1e-9);
    }
  }
  EXPECT_GT(invalid, 100) << "a narrow q4 range excludes most random poses";
}

TEST(Haptic6R, ActuatorTableAndOnDemandQuantities) {
  Fixture f(paper_like_design());
  const ActuatorTable& t = f.setup.actuators;
  EXPECT_NEAR(t.max_velocity(3, 2), 4000 * 2 * kPi / 60 / 50, 1e-12);
  EXPECT_NEAR(t.max_torque(3, 2), 1.2 * 50 * 0.8, 1e-12);
  EXPECT_NEAR(t.max_torque(1, 6), 30.0, 1e-12) << "capped by the gear's peak torque";
  EXPECT_NEAR(f.model.max_torque()(3), t.max_torque(2, 2), 1e-12);
  // Motor 5 (size s5 = 1) sits at the origin of frame 4, +20 %, with the l4 tube.
  EXPECT_NEAR(f.model.bodies()[3].mass, 1.2 * 0.9 + 4.0 * 0.55, 1e-12);
  EXPECT_NEAR(f.model.bodies()[5].mass, 0.5 + 4.0 * 0.15, 1e-12);
  // Quantities not asked for are left untouched.
  auto scratch = std::make_unique<MechanismScratch>();
  Vector6d q;
  q << 0.3, 1.0, -0.5, 1.2, 1.0, 0.2;
  const auto row = pose_row(f.model.forward(q));
  SampleQuantities out;
  out.jacobian.setConstant(6, 6, 7.0);
  out.inertia.setConstant(6, 6, 7.0);
  out.gravity.setConstant(6, 7.0);
  out.max_torque.setConstant(6, 7.0);
  f.model.solve(row.data(), kNeedPose, *scratch, out);
  ASSERT_EQ(out.status, SampleStatus::kReachable);
  EXPECT_EQ(out.jacobian(0, 0), 7.0);
  EXPECT_EQ(out.inertia(0, 0), 7.0);
  EXPECT_EQ(out.gravity(0), 7.0);
  EXPECT_EQ(out.max_torque(0), 7.0);
  f.model.solve(row.data(), kNeedJacobian | kNeedActuatorLimits, *scratch, out);
  EXPECT_NE(out.jacobian(0, 0), 7.0);
  EXPECT_EQ(out.inertia(0, 0), 7.0);
  EXPECT_EQ(out.gravity(0), 7.0);
  EXPECT_EQ(out.max_torque(3), f.model.max_torque()(3));
  // Gravity on joint 4 is largest with l4 horizontal (q4 = 90 deg) and tens of N m at most.
  Vector6d g;
  q(3) = kPi / 2;
  f.model.dynamics(q, nullptr, &g);
  EXPECT_GT(std::abs(g(3)), 5.0);
  EXPECT_LT(std::abs(g(3)), 60.0);
  EXPECT_NEAR(g(0), 0.0, 1e-9) << "vertical axes carry no gravity torque";
}

TEST(Haptic6R, DesignSpaceAndConstraints) {
  const Haptic6R mech = haptic6r();
  const auto vars = mech.variables();
  ASSERT_EQ(vars.size(), 3u);
  EXPECT_EQ(vars[0].name, "l");
  EXPECT_EQ(vars[0].size, 5);
  EXPECT_EQ(vars[0].default_upper[2], 1.5);
  EXPECT_TRUE(vars[1].integer);
  EXPECT_EQ(vars[1].default_lower, (std::vector<double>{3, 3, 1, 1, 1, 1}));
  EXPECT_TRUE(vars[2].integer);
  ASSERT_EQ(mech.constraints().size(), 5u);
  std::vector<double> d = paper_like_design();
  d[7] = 3;  // s3 = 3 > s2? no: s2 = 3, s3 = 3 fine; s4 = 2 < 3 fine
  double g[5];
  SampleSet empty;
  mech.evaluate_constraints(d.data(), empty, g);
  for (double v : g) EXPECT_LE(v, 0.0);
  d[9] = 3;  // s5 = 3 > s4 = 2
  mech.evaluate_constraints(d.data(), empty, g);
  EXPECT_EQ(g[3], 1.0);
  EXPECT_EQ(mech.provides(), kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits | kNeedJointVelocity |
                                 kNeedJointAcceleration | kNeedVelocityTorque);
  // build_in reuses the scratch.
  auto scratch = mech.make_scratch();
  const MechanismModel* m1 = mech.build_in(paper_like_design().data(), *scratch);
  const MechanismModel* m2 = mech.build_in(paper_like_design().data(), *scratch);
  EXPECT_NE(m1, nullptr);
  EXPECT_EQ(m1, m2);
}

TEST(Haptic6R, ErrorMessagesNameTheOptionValueAndRule) {
  using test::expect_error;
  // The declared rules (the framework's messages), then the relations and files the constructor checks.
  expect_error([] { haptic6r(Json{{"bogus", 1}}); }, {"problem", "options.bogus", "unknown key"});
  expect_error([] { haptic6r(Json{{"selection", "nearest"}}); }, {"options.selection", "nearest", "closest_to_home"});
  // (A list's size through the registry: the schema as the plugin file exports it.)
  expect_error([] { test::registry().create_mechanism("haptic6r", Json{{"home", {1, 2}}}, "mechanism"); },
               {"options.home", "must have at least 6 items"});
  expect_error([] { haptic6r(Json{{"joint_lower", {0, 0, 0, 90, 0, 0}}, {"joint_upper", {10, 10, 10, 80, 10, 10}}}); },
               {"options.joint_upper[3]", "must be >= joint_lower[3]"});
  expect_error([] { haptic6r(Json{{"tube_wall", 0.2}}); }, {"options.tube_wall", "tube_outer_diameter"});
  // Angles within two turns either way (the lane selection takes a bounded number of turns).
  expect_error([] { haptic6r(Json{{"home", {0, 90, 0, 90, 900, 0}}}); }, {"options.home[4]", "900", "720"});
  expect_error([] { haptic6r(Json{{"joint_lower", {-180, -180, -1e300, 0, -180, -180}}}); },
               {"options.joint_lower[2]", "-720"});
  expect_error([] { haptic6r(Json{{"joint_upper", {180, 180, 180, 180, 180, 721}}}); }, {"options.joint_upper[5]", "721"});
  expect_error([] { haptic6r(Json{{"dh_file", "/nonexistent/dh.json"}}); }, {"options.dh_file", "no such file"});
  const std::string dir = ::testing::TempDir();
  {
    std::ofstream(dir + "/bad_dh.json") << R"({"format": "hapsyn-haptic6r-dh", "dh": [
      {"theta_offset": 0, "d": 0, "a": "l1", "alpha": 0}, {"theta_offset": 0, "d": 0, "a": "l2", "alpha": 0},
      {"theta_offset": 0, "d": "l3", "a": 0, "alpha": 90}, {"theta_offset": -90, "d": 0, "a": "l4", "alpha": 0},
      {"theta_offset": 0, "d": 0, "a": 0, "alpha": 90}, {"theta_offset": 0, "d": "l5", "a": 0, "alpha": 0}]})";
    expect_error([&] { haptic6r(Json{{"dh_file", dir + "/bad_dh.json"}}); },
                 {"bad_dh.json", "dh[2]", "d = (0, 0, -l3, 0, 0, l5)"});
    std::ofstream(dir + "/bad_dh2.json") << R"({"format": "hapsyn-haptic6r-dh", "dh": [{"theta_offset": 0, "d": "l9", "a": 0, "alpha": 0}, 1, 2, 3, 4, 5]})";
    expect_error([&] { haptic6r(Json{{"dh_file", dir + "/bad_dh2.json"}}); }, {"bad_dh2.json", "dh[0].d = \"l9\"", "link name"});
    std::ofstream(dir + "/bad_act.json") << R"({"format": "hapsyn-actuator-table", "gear_ratios": [30, 50, -80, 100, 120, 160],
      "gear_efficiency": 0.8, "sizes": []})";
    expect_error([&] { haptic6r(Json{{"actuator_file", dir + "/bad_act.json"}}); }, {"bad_act.json", "gear_ratios[2] = -80"});
  }
  const Haptic6R mech = haptic6r();
  std::vector<double> d = paper_like_design();
  d[6] = 4;
  expect_error([&] { mech.build(d.data()); }, {"design s[1] = 4", "sizes must be in {1, 2, 3}"});
  d = paper_like_design();
  d[2] = -0.1;
  expect_error([&] { mech.build(d.data()); }, {"design l[2] = -0.1", "> 0"});
  SampleSet planar;
  planar.poses.resize(1, 2);
  planar.poses.setZero();
  expect_error([&] { mech.check_scene(planar); }, {"haptic6r", "2 coordinates"});
}

// A DH file's alpha within the admitted 1e-12 rad of the structure's is taken as exactly the
// structure's: the kinematics multiply none of its zeros and ones (haptic6r_chain.hpp), so a
// cosine of 1e-13 left in would make the Jacobian and the IK disagree.
TEST(Haptic6R, AlphaWithinToleranceIsExactlyTheStructuresAngle) {
  const std::string path = ::testing::TempDir() + "/near_dh.json";
  std::ofstream(path) << R"({"format": "hapsyn-haptic6r-dh", "dh": [
    {"theta_offset": 0, "d": 0, "a": "l1", "alpha": 0}, {"theta_offset": 0, "d": 0, "a": "l2", "alpha": 1e-11},
    {"theta_offset": 0, "d": "-l3", "a": 0, "alpha": 90.00000000001}, {"theta_offset": -90, "d": 0, "a": "l4", "alpha": 0},
    {"theta_offset": 0, "d": 0, "a": 0, "alpha": 89.99999999999}, {"theta_offset": 0, "d": "l5", "a": 0, "alpha": 0}]})";
  const Haptic6RSetup setup = Haptic6RSetup::from_options(make_options<Haptic6ROptions>(Json{{"dh_file", path}}));
  const double structure[6] = {0.0, 0.0, kPi / 2, 0.0, kPi / 2, 0.0};
  for (int i = 0; i < 6; ++i) EXPECT_EQ(setup.dh.rows[static_cast<std::size_t>(i)].alpha, structure[i]) << "row " << i;
  // A file beyond the tolerance is refused (the message names the row).
  std::ofstream(path) << R"({"format": "hapsyn-haptic6r-dh", "dh": [
    {"theta_offset": 0, "d": 0, "a": "l1", "alpha": 0}, {"theta_offset": 0, "d": 0, "a": "l2", "alpha": 0},
    {"theta_offset": 0, "d": "-l3", "a": 0, "alpha": 90.0001}, {"theta_offset": -90, "d": 0, "a": "l4", "alpha": 0},
    {"theta_offset": 0, "d": 0, "a": 0, "alpha": 90}, {"theta_offset": 0, "d": "l5", "a": 0, "alpha": 0}]})";
  test::expect_error([&] { haptic6r(Json{{"dh_file", path}}); }, {"near_dh.json", "dh[2]", "alpha = (0, 0, 90, 0, 90, 0) deg"});
}

TEST(Haptic6R, PluginLoadsThroughTheRegistry) {
  const auto mech = test::registry().create_mechanism("haptic6r", Json::object(), "mechanism");
  ASSERT_TRUE(mech);
  EXPECT_EQ(mech->variables().size(), 3u);
}

TEST(Haptic6R, DataFilesThatAreNotRegularFilesAreRefusedWithoutBlocking) {
  using test::expect_error;
  expect_error([] { read_haptic6r_dh("/dev/zero"); }, {"haptic6r: data file /dev/zero is not a regular file (a device or socket)"});
  // The actuator table's (the framework's reader, named by the plugin): tests/actuator_table_test.cpp.
}

namespace {
// |a - b| within 1e-12 of the larger magnitude (and of 1 near zero).
bool close(double a, double b) { return std::abs(a - b) <= 1e-12 * std::max({1.0, std::abs(a), std::abs(b)}); }

// The block of poses[first, first + n) over `coordinates`; the lanes past n repeat the last pose
// when `repeat_last`, else keep what `coordinates` holds.
PoseBlock pose_block(const std::vector<std::array<double, 7>>& poses, std::size_t first, int n, bool repeat_last,
                     double (&coordinates)[7][kBlockLanes]) {
  PoseBlock block;
  block.dimension = 7;
  block.count = n;
  for (int c = 0; c < 7; ++c) {
    for (int lane = 0; lane < (repeat_last ? kBlockLanes : n); ++lane) {
      coordinates[c][lane] = poses[first + static_cast<std::size_t>(std::min(lane, n - 1))][static_cast<std::size_t>(c)];
    }
    block.coordinate[c] = coordinates[c];
  }
  return block;
}
}  // namespace

void block_kernel_equals_solve_lane_by_lane_on_the_current_target() {
  // Poses of random configurations (reachable), their singular and boundary neighbours, poses
  // out of reach and a degenerate quaternion, in blocks of every fill (1..8 lanes).
  std::mt19937 rng(17);
  auto scratch = std::make_unique<MechanismScratch>();
  const Needs all = kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits;
  EXPECT_TRUE(haptic6r().solves_blocks(all));
  EXPECT_FALSE(haptic6r().solves_blocks(all | kNeedJointVelocity));  // the demanded motion stays per sample
  long reachable = 0, other = 0;
  for (int d = 0; d < 6; ++d) {
    Fixture f(d == 0 ? paper_like_design() : random_design(rng));
    std::vector<std::array<double, 7>> poses;
    for (int k = 0; k < 40; ++k) {
      Vector6d q = random_q(rng);
      if (k % 5 == 1) q(1) = 0.0;  // SCARA stretched: singular
      if (k % 5 == 2) q(3) = 0.0;  // l4 vertical: singular
      std::array<double, 7> row = pose_row(f.model.forward(q));
      if (k % 7 == 3) row[2] += 5.0;  // out of reach
      if (k % 11 == 4) row[3] = row[4] = row[5] = row[6] = 0.0;  // no rotation
      poses.push_back(row);
    }
    std::size_t first = 0;
    for (int count = 1; first < poses.size(); count = count % kBlockLanes + 1) {
      const int n = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(count), poses.size() - first));
      double coordinates[7][kBlockLanes];
      const PoseBlock block = pose_block(poses, first, n, true, coordinates);
      auto out = std::make_unique<QuantityBlock>();
      f.model.solve_block(block, all, *scratch, *out);
      for (int lane = 0; lane < n; ++lane) {
        SampleQuantities expected;
        f.model.solve(poses[first + static_cast<std::size_t>(lane)].data(), all, *scratch, expected);
        ASSERT_EQ(out->lane_status(lane), expected.status) << "design " << d << ", pose " << first + lane;
        if (expected.status != SampleStatus::kReachable) {
          ++other;
          continue;
        }
        ++reachable;
        for (int r = 0; r < 6; ++r) {
          EXPECT_TRUE(close(out->gravity[r][lane], expected.gravity(r))) << "g(" << r << ")";
          EXPECT_EQ(out->max_velocity[r], expected.max_velocity(r));
          EXPECT_EQ(out->max_torque[r], expected.max_torque(r));
          for (int c = 0; c < 6; ++c) {
            EXPECT_TRUE(close(out->jacobian[r * 6 + c][lane], expected.jacobian(r, c))) << "J(" << r << ", " << c << ")";
            EXPECT_TRUE(close(out->inertia[r * 6 + c][lane], expected.inertia(r, c))) << "H(" << r << ", " << c << ")";
          }
        }
      }
      for (int lane = n; lane < kBlockLanes; ++lane) EXPECT_EQ(out->lane_status(lane), SampleStatus::kUnreachable);
      first += static_cast<std::size_t>(n);
    }
  }
  EXPECT_GT(reachable, 100);  // both kinds of lanes were exercised
  EXPECT_GT(other, 50);
}

// On every vector target this machine runs (hapsyn/accel/vector_dispatch.hpp).
TEST(Haptic6R, BlockKernelEqualsSolveLaneByLane) {
  hapsyn::testing::for_each_vector_target(block_kernel_equals_solve_lane_by_lane_on_the_current_target);
}

// wrap_near() is wrap() for angles in [-3 pi, 3 pi) (the range the IK gives it): bit for bit
// on random angles, at the neighbours of every multiple of pi in the range, and for lanes.
TEST(Haptic6RWrap, NearWrapEqualsWrapInItsRange) {
  namespace ik = hapsyn::plugins::haptic6r_ik;
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> angle(-3.0 * kPi, 3.0 * kPi);
  std::vector<double> angles;
  for (int i = 0; i < 200000; ++i) angles.push_back(angle(rng));
  for (int k = -3; k <= 3; ++k) {
    double x = k * kPi;
    for (int step = 0; step < 40; ++step) x = std::nextafter(x, -INFINITY);
    for (int step = 0; step < 80; ++step, x = std::nextafter(x, INFINITY)) {
      if (x >= -3.0 * kPi && x < 3.0 * kPi) angles.push_back(x);
    }
  }
  for (const double x : angles) {
    const double near = ik::wrap_near(x), full = ik::wrap(x);
    ASSERT_EQ(std::memcmp(&near, &full, sizeof near), 0) << std::setprecision(17) << x << ": " << near << " vs " << full;
    ASSERT_GE(near, -kPi) << x;
    ASSERT_LT(near, kPi) << x;
  }
  for (std::size_t first = 0; first + kBlockLanes <= angles.size(); first += kBlockLanes) {
    const hapsyn::Lanes lanes = ik::wrap_near(hapsyn::Lanes::load(angles.data() + first));
    for (int lane = 0; lane < kBlockLanes; ++lane) ASSERT_EQ(lanes[lane], ik::wrap(angles[first + static_cast<std::size_t>(lane)]));
  }
  // Outside the range it would not be wrap(): the selection guards its use (IkModel::near_offset).
  EXPECT_NE(ik::wrap_near(3.5 * kPi), ik::wrap(3.5 * kPi));
}

TEST(Haptic6R, BlockStatusesAndQuantitiesEqualSolveUnderEveryRule) {
  // The lane IK and selection (haptic6r_ik.hpp at T = Lanes) against solve() (the same templates
  // at T = double) on 4,000 poses per rule: random configurations, their stretched and vertical
  // neighbours, a vertical roll axis (h free), poses just inside and outside l4's reach, scaled
  // and non-finite quaternions and positions. Statuses must be equal (the same decisions at every
  // threshold), and the quantities of every reachable lane agree to 1e-12 relative (the scalar
  // and the lane clones fuse multiply-adds differently).
  std::mt19937 rng(31);
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Json> rules = {
      Json::object(), Json{{"selection", "elbow_left"}}, Json{{"selection", "elbow_right"}},
      Json{{"home", {10, -60, 20, 45, 30, 0}}},
      Json{{"joint_lower", {-90, -150, -180, 60, -120, -180}}, {"joint_upper", {90, 150, 180, 120, 120, 180}}},
      Json{{"joint_lower", {0, 0, 0, 0, 0, 0}}, {"joint_upper", {350, 350, 350, 350, 350, 350}}},
      // Limits and home up to two turns away: the per-pose loops turn an angle several times.
      Json{{"joint_lower", {400, -720, 200, 360, -540, 500}},
           {"joint_upper", {700, -400, 500, 540, -300, 720}},
           {"home", {600, -600, 300, 450, -400, 650}}},
      Json{{"joint_lower", {-720, -700, -500, -360, 180, -380}},
           {"joint_upper", {-400, -380, -200, -180, 500, -20}},
           {"home", {-700, 720, -720, -270, 360, -200}}}};
  auto scratch = std::make_unique<MechanismScratch>();
  const Needs all = kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits;
  std::map<SampleStatus, long> seen;
  for (std::size_t r = 0; r < rules.size(); ++r) {
    Fixture f(r % 2 ? random_design(rng) : paper_like_design(), rules[r]);
    std::vector<std::array<double, 7>> poses;
    for (int k = 0; k < 4000; ++k) {
      Vector6d q = random_q(rng);
      if (k % 9 == 1) q(1) = 0.0;
      if (k % 9 == 2) q(3) = 0.5 * kPi;
      if (k % 9 == 3) q(4) = 0.0;  // roll axis along h's neighbour: exercises the near-vertical cases
      std::array<double, 7> row = pose_row(f.model.forward(q));
      if (k % 13 == 4) row = {row[0], row[1], row[2], 1.0, 0.0, 0.0, 0.0};      // roll axis vertical
      if (k % 13 == 5) row = {row[0], row[1], row[2], 0.0, 1.0, 0.0, 0.0};      // vertical, pointing down
      if (k % 17 == 6) row[2] += (k % 2 ? 1.0 : -1.0) * 1e-3 * (k % 5);          // near l4's reach
      if (k % 19 == 7) row[3] *= 3.0;                                             // not normalised
      if (k % 23 == 8) row[k % 7] = (k % 3 == 0) ? nan : (k % 3 == 1 ? inf : -inf);  // non-finite
      if (k % 29 == 9) row[3] = row[4] = row[5] = row[6] = 1e-10;                // below the norm floor
      poses.push_back(row);
    }
    for (std::size_t first = 0; first < poses.size(); first += kBlockLanes) {
      const int n = static_cast<int>(std::min<std::size_t>(kBlockLanes, poses.size() - first));
      double coordinates[7][kBlockLanes] = {};
      const PoseBlock block = pose_block(poses, first, n, false, coordinates);  // lanes past n: zeros
      auto out = std::make_unique<QuantityBlock>();
      f.model.solve_block(block, all, *scratch, *out);
      for (int lane = 0; lane < n; ++lane) {
        SampleQuantities expected;
        f.model.solve(poses[first + static_cast<std::size_t>(lane)].data(), all, *scratch, expected);
        ++seen[expected.status];
        ASSERT_EQ(out->lane_status(lane), expected.status) << "rule " << r << ", pose " << first + static_cast<std::size_t>(lane);
        if (expected.status != SampleStatus::kReachable) continue;
        for (int i = 0; i < 6; ++i) {
          ASSERT_TRUE(close(out->gravity[i][lane], expected.gravity(i))) << "rule " << r << ", pose " << first + static_cast<std::size_t>(lane);
          for (int c = 0; c < 6; ++c) {
            ASSERT_TRUE(close(out->jacobian[i * 6 + c][lane], expected.jacobian(i, c))) << "rule " << r << ", J(" << i << ", " << c << ")";
            ASSERT_TRUE(close(out->inertia[i * 6 + c][lane], expected.inertia(i, c))) << "rule " << r << ", H(" << i << ", " << c << ") " << out->inertia[i * 6 + c][lane] << " vs " << expected.inertia(i, c);
          }
        }
      }
    }
  }
  // Every status occurred often enough to mean something.
  EXPECT_GT(seen[SampleStatus::kReachable], 5000);
  EXPECT_GT(seen[SampleStatus::kUnreachable], 500);
  EXPECT_GT(seen[SampleStatus::kSingular], 500);
  EXPECT_GT(seen[SampleStatus::kInvalid], 500);
}

void quantities_block_equals_quantities_lane_by_lane_on_the_current_target() {
  std::mt19937 rng(23);
  Fixture f(random_design(rng));
  const Needs needs = kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits;
  auto out = std::make_unique<QuantityBlock>();
  for (int count = 1; count <= kBlockLanes; ++count) {
    std::vector<Vector6d> qs;
    for (int i = 0; i < count; ++i) qs.push_back(random_q(rng) * (i == 3 ? 1e5 : 1.0));  // one far past 2 pi
    f.model.quantities_block(qs.data(), count, needs, *out);
    for (int lane = 0; lane < kBlockLanes; ++lane) {
      EXPECT_EQ(out->lane_status(lane), lane < count ? SampleStatus::kReachable : SampleStatus::kUnreachable);
      if (lane >= count) continue;
      Matrix6d j, h;
      Vector6d g;
      f.model.quantities(qs[static_cast<std::size_t>(lane)], &j, &h, &g);
      for (int r = 0; r < 6; ++r) {
        EXPECT_TRUE(close(out->gravity[r][lane], g(r))) << "count " << count << ", lane " << lane;
        for (int c = 0; c < 6; ++c) {
          EXPECT_TRUE(close(out->jacobian[r * 6 + c][lane], j(r, c))) << "count " << count << ", lane " << lane;
          EXPECT_TRUE(close(out->inertia[r * 6 + c][lane], h(r, c))) << "count " << count << ", lane " << lane;
        }
      }
    }
  }
  for (const int bad : {0, kBlockLanes + 1}) {
    std::vector<Vector6d> qs(static_cast<std::size_t>(kBlockLanes + 1), Vector6d::Zero());
    const std::string message = hapsyn::test::error_of([&] { f.model.quantities_block(qs.data(), bad, needs, *out); });
    EXPECT_NE(message.find("haptic6r: quantities_block: count = " + std::to_string(bad) + ": must be 1..8"), std::string::npos)
        << message;
  }
}

// On every vector target this machine runs (hapsyn/accel/vector_dispatch.hpp).
TEST(Haptic6R, QuantitiesBlockEqualsQuantitiesLaneByLane) {
  hapsyn::testing::for_each_vector_target(quantities_block_equals_quantities_lane_by_lane_on_the_current_target);
}
