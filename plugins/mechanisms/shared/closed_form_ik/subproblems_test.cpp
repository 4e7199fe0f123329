// Tests of the IK-Geo subproblems (subproblems.hpp): random instances built from known angles
// (the known angles are among the solutions; every exact solution satisfies its equation to
// 1e-10), least-squares instances (flagged, and no better angle nearby), degenerate inputs
// (flagged, finite).
#include "shared/closed_form_ik/subproblems.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using namespace hapsyn::plugins::closed_form_ik;
using Eigen::Vector3d;

constexpr int kTrials = 2000;
constexpr double kResidual = 1e-10;
constexpr double kAngle = 1e-7;  // a root that is nearly double is only this well conditioned

struct Random {
  std::mt19937 rng{12345};
  double angle() { return std::uniform_real_distribution<double>(-M_PI, M_PI)(rng); }
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
  Vector3d vector() {
    std::normal_distribution<double> n;
    return Vector3d(n(rng), n(rng), n(rng));
  }
  Vector3d unit() { return vector().normalized(); }
};

double angle_error(double a, double b) { return std::abs(std::remainder(a - b, 2 * M_PI)); }

bool contains(const Angles1& s, double theta) {
  for (int i = 0; i < s.count; ++i) {
    if (angle_error(s.theta[static_cast<std::size_t>(i)], theta) < kAngle) return true;
  }
  return false;
}

TEST(ClosedFormIkSubproblems, Sp1RecoversTheKnownAngle) {
  Random r;
  for (int t = 0; t < kTrials; ++t) {
    const Vector3d k = r.unit(), p1 = r.vector();
    const double theta = r.angle();
    const Vector3d p2 = rot(k, theta) * p1;
    const Angles1 s = sp1(p1, p2, k);
    ASSERT_EQ(s.count, 1);
    EXPECT_FALSE(s.least_squares);
    EXPECT_FALSE(s.degenerate);
    EXPECT_LT(angle_error(s.theta[0], theta), 1e-9);
    EXPECT_LT((rot(k, s.theta[0]) * p1 - p2).norm(), kResidual);
  }
}

TEST(ClosedFormIkSubproblems, Sp1LeastSquaresMinimisesTheDistance) {
  Random r;
  for (int t = 0; t < 200; ++t) {
    const Vector3d k = r.unit(), p1 = r.vector(), p2 = r.vector();
    const Angles1 s = sp1(p1, p2, k);
    EXPECT_TRUE(s.least_squares);
    const double best = (rot(k, s.theta[0]) * p1 - p2).norm();
    for (double d : {-1e-3, 1e-3}) EXPECT_LE(best, (rot(k, s.theta[0] + d) * p1 - p2).norm());
  }
}

TEST(ClosedFormIkSubproblems, Sp1VectorAlongTheAxisIsDegenerate) {
  const Vector3d k = Vector3d::UnitZ();
  const Angles1 s = sp1(2.0 * k, 2.0 * k, k);
  EXPECT_TRUE(s.degenerate);
  EXPECT_FALSE(s.least_squares);
  ASSERT_EQ(s.count, 1);
  EXPECT_EQ(s.theta[0], 0.0);
  const Angles1 zero = sp1(Vector3d::Zero(), Vector3d::Zero(), k);
  EXPECT_TRUE(zero.degenerate);
  EXPECT_TRUE(std::isfinite(zero.theta[0]));
}

TEST(ClosedFormIkSubproblems, Sp4RecoversTheKnownAngle) {
  Random r;
  for (int t = 0; t < kTrials; ++t) {
    const Vector3d h = r.vector(), p = r.vector(), k = r.unit();
    const double theta = r.angle();
    const double d = h.dot(rot(k, theta) * p);
    const Angles1 s = sp4(h, p, k, d);
    EXPECT_FALSE(s.least_squares);
    EXPECT_TRUE(contains(s, theta)) << "trial " << t;
    for (int i = 0; i < s.count; ++i) EXPECT_LT(std::abs(h.dot(rot(k, s.theta[static_cast<std::size_t>(i)]) * p) - d), kResidual);
  }
}

