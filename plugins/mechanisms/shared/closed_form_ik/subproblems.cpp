// The IK-Geo subproblems (Elias & Wen 2022), from the paper's geometry. The common step: a
// rotation of p about k is affine in x = (sin theta, cos theta),
//   R(k, theta) p = k (k . p) + A x,  A = [k x p, p - k (k . p)],
// so each scalar equation of the subproblems is a . x = b on the unit circle (SP1, SP3, SP4),
// or a pair of such equations in two angles (SP5, SP6: solve_two_circles).
#include "shared/closed_form_ik/subproblems.hpp"

#include <hapsyn/accel/fast_math.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace hapsyn::plugins::closed_form_ik {

namespace {

// A of the file comment: R(k, theta) p = k (k . p) + A (sin theta, cos theta).
Eigen::Matrix<double, 3, 2> rotation_basis(const Eigen::Vector3d& k, const Eigen::Vector3d& p) {
  Eigen::Matrix<double, 3, 2> a;
  a.col(0) = k.cross(p);
  a.col(1) = p - k * k.dot(p);
  return a;
}

// hapsyn::fast's atan2 and sin_cos (errors <= 4.5e-16 rad and 2.3e-16) inline where libm's
// calls, with their rounding-mode switches, took a third of the closed-form IK's time.
double angle_of(const Eigen::Vector2d& x) { return fast::atan2(x(0), x(1)); }

// Solution i of `out`: the angle of x = r (sin theta, cos theta), r > 0, with its sine and cosine.
void set_angle(Angles1& out, int i, const Eigen::Vector2d& x) {
  const std::size_t k = static_cast<std::size_t>(i);
  out.theta[k] = angle_of(x);
  const double r = x.norm();
  out.sine[k] = x(0) / r;
  out.cosine[k] = x(1) / r;
}

// (sin t, cos t).
Eigen::Vector2d unit_of(double t) {
  Eigen::Vector2d x;
  fast::sin_cos(t, x(0), x(1));
  return x;
}

// theta with a . (sin theta, cos theta) = b: the line a . x = b meets the unit circle in 0, 1 or 2
// points; with none, the point of the circle nearest to the line (least squares in |a . x - b|).
Angles1 solve_unit(const Eigen::Vector2d& a, double b, double scale) {
  Angles1 out;
  const double na2 = a.squaredNorm();
  if (std::sqrt(na2) <= kDegenerateTolerance * std::max(scale, 1e-300)) {
    out.degenerate = true;
    out.count = 1;
    out.theta[0] = 0.0;
    out.least_squares = std::abs(b) > 1e-9 * std::max(scale, 1e-300);
    return out;
  }
  const Eigen::Vector2d x_ls = a * (b / na2);
  const double r2 = x_ls.squaredNorm();
  if (r2 > 1.0) {
    out.least_squares = true;
    out.count = 1;
    set_angle(out, 0, x_ls);
    return out;
  }
  const double xi = std::sqrt(1.0 - r2);
  const Eigen::Vector2d perp = Eigen::Vector2d(a(1), -a(0)) / std::sqrt(na2);
  out.count = 2;
  set_angle(out, 0, x_ls + xi * perp);
  set_angle(out, 1, x_ls - xi * perp);
  return out;
}

// f(theta) = a2 cos 2t + b2 sin 2t + c1 cos t + d1 sin t + e0, the |x1| = 1 condition of the
// quartic route, and its derivative (one sin/cos pair per evaluation).
struct TrigQuadratic {
  double a2, b2, c1, d1, e0;
  double value(double t) const {
    double s, c;
    fast::sin_cos(t, s, c);
    return a2 * (c * c - s * s) + b2 * 2 * s * c + c1 * c + d1 * s + e0;
  }
  void value_slope(double t, double& v, double& dv) const {
    double s, c;
    fast::sin_cos(t, s, c);
    const double c2 = c * c - s * s, s2 = 2 * s * c;
    v = a2 * c2 + b2 * s2 + c1 * c + d1 * s + e0;
    dv = -2 * a2 * s2 + 2 * b2 * c2 - c1 * s + d1 * c;
  }
  double scale() const { return std::abs(a2) + std::abs(b2) + std::abs(c1) + std::abs(d1) + std::abs(e0); }
};

// Angle a - b wrapped into [-pi, pi] (cheaper than std::remainder).
double wrapped_difference(double a, double b) {
  const double d = a - b;
  return d - 2 * M_PI * std::nearbyint(d / (2 * M_PI));
}

// Newton on f from theta; stops at rounding level, or when a step does not help (linear
// convergence near a double root: up to 40 steps there).
double polish(const TrigQuadratic& f, double theta) {
  const double floor = 1e-15 * f.scale();
  double v, s;
  f.value_slope(theta, v, s);
  for (int it = 0; it < 40 && std::abs(v) > floor && s != 0.0; ++it) {
    const double next = theta - v / s;
    double nv, ns;
    f.value_slope(next, nv, ns);
    if (!(std::abs(nv) < std::abs(v))) break;
    theta = next, v = nv, s = ns;
  }
  return theta;
}

// A real root of the cubic m^3 + b m^2 + c m + d (the largest, by the trigonometric or Cardano
// form, Newton polished).
double cubic_largest_root(double b, double c, double d) {
  const double q = (3 * c - b * b) / 9, r = (9 * b * c - 27 * d - 2 * b * b * b) / 54;
  const double disc = q * q * q + r * r;
  double m;
  if (disc <= 0.0) {  // three real roots
    const double sq = std::sqrt(-q);
    const double phi = std::acos(std::clamp(r / (sq * sq * sq), -1.0, 1.0));
    m = 2 * sq * std::cos(phi / 3) - b / 3;
  } else {
    const double s = std::cbrt(r + std::sqrt(disc)), t = std::cbrt(r - std::sqrt(disc));
    m = s + t - b / 3;
  }
  for (int it = 0; it < 3; ++it) {
    const double f = ((m + b) * m + c) * m + d, df = (3 * m + 2 * b) * m + c;
    if (df == 0.0) break;
    m -= f / df;
  }
  return m;
}

// Roots of y^2 + s y + t; a (nearly) negative discriminant gives the real part as a candidate
// (flagged by near = true) for the caller to polish and test.
void quadratic_roots(double s, double t, std::array<double, 4>& y, std::array<bool, 4>& near, int& count) {
  const double disc = s * s / 4 - t;
  if (disc >= 0.0) {
    const double sq = std::sqrt(disc);
    y[static_cast<std::size_t>(count)] = -s / 2 + sq, near[static_cast<std::size_t>(count++)] = false;
    y[static_cast<std::size_t>(count)] = -s / 2 - sq, near[static_cast<std::size_t>(count++)] = false;
  } else {
    y[static_cast<std::size_t>(count)] = -s / 2, near[static_cast<std::size_t>(count++)] = true;
  }
}

// Roots theta of f, a degree-2 trigonometric polynomial. Shifted by phi (so that f(phi + pi),
// the quartic's leading coefficient, is the largest of four trial values) and written in
// t = tan((theta - phi) / 2), (1 + t^2)^2 f is the quartic
//   (A - C + E) t^4 + (2D - 4B) t^3 + (2E - 6A) t^2 + (4B + 2D) t + (A + C + E)
// (A, B, C, D, E the coefficients of cos 2u, sin 2u, cos u, sin u, 1 in u = theta - phi), solved
// by Ferrari's method; each root is Newton polished on f. A vanishing 2-theta part leaves
// degree 1 (solve_unit). No real root: the best candidate, flagged least squares.
Angles1 trig_quadratic_roots(const TrigQuadratic& f, std::array<double, 4>& theta, int& count) {
  Angles1 status;
  count = 0;
  const double scale = f.scale();
  if (std::hypot(f.a2, f.b2) <= 1e-12 * scale) {
    const Angles1 lin = solve_unit(Eigen::Vector2d(f.d1, f.c1), -f.e0, scale);
    for (int i = 0; i < lin.count; ++i) theta[static_cast<std::size_t>(count++)] = lin.theta[static_cast<std::size_t>(i)];
    return lin;
  }
  // f(phi + pi) for phi = 0, pi/2, pi/4, -pi/4, written out.
  const double h = std::sqrt(0.5);
  const std::array<double, 4> trial{0.0, M_PI / 2, M_PI / 4, -M_PI / 4};
  const std::array<double, 4> lead{f.a2 - f.c1 + f.e0, -f.a2 - f.d1 + f.e0, f.b2 - h * (f.c1 + f.d1) + f.e0,
                                   -f.b2 - h * (f.c1 - f.d1) + f.e0};
  double phi = 0.0, largest = -1.0;
  for (std::size_t i = 0; i < 4; ++i) {
    if (std::abs(lead[i]) > largest) largest = std::abs(lead[i]), phi = trial[i];
  }
  // The coefficients in u = theta - phi: cos 2theta = cos 2u cos 2phi - sin 2u sin 2phi, etc.
  const double c2 = std::cos(2 * phi), s2 = std::sin(2 * phi), c1 = std::cos(phi), s1 = std::sin(phi);
  const double A = f.a2 * c2 + f.b2 * s2, B = f.b2 * c2 - f.a2 * s2;
  const double C = f.c1 * c1 + f.d1 * s1, D = f.d1 * c1 - f.c1 * s1, E = f.e0;
  const double a4 = A - C + E;
  const double a = (2 * D - 4 * B) / a4, b = (2 * E - 6 * A) / a4, c = (4 * B + 2 * D) / a4, d = (A + C + E) / a4;
  // Depressed quartic y^4 + p y^2 + q y + r (t = y - a / 4).
  const double p = b - 3 * a * a / 8, q = c - a * b / 2 + a * a * a / 8,
               r = d - a * c / 4 + a * a * b / 16 - 3 * a * a * a * a / 256;
  std::array<double, 4> y{};
  std::array<bool, 4> near{};
  int n = 0;
  if (std::abs(q) <= 1e-14 * (1.0 + std::abs(p) * std::sqrt(std::abs(p)) + std::abs(r))) {  // biquadratic
    std::array<double, 4> z{};
    std::array<bool, 4> zn{};
    int m = 0;
    quadratic_roots(p, r, z, zn, m);
    for (int i = 0; i < m; ++i) {
      const double zi = z[static_cast<std::size_t>(i)];
      if (zi >= 0.0) {
        y[static_cast<std::size_t>(n)] = std::sqrt(zi), near[static_cast<std::size_t>(n++)] = zn[static_cast<std::size_t>(i)];
        y[static_cast<std::size_t>(n)] = -std::sqrt(zi), near[static_cast<std::size_t>(n++)] = zn[static_cast<std::size_t>(i)];
      } else {
        y[static_cast<std::size_t>(n)] = 0.0, near[static_cast<std::size_t>(n++)] = true;
      }
    }
  } else {
    // Resolvent: (y^2 + p/2 + m)^2 = 2m y^2 - q y + (m^2 + m p + p^2/4 - r) is a square for
    // 8 m^3 + 8 p m^2 + (2 p^2 - 8 r) m - q^2 = 0 (m > 0).
    const double m = std::max(cubic_largest_root(p, p * p / 4 - r, -q * q / 8), 1e-300);
    const double w = std::sqrt(2 * m);
    quadratic_roots(w, p / 2 + m - q / (2 * w), y, near, n);
    quadratic_roots(-w, p / 2 + m + q / (2 * w), y, near, n);
  }
  double best_value = INFINITY, best = 0.0;
  for (int i = 0; i < n; ++i) {
    const double t = polish(f, phi + 2 * std::atan(y[static_cast<std::size_t>(i)] - a / 4));
    const double v = std::abs(f.value(t));
    if (v < best_value) best_value = v, best = t;
    if (v > 1e-10 * scale && near[static_cast<std::size_t>(i)]) continue;
    if (v > 1e-8 * scale) continue;
    bool duplicate = false;
    for (int j = 0; j < count; ++j) duplicate = duplicate || std::abs(wrapped_difference(theta[static_cast<std::size_t>(j)], t)) < 1e-13;
    if (!duplicate) theta[static_cast<std::size_t>(count++)] = wrapped_difference(t, 0.0);
  }
  if (count == 0) {
    status.least_squares = true;
    theta[0] = wrapped_difference(best, 0.0);
    count = 1;
  }
  return status;
}

Angles2 swapped(const Angles2& a) {
  Angles2 b = a;
  b.theta1 = a.theta2;
  b.theta2 = a.theta1;
  return b;
}

// Both matrices (nearly) rank one: w^T M1 = 0 for w normal to M1's column space, so
// w . (M2 x2) = w . c gives theta2, then u . (M1 x1) = u . (c - M2 x2) theta1.
Angles2 rank_one_route(const Eigen::Matrix2d& m1, const Eigen::Matrix2d& m2, const Eigen::Vector2d& c, double scale) {
  Angles2 out;
  const Eigen::Vector2d col = m1.col(0).squaredNorm() >= m1.col(1).squaredNorm() ? m1.col(0) : m1.col(1);
  if (col.norm() <= kDegenerateTolerance * scale) {  // x1 free: solve the larger row of M2 x2 = c
    out.degenerate = true;
    const int r = m2.row(0).squaredNorm() >= m2.row(1).squaredNorm() ? 0 : 1;
    const Angles1 t2 = solve_unit(m2.row(r).transpose(), c(r), scale);
    out.least_squares = t2.least_squares;
    for (int i = 0; i < t2.count; ++i) {
      out.theta1[static_cast<std::size_t>(i)] = 0.0;
      out.theta2[static_cast<std::size_t>(i)] = t2.theta[static_cast<std::size_t>(i)];
    }
    out.count = t2.count;
    return out;
  }
  const Eigen::Vector2d u = col.normalized();
  const Eigen::Vector2d w(-u(1), u(0));
  const Angles1 t2 = solve_unit(m2.transpose() * w, w.dot(c), scale);
  out.least_squares = t2.least_squares;
  out.degenerate = t2.degenerate;
  for (int i = 0; i < t2.count; ++i) {
    const double th2 = t2.theta[static_cast<std::size_t>(i)];
    const Eigen::Vector2d x2 = unit_of(th2);
    const Angles1 t1 = solve_unit(m1.transpose() * u, u.dot(c - m2 * x2), scale);
    out.least_squares = out.least_squares || t1.least_squares;
    out.degenerate = out.degenerate || t1.degenerate;
    for (int j = 0; j < t1.count && out.count < 4; ++j) {
      out.theta1[static_cast<std::size_t>(out.count)] = t1.theta[static_cast<std::size_t>(j)];
      out.theta2[static_cast<std::size_t>(out.count)] = th2;
      ++out.count;
    }
  }
  return out;
}

// Newton steps on M1 x1(t1) + M2 x2(t2) = c (x' = (cos t, -sin t)): the elimination rounds
// x1's length; two steps restore the system's own accuracy (kept only when they help).
void newton_pair(const Eigen::Matrix2d& m1, const Eigen::Matrix2d& m2, const Eigen::Vector2d& c, double& t1, double& t2) {
  auto residual = [&](double a, double b) {
    return Eigen::Vector2d(m1 * unit_of(a) + m2 * unit_of(b) - c);
  };
  Eigen::Vector2d r = residual(t1, t2);
  const double floor = 1e-15 * (m1.norm() + m2.norm() + c.norm());
  for (int it = 0; it < 2 && r.norm() > floor; ++it) {
    Eigen::Matrix2d j;
    const Eigen::Vector2d x1 = unit_of(t1), x2 = unit_of(t2);
    j.col(0) = m1 * Eigen::Vector2d(x1(1), -x1(0));
    j.col(1) = m2 * Eigen::Vector2d(x2(1), -x2(0));
    const double det = j.determinant();
    if (std::abs(det) <= 1e-12 * j.squaredNorm()) return;
    const Eigen::Vector2d step = j.inverse() * r;
    const Eigen::Vector2d next = residual(t1 - step(0), t2 - step(1));
    if (!(next.norm() < r.norm())) return;
    t1 -= step(0), t2 -= step(1), r = next;
  }
}

// M1 well conditioned: x1 = e - B x2 with e = M1^-1 c, B = M1^-1 M2, and |x1|^2 = 1 is
// x2^T P x2 - 2 g . x2 + e . e - 1 = 0 (P = B^T B, g = B^T e), a degree-2 trigonometric
// polynomial in theta2 (s^2 = (1 - cos 2t) / 2, c^2 = (1 + cos 2t) / 2, 2 s c = sin 2t).
Angles2 quartic_route(const Eigen::Matrix2d& m1, const Eigen::Matrix2d& m2, const Eigen::Vector2d& c) {
  const Eigen::Matrix2d inv = m1.inverse();
  const Eigen::Vector2d e = inv * c;
  const Eigen::Matrix2d b = inv * m2;
  const Eigen::Matrix2d p = b.transpose() * b;
  const Eigen::Vector2d g = b.transpose() * e;
  const TrigQuadratic f{(p(1, 1) - p(0, 0)) / 2, p(0, 1), -2 * g(1), -2 * g(0), (p(0, 0) + p(1, 1)) / 2 + e.squaredNorm() - 1.0};
  Angles2 out;
  std::array<double, 4> theta2{};
  int count = 0;
  const Angles1 status = trig_quadratic_roots(f, theta2, count);
  out.least_squares = status.least_squares;
  out.degenerate = status.degenerate;
  for (int i = 0; i < count; ++i) {
    const double th2 = theta2[static_cast<std::size_t>(i)];
    const Eigen::Vector2d x1 = e - b * unit_of(th2);
    out.theta1[static_cast<std::size_t>(i)] = angle_of(x1);
    out.theta2[static_cast<std::size_t>(i)] = th2;
    newton_pair(m1, m2, c, out.theta1[static_cast<std::size_t>(i)], out.theta2[static_cast<std::size_t>(i)]);
  }
  out.count = count;
  return out;
}

}  // namespace

