#pragma once
/// \file
/// Private to the haptic6r model: the closed-form inverse kinematics, the selection of one
/// solution and the classification of a pose, written once for T = double (one pose: solve(),
/// inverse_kinematics()) and T = hapsyn::Lanes (one pose per SIMD lane: solve_block()). Both run
/// the same expressions in the same order, so a lane's status, q and DH-angle cosines and sines
/// are the per-pose ones bit for bit wherever the compiler fuses multiply-adds alike (the tests
/// compare them exactly). Branches become selections: every one of the eight branches (h sign,
/// theta4 branch, elbow) is computed for every pose and marked valid or not.
///
/// Shared denominators (the norm of h, of the planar and wrist unit vectors; L4 and 2 L1 L2 per
/// design) are inverted once and multiplied: the divider is the IK's scarcest unit (12 fewer
/// divisions per pose made the haptic 6R objective 2 to 4 % faster, measured on 2026-12-05;
/// `git log -- README.md` holds that round). The quaternion's four are not (see target_of()).
///
/// Every function is [[gnu::always_inline]]: it is compiled inside each multiversioned caller
/// (hapsyn/accel/multiversion.hpp). The model's translation units are compiled with -fno-math-errno
/// so that a lane square root is one instruction (no result changes: only errno is dropped).
#include "haptic6r.hpp"

#include <hapsyn/accel/fast_math.hpp>
#include <hapsyn/accel/lanes.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace hapsyn::plugins::haptic6r_ik {

constexpr double kPi = 3.14159265358979323846;
// acos/asin arguments this far past +-1 are rounding at the reach boundary, not a miss.
constexpr double kBoundaryTolerance = 1e-12;

// ---- The scalar counterparts of the Lanes operations (hapsyn/accel/lanes.hpp), so that one template
// serves both. Truth values are numbers holding 1 or 0, as in the lane kernels.

[[gnu::always_inline]] inline double where_less(double x, double y, double a, double b) { return x < y ? a : b; }
[[gnu::always_inline]] inline double where_greater(double x, double y, double a, double b) { return x > y ? a : b; }
[[gnu::always_inline]] inline double where_equal(double x, double y, double a, double b) { return x == y ? a : b; }
[[gnu::always_inline]] inline double magnitude(double a) { return std::fabs(a); }
template <int B, int N>
[[gnu::always_inline]] inline LanesOf<B, N> magnitude(const LanesOf<B, N>& a) { return abs(a); }
[[gnu::always_inline]] inline double root(double a) { return std::sqrt(a); }
template <int B, int N>
[[gnu::always_inline]] inline LanesOf<B, N> root(const LanesOf<B, N>& a) { return hapsyn::sqrt(a); }
[[gnu::always_inline]] inline double angle_of(double y, double x) { return fast::atan2(y, x); }
template <int B, int N>
[[gnu::always_inline]] inline LanesOf<B, N> angle_of(const LanesOf<B, N>& y, const LanesOf<B, N>& x) { return hapsyn::atan2(y, x); }
/// angle_of(y, x) and angle_of(y, -x); the lanes share the work of the two (the same values).
[[gnu::always_inline]] inline void angles_of(double y, double x, double& angle, double& mirrored) {
  angle = fast::atan2(y, x);
  mirrored = fast::atan2(y, -x);
}
template <int B, int N>
[[gnu::always_inline]] inline void angles_of(const LanesOf<B, N>& y, const LanesOf<B, N>& x, LanesOf<B, N>& angle,
                                          LanesOf<B, N>& mirrored) {
  atan2_and_mirrored(y, x, angle, mirrored);
}
[[gnu::always_inline]] inline double round_down(double a) { return std::floor(a); }
template <int B, int N>
[[gnu::always_inline]] inline LanesOf<B, N> round_down(const LanesOf<B, N>& a) { return floor_small(a); }  // |a| < 2^51 here
/// Whether any lane holds a non-zero truth value.
[[gnu::always_inline]] inline bool any(double truth) { return truth != 0.0; }
template <int B, int N>
[[gnu::always_inline]] inline bool any(const LanesOf<B, N>& truth) { return any_nonzero(truth); }
template <typename T>
[[gnu::always_inline]] inline T splat(double value) {
  if constexpr (std::is_same_v<T, double>) {
    return value;
  } else {
    return T::splat(value);
  }
}
/// `truth ? a : b` for a truth value holding 1 or 0.
template <typename T>
[[gnu::always_inline]] inline T pick(const T& truth, const T& a, const T& b) {
  return where_equal(truth, splat<T>(0.0), b, a);
}
/// max(a, 0) as std::max(0.0, a) gives it: 0 for a NaN.
template <typename T>
[[gnu::always_inline]] inline T at_least_zero(const T& a) {
  return where_greater(a, splat<T>(0.0), a, splat<T>(0.0));
}
/// std::clamp(a, lo, hi).
template <typename T>
[[gnu::always_inline]] inline T clamp_to(const T& a, const T& lo, const T& hi) {
  return where_less(a, lo, lo, where_less(hi, a, hi, a));
}