TEST(ClosedFormIkSubproblems, Sp4OutOfRangeIsLeastSquaresAtTheExtremum) {
  Random r;
  for (int t = 0; t < 200; ++t) {
    const Vector3d h = r.vector(), p = r.vector(), k = r.unit();
    const double d = h.norm() * p.norm() * 1.5 + 0.1;  // beyond max h . R p
    const Angles1 s = sp4(h, p, k, d);
    EXPECT_TRUE(s.least_squares);
    ASSERT_EQ(s.count, 1);
    const double at = h.dot(rot(k, s.theta[0]) * p);
    for (double e : {-1e-3, 1e-3}) EXPECT_GE(at, h.dot(rot(k, s.theta[0] + e) * p));
  }
}

TEST(ClosedFormIkSubproblems, Sp4AxisAlongTheVectorIsDegenerate) {
  const Vector3d k = Vector3d::UnitX();
  const Angles1 met = sp4(Vector3d(1, 2, 3), 2.0 * k, k, 2.0);
  EXPECT_TRUE(met.degenerate);
  EXPECT_FALSE(met.least_squares);
  const Angles1 missed = sp4(Vector3d(1, 2, 3), 2.0 * k, k, 5.0);
  EXPECT_TRUE(missed.degenerate);
  EXPECT_TRUE(missed.least_squares);
  EXPECT_EQ(missed.count, 1);
}

TEST(ClosedFormIkSubproblems, Sp3RecoversTheKnownAngle) {
  Random r;
  for (int t = 0; t < kTrials; ++t) {
    const Vector3d p1 = r.vector(), p2 = r.vector(), k = r.unit();
    const double theta = r.angle();
    const double d = (rot(k, theta) * p1 - p2).norm();
    const Angles1 s = sp3(p1, p2, k, d);
    EXPECT_FALSE(s.least_squares);
    EXPECT_TRUE(contains(s, theta)) << "trial " << t;
    for (int i = 0; i < s.count; ++i) {
      EXPECT_LT(std::abs((rot(k, s.theta[static_cast<std::size_t>(i)]) * p1 - p2).norm() - d), kResidual);
    }
  }
}

TEST(ClosedFormIkSubproblems, Sp3UnreachableDistanceIsLeastSquares) {
  const Vector3d k = Vector3d::UnitZ();
  const Angles1 s = sp3(Vector3d(1, 0, 0), Vector3d(0, 0, 0.5), k, 10.0);
  EXPECT_TRUE(s.least_squares);
  EXPECT_EQ(s.count, 1);
}

TEST(ClosedFormIkSubproblems, Sp2RecoversTheKnownAngles) {
  Random r;
  for (int t = 0; t < kTrials; ++t) {
    const Vector3d k1 = r.unit(), k2 = r.unit(), p2 = r.vector();
    const double t1 = r.angle(), t2 = r.angle();
    const Vector3d p1 = rot(k1, t1).transpose() * rot(k2, t2) * p2;
    const Angles2 s = sp2(p1, p2, k1, k2);
    EXPECT_FALSE(s.least_squares);
    bool found = false;
    for (int i = 0; i < s.count; ++i) {
      const std::size_t a = static_cast<std::size_t>(i);
      EXPECT_LT((rot(k1, s.theta1[a]) * p1 - rot(k2, s.theta2[a]) * p2).norm(), kResidual) << "trial " << t;
      found = found || (angle_error(s.theta1[a], t1) < kAngle && angle_error(s.theta2[a], t2) < kAngle);
    }
    EXPECT_TRUE(found) << "trial " << t;
  }
}