Eigen::Matrix3d rot(const Eigen::Vector3d& k, double theta) {
  double s, c;
  fast::sin_cos(theta, s, c);
  return rot(k, s, c);
}

Eigen::Matrix3d rot(const Eigen::Vector3d& k, double s, double c) {
  // Rodrigues: R = cos I + sin [k]x + (1 - cos) k k^T.
  Eigen::Matrix3d r = (1.0 - c) * (k * k.transpose());
  r.diagonal().array() += c;
  r(0, 1) -= s * k.z();
  r(1, 0) += s * k.z();
  r(0, 2) += s * k.y();
  r(2, 0) -= s * k.y();
  r(1, 2) -= s * k.x();
  r(2, 1) += s * k.x();
  return r;
}

Angles1 sp1(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, const Eigen::Vector3d& k) {
  const Eigen::Vector2d x = rotation_basis(k, p1).transpose() * p2;
  const double scale = p1.norm() + p2.norm();
  Angles1 out;
  out.count = 1;
  if (x.norm() <= kDegenerateTolerance * std::max(scale * scale, 1e-300)) {
    out.degenerate = true;
    out.theta[0] = 0.0;
  } else {
    set_angle(out, 0, x);
  }
  const double tol = 1e-9 * std::max(scale, 1e-300);
  out.least_squares = std::abs(k.dot(p1) - k.dot(p2)) > tol || std::abs(p1.norm() - p2.norm()) > tol;
  return out;
}