/// Into [-pi, pi): angle - 2 pi n, n = floor((angle + pi) / (2 pi)). An angle already inside
/// gets n = 0 and comes back unchanged (the subtraction of 0 is exact); the turn count can be
/// off by one only where (angle + pi) / (2 pi) rounds across an integer, and the two corrections
/// (rarely taken, so predictable for one pose) bring r into [-pi, pi) there. No test of whether
/// the angle is inside: for IK angles that is a coin toss, which a branch mispredicts.
template <typename T>
[[gnu::always_inline]] inline T wrap(const T& angle) {
  constexpr double kInverseTwoPi = 0.15915494309189533577;
  T r = angle - 2.0 * kPi * round_down((angle + kPi) * kInverseTwoPi);
  r = where_less(r, splat<T>(kPi), r, r - 2.0 * kPi);
  return where_less(r, splat<T>(-kPi), r + 2.0 * kPi, r);
}

/// wrap() of an angle in [-3 pi, 3 pi): wrap()'s two corrections without its turn count (for
/// such an angle the count is -1, 0 or 1, and subtracting 2 pi n is the correction's own
/// subtraction), so the same value with a third of the operations; the IK's angles minus
/// their offsets and wrapped angles minus home are in that range (IkModel::near_offset,
/// near_home; for theta1, phi -+ beta in [-2 pi, 2 pi], minus at most 3 pi / 4).
template <typename T>
[[gnu::always_inline]] inline T wrap_near(const T& angle) {
  const T r = where_less(angle, splat<T>(kPi), angle, angle - 2.0 * kPi);
  return where_less(r, splat<T>(-kPi), r + 2.0 * kPi, r);
}

/// Joint i's q = wrap(theta - theta_offset_i) for an angle theta of the IK: theta1 in [-2 pi, 2
/// pi], theta3 (i = 2) any, the others in [-pi, 2 pi].
template <typename T>
[[gnu::always_inline]] inline T joint_angle(const T& theta, const IkModel& m, std::size_t i) {
  return i != 2 && m.near_offset[i] ? wrap_near(theta - m.offset[i]) : wrap(theta - m.offset[i]);
}

/// wrap(q - home_i) for a wrapped q (in [-pi, pi)).
template <typename T>
[[gnu::always_inline]] inline T from_home(const T& q, const IkModel& m, std::size_t i) {
  return m.near_home[i] ? wrap_near(q - m.home[i]) : wrap(q - m.home[i]);
}

/// A target frame: position p [m] and rotation r (r[row][col], columns x_E, y_E, z_E).
template <typename T>
struct Target {
  T p[3], r[3][3];
};


// Rotation of one DH row from cos/sin of its angle: m = Rz(theta) Rx(alpha).
template <typename T>
[[gnu::always_inline]] inline void dh_rotation(const T& ct, const T& st, double ca, double sa, T (&m)[3][3]) {
  m[0][0] = ct;
  m[0][1] = -st * ca;
  m[0][2] = st * sa;
  m[1][0] = st;
  m[1][1] = ct * ca;
  m[1][2] = -ct * sa;
  m[2][0] = splat<T>(0.0);
  m[2][1] = splat<T>(sa);
  m[2][2] = splat<T>(ca);
}

// ---- The IK in four steps. The eight branches share most of their work: flipping h flips
// x3 = e_z x h (yaw + pi), and the wrist centre o = w - L4 cos(theta4) x3 depends only on the
// product of the two signs, so the planar 2R solve (three atan2) is done for two points only;
// rotations are built from the cosines and sines at hand, not from angles.

// Step 1: the wrist point w = p - L5 z_E, the unit axis h of joints 4 and 5 (for h = +hz) and
// theta4's sine and |cosine|; ok is 0 when the target has no solution (not a rotation, or w out
// of l4's reach).
template <typename T>
struct WristGeometry {
  T w[3], hx, hy, s4, c4_abs, ok;
};

template <typename T>
[[gnu::always_inline]] inline void wrist_geometry(const Target<T>& target, const IkModel& m, WristGeometry<T>& g) {
  const T zero = splat<T>(0.0), one = splat<T>(1.0), tiny = splat<T>(1e-12);
  for (int i = 0; i < 3; ++i) g.w[i] = target.p[i] - m.L5 * target.r[i][2];
  // Axis of joints 4 and 5: horizontal and perpendicular to the roll axis. With the roll axis
  // vertical, h is free (a singular family); take the one normal to x_E so that the solution
  // stays finite and deterministic.
  const T hx_roll = -target.r[1][2], hy_roll = target.r[0][2];
  const T n_roll = root(hx_roll * hx_roll + hy_roll * hy_roll);
  const T hx_x = -target.r[1][0], hy_x = target.r[0][0];
  const T n_x = root(hx_x * hx_x + hy_x * hy_x);
  const T vertical = where_less(n_roll, tiny, one, zero);
  const T n = pick(vertical, n_x, n_roll);
  const T rotation_ok = where_less(n, tiny, zero, one);  // else not a rotation
  const T inverse_n = 1.0 / pick(rotation_ok, n, one);
  g.hx = pick(vertical, hx_x, hx_roll) * inverse_n;
  g.hy = pick(vertical, hy_x, hy_roll) * inverse_n;
  const T s4 = (g.w[2] + m.L3) * m.inverse_L4;
  const T reach_ok = where_greater(magnitude(s4), splat<T>(1.0 + kBoundaryTolerance), zero, one);
  g.s4 = clamp_to(s4, splat<T>(-1.0), one);
  g.c4_abs = root(at_least_zero(1.0 - g.s4 * g.s4));
  g.ok = rotation_ok * reach_ok;
}