TEST(ClosedFormIkSubproblems, Sp2ParallelAxesAreDegenerate) {
  const Vector3d k = Vector3d::UnitZ();
  const Angles2 s = sp2(Vector3d(1, 0, 0.3), Vector3d(0, 1, 0.3), k, k);
  EXPECT_TRUE(s.degenerate);
  ASSERT_EQ(s.count, 1);
  EXPECT_LT((rot(k, s.theta1[0]) * Vector3d(1, 0, 0.3) - rot(k, s.theta2[0]) * Vector3d(0, 1, 0.3)).norm(), 1e-12);
}

TEST(ClosedFormIkSubproblems, Sp2DifferentLengthsAreLeastSquares) {
  const Angles2 s = sp2(Vector3d(1, 0, 0), Vector3d(0, 2, 0), Vector3d::UnitZ(), Vector3d::UnitX());
  EXPECT_TRUE(s.least_squares);
  EXPECT_GE(s.count, 1);
}

TEST(ClosedFormIkSubproblems, Sp5RecoversTheKnownAngles) {
  Random r;
  int checked = 0;
  for (int t = 0; t < kTrials; ++t) {
    const Vector3d k1 = r.unit(), k2 = r.unit(), k3 = r.unit(), p1 = r.vector(), p2 = r.vector(), p3 = r.vector();
    const double t1 = r.angle(), t2 = r.angle(), t3 = r.angle();
    const Vector3d p0 = rot(k2, t2) * (p2 + rot(k3, t3) * p3) - rot(k1, t1) * p1;
    const Angles3 s = sp5(p0, p1, p2, p3, k1, k2, k3);
    EXPECT_FALSE(s.least_squares);
    bool found = false;
    for (int i = 0; i < s.count; ++i) {
      const std::size_t a = static_cast<std::size_t>(i);
      const Vector3d lhs = p0 + rot(k1, s.theta1[a]) * p1;
      const Vector3d rhs = rot(k2, s.theta2[a]) * (p2 + rot(k3, s.theta3[a]) * p3);
      EXPECT_LT((lhs - rhs).norm(), kResidual) << "trial " << t;
      found = found || (angle_error(s.theta1[a], t1) < kAngle && angle_error(s.theta2[a], t2) < kAngle &&
                        angle_error(s.theta3[a], t3) < kAngle);
    }
    EXPECT_TRUE(found) << "trial " << t;
    ++checked;
  }
  EXPECT_EQ(checked, kTrials);
}

// The Puma shoulder: k2 || k3 and p0 = 0 make both equations one-angle each (the rank-one route).
TEST(ClosedFormIkSubproblems, Sp5RankOneRouteRecoversTheKnownAngles) {
  Random r;
  for (int t = 0; t < 500; ++t) {
    const Vector3d k1 = Vector3d::UnitZ(), k2 = Vector3d::UnitY(), k3 = Vector3d::UnitY();
    const Vector3d p2(0.4, 0.1, 0.0), p3(0.05, -0.1, 0.45);
    const double t1 = r.angle(), t2 = r.angle(), t3 = r.angle();
    // p0 + R1 p1 = R2 (p2 + R3 p3) with p0 = 0: p1 = R1^T R2 (p2 + R3 p3).
    const Vector3d p1 = rot(k1, t1).transpose() * rot(k2, t2) * (p2 + rot(k3, t3) * p3);
    const Angles3 s = sp5(Vector3d::Zero(), p1, p2, p3, k1, k2, k3);
    bool found = false;
    for (int i = 0; i < s.count; ++i) {
      const std::size_t a = static_cast<std::size_t>(i);
      const Vector3d lhs = rot(k1, s.theta1[a]) * p1;
      const Vector3d rhs = rot(k2, s.theta2[a]) * (p2 + rot(k3, s.theta3[a]) * p3);
      EXPECT_LT((lhs - rhs).norm(), kResidual) << "trial " << t;
      found = found || (angle_error(s.theta1[a], t1) < kAngle && angle_error(s.theta2[a], t2) < kAngle &&
                        angle_error(s.theta3[a], t3) < kAngle);
    }
    EXPECT_TRUE(found) << "trial " << t;
  }
}