Angles1 sp4(const Eigen::Vector3d& h, const Eigen::Vector3d& p, const Eigen::Vector3d& k, double d) {
  const Eigen::Vector2d a = rotation_basis(k, p).transpose() * h;
  return solve_unit(a, d - h.dot(k) * k.dot(p), h.norm() * p.norm() + std::abs(d));
}

Angles1 sp3(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, const Eigen::Vector3d& k, double d) {
  return sp4(p2, p1, k, (p1.squaredNorm() + p2.squaredNorm() - d * d) / 2);
}

Angles2 sp2(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, const Eigen::Vector3d& k1,
            const Eigen::Vector3d& k2) {
  Angles2 out;
  const double n1 = p1.norm(), n2 = p2.norm();
  if (k1.cross(k2).norm() <= kDegenerateTolerance || n1 == 0.0 || n2 == 0.0) {
    const Angles1 t = sp1(p1, p2, k1);
    out.degenerate = true;
    out.least_squares = t.least_squares;
    out.count = 1;
    out.theta1[0] = t.theta[0];
    out.theta2[0] = 0.0;
    return out;
  }
  const Angles1 t1 = sp4(k2, p1 / n1, k1, k2.dot(p2 / n2));
  out.least_squares = t1.least_squares || std::abs(n1 - n2) > 1e-9 * (n1 + n2);
  out.degenerate = t1.degenerate;
  for (int i = 0; i < t1.count; ++i) {
    const double th1 = t1.theta[static_cast<std::size_t>(i)];
    const Angles1 t2 = sp1(p2, rot(k1, th1) * p1, k2);
    out.degenerate = out.degenerate || t2.degenerate;
    out.theta1[static_cast<std::size_t>(i)] = th1;
    out.theta2[static_cast<std::size_t>(i)] = t2.theta[0];
  }
  out.count = t1.count;
  return out;
}

