#pragma once
/// \file
/// The six geometric subproblems of IK-Geo (A. J. Elias and J. T. Wen, "IK-Geo: Unified robot
/// inverse kinematics using subproblem decomposition", arXiv:2211.05737, 2022; Mechanism and
/// Machine Theory 2025), written from the paper's equations. Each returns ALL solutions and
/// says whether they are exact or least-squares.
///
/// Conventions: R(k, theta) is the rotation by theta [rad] about the unit axis k (right hand),
/// R(k, theta) p = cos(theta) p + sin(theta) k x p + (1 - cos(theta)) k (k . p). Axes must be
/// unit vectors (not checked: the callers are solvers that normalise once). Angles are returned
/// in (-pi, pi]. Every function is allocation-free.
///
/// Degenerate inputs (documented per function) never give NaN: a rotation that leaves the
/// equation unchanged (vector along the axis, zero-length vector, parallel axes) reports
/// `degenerate` (infinitely many solutions) and returns one representative solution.
#include <Eigen/Core>

#include <array>

namespace hapsyn::plugins::closed_form_ik {

/// Solutions of a one-angle subproblem (at most 2).
struct Angles1 {
  std::array<double, 2> theta{};  ///< theta[0..count)
  /// sin and cos of theta[i] as the subproblem found them (the unit vector it took theta from),
  /// for rot(k, sine, cosine) without another sin/cos: equal to sin/cos(theta) to about 1e-16.
  std::array<double, 2> sine{}, cosine{1.0, 1.0};
  int count = 0;
  bool least_squares = false;  ///< no exact solution: theta minimises the subproblem's residual
  bool degenerate = false;     ///< infinitely many solutions (or none depends on theta); one returned
};

/// Solutions of a two-angle subproblem (at most 4: SP6; SP2 gives at most 2).
struct Angles2 {
  std::array<double, 4> theta1{}, theta2{};  ///< pairs (theta1[i], theta2[i]), i < count
  int count = 0;
  bool least_squares = false;  ///< no exact solution: approximate (see each subproblem)
  bool degenerate = false;     ///< a continuum of solutions; representatives returned
};

/// Solutions of SP5 (at most 4 triples).
struct Angles3 {
  std::array<double, 4> theta1{}, theta2{}, theta3{};
  int count = 0;
  bool least_squares = false;
  bool degenerate = false;
};

/// Tolerance below which a length or a sine of an angle between axes counts as zero.
constexpr double kDegenerateTolerance = 1e-12;

/// R(k, theta) (Rodrigues).
Eigen::Matrix3d rot(const Eigen::Vector3d& k, double theta);
/// R(k, theta) from sin theta and cos theta (a unit vector (sine, cosine)).
Eigen::Matrix3d rot(const Eigen::Vector3d& k, double sine, double cosine);

/// SP1: theta with R(k, theta) p1 = p2. Exact when k.p1 = k.p2 and |p1| = |p2| (to 1e-9 relative
/// to |p1| + |p2|), else least squares: the theta minimising |R(k, theta) p1 - p2|. Degenerate
/// when p1 or p2 is (nearly) along k: every theta gives the same residual; returns theta = 0.
Angles1 sp1(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, const Eigen::Vector3d& k);

/// SP4: theta with h . R(k, theta) p = d (h need not be unit). Zero, one or two exact solutions;
/// when none exists, the least-squares theta minimising |h . R(k, theta) p - d| (one solution).
/// Degenerate when h or p is (nearly) along k (the left side does not depend on theta): returns
/// theta = 0 and flags least_squares too when the equation is not met.
Angles1 sp4(const Eigen::Vector3d& h, const Eigen::Vector3d& p, const Eigen::Vector3d& k, double d);

/// SP3: theta with |R(k, theta) p1 - p2| = d (d >= 0). Reduced to SP4 with h = p2 (the square of
/// the distance is affine in cos/sin theta); least squares and degenerate as SP4 (degenerate when
/// p1 or p2 is along k).
Angles1 sp3(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, const Eigen::Vector3d& k, double d);

/// SP2: (theta1, theta2) with R(k1, theta1) p1 = R(k2, theta2) p2; up to 2 pairs. theta1 solves
/// the SP4 k2 . R(k1, theta1) p1 = k2 . p2 (on the vectors scaled to unit length, as IK-Geo), theta2
/// the SP1 that rotates p2 onto R(k1, theta1) p1. Least squares when |p1| != |p2| or the circles
/// do not meet. Degenerate when k1 and k2 are parallel (only theta1 - theta2 or theta1 + theta2 is
/// determined): returns theta2 = 0 and theta1 from SP1.
Angles2 sp2(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, const Eigen::Vector3d& k1,
            const Eigen::Vector3d& k2);

/// SP5: (theta1, theta2, theta3) with p0 + R(k1, theta1) p1 = R(k2, theta2) (p2 + R(k3, theta3) p3);
/// up to 4 triples. The two scalar equations free of theta2 (the squared norms and the component
/// along k2 of both sides) are affine in (sin, cos) of theta1 and theta3: solve_two_circles gives
/// (theta1, theta3), SP1 then theta2. Least squares when no exact triple exists (the pair nearest
/// to the circles). Degenerate when both sides leave a continuum (e.g. p1 along k1 and p3 along k3).
Angles3 sp5(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
            const Eigen::Vector3d& p3, const Eigen::Vector3d& k1, const Eigen::Vector3d& k2,
            const Eigen::Vector3d& k3);

/// SP6: (theta1, theta2) with
///   h1 . R(k1, theta1) p1 + h2 . R(k2, theta2) p2 = d1,
///   h3 . R(k3, theta1) p3 + h4 . R(k4, theta2) p4 = d2;  up to 4 pairs (solve_two_circles).
Angles2 sp6(const std::array<Eigen::Vector3d, 4>& h, const std::array<Eigen::Vector3d, 4>& k,
            const std::array<Eigen::Vector3d, 4>& p, double d1, double d2);

/// The core of SP5 and SP6: unit 2-vectors x1 = (sin theta1, cos theta1), x2 = (sin theta2,
/// cos theta2) with M1 x1 + M2 x2 = c; up to 4 pairs. When M1 (or M2) is well conditioned, x1 is
/// eliminated and |x1| = 1 becomes a trigonometric polynomial of degree 2 in theta2, solved as a
/// quartic in the tangent of the half angle (shifted so that no root lies at the half angle's
/// pole) by Ferrari's method, each root Newton polished. When both are (nearly) rank one, a
/// combination of the rows free of x1 gives theta2 by SP4, then theta1 by SP4. least_squares: no
/// real root (the angle where the polynomial is smallest in magnitude among the candidates is
/// returned); degenerate: M1 (or M2) zero, or both rank one along the same row direction.
Angles2 solve_two_circles(const Eigen::Matrix2d& m1, const Eigen::Matrix2d& m2, const Eigen::Vector2d& c);

}  // namespace hapsyn::plugins::closed_form_ik