// Step 2: the planar 2R solve (joints 1, 2) for the wrist centre of sign product k (0: +, 1: -):
// theta1 = phi -+ beta, theta2 = +-theta2, with the same angles as cosines and sines.
template <typename T>
struct PlanarSolution {
  T valid, c2, s2, theta2, phi, beta, cos_phi, sin_phi, cos_beta, sin_beta;
};

template <typename T>
[[gnu::always_inline]] inline void solve_planar(const WristGeometry<T>& g, const IkModel& m,
                                                PlanarSolution<T> (&planar)[2]) {
  const T zero = splat<T>(0.0), one = splat<T>(1.0);
  const double L1 = m.L1, L2 = m.L2;
  for (int k = 0; k < 2; ++k) {
    const T c4x3 = (k == 0 ? g.c4_abs : -g.c4_abs) * m.L4;  // L4 c4 times the sign of x3
    const T ox = g.w[0] + c4x3 * g.hy, oy = g.w[1] - c4x3 * g.hx;  // x3 = (-h_y, h_x, 0)
    const T c2_raw = (ox * ox + oy * oy - L1 * L1 - L2 * L2) * m.inverse_2L1L2;
    PlanarSolution<T>& p = planar[k];
    p.valid = where_greater(magnitude(c2_raw), splat<T>(1.0 + kBoundaryTolerance), zero, one);
    if (!any(g.ok * p.valid)) {  // out of reach for every lane: nothing else of it is read
      p = PlanarSolution<T>{zero, zero, zero, zero, zero, zero, one, zero, one, zero};
      continue;
    }
    p.c2 = clamp_to(c2_raw, splat<T>(-1.0), one);
    p.s2 = root(at_least_zero(1.0 - p.c2 * p.c2));
    p.theta2 = angle_of(p.s2, p.c2);
    p.phi = angle_of(oy, ox);
    const T bx = L1 + L2 * p.c2, by = L2 * p.s2;
    p.beta = angle_of(by, bx);
    // Lengths of order 1 m: sqrt(x^2 + y^2) cannot overflow, and is several times cheaper than hypot.
    const T ro = root(ox * ox + oy * oy), rb = root(bx * bx + by * by);
    const T inverse_ro = 1.0 / where_greater(ro, zero, ro, one), inverse_rb = 1.0 / where_greater(rb, zero, rb, one);
    p.cos_phi = where_greater(ro, zero, ox * inverse_ro, one);
    p.sin_phi = where_greater(ro, zero, oy * inverse_ro, zero);
    p.cos_beta = where_greater(rb, zero, bx * inverse_rb, one);
    p.sin_beta = where_greater(rb, zero, by * inverse_rb, zero);
  }
}

// Step 3: the wrist angles theta5, theta6 for h = +hz and each theta4 branch b4. Flipping h and
// the theta4 branch together turns R_04 into R_04 Rx(pi) (x3 -> -x3, cos theta4 -> -cos
// theta4), which maps theta5 -> pi - theta5 and theta6 -> theta6 + pi: the h = -hz branches
// reuse these (two atan2 pairs instead of four).
template <typename T>
struct WristAngles {
  T theta5[2], theta6[2], cos5[2], sin5[2], cos6[2], sin6[2];
};

template <typename T>
[[gnu::always_inline]] inline void solve_wrist(const Target<T>& target, const WristGeometry<T>& g,
                                               const PlanarSolution<T> (&planar)[2], const IkModel& m,
                                               WristAngles<T>& wrist) {
  const T zero = splat<T>(0.0), one = splat<T>(1.0);
  T r3[3][3];
  dh_rotation(-g.hy, g.hx, m.ca[2], m.sa[2], r3);
  for (int b4 = 0; b4 < 2; ++b4) {
    // Branch b4's wrist angles serve the slots built on planar[b4] only (see assemble()).
    if (!any(planar[b4].valid)) {
      wrist.theta5[b4] = wrist.theta6[b4] = wrist.sin5[b4] = wrist.sin6[b4] = zero;
      wrist.cos5[b4] = wrist.cos6[b4] = one;
      continue;
    }
    T r4[3][3], r04[3][3], r5[3][3];
    dh_rotation(b4 == 0 ? g.c4_abs : -g.c4_abs, g.s4, m.ca[3], m.sa[3], r4);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) r04[i][j] = r3[i][0] * r4[0][j] + r3[i][1] * r4[1][j] + r3[i][2] * r4[2][j];
    }
    // The approach in frame 4: a4 = R_04^T z_E.
    T a4[2];
    for (int j = 0; j < 2; ++j) {
      a4[j] = r04[0][j] * target.r[0][2] + r04[1][j] * target.r[1][2] + r04[2][j] * target.r[2][2];
    }
    // z_5 in frame 4 is Rz(theta5) (0, -sin alpha5, cos alpha5) = (sin theta5, -cos theta5, 0).
    wrist.theta5[b4] = angle_of(a4[0], -a4[1]);
    const T n5 = root(a4[0] * a4[0] + a4[1] * a4[1]);  // 1 up to rounding: the approach is normal to h
    const T inverse_n5 = 1.0 / where_greater(n5, zero, n5, one);
    wrist.cos5[b4] = where_greater(n5, zero, -a4[1] * inverse_n5, one);
    wrist.sin5[b4] = where_greater(n5, zero, a4[0] * inverse_n5, zero);
    dh_rotation(wrist.cos5[b4], wrist.sin5[b4], m.ca[4], m.sa[4], r5);
    // theta6 from x_E in frame 5: (x_5 . x_E, y_5 . x_E), x_5 = R_04 r5.col(0), y_5 = R_04 r5.col(1).
    T along_x = zero, along_y = zero;
    for (int i = 0; i < 3; ++i) {
      const T x5 = r04[i][0] * r5[0][0] + r04[i][1] * r5[1][0] + r04[i][2] * r5[2][0];
      const T y5 = r04[i][0] * r5[0][1] + r04[i][1] * r5[1][1] + r04[i][2] * r5[2][1];
      along_x = along_x + x5 * target.r[i][0];
      along_y = along_y + y5 * target.r[i][0];
    }
    wrist.theta6[b4] = angle_of(along_y, along_x);
    const T n6 = root(along_y * along_y + along_x * along_x);
    const T inverse_n6 = 1.0 / where_greater(n6, zero, n6, one);
    wrist.cos6[b4] = where_greater(n6, zero, along_x * inverse_n6, one);
    wrist.sin6[b4] = where_greater(n6, zero, along_y * inverse_n6, zero);
  }
}

