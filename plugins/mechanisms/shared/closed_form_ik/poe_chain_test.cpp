// Tests of the product-of-exponentials chain (poe_chain.hpp): forward kinematics and Jacobian
// against KDL (an independent implementation, built from the same local frames) and finite
// differences, the reversed chain, the classifier on known arms, and the errors.
#include "shared/closed_form_ik/poe_chain.hpp"
#include "shared/closed_form_ik/test_arms.hpp"

#include <hapsyn/error.hpp>

#include <gtest/gtest.h>

#include "test_support.hpp"

#include <functional>
#include <random>
#include <string>

#ifdef HAPSYN_HAVE_KDL
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#endif

namespace {

using namespace hapsyn::plugins::closed_form_ik;
using namespace hapsyn::plugins::closed_form_ik::test_arms;

std::array<double, 6> random_q(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-M_PI, M_PI);
  return {u(rng), u(rng), u(rng), u(rng), u(rng), u(rng)};
}

// The pose the local frames give directly: O_1 Rot(a_1, q_1) ... O_n Rot(a_n, q_n) T_tip.
Eigen::Isometry3d local_forward(const LocalFrames& f, const double* q) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < f.origins.size(); ++i) t = t * f.origins[i] * Eigen::AngleAxisd(q[i], f.axes[i]);
  return t * f.tip;
}

using hapsyn::test::error_of;  // tests/test_support.hpp

TEST(ClosedFormIkPoeChain, ForwardMatchesTheLocalFrames) {
  std::mt19937 rng(1);
  for (const LocalFrames& f : {ur5(), puma(), offset_wrist(), haptic6r()}) {
    const PoeChain c = f.poe();
    for (int t = 0; t < 500; ++t) {
      const auto q = random_q(rng);
      const Eigen::Isometry3d a = c.forward(q.data()), b = local_forward(f, q.data());
      EXPECT_LT((a.matrix() - b.matrix()).norm(), 1e-12);
    }
  }
}

TEST(ClosedFormIkPoeChain, JacobianMatchesFiniteDifferences) {
  std::mt19937 rng(2);
  const PoeChain c = offset_wrist().poe();
  for (int t = 0; t < 50; ++t) {
    auto q = random_q(rng);
    Eigen::Isometry3d pose;
    Eigen::Matrix<double, 6, kMaxJoints> j;
    c.forward_jacobian(q.data(), pose, j);
    EXPECT_LT((pose.matrix() - c.forward(q.data()).matrix()).norm(), 1e-14);
    for (int i = 0; i < 6; ++i) {
      const double hstep = 1e-6;
      auto qp = q, qm = q;
      qp[static_cast<std::size_t>(i)] += hstep;
      qm[static_cast<std::size_t>(i)] -= hstep;
      const Eigen::Isometry3d tp = c.forward(qp.data()), tm = c.forward(qm.data());
      const Eigen::Vector3d v = (tp.translation() - tm.translation()) / (2 * hstep);
      const Eigen::AngleAxisd w(tp.linear() * tm.linear().transpose());
      EXPECT_LT((v - j.col(i).tail<3>()).norm(), 1e-8);
      EXPECT_LT((w.angle() * w.axis() / (2 * hstep) - j.col(i).head<3>()).norm(), 1e-8);
    }
  }
}

#ifdef HAPSYN_HAVE_KDL
KDL::Vector kdl_vector(const Eigen::Vector3d& v) { return KDL::Vector(v.x(), v.y(), v.z()); }

KDL::Frame kdl_frame(const Eigen::Isometry3d& t) {
  const Eigen::Matrix3d& r = t.linear();
  return KDL::Frame(KDL::Rotation(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)),
                    kdl_vector(t.translation()));
}

// Segment i turns about its axis (in its parent's frame: O_i a_i through O_i's origin), then
// carries O_i to its tip; a last fixed segment carries T_tip.
KDL::Chain kdl_chain(const LocalFrames& f) {
  KDL::Chain k;
  for (std::size_t i = 0; i < f.origins.size(); ++i) {
    const KDL::Joint joint("j" + std::to_string(i), kdl_vector(f.origins[i].translation()),
                           kdl_vector(f.origins[i].linear() * f.axes[i]), KDL::Joint::RotAxis);
    k.addSegment(KDL::Segment(joint, kdl_frame(f.origins[i])));
  }
  k.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), kdl_frame(f.tip)));
  return k;
}