TEST(ClosedFormIkSubproblems, Sp6RecoversTheKnownAngles) {
  Random r;
  for (int t = 0; t < kTrials; ++t) {
    const std::array<Vector3d, 4> h{r.vector(), r.vector(), r.vector(), r.vector()};
    const std::array<Vector3d, 4> p{r.vector(), r.vector(), r.vector(), r.vector()};
    const Vector3d ka = r.unit(), kb = r.unit();
    const std::array<Vector3d, 4> k{ka, kb, ka, kb};
    const double t1 = r.angle(), t2 = r.angle();
    const double d1 = h[0].dot(rot(k[0], t1) * p[0]) + h[1].dot(rot(k[1], t2) * p[1]);
    const double d2 = h[2].dot(rot(k[2], t1) * p[2]) + h[3].dot(rot(k[3], t2) * p[3]);
    const Angles2 s = sp6(h, k, p, d1, d2);
    EXPECT_FALSE(s.least_squares);
    bool found = false;
    for (int i = 0; i < s.count; ++i) {
      const std::size_t a = static_cast<std::size_t>(i);
      const double e1 = h[0].dot(rot(k[0], s.theta1[a]) * p[0]) + h[1].dot(rot(k[1], s.theta2[a]) * p[1]) - d1;
      const double e2 = h[2].dot(rot(k[2], s.theta1[a]) * p[2]) + h[3].dot(rot(k[3], s.theta2[a]) * p[3]) - d2;
      EXPECT_LT(std::abs(e1) + std::abs(e2), kResidual) << "trial " << t;
      found = found || (angle_error(s.theta1[a], t1) < kAngle && angle_error(s.theta2[a], t2) < kAngle);
    }
    EXPECT_TRUE(found) << "trial " << t;
  }
}

// All four solutions: a 2x2 system whose solution count is known (two unit circles, x1 = x2
// rotated: M1 = I, M2 = -R(phi), c = 0 holds for every theta1 = theta2 - phi... is degenerate;
// instead, a quartic with four real roots built from four known pairs is checked by count).
TEST(ClosedFormIkSubproblems, TwoCirclesFindsUpToFourSolutions) {
  Random r;
  int four = 0;
  for (int t = 0; t < kTrials; ++t) {
    Eigen::Matrix2d m1, m2;
    m1 << r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1);
    m2 << r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1);
    const double t1 = r.angle(), t2 = r.angle();
    const Eigen::Vector2d c = m1 * Eigen::Vector2d(std::sin(t1), std::cos(t1)) + m2 * Eigen::Vector2d(std::sin(t2), std::cos(t2));
    const Angles2 s = solve_two_circles(m1, m2, c);
    for (int i = 0; i < s.count; ++i) {
      const std::size_t a = static_cast<std::size_t>(i);
      const Eigen::Vector2d res = m1 * Eigen::Vector2d(std::sin(s.theta1[a]), std::cos(s.theta1[a])) +
                                  m2 * Eigen::Vector2d(std::sin(s.theta2[a]), std::cos(s.theta2[a])) - c;
      EXPECT_LT(res.norm(), kResidual) << "trial " << t;
    }
    four += s.count == 4;
  }
  EXPECT_GT(four, 0);  // random systems do have four real solutions sometimes
}

TEST(ClosedFormIkSubproblems, TwoCirclesZeroMatrixIsDegenerate) {
  const Angles2 s = solve_two_circles(Eigen::Matrix2d::Zero(), Eigen::Matrix2d::Identity(), Eigen::Vector2d(0.6, 0.8));
  EXPECT_TRUE(s.degenerate);
  ASSERT_GE(s.count, 1);
  EXPECT_TRUE(std::isfinite(s.theta1[0]) && std::isfinite(s.theta2[0]));
  EXPECT_NEAR(std::sin(s.theta2[0]), 0.6, 1e-12);
  EXPECT_NEAR(std::cos(s.theta2[0]), 0.8, 1e-12);
}

}  // namespace
