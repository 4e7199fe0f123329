// Tests of the shared human arm model (human_arm_model.hpp): the arm file (Table II in radians,
// errors naming the file, the JSON path, the value and the rule; unreadable, malformed and
// non-regular files), forward kinematics against KDL and a second formulation, the Jacobian
// against finite differences, IK round trips, joint limits, manipulability selection by brute
// force, M_v / M_a against a direct SVD, and the left arm as the mirrored right arm. The
// human_arm scene's tests are in plugins/scenes/human_arm/human_arm_test.cpp.
#include "human_arm_model.hpp"
#include "human_arm_model_testing.hpp"

#include <hapsyn/error.hpp>

#include <gtest/gtest.h>

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <sys/stat.h>
#include <unistd.h>

#ifdef HAPSYN_HAVE_KDL
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#endif

namespace {

namespace fs = std::filesystem;
using hapsyn::Json;
using namespace hapsyn::plugins;
using namespace hapsyn::plugins::human_arm_testing;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

std::string arm_error(const Json& doc) {
  try {
    parse_human_arm(doc, "arm.json");
  } catch (const hapsyn::Error& e) {
    return e.what();
  }
  return "no error";
}

template <class Fn>
std::string error_of(Fn&& fn) {
  try {
    fn();
  } catch (const hapsyn::Error& e) {
    return e.what();
  }
  return "no error";
}

Vector7d random_q(std::mt19937& rng, bool q3_on_grid, int steps = 17) {
  const HumanArmData& d = arm().data();
  Vector7d q;
  for (int i = 0; i < 7; ++i) q(i) = std::uniform_real_distribution<double>(d.lower(i), d.upper(i))(rng);
  if (q3_on_grid) {
    const std::vector<double> grid = arm().joint3_grid(steps);
    q(2) = grid[std::uniform_int_distribution<int>(0, steps - 1)(rng)];
  }
  return q;
}

// An independent formulation of the same chain: each DH row as a product of elementary
// rotations and translations built with Eigen's geometry module.
Eigen::Isometry3d second_dh(const Vector7d& q) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 7; ++i) {
    const DhRow& r = arm().data().dh[i];
    T = T * Eigen::AngleAxisd(q(i) + r.theta_offset, Eigen::Vector3d::UnitZ()) * Eigen::Translation3d(0, 0, r.d) *
        Eigen::Translation3d(r.a, 0, 0) * Eigen::AngleAxisd(r.alpha, Eigen::Vector3d::UnitX());
  }
  return T;
}

// ------------------------------------------------------------------------- model ----

TEST(HumanArm, ArmFileHoldsTableTwoInRadians) {
  const HumanArmData& d = arm().data();
  EXPECT_EQ(d.name, "fennel2022_right_arm");
  EXPECT_EQ(d.side, "right");
  EXPECT_NEAR(d.dh[2].d, -0.326, 1e-15);
  EXPECT_NEAR(d.dh[4].d, -0.256, 1e-15);
  EXPECT_NEAR(d.dh[6].a, -0.095, 1e-15);
  EXPECT_NEAR(d.lower(2), -80 * kDeg, 1e-15);
  EXPECT_NEAR(d.upper(3), 160 * kDeg, 1e-15);
  EXPECT_NEAR(d.velocity_max(4), 486 * kDeg, 1e-12);
  EXPECT_NEAR(d.acceleration_max(0), 1312 * kDeg, 1e-12);
  EXPECT_NEAR(arm().reach(), 0.326 + 0.256 + 0.095, 1e-12);
}

TEST(HumanArm, ForwardKinematicsMatchesASecondDhFormulation) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 200; ++trial) {
    const Vector7d q = random_q(rng, false);
    const Eigen::Isometry3d a = arm().forward(q), b = second_dh(q);
    EXPECT_LT((a.translation() - b.translation()).norm(), 1e-12);
    EXPECT_LT(rotation_distance(a.linear(), b.linear()), 1e-12);
  }
  // The zero configuration: the arm stretched along -y_S (sideways, horizontal), the palm
  // l_ua + l_la + l_p from the shoulder.
  const Eigen::Vector3d p0 = arm().forward(Vector7d::Zero()).translation();
  EXPECT_LT((p0 - Eigen::Vector3d(0, -(0.326 + 0.256 + 0.095), 0)).norm(), 1e-12);
}

#ifdef HAPSYN_HAVE_KDL
KDL::Chain kdl_chain() {
  KDL::Chain chain;
  for (const DhRow& r : arm().data().dh) {
    chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotZ), KDL::Frame::DH(r.a, r.alpha, r.d, r.theta_offset)));
  }
  return chain;
}