/// Steps 1 to 3 and the remaining angles (the yaw of h, theta4 of both branches): everything
/// the branches are assembled from. All of it is arithmetic without branches; solve() then
/// assembles, selects and classifies with the per-pose code below, the block kernel with
/// configure_lanes().
template <typename T>
struct Branches {
  Target<T> target;
  WristGeometry<T> g;
  PlanarSolution<T> planar[2];
  WristAngles<T> wrist;
  T yaw0, theta4_branch[2];
};

template <typename T>
[[gnu::always_inline]] inline void branch_angles(const Target<T>& target, const IkModel& m, Branches<T>& b) {
  b.target = target;
  wrist_geometry(target, m, b.g);
  solve_planar(b.g, m, b.planar);
  solve_wrist(target, b.g, b.planar, m, b.wrist);
  b.yaw0 = angle_of(b.g.hx, -b.g.hy);
  angles_of(b.g.s4, b.g.c4_abs, b.theta4_branch[0], b.theta4_branch[1]);
}

// Step 4 and after, per pose (T = double): solve() and inverse_kinematics(). The block kernel
// does the same for eight poses at once with configure_lanes() (below), whose statuses and
// cosines and sines the tests compare with these.

/// The eight branches in the order (h sign, theta4 branch, elbow), slot 4 hs + 2 b4 + b2: q
/// [rad] wrapped into [-pi, pi), the DH-angle cosines c and sines s (when asked for), valid where
/// the branch is a solution. Compacting the valid slots in order gives inverse_kinematics()'s list.
struct Slots {
  double q[8][6], c[8][6], s[8][6];
  bool valid[8];
};

// The DH-angle cosines c and sines s of slot 4 hs + 2 b4 + b2, by angle-sum identities on the
// vectors its angles came from (no trigonometric call).
[[gnu::always_inline]] inline void slot_trig(const Branches<double>& b, int slot, double* c, double* s) {
  const int hs = slot >> 2, b4 = (slot >> 1) & 1, b2 = slot & 1;
  const WristGeometry<double>& g = b.g;
  const WristAngles<double>& wrist = b.wrist;
  const PlanarSolution<double>& p = b.planar[hs ^ b4];
  const double sb = b2 == 0 ? -p.sin_beta : p.sin_beta;  // theta1 = phi + (-+beta)
  c[0] = p.cos_phi * p.cos_beta - p.sin_phi * sb;
  s[0] = p.sin_phi * p.cos_beta + p.cos_phi * sb;
  c[1] = p.c2;
  s[1] = b2 == 0 ? p.s2 : -p.s2;
  const double c12 = c[0] * c[1] - s[0] * s[1], s12 = s[0] * c[1] + c[0] * s[1];
  const double sign = hs == 0 ? 1.0 : -1.0;
  const double cy = -sign * g.hy, sy = sign * g.hx;  // the yaw: x3 = e_z x h
  c[2] = cy * c12 + sy * s12;  // theta3 = yaw - (theta1 + theta2)
  s[2] = sy * c12 - cy * s12;
  c[3] = b4 == 0 ? g.c4_abs : -g.c4_abs;
  s[3] = g.s4;
  c[4] = hs == 0 ? wrist.cos5[b4] : -wrist.cos5[1 - b4];  // pi - theta5
  s[4] = hs == 0 ? wrist.sin5[b4] : wrist.sin5[1 - b4];
  c[5] = hs == 0 ? wrist.cos6[b4] : -wrist.cos6[1 - b4];  // theta6 + pi
  s[5] = hs == 0 ? wrist.sin6[b4] : -wrist.sin6[1 - b4];
}