Angles2 solve_two_circles(const Eigen::Matrix2d& m1_in, const Eigen::Matrix2d& m2_in, const Eigen::Vector2d& c_in) {
  // Each equation scaled to unit size, so the rank tests compare like with like (SP5's first
  // equation is in length^2, its second in length).
  Eigen::Matrix2d m1 = m1_in, m2 = m2_in;
  Eigen::Vector2d c = c_in;
  for (int r = 0; r < 2; ++r) {
    const double s = std::max({m1.row(r).norm(), m2.row(r).norm(), std::abs(c(r))});
    if (s > 0.0) m1.row(r) /= s, m2.row(r) /= s, c(r) /= s;
  }
  const double n1 = m1.squaredNorm(), n2 = m2.squaredNorm();
  const double r1 = n1 > 0.0 ? std::abs(m1.determinant()) / n1 : 0.0;
  const double r2 = n2 > 0.0 ? std::abs(m2.determinant()) / n2 : 0.0;
  constexpr double kRankTolerance = 1e-9;  // |det| / |M|_F^2, at most 1/2
  if (std::max(r1, r2) > kRankTolerance) {
    return r1 >= r2 ? quartic_route(m1, m2, c) : swapped(quartic_route(m2, m1, c));
  }
  if (n1 >= n2) return rank_one_route(m1, m2, c, 1.0);
  return swapped(rank_one_route(m2, m1, c, 1.0));
}