TEST(HumanArm, ForwardKinematicsAndJacobianMatchKdl) {
  const KDL::Chain chain = kdl_chain();
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainJntToJacSolver jac(chain);
  std::mt19937 rng(2);
  for (int trial = 0; trial < 200; ++trial) {
    const Vector7d q = random_q(rng, false);
    KDL::JntArray jq(7);
    for (int i = 0; i < 7; ++i) jq(i) = q(i);
    KDL::Frame frame;
    ASSERT_GE(fk.JntToCart(jq, frame), 0);
    const Eigen::Isometry3d T = arm().forward(q);
    for (int r = 0; r < 3; ++r) {
      EXPECT_NEAR(T.translation()(r), frame.p(r), 1e-12);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(T.linear()(r, c), frame.M(r, c), 1e-12);
    }
    KDL::Jacobian jk(7);
    ASSERT_GE(jac.JntToJac(jq, jk), 0);
    const Matrix67d J = arm().jacobian(q);
    for (int c = 0; c < 7; ++c) {
      for (int r = 0; r < 3; ++r) {
        EXPECT_NEAR(J(r, c), jk(3 + r, c), 1e-12);  // KDL rows are (v, omega); ours (omega, v)
        EXPECT_NEAR(J(3 + r, c), jk(r, c), 1e-12);
      }
    }
  }
}
#endif

TEST(HumanArm, JacobianMatchesFiniteDifferencesOfForwardKinematics) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const Vector7d q = random_q(rng, false);
    const Matrix67d J = arm().jacobian(q);
    const Eigen::Isometry3d T = arm().forward(q);
    for (int i = 0; i < 7; ++i) {
      const double h = 1e-6;
      Vector7d qp = q, qm = q;
      qp(i) += h;
      qm(i) -= h;
      const Eigen::Isometry3d Tp = arm().forward(qp), Tm = arm().forward(qm);
      const Eigen::Vector3d v = (Tp.translation() - Tm.translation()) / (2 * h);
      const Eigen::AngleAxisd d(Tp.linear() * Tm.linear().transpose());
      const Eigen::Vector3d w = d.axis() * d.angle() / (2 * h);
      EXPECT_LT((J.block<3, 1>(3, i) - v).norm(), 1e-7);
      EXPECT_LT((J.block<3, 1>(0, i) - w).norm(), 1e-7);
    }
    (void)T;
  }
}

TEST(HumanArm, IkRoundTripsRandomConfigurationsWithJointThreeOnTheGrid) {
  std::mt19937 rng(4);
  int found = 0;
  const int trials = 2000;
  for (int trial = 0; trial < trials; ++trial) {
    const Vector7d q = random_q(rng, true);
    const Eigen::Isometry3d T = arm().forward(q);
    ArmIkSolution solutions[8];
    const int n = arm().solve(T.linear(), T.translation(), q(2), solutions);
    ASSERT_GE(n, 1) << q.transpose();
    double nearest = 1e9;
    for (int i = 0; i < n; ++i) {
      nearest = std::min(nearest, (solutions[i].q - q).cwiseAbs().maxCoeff());
      // Every returned solution reaches the pose.
      const Eigen::Isometry3d Ti = arm().forward(solutions[i].q);
      EXPECT_LT((Ti.translation() - T.translation()).norm(), 1e-10);
      EXPECT_LT(rotation_distance(Ti.linear(), T.linear()), 1e-10);
    }
    if (nearest < 1e-7) ++found;
  }
  EXPECT_EQ(found, trials);
}

TEST(HumanArm, BestSolutionReachesThePoseAndBeatsTheSourceConfiguration) {
  std::mt19937 rng(5);
  const std::vector<double> grid = arm().joint3_grid(17);
  for (int trial = 0; trial < 200; ++trial) {
    const Vector7d q = random_q(rng, true);
    const Eigen::Isometry3d T = arm().forward(q);
    Vector7d best;
    double m = -1;
    ASSERT_TRUE(arm().best(T.linear(), T.translation(), grid, &best, &m));
    EXPECT_GE(m, arm().manipulability(q) - 1e-12);
    EXPECT_DOUBLE_EQ(m, arm().manipulability(best));
    const Eigen::Isometry3d Tb = arm().forward(best);
    EXPECT_LT((Tb.translation() - T.translation()).norm(), 1e-10);
    EXPECT_LT(rotation_distance(Tb.linear(), T.linear()), 1e-10);
  }
}