// Every branch's q = DH angles - theta offsets wrapped into [-pi, pi) and its validity; with
// `with_trig` also its DH-angle cosines and sines (slot_trig). A pose needs them for the chosen
// branch only.
[[gnu::always_inline]] inline void assemble(const Branches<double>& b, const IkModel& m, bool with_trig, Slots& out) {
  const WristAngles<double>& wrist = b.wrist;
  for (int hs = 0; hs < 2; ++hs) {
    const double yaw = hs == 0 ? b.yaw0 : b.yaw0 + kPi;
    for (int b4 = 0; b4 < 2; ++b4) {
      const PlanarSolution<double>& p = b.planar[hs ^ b4];
      const double theta5 = hs == 0 ? wrist.theta5[b4] : kPi - wrist.theta5[1 - b4];
      const double theta6 = hs == 0 ? wrist.theta6[b4] : wrist.theta6[1 - b4] + kPi;
      for (int b2 = 0; b2 < 2; ++b2) {
        const int slot = 4 * hs + 2 * b4 + b2;
        out.valid[slot] = b.g.ok != 0.0 && p.valid != 0.0;
        if (!out.valid[slot]) continue;
        const double theta2 = b2 == 0 ? p.theta2 : -p.theta2;
        const double theta1 = b2 == 0 ? p.phi - p.beta : p.phi + p.beta;
        const double theta3 = yaw - theta1 - theta2;
        const double theta[6] = {theta1, theta2, theta3, b.theta4_branch[b4], theta5, theta6};
        for (std::size_t i = 0; i < 6; ++i) out.q[slot][i] = joint_angle(theta[i], m, i);
        if (with_trig) slot_trig(b, slot, out.c[slot], out.s[slot]);
      }
    }
  }
}

/// Every branch of the target's IK (joint limits ignored), into `out`.
[[gnu::always_inline]] inline void inverse_kinematics(const Target<double>& target, const IkModel& m, Slots& out) {
  Branches<double> b;
  branch_angles(target, m, b);
  assemble(b, m, true, out);
}

/// Whether q has a representative in [lower, upper] in every joint (tolerance
/// kHaptic6RAngleTolerance) and lies on the selected elbow side.
[[gnu::always_inline]] inline bool admissible(const double (&q)[6], const IkModel& m) {
  constexpr double tol = kHaptic6RAngleTolerance;
  for (std::size_t i = 0; i < 6; ++i) {
    if (q[i] >= m.lower[i] && q[i] <= m.upper[i]) continue;  // the common case
    // The representative of q_i in [lower, lower + 2 pi) must not exceed upper (with tolerance).
    double v = q[i];
    while (v < m.lower[i] - tol) v += 2.0 * kPi;
    while (v > m.lower[i] + 2.0 * kPi - tol) v -= 2.0 * kPi;
    if (v < m.lower[i] - tol) v += 2.0 * kPi;
    if (!(v <= m.upper[i] + tol)) return false;
  }
  if (m.selection == Haptic6RSelection::kElbowLeft && q[1] < -tol) return false;
  if (m.selection == Haptic6RSelection::kElbowRight && q[1] > tol) return false;
  return true;
}

/// The slot the selection rule picks among the valid admissible ones: the one closest to home,
/// the first on ties; -1 when there is none.
[[gnu::always_inline]] inline int select(const Slots& slots, const IkModel& m) {
  int best = -1;
  double best_distance = INFINITY;
  for (int k = 0; k < 8; ++k) {
    if (!slots.valid[k] || !admissible(slots.q[k], m)) continue;
    double distance = 0.0;
    for (std::size_t i = 0; i < 6; ++i) {
      const double e = from_home(slots.q[k][i], m, i);
      distance += e * e;
    }
    if (distance < best_distance) {
      best_distance = distance;
      best = k;
    }
  }
  return best;
}

/// A pose's outcome: its status, q as solve() sets it (zero when unreachable, the first solution
/// when invalid, the chosen one brought into the limits otherwise) and, for a reachable or
/// singular pose, the chosen configuration's DH-angle cosines c and sines s.
struct PoseOutcome {
  SampleStatus status = SampleStatus::kUnreachable;
  double q[6] = {}, c[6] = {}, s[6] = {};
};

/// The target of a pose (x, y, z, qw, qx, qy, qz) with a finite position and a quaternion of
/// norm > 1e-9 (the caller checks): the quaternion normalised, then Eigen's toRotationMatrix().
template <typename T>
[[gnu::always_inline]] inline void target_of(const T (&pose)[7], const T& quaternion_norm, Target<T>& t) {
  for (int i = 0; i < 3; ++i) t.p[i] = pose[i];
  // Four divisions, not a reciprocal and four products (as the IK's other shared denominators
  // are): with the reciprocal, solve() and solve_block() differed by 1.6e-11 relative in an
  // inertia entry (haptic6r_test, BlockStatusesAndQuantitiesEqualSolveUnderEveryRule, rule 1).
  const T w = pose[3] / quaternion_norm, x = pose[4] / quaternion_norm, y = pose[5] / quaternion_norm,
          z = pose[6] / quaternion_norm;
  const T tx = 2.0 * x, ty = 2.0 * y, tz = 2.0 * z;
  const T twx = tx * w, twy = ty * w, twz = tz * w, txx = tx * x, txy = ty * x, txz = tz * x;
  const T tyy = ty * y, tyz = tz * y, tzz = tz * z;
  t.r[0][0] = 1.0 - (tyy + tzz);
  t.r[0][1] = txy - twz;
  t.r[0][2] = txz + twy;
  t.r[1][0] = txy + twz;
  t.r[1][1] = 1.0 - (txx + tzz);
  t.r[1][2] = tyz - twx;
  t.r[2][0] = txz - twy;
  t.r[2][1] = tyz + twx;
  t.r[2][2] = 1.0 - (txx + tyy);
}