TEST(ClosedFormIkPoeChain, ForwardAndJacobianMatchKdl) {
  std::mt19937 rng(3);
  for (const LocalFrames& f : {ur5(), puma(), offset_wrist(), haptic6r()}) {
    const PoeChain c = f.poe();
    const KDL::Chain k = kdl_chain(f);
    KDL::ChainFkSolverPos_recursive fk(k);
    KDL::ChainJntToJacSolver jac(k);
    for (int t = 0; t < 500; ++t) {
      const auto q = random_q(rng);
      KDL::JntArray kq(6);
      for (int i = 0; i < 6; ++i) kq(static_cast<unsigned>(i)) = q[static_cast<std::size_t>(i)];
      KDL::Frame frame;
      ASSERT_GE(fk.JntToCart(kq, frame), 0);
      KDL::Jacobian kj(6);
      ASSERT_GE(jac.JntToJac(kq, kj), 0);
      Eigen::Isometry3d pose;
      Eigen::Matrix<double, 6, kMaxJoints> j;
      c.forward_jacobian(q.data(), pose, j);
      for (int r = 0; r < 3; ++r) {
        EXPECT_NEAR(pose.translation()(r), frame.p(r), 1e-12);
        for (int s = 0; s < 3; ++s) EXPECT_NEAR(pose.linear()(r, s), frame.M(r, s), 1e-12);
        for (int col = 0; col < 6; ++col) {
          EXPECT_NEAR(j(r, col), kj(3 + r, static_cast<unsigned>(col)), 1e-12);  // KDL rows are (v, omega)
          EXPECT_NEAR(j(3 + r, col), kj(r, static_cast<unsigned>(col)), 1e-12);
        }
      }
    }
  }
}
#endif

TEST(ClosedFormIkPoeChain, ReversedChainGivesTheInversePose) {
  std::mt19937 rng(4);
  for (const LocalFrames& f : {ur5(), puma(), offset_wrist()}) {
    const PoeChain c = f.poe(), r = c.reversed();
    for (int t = 0; t < 200; ++t) {
      const auto q = random_q(rng);
      const std::array<double, 6> qr{q[5], q[4], q[3], q[2], q[1], q[0]};
      EXPECT_LT((r.forward(qr.data()).matrix() - c.forward(q.data()).inverse().matrix()).norm(), 1e-12);
    }
  }
}

TEST(ClosedFormIkPoeChain, ClassifiesTheKnownArms) {
  const ChainGeometry u = classify(ur5().poe());
  EXPECT_EQ(u.family, IkFamily::kThreeParallel);
  EXPECT_FALSE(u.reversed);
  EXPECT_EQ(u.three_parallel, 1);
  EXPECT_EQ(u.describe(), "6R: 1x2, 2||3, 3||4, 4x5, 5x6; three parallel axes 2-3-4; family: three parallel axes 2-3-4 (UR type)");

  const ChainGeometry p = classify(puma().poe());
  EXPECT_EQ(p.family, IkFamily::kSphericalWrist);
  EXPECT_TRUE(p.spherical_wrist);
  EXPECT_LT((p.wrist_point - Eigen::Vector3d(0.4521, -0.15005, 0.4318)).norm(), 1e-12);
  EXPECT_EQ(p.describe(), "6R: 1x2, 2||3, 4x5, 5x6; spherical wrist; family: spherical wrist");

  const ChainGeometry o = classify(offset_wrist().poe());
  EXPECT_EQ(o.family, IkFamily::kSearch1d);
  EXPECT_EQ(o.describe(), "6R: 5x6; family: 1-D search over joint 1 (axes 5x6 intersect)");

  const ChainGeometry h = classify(haptic6r().poe());
  EXPECT_EQ(h.three_parallel, 0);
  EXPECT_EQ(h.family, IkFamily::kScaraPair);
  EXPECT_EQ(h.describe(), "6R: 1||2, 2||3, 3x4, 4||5, 5x6; three parallel axes 1-2-3; family: three parallel axes 1-2-3 and "
                          "4||5 (haptic 6R type)");

  const ChainGeometry pr = classify(puma().poe().reversed());
  EXPECT_EQ(pr.family, IkFamily::kSphericalWrist);
  EXPECT_TRUE(pr.reversed);
  const ChainGeometry ur = classify(ur5().poe().reversed());
  EXPECT_EQ(ur.family, IkFamily::kThreeParallel);
  EXPECT_TRUE(ur.reversed);
}

TEST(ClosedFormIkPoeChain, GeneralSixRIsUnsupported) {
  const ChainGeometry g = classify(from_dh({{{0.32, 0.05, 1.4}}, {{0.11, 0.41, 0.25}}, {{-0.06, 0.03, -1.2}},
                                            {{0.37, 0.07, 1.0}}, {{0.09, 0.04, -1.3}}, {{0.08, 0.02, 0.3}}})
                                       .poe());
  EXPECT_EQ(g.family, IkFamily::kUnsupported);
  EXPECT_EQ(g.describe(), "6R: no parallel or intersecting consecutive axes; family: none (general 6R: needs a 2-D search, not implemented)");
}

TEST(ClosedFormIkPoeChain, FromLocalFramesRefusesBadSizesAndAxes) {
  const Eigen::Isometry3d id = Eigen::Isometry3d::Identity();
  EXPECT_EQ(error_of([&] { PoeChain::from_local_frames({id, id}, {Eigen::Vector3d::UnitZ()}, id); }),
            "closed_form_ik: 2 joint origins and 1 axes: need the same number, 1 to 7");
  EXPECT_EQ(error_of([&] { PoeChain::from_local_frames({}, {}, id); }),
            "closed_form_ik: 0 joint origins and 0 axes: need the same number, 1 to 7");
  EXPECT_EQ(error_of([&] { PoeChain::from_local_frames({id}, {Eigen::Vector3d::Zero()}, id); }),
            "closed_form_ik: joint 1: axis has length 0.000000: must be finite and > 0");
}

}  // namespace