TEST(HumanArm, NoSolutionOutsideTheJointLimits) {
  std::mt19937 rng(6);
  const HumanArmData& d = arm().data();
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  long solutions_seen = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Eigen::Vector3d p(0.7 * unit(rng), 0.7 * unit(rng), 0.7 * unit(rng));
    const Eigen::Matrix3d R = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    const double q3 = d.lower(2) + (d.upper(2) - d.lower(2)) * (unit(rng) + 1) / 2;
    ArmIkSolution s[8];
    const int n = arm().solve(R, p, q3, s);
    solutions_seen += n;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < 7; ++j) {
        ASSERT_GE(s[i].q(j), d.lower(j)) << "joint " << j + 1;
        ASSERT_LE(s[i].q(j), d.upper(j)) << "joint " << j + 1;
        ASSERT_TRUE(std::isfinite(s[i].q(j)));
      }
    }
  }
  EXPECT_GT(solutions_seen, 100);  // the check saw real solutions
}

// Brute force: with joint 3 fixed, the remaining 6 joints are found by damped Newton from many
// random starts (no closed form involved); the best manipulability over all solutions found on
// the joint-3 grid must equal the scene's choice.
TEST(HumanArm, ManipulabilitySelectionMatchesBruteForce) {
  std::mt19937 rng(7);
  const HumanArmData& d = arm().data();
  const int steps = 5;
  const std::vector<double> grid = arm().joint3_grid(steps);
  for (int pose = 0; pose < 4; ++pose) {
    const Vector7d source = random_q(rng, true, steps);
    const Eigen::Isometry3d T = arm().forward(source);
    double brute = -1;
    for (const double q3 : grid) {
      for (int start = 0; start < 150; ++start) {
        Vector7d q = random_q(rng, false);
        q(2) = q3;
        bool converged = false;
        for (int it = 0; it < 100; ++it) {
          const Eigen::Isometry3d Tq = arm().forward(q);
          Eigen::Matrix<double, 6, 1> e;
          const Eigen::AngleAxisd rot(T.linear() * Tq.linear().transpose());
          e.head<3>() = rot.axis() * rot.angle();
          e.tail<3>() = T.translation() - Tq.translation();
          if (e.norm() < 1e-12) {
            converged = true;
            break;
          }
          Matrix67d J = arm().jacobian(q);
          J.col(2).setZero();
          const Eigen::Matrix<double, 7, 1> dq =
              J.transpose() * (J * J.transpose() + 1e-10 * Matrix6d::Identity()).ldlt().solve(e);
          q += dq;
          q(2) = q3;
        }
        if (!converged) continue;
        bool inside = true;
        for (int j = 0; j < 7; ++j) {
          const double wrapped = d.lower(j) + std::fmod(std::fmod(q(j) - d.lower(j), 2 * kPi) + 2 * kPi, 2 * kPi);
          inside = inside && wrapped <= d.upper(j) + 1e-9;
        }
        if (inside) brute = std::max(brute, arm().manipulability(q));
      }
    }
    Vector7d best;
    double m = -1;
    ASSERT_TRUE(arm().best(T.linear(), T.translation(), grid, &best, &m));
    ASSERT_GT(brute, 0.0) << "brute force found nothing for pose " << pose;
    EXPECT_NEAR(m, brute, 1e-9 * std::max(1.0, brute)) << "pose " << pose;
  }
}

TEST(HumanArm, ManipulabilityIsTheProductOfSingularValues) {
  std::mt19937 rng(8);
  for (int trial = 0; trial < 50; ++trial) {
    const Vector7d q = random_q(rng, false);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Eigen::MatrixXd(arm().jacobian(q)));
    EXPECT_NEAR(arm().manipulability(q), svd.singularValues().prod(), 1e-12);
  }
}

TEST(HumanArm, EllipsoidAxesMatchADirectSvd) {
  std::mt19937 rng(9);
  const HumanArmData& d = arm().data();
  for (int trial = 0; trial < 100; ++trial) {
    const Vector7d q = random_q(rng, false);
    const Matrix67d J = arm().jacobian(q);
    for (const Vector7d* scale : {&d.velocity_max, &d.acceleration_max}) {
      const Matrix6d M = ellipsoid_axes(J, *scale);
      const Matrix67d Js = J * scale->asDiagonal();
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js, Eigen::ComputeFullU | Eigen::ComputeFullV);
      for (int c = 0; c < 6; ++c) {
        const Eigen::Matrix<double, 6, 1> expected = svd.matrixU().col(c) * svd.singularValues()(c);
        const double same = (M.col(c) - expected).norm(), flipped = (M.col(c) + expected).norm();
        EXPECT_LT(std::min(same, flipped), 1e-9 * svd.singularValues()(0)) << "column " << c;
      }
      // Sign-free check: M M^T = J diag(s)^2 J^T.
      EXPECT_LT((M * M.transpose() - Js * Js.transpose()).norm(), 1e-9 * (Js * Js.transpose()).norm());
    }
  }
}