/// Norm of the pose's quaternion (its coordinates 3..6).
template <typename T>
[[gnu::always_inline]] inline T quaternion_norm(const T (&pose)[7]) {
  return root(pose[3] * pose[3] + pose[4] * pose[4] + pose[5] * pose[5] + pose[6] * pose[6]);
}

/// The selection and classification of a pose from its branches (what configure() does after
/// branch_angles()).
[[gnu::always_inline]] inline void configure_branches(const Branches<double>& b, const IkModel& m, PoseOutcome& out) {
  Slots slots;
  assemble(b, m, false, slots);
  int first = -1;
  for (int k = 7; k >= 0; --k) first = slots.valid[k] ? k : first;
  out = PoseOutcome{};
  if (first < 0) return;  // unreachable: q zero
  const int chosen = select(slots, m);
  if (chosen < 0) {  // invalid: the first solution's q
    for (int i = 0; i < 6; ++i) out.q[i] = slots.q[first][i];
    out.status = SampleStatus::kInvalid;
    return;
  }
  // Brings q_i to its representative inside [lower, upper] (select() checked it exists).
  constexpr double tol = kHaptic6RAngleTolerance;
  for (std::size_t i = 0; i < 6; ++i) {
    double v = slots.q[chosen][i];
    while (v < m.lower[i] - tol) v += 2.0 * kPi;
    while (v > m.upper[i] + tol) v -= 2.0 * kPi;
    out.q[i] = v < m.lower[i] ? m.lower[i] : (m.upper[i] < v ? m.upper[i] : v);
  }
  slot_trig(b, chosen, out.c, out.s);
  const double singular_below = m.singularity_tolerance;
  const double wrist = std::sqrt(b.target.r[0][2] * b.target.r[0][2] + b.target.r[1][2] * b.target.r[1][2]);
  const bool singular = std::fabs(out.s[1]) < singular_below || std::fabs(out.c[3]) < singular_below || wrist < singular_below;
  out.status = singular ? SampleStatus::kSingular : SampleStatus::kReachable;
}

// ---- Step 4 and after for a block (T = a lanes type): what configure_branches() decides for each
// lane, as lane-wise selections (KERNELS.md section 14.4). The eight slots share their
// angles (theta1 and theta2 come from two planar solutions and two elbows, theta4 from two
// branches, theta5 and theta6 from two branches and two h signs; only theta3 is the slot's
// own), so 26 wrapped angles serve the 48 of the per-pose code, each wrapped, tested against
// its limits and measured from home once for eight poses.

/// One joint's admissibility for every lane (1 or 0) as admissible() decides it for a wrapped
/// angle q: inside [lower, upper], or a representative in [lower, lower + 2 pi) that does not
/// pass upper (with tolerance). admissible()'s loops become a fixed number of conditional turns
/// (IkModel::turns_up, turns_down, enough for any wrapped angle): each is the loop's addition
/// where a lane still needs it and leaves the other lanes unchanged.
template <class L>
[[gnu::always_inline]] inline L admissible_lanes(const L& q, const IkModel& m, std::size_t i) {
  constexpr double tol = kHaptic6RAngleTolerance;
  const L zero = L::splat(0.0), one = L::splat(1.0);
  if (m.full_turn[i]) return where_equal(q, q, one, zero);  // q in [-pi, pi] is inside unless NaN
  const L lower = L::splat(m.lower[i]), upper = L::splat(m.upper[i]);
  // Written with < , > and == only: GCC 12 compiles a lane-wise <= or >= of doubles as one scalar
  // comparison per lane. A NaN is not inside (the last test), as in admissible().
  const L inside = where_less(q, lower, zero, where_greater(q, upper, zero, where_equal(q, q, one, zero)));
  if (!any_zero(inside)) return inside;  // the common case
  const L low = L::splat(m.lower[i] - tol), high = L::splat(m.lower[i] + 2.0 * kPi - tol);
  L v = q;
  for (int t = 0; t < m.turns_up[i]; ++t) v = where_less(v, low, v + 2.0 * kPi, v);
  for (int t = 0; t < m.turns_down[i]; ++t) v = where_greater(v, high, v - 2.0 * kPi, v);
  v = where_less(v, low, v + 2.0 * kPi, v);
  const L below_upper = where_greater(v, L::splat(m.upper[i] + tol), zero, where_equal(v, v, one, zero));
  return where_equal(inside, one, one, below_upper);
}

/// One joint's wrapped angle q = wrap(theta - offset), its admissibility and its wrapped
/// difference to home, for every lane.
template <class L>
struct JointLanes {
  L q, admissible, from_home;
};