Angles3 sp5(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
            const Eigen::Vector3d& p3, const Eigen::Vector3d& k1, const Eigen::Vector3d& k2,
            const Eigen::Vector3d& k3) {
  // |p0 + R1 p1|^2 = |p2 + R3 p3|^2 and k2 . (p0 + R1 p1) = k2 . (p2 + R3 p3).
  const Eigen::Matrix<double, 3, 2> a1 = rotation_basis(k1, p1), a3 = rotation_basis(k3, p3);
  Eigen::Matrix2d m1, m3;
  m1.row(0) = 2 * (a1.transpose() * p0).transpose();
  m1.row(1) = (a1.transpose() * k2).transpose();
  m3.row(0) = -2 * (a3.transpose() * p2).transpose();
  m3.row(1) = -(a3.transpose() * k2).transpose();
  const Eigen::Vector2d c(
      p2.squaredNorm() + p3.squaredNorm() + 2 * p2.dot(k3) * k3.dot(p3) - p0.squaredNorm() - p1.squaredNorm() -
          2 * p0.dot(k1) * k1.dot(p1),
      k2.dot(p2) + k2.dot(k3) * k3.dot(p3) - k2.dot(p0) - k2.dot(k1) * k1.dot(p1));
  const Angles2 t13 = solve_two_circles(m1, m3, c);
  Angles3 out;
  out.least_squares = t13.least_squares;
  out.degenerate = t13.degenerate;
  for (int i = 0; i < t13.count; ++i) {
    const std::size_t s = static_cast<std::size_t>(i);
    const Eigen::Vector3d left = p0 + k1 * k1.dot(p1) + a1 * unit_of(t13.theta1[s]);
    const Eigen::Vector3d right = p2 + k3 * k3.dot(p3) + a3 * unit_of(t13.theta2[s]);
    const Angles1 t2 = sp1(right, left, k2);
    out.least_squares = out.least_squares || t2.least_squares;
    out.degenerate = out.degenerate || t2.degenerate;
    out.theta1[s] = t13.theta1[s];
    out.theta2[s] = t2.theta[0];
    out.theta3[s] = t13.theta2[s];
  }
  out.count = t13.count;
  return out;
}

Angles2 sp6(const std::array<Eigen::Vector3d, 4>& h, const std::array<Eigen::Vector3d, 4>& k,
            const std::array<Eigen::Vector3d, 4>& p, double d1, double d2) {
  Eigen::Matrix2d m1, m2;
  m1.row(0) = (rotation_basis(k[0], p[0]).transpose() * h[0]).transpose();
  m2.row(0) = (rotation_basis(k[1], p[1]).transpose() * h[1]).transpose();
  m1.row(1) = (rotation_basis(k[2], p[2]).transpose() * h[2]).transpose();
  m2.row(1) = (rotation_basis(k[3], p[3]).transpose() * h[3]).transpose();
  const Eigen::Vector2d c(d1 - h[0].dot(k[0]) * k[0].dot(p[0]) - h[1].dot(k[1]) * k[1].dot(p[1]),
                          d2 - h[2].dot(k[2]) * k[2].dot(p[2]) - h[3].dot(k[3]) * k[3].dot(p[3]));
  return solve_two_circles(m1, m2, c);
}

}  // namespace hapsyn::plugins::closed_form_ik