TEST(HumanArm, PosesAtJointLimitsAreFound) {
  const HumanArmData& d = arm().data();
  const std::vector<double> grid = arm().joint3_grid(17);
  int exact = 0;
  // Every joint at its lower or upper limit (q3 = +-80 deg, on the grid's ends): 2^7 poses.
  // Several are singular as well (q2 = 90 deg aligns axes 1 and 3; q4 = 0 aligns axes 3 and 5),
  // where the closed form loses digits right at a limit: they must still be found (snapped
  // onto the limit and verified), finite, and reach the pose.
  for (int mask = 0; mask < 128; ++mask) {
    Vector7d q;
    for (int j = 0; j < 7; ++j) q(j) = (mask >> j & 1) ? d.upper(j) : d.lower(j);
    const Eigen::Isometry3d T = arm().forward(q);
    ArmIkSolution s[8];
    const int n = arm().solve(T.linear(), T.translation(), q(2), s);
    double nearest = 1e9;
    for (int i = 0; i < n; ++i) {
      nearest = std::min(nearest, (s[i].q - q).cwiseAbs().maxCoeff());
      ASSERT_TRUE(s[i].q.allFinite());
      const Eigen::Isometry3d Ti = arm().forward(s[i].q);
      EXPECT_LT((Ti.translation() - T.translation()).norm(), 1e-9) << "mask " << mask;
      EXPECT_LT(rotation_distance(Ti.linear(), T.linear()), 1e-9) << "mask " << mask;
      for (int j = 0; j < 7; ++j) {
        EXPECT_GE(s[i].q(j), d.lower(j));
        EXPECT_LE(s[i].q(j), d.upper(j));
      }
    }
    const bool doubly_singular = (mask >> 1 & 1) && !(mask >> 3 & 1);  // q2 = 90 and q4 = 0
    if (!doubly_singular) {
      // Isolated or singly singular: a solution exists at this q3 (not necessarily the same
      // configuration when a singularity makes a family of them).
      EXPECT_GE(n, 1) << "mask " << mask;
      Vector7d best;
      double m;
      EXPECT_TRUE(arm().best(T.linear(), T.translation(), grid, &best, &m)) << "mask " << mask;
    }
    if (nearest < 1e-6) ++exact;
  }
  EXPECT_GE(exact, 64);  // at least the regular half comes back exactly
  // The grid ends are exactly the limits (no rounding off the end).
  EXPECT_EQ(grid.front(), d.lower(2));
  EXPECT_EQ(grid.back(), d.upper(2));
}

// ------------------------------------------------------------------- input errors ----