template <class L>
[[gnu::always_inline]] inline void joint_lanes(const L& theta, const IkModel& m, std::size_t i, JointLanes<L>& out) {
  out.q = joint_angle(theta, m, i);
  out.admissible = admissible_lanes(out.q, m, i);
  out.from_home = from_home(out.q, m, i);
}

/// The joints the eight slots share, each computed once: joints 1 and 2 of planar solution k
/// and elbow b2 (the slots with hs ^ b4 = k), joint 4 of branch b4, joints 5 and 6 of h sign hs
/// and branch b4; theta1 and theta2 unwrapped (theta3 is each slot's own); valid[k] is 1 where
/// planar solution k's slots are solutions.
template <class L>
struct SharedJoints {
  JointLanes<L> j1[2][2], j2[2][2], j4[2], j5[2][2], j6[2][2];
  L theta1[2][2], theta2[2][2], valid[2];
};

template <class L>
[[gnu::always_inline]] inline void shared_joints(const Branches<L>& b, const IkModel& m, const L& solvable,
                                                 SharedJoints<L>& out) {
  constexpr double tol = kHaptic6RAngleTolerance;
  const L zero = L::splat(0.0);
  for (int k = 0; k < 2; ++k) {
    const PlanarSolution<L>& p = b.planar[k];
    out.valid[k] = solvable * b.g.ok * p.valid;
    for (int b2 = 0; b2 < 2; ++b2) {  // assemble()'s angles of joints 1 and 2
      out.theta2[k][b2] = b2 == 0 ? p.theta2 : -p.theta2;
      out.theta1[k][b2] = b2 == 0 ? p.phi - p.beta : p.phi + p.beta;
      joint_lanes(out.theta1[k][b2], m, 0, out.j1[k][b2]);
      JointLanes<L>& j2 = out.j2[k][b2];
      joint_lanes(out.theta2[k][b2], m, 1, j2);
      if (m.selection == Haptic6RSelection::kElbowLeft) {  // admissible()'s elbow side
        j2.admissible = where_less(j2.q, L::splat(-tol), zero, j2.admissible);
      } else if (m.selection == Haptic6RSelection::kElbowRight) {
        j2.admissible = where_greater(j2.q, L::splat(tol), zero, j2.admissible);
      }
    }
  }
  for (int b4 = 0; b4 < 2; ++b4) joint_lanes(b.theta4_branch[b4], m, 3, out.j4[b4]);
  for (int hs = 0; hs < 2; ++hs) {
    for (int b4 = 0; b4 < 2; ++b4) {  // assemble()'s theta5 and theta6
      const L theta5 = hs == 0 ? b.wrist.theta5[b4] : kPi - b.wrist.theta5[1 - b4];
      const L theta6 = hs == 0 ? b.wrist.theta6[b4] : b.wrist.theta6[1 - b4] + kPi;
      joint_lanes(theta5, m, 4, out.j5[hs][b4]);
      joint_lanes(theta6, m, 5, out.j6[hs][b4]);
    }
  }
}

/// select() for every lane: the slot (as a number, -1 for none) of the admissible valid slot
/// closest to home, the first on ties (a strict < in slot order).
template <class L>
[[gnu::always_inline]] inline L select_lanes(const Branches<L>& b, const IkModel& m, const SharedJoints<L>& j) {
  const L zero = L::splat(0.0), one = L::splat(1.0);
  L best = L::splat(-1.0), best_distance = L::splat(INFINITY);
  for (int slot = 0; slot < 8; ++slot) {
    const int hs = slot >> 2, b4 = (slot >> 1) & 1, b2 = slot & 1, k = hs ^ b4;
    if (!any_nonzero(j.valid[k])) continue;
    const L yaw = hs == 0 ? b.yaw0 : b.yaw0 + kPi;
    JointLanes<L> j3;
    joint_lanes(yaw - j.theta1[k][b2] - j.theta2[k][b2], m, 2, j3);
    const JointLanes<L>* joint[6] = {&j.j1[k][b2], &j.j2[k][b2], &j3, &j.j4[b4], &j.j5[hs][b4], &j.j6[hs][b4]};
    L candidate = j.valid[k], distance = zero;
    for (int i = 0; i < 6; ++i) {
      candidate = candidate * joint[i]->admissible;
      distance += joint[i]->from_home * joint[i]->from_home;
    }
    const L take = where_less(distance, best_distance, candidate, zero);
    best_distance = where_equal(take, one, distance, best_distance);
    best = where_equal(take, one, L::splat(slot), best);
  }
  return best;
}