TEST(HumanArm, ArmFileErrorsNameTheFileThePathTheValueAndTheRule) {
  Json doc = arm_document();
  EXPECT_EQ(arm_error(doc), "no error");
  doc["joints"][3]["upper"] = -10;
  EXPECT_EQ(arm_error(doc), "human_arm: arm.json: joints[3].upper = -10: must be >= lower (0)");
  doc = arm_document();
  doc["joints"][4]["velocity_max"] = 0;
  EXPECT_EQ(arm_error(doc), "human_arm: arm.json: joints[4].velocity_max = 0: must be > 0");
  doc = arm_document();
  doc["joints"][1]["acceleration_max"] = -1;
  EXPECT_EQ(arm_error(doc), "human_arm: arm.json: joints[1].acceleration_max = -1: must be > 0");
  doc = arm_document();
  doc["joints"][0].erase("lower");
  EXPECT_EQ(arm_error(doc), "human_arm: arm.json: joints[0].lower: missing");
  doc = arm_document();
  doc["joints"][0]["lower"] = "low";
  EXPECT_EQ(arm_error(doc), "human_arm: arm.json: joints[0].lower = \"low\": must be a number");
  doc = arm_document();
  doc["dh"][2]["d"] = "-l_upper";
  EXPECT_EQ(arm_error(doc), "human_arm: arm.json: dh[2].d = \"-l_upper\": unknown segment (known: l_la, l_p, l_ua)");
  doc = arm_document();
  doc["dh"][3]["a"] = 0.02;
  EXPECT_EQ(arm_error(doc),
            "human_arm: arm.json: dh[3].a = 0.02: must be 0 (the closed-form IK needs a spherical shoulder at the "
            "origin, an elbow on the upper-arm axis and a spherical wrist)");
  doc = arm_document();
  doc["dh"][4]["alpha"] = 0;
  EXPECT_EQ(arm_error(doc),
            "human_arm: arm.json: dh[4].alpha = 0: sin(alpha) must not be 0 here (adjacent joint axes would be "
            "parallel: no closed-form IK)");
  doc = arm_document();
  doc["dh"][2]["d"] = 0;
  EXPECT_EQ(arm_error(doc), "human_arm: arm.json: dh[2].d = 0: must be != 0 (a limb length)");
  doc = arm_document();
  doc["dh"].erase(6);
  EXPECT_EQ(arm_error(doc).rfind("human_arm: arm.json: dh = ", 0), 0u);
  EXPECT_NE(arm_error(doc).find(": must be an array of 7 rows"), std::string::npos);
  doc = arm_document();
  doc["segments"]["l_la"] = -0.2;
  EXPECT_EQ(arm_error(doc), "human_arm: arm.json: segments.l_la = -0.2: must be > 0");
  doc = arm_document();
  doc["units"]["angle"] = "rad";
  EXPECT_EQ(arm_error(doc), "human_arm: arm.json: units.angle = \"rad\": must be \"deg\"");
  doc = arm_document();
  doc["side"] = "both";
  EXPECT_EQ(arm_error(doc), "human_arm: arm.json: side = \"both\": must be \"right\" or \"left\"");
  doc = arm_document();
  doc["dh"][0]["theta"] = 90;
  EXPECT_EQ(arm_error(doc), "human_arm: arm.json: dh[0].theta: unknown key (known: theta_offset, d, a, alpha)");
  EXPECT_EQ(arm_error(Json::array()), "human_arm: arm.json: (document) = []: must be a JSON object");
}

TEST(HumanArm, LeftArmFileIsTheRightArmMirroredInTheSagittalPlane) {
  const HumanArm left(load_human_arm(HAPSYN_SOURCE_DIR "/share/human_arm/fennel2022_left_arm.json"));
  EXPECT_EQ(left.data().side, "left");
  // x_S is lateral (the right arm abducts towards +x_S; y_S is up, z_S backwards), so the mirror
  // is M = diag(-1, 1, 1): the left arm reaches M p with orientation M R M exactly when the right
  // arm reaches (R, p), with the same best manipulability and the negated configuration.
  const Eigen::Matrix3d M = Eigen::Vector3d(-1, 1, 1).asDiagonal();
  std::mt19937 rng(11);
  const std::vector<double> grid = left.joint3_grid(17);
  for (int trial = 0; trial < 100; ++trial) {
    const Vector7d q = random_q(rng, true);
    const Eigen::Isometry3d T = arm().forward(q);
    const Eigen::Isometry3d Tl = left.forward(-q);
    EXPECT_LT((Tl.translation() - M * T.translation()).norm(), 1e-12);
    EXPECT_LT(rotation_distance(Tl.linear(), M * T.linear() * M), 1e-12);
    Vector7d qr, ql;
    double mr, ml;
    ASSERT_TRUE(arm().best(T.linear(), T.translation(), grid, &qr, &mr));
    ASSERT_TRUE(left.best(M * T.linear() * M, M * T.translation(), grid, &ql, &ml)) << q.transpose();
    EXPECT_NEAR(ml, mr, 1e-12 + 1e-9 * mr);
  }
}

TEST(HumanArm, ArmFileThatIsNotARegularFileIsRefusedWithoutBlocking) {
  const fs::path dir = temp_dir("armfifo");
  const std::string fifo = (dir / "arm.json").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(error_of([&] { load_human_arm(fifo); }), "human_arm: arm file " + fifo + " is not a regular file (a FIFO)");
  EXPECT_EQ(error_of([&] { load_human_arm("/dev/zero"); }),
            "human_arm: arm file /dev/zero is not a regular file (a device or socket)");
  EXPECT_EQ(error_of([&] { load_human_arm(dir.string()); }),
            "human_arm: arm file " + dir.string() + " is not a regular file (a directory)");
  const fs::path huge = dir / "huge.json";
  std::ofstream(huge) << "{}";
  fs::resize_file(huge, kHumanArmMaxArmFileBytes + 1);
  EXPECT_EQ(error_of([&] { load_human_arm(huge.string()); }),
            "human_arm: arm file " + huge.string() + " is " + std::to_string(kHumanArmMaxArmFileBytes + 1) +
                " bytes, more than the " + std::to_string(kHumanArmMaxArmFileBytes) + " this reader accepts");
  fs::remove_all(dir);
}

}  // namespace