/// slot_trig() for every lane's slot `slot` (0..7; a lane without a slot gets slot 0's values):
/// the same expressions on the inputs the slot's bits pick.
template <class L>
[[gnu::always_inline]] inline void slot_trig_lanes(const Branches<L>& b, const L& slot, L (&c)[6],
                                                   L (&s)[6]) {
  const L zero = L::splat(0.0), one = L::splat(1.0);
  const L hs = where_greater(slot, L::splat(3.5), one, zero);
  const L b4 = where_greater(slot - 4.0 * hs, L::splat(1.5), one, zero);
  const L b2 = slot - 4.0 * hs - 2.0 * b4;
  const L k = where_equal(hs, b4, zero, one);  // hs ^ b4
  const PlanarSolution<L>&p0 = b.planar[0], &p1 = b.planar[1];
  const L cos_phi = pick(k, p1.cos_phi, p0.cos_phi), sin_phi = pick(k, p1.sin_phi, p0.sin_phi);
  const L cos_beta = pick(k, p1.cos_beta, p0.cos_beta), sin_beta = pick(k, p1.sin_beta, p0.sin_beta);
  const L c2 = pick(k, p1.c2, p0.c2), s2 = pick(k, p1.s2, p0.s2);
  const L sb = pick(b2, sin_beta, -sin_beta);
  c[0] = cos_phi * cos_beta - sin_phi * sb;
  s[0] = sin_phi * cos_beta + cos_phi * sb;
  c[1] = c2;
  s[1] = pick(b2, -s2, s2);
  const L c12 = c[0] * c[1] - s[0] * s[1], s12 = s[0] * c[1] + c[0] * s[1];
  const L sign = pick(hs, L::splat(-1.0), one);
  const L cy = -sign * b.g.hy, sy = sign * b.g.hx;
  c[2] = cy * c12 + sy * s12;
  s[2] = sy * c12 - cy * s12;
  c[3] = pick(b4, -b.g.c4_abs, b.g.c4_abs);
  s[3] = b.g.s4;
  // hs = 0 takes branch b4's wrist angles, hs = 1 the other branch's (pi - theta5, theta6 + pi).
  const WristAngles<L>& w = b.wrist;
  const L cos5_same = pick(b4, w.cos5[1], w.cos5[0]), cos5_other = pick(b4, w.cos5[0], w.cos5[1]);
  const L sin5_same = pick(b4, w.sin5[1], w.sin5[0]), sin5_other = pick(b4, w.sin5[0], w.sin5[1]);
  const L cos6_same = pick(b4, w.cos6[1], w.cos6[0]), cos6_other = pick(b4, w.cos6[0], w.cos6[1]);
  const L sin6_same = pick(b4, w.sin6[1], w.sin6[0]), sin6_other = pick(b4, w.sin6[0], w.sin6[1]);
  c[4] = pick(hs, -cos5_other, cos5_same);
  s[4] = pick(hs, sin5_other, sin5_same);
  c[5] = pick(hs, -cos6_other, cos6_same);
  s[5] = pick(hs, -sin6_other, sin6_same);
}

/// What the block kernel needs of each lane's outcome: the status, and the chosen
/// configuration's DH-angle cosines c and sines s where it is reachable (1 and 0 elsewhere).
template <class L>
struct LaneOutcomes {
  alignas(64) std::int32_t status[kBlockLanes];  // SampleStatus values
  L reachable;  // 1 where the status is kReachable, else 0
  L c[6], s[6];
};

/// configure_branches() for every lane of a block at once: the same statuses and, for reachable
/// lanes, the same cosines and sines (the same expressions in the same order). `solvable` is 1
/// for lanes whose pose solve() takes to the IK (finite position, quaternion of norm > 1e-9),
/// 0 for lanes it settles as unreachable before.
template <class L>
[[gnu::always_inline]] inline void configure_lanes(const Branches<L>& b, const IkModel& m, const L& solvable,
                                                   LaneOutcomes<L>& out) {
  const L zero = L::splat(0.0), one = L::splat(1.0);
  SharedJoints<L> joints;
  shared_joints(b, m, solvable, joints);
  const L best = select_lanes(b, m, joints);
  slot_trig_lanes(b, best, out.c, out.s);
  // The classification, and the zero configuration (1, 0) for lanes that are not reachable.
  const L below = L::splat(m.singularity_tolerance);
  const L wrist_norm = root(b.target.r[0][2] * b.target.r[0][2] + b.target.r[1][2] * b.target.r[1][2]);
  const L singular = where_less(abs(out.s[1]), below, one,
                                    where_less(abs(out.c[3]), below, one, where_less(wrist_norm, below, one, zero)));
  const L found = where_equal(joints.valid[0] + joints.valid[1], zero, zero, one);
  const L chosen = where_less(best, zero, zero, one);
  const L reachable = chosen * (one - singular);
  out.reachable = reachable;
  for (int i = 0; i < 6; ++i) {
    out.c[i] = pick(reachable, out.c[i], one);
    out.s[i] = pick(reachable, out.s[i], zero);
  }
  // The status codes as lane selections, converted to integers at once (reading the truth values
  // lane by lane cost a store and a reload per lane).
  const L code = where_equal(
      found, zero, L::splat(static_cast<double>(SampleStatus::kUnreachable)),
      where_equal(chosen, zero, L::splat(static_cast<double>(SampleStatus::kInvalid)),
                  where_equal(singular, zero, L::splat(static_cast<double>(SampleStatus::kReachable)),
                              L::splat(static_cast<double>(SampleStatus::kSingular)))));
  to_int32(code, out.status);
}

/// IK, selection and classification of a pose whose position is finite and whose quaternion has
/// a finite norm > 1e-9 (`norm`, from quaternion_norm(); the caller settles other poses).
[[gnu::always_inline]] inline void configure(const double (&pose)[7], double norm, const IkModel& m, PoseOutcome& out) {
  Target<double> target;
  target_of(pose, norm, target);
  Branches<double> b;
  branch_angles(target, m, b);
  configure_branches(b, m, out);
}

}  // namespace hapsyn::plugins::haptic6r_ik
