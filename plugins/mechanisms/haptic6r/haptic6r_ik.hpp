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
/// Every function is [[gnu::always_inline]]: it is compiled inside each multiversioned caller
/// (hapsyn/multiversion.hpp). The model's translation units are compiled with -fno-math-errno
/// so that a lane square root is one instruction (no result changes: only errno is dropped).
#include "haptic6r.hpp"

#include <hapsyn/fast_math.hpp>
#include <hapsyn/lanes.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <type_traits>

namespace hapsyn::plugins::haptic6r_ik {

constexpr double kPi = 3.14159265358979323846;
// acos/asin arguments this far past +-1 are rounding at the reach boundary, not a miss.
constexpr double kBoundaryTolerance = 1e-12;

// ---- The scalar counterparts of the Lanes operations (hapsyn/lanes.hpp), so that one template
// serves both. Truth values are numbers holding 1 or 0, as in the lane kernels.

[[gnu::always_inline]] inline double where_less(double x, double y, double a, double b) { return x < y ? a : b; }
[[gnu::always_inline]] inline double where_greater(double x, double y, double a, double b) { return x > y ? a : b; }
[[gnu::always_inline]] inline double where_equal(double x, double y, double a, double b) { return x == y ? a : b; }
[[gnu::always_inline]] inline double where_sign_bit(double x, double a, double b) { return std::signbit(x) ? a : b; }
[[gnu::always_inline]] inline double magnitude(double a) { return std::fabs(a); }
[[gnu::always_inline]] inline Lanes magnitude(const Lanes& a) { return abs(a); }
[[gnu::always_inline]] inline double root(double a) { return std::sqrt(a); }
[[gnu::always_inline]] inline Lanes root(const Lanes& a) { return hapsyn::sqrt(a); }
[[gnu::always_inline]] inline double angle_of(double y, double x) { return fast::atan2(y, x); }
[[gnu::always_inline]] inline Lanes angle_of(const Lanes& y, const Lanes& x) { return hapsyn::atan2(y, x); }
[[gnu::always_inline]] inline double round_down(double a) { return std::floor(a); }
[[gnu::always_inline]] inline Lanes round_down(const Lanes& a) { return floor_small(a); }  // |a| < 2^51 here
/// Whether any lane holds a non-zero truth value.
[[gnu::always_inline]] inline bool any(double truth) { return truth != 0.0; }
[[gnu::always_inline]] inline bool any(const Lanes& truth) {
  bool r = false;
  for (int i = 0; i < kBlockLanes; ++i) r |= truth.v[i] != 0.0;
  return r;
}
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

/// Into [-pi, pi). IK angles are sums of a few atan2 values (|angle| < 6 pi): the common case is
/// the angle itself, which one pose returns at once (the same value the selection picks).
template <typename T>
[[gnu::always_inline]] inline T wrap(const T& angle) {
  if constexpr (std::is_same_v<T, double>) {
    if (angle >= -kPi && angle < kPi) return angle;
  }
  T r = angle - 2.0 * kPi * round_down((angle + kPi) / (2.0 * kPi));
  r = where_less(r, splat<T>(kPi), r, r - 2.0 * kPi);
  r = where_less(r, splat<T>(-kPi), r + 2.0 * kPi, r);
  return where_less(angle, splat<T>(-kPi), r, where_less(angle, splat<T>(kPi), angle, r));
}

/// The design's numbers the IK and the selection read (from Haptic6RModel and its setup).
struct IkModel {
  double L1 = 0.0, L2 = 0.0, L3 = 0.0, L4 = 0.0, L5 = 0.0;  // a1, a2, -d3, a4, d6 [m]
  std::array<double, 6> ca{}, sa{}, offset{};               // cos, sin alpha_i; theta_offset_i [rad]
  std::array<double, 6> lower{}, upper{}, home{};            // joint limits and home [rad]
  Haptic6RSelection selection = Haptic6RSelection::kClosestToHome;
  double singularity_tolerance = 0.0;
};

/// A target frame: position p [m] and rotation r (r[row][col], columns x_E, y_E, z_E).
template <typename T>
struct Target {
  T p[3], r[3][3];
};

/// The eight branches in the order (h sign, theta4 branch, elbow), slot 4 hs + 2 b4 + b2: q
/// [rad] wrapped into [-pi, pi), the DH-angle cosines c and sines s, valid 1 where the branch
/// is a solution. Compacting the valid slots in order gives inverse_kinematics()'s list.
template <typename T>
struct Slots {
  T q[8][6], c[8][6], s[8][6], valid[8];
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
  const T n_safe = pick(rotation_ok, n, one);
  g.hx = pick(vertical, hx_x, hx_roll) / n_safe;
  g.hy = pick(vertical, hy_x, hy_roll) / n_safe;
  const T s4 = (g.w[2] + m.L3) / m.L4;
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
    const T c2_raw = (ox * ox + oy * oy - L1 * L1 - L2 * L2) / (2.0 * L1 * L2);
    PlanarSolution<T>& p = planar[k];
    p.valid = where_greater(magnitude(c2_raw), splat<T>(1.0 + kBoundaryTolerance), zero, one);
    p.c2 = clamp_to(c2_raw, splat<T>(-1.0), one);
    p.s2 = root(at_least_zero(1.0 - p.c2 * p.c2));
    p.theta2 = angle_of(p.s2, p.c2);
    p.phi = angle_of(oy, ox);
    const T bx = L1 + L2 * p.c2, by = L2 * p.s2;
    p.beta = angle_of(by, bx);
    // Lengths of order 1 m: sqrt(x^2 + y^2) cannot overflow, and is several times cheaper than hypot.
    const T ro = root(ox * ox + oy * oy), rb = root(bx * bx + by * by);
    const T ro_safe = where_greater(ro, zero, ro, one), rb_safe = where_greater(rb, zero, rb, one);
    p.cos_phi = where_greater(ro, zero, ox / ro_safe, one);
    p.sin_phi = where_greater(ro, zero, oy / ro_safe, zero);
    p.cos_beta = where_greater(rb, zero, bx / rb_safe, one);
    p.sin_beta = where_greater(rb, zero, by / rb_safe, zero);
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
[[gnu::always_inline]] inline void solve_wrist(const Target<T>& target, const WristGeometry<T>& g, const IkModel& m,
                                               WristAngles<T>& wrist) {
  const T zero = splat<T>(0.0), one = splat<T>(1.0);
  T r3[3][3];
  dh_rotation(-g.hy, g.hx, m.ca[2], m.sa[2], r3);
  for (int b4 = 0; b4 < 2; ++b4) {
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
    const T n5_safe = where_greater(n5, zero, n5, one);
    wrist.cos5[b4] = where_greater(n5, zero, -a4[1] / n5_safe, one);
    wrist.sin5[b4] = where_greater(n5, zero, a4[0] / n5_safe, zero);
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
    const T n6_safe = where_greater(n6, zero, n6, one);
    wrist.cos6[b4] = where_greater(n6, zero, along_x / n6_safe, one);
    wrist.sin6[b4] = where_greater(n6, zero, along_y / n6_safe, zero);
  }
}

// Step 4: every branch's q = DH angles - theta offsets wrapped into [-pi, pi), its DH-angle
// cosines and sines (angle-sum identities on the vectors they came from) and its validity.
template <typename T>
[[gnu::always_inline]] inline void assemble(const WristGeometry<T>& g, const PlanarSolution<T> (&planar)[2],
                                            const WristAngles<T>& wrist, const IkModel& m, Slots<T>& out) {
  const T yaw0 = angle_of(g.hx, -g.hy);
  const T theta4_branch[2] = {angle_of(g.s4, g.c4_abs), angle_of(g.s4, -g.c4_abs)};
  for (int hs = 0; hs < 2; ++hs) {
    const T yaw = hs == 0 ? yaw0 : yaw0 + kPi;
    for (int b4 = 0; b4 < 2; ++b4) {
      const PlanarSolution<T>& p = planar[hs ^ b4];
      const T theta5 = hs == 0 ? wrist.theta5[b4] : kPi - wrist.theta5[1 - b4];
      const T theta6 = hs == 0 ? wrist.theta6[b4] : wrist.theta6[1 - b4] + kPi;
      for (int b2 = 0; b2 < 2; ++b2) {
        const int slot = 4 * hs + 2 * b4 + b2;
        out.valid[slot] = g.ok * p.valid;
        const T theta2 = b2 == 0 ? p.theta2 : -p.theta2;
        const T theta1 = b2 == 0 ? p.phi - p.beta : p.phi + p.beta;
        const T theta3 = yaw - theta1 - theta2;
        const T theta[6] = {theta1, theta2, theta3, theta4_branch[b4], theta5, theta6};
        for (int i = 0; i < 6; ++i) out.q[slot][i] = wrap(theta[i] - m.offset[static_cast<std::size_t>(i)]);
        T* c = out.c[slot];
        T* s = out.s[slot];
        const T sb = b2 == 0 ? -p.sin_beta : p.sin_beta;  // theta1 = phi + (-+beta)
        c[0] = p.cos_phi * p.cos_beta - p.sin_phi * sb;
        s[0] = p.sin_phi * p.cos_beta + p.cos_phi * sb;
        c[1] = p.c2;
        s[1] = b2 == 0 ? p.s2 : -p.s2;
        const T c12 = c[0] * c[1] - s[0] * s[1], s12 = s[0] * c[1] + c[0] * s[1];
        const double sign = hs == 0 ? 1.0 : -1.0;
        const T cy = -sign * g.hy, sy = sign * g.hx;  // the yaw: x3 = e_z x h
        c[2] = cy * c12 + sy * s12;  // theta3 = yaw - (theta1 + theta2)
        s[2] = sy * c12 - cy * s12;
        c[3] = b4 == 0 ? g.c4_abs : -g.c4_abs;
        s[3] = g.s4;
        c[4] = hs == 0 ? wrist.cos5[b4] : -wrist.cos5[1 - b4];  // pi - theta5
        s[4] = hs == 0 ? wrist.sin5[b4] : wrist.sin5[1 - b4];
        c[5] = hs == 0 ? wrist.cos6[b4] : -wrist.cos6[1 - b4];  // theta6 + pi
        s[5] = hs == 0 ? wrist.sin6[b4] : -wrist.sin6[1 - b4];
      }
    }
  }
}

/// Every branch of the target's IK (joint limits ignored), into `out`.
template <typename T>
[[gnu::always_inline]] inline void inverse_kinematics(const Target<T>& target, const IkModel& m, Slots<T>& out) {
  WristGeometry<T> g;
  wrist_geometry(target, m, g);
  PlanarSolution<T> planar[2];
  solve_planar(g, m, planar);
  WristAngles<T> wrist;
  solve_wrist(target, g, m, wrist);
  assemble(g, planar, wrist, m, out);
}

// ---- The selection: among the valid branches inside the joint limits (and on the selected
// elbow side), the one closest to home; the first one on ties.

// Adds or subtracts 2 pi while `v` is below `bound` (above it when `above`), as the per-pose
// while loop does: a lane stops when its own condition fails, so each lane gets exactly the
// scalar's sequence of additions. `v` must be finite in every lane (an infinite one never stops).
template <typename T>
[[gnu::always_inline]] inline void shift_by_turns(T& v, double bound, bool above) {
  const T b = splat<T>(bound), zero = splat<T>(0.0), one = splat<T>(1.0);
  for (;;) {
    const T beyond = above ? where_greater(v, b, one, zero) : where_less(v, b, one, zero);
    if (!any(beyond)) return;
    v = pick(beyond, above ? v - 2.0 * kPi : v + 2.0 * kPi, v);
  }
}

/// 1 where q (finite) has a representative in [lower, upper] in every joint (tolerance
/// kHaptic6RAngleTolerance) and lies on the selected elbow side, else 0.
template <typename T>
[[gnu::always_inline]] inline T admissible(const T (&q)[6], const IkModel& m) {
  const T zero = splat<T>(0.0), one = splat<T>(1.0);
  constexpr double tol = kHaptic6RAngleTolerance;
  T inside = one;
  for (std::size_t i = 0; i < 6; ++i) {
    // q_i in [lower, upper] (0 for a NaN, as the comparisons of the per-pose code give).
    const T plain = where_less(q[i], splat<T>(m.lower[i]), zero,
                               where_greater(q[i], splat<T>(m.upper[i]), zero, where_equal(q[i], q[i], one, zero)));
    if constexpr (std::is_same_v<T, double>) {
      if (plain != 0.0) continue;  // the common case
    }
    // The representative of q_i in [lower, lower + 2 pi) must not exceed upper (with tolerance).
    T v = pick(plain, zero, q[i]);  // lanes inside already need no turns
    shift_by_turns(v, m.lower[i] - tol, false);
    shift_by_turns(v, m.lower[i] + 2.0 * kPi - tol, true);
    v = where_less(v, splat<T>(m.lower[i] - tol), v + 2.0 * kPi, v);
    const T below_upper = where_greater(v, splat<T>(m.upper[i] + tol), zero, where_equal(v, v, one, zero));
    inside = inside * pick(plain, one, below_upper);
  }
  if (m.selection == Haptic6RSelection::kElbowLeft) inside = where_less(q[1], splat<T>(-tol), zero, inside);
  if (m.selection == Haptic6RSelection::kElbowRight) inside = where_greater(q[1], splat<T>(tol), zero, inside);
  return inside;
}

/// The slot the selection rule picks, -1 where none is admissible.
template <typename T>
[[gnu::always_inline]] inline T select(const Slots<T>& slots, const IkModel& m) {
  const T zero = splat<T>(0.0);
  T best = splat<T>(-1.0), best_distance = splat<T>(INFINITY);
  for (int k = 0; k < 8; ++k) {
    if (!any(slots.valid[k])) continue;
    T q[6];
    for (int i = 0; i < 6; ++i) q[i] = pick(slots.valid[k], slots.q[k][i], zero);  // invalid lanes: finite
    const T ok = slots.valid[k] * admissible(q, m);
    T distance = zero;
    for (std::size_t i = 0; i < 6; ++i) {
      const T e = wrap(q[i] - m.home[i]);
      distance = distance + e * e;
    }
    const T better = pick(ok, where_less(distance, best_distance, splat<T>(1.0), zero), zero);
    best = pick(better, splat<T>(k), best);
    best_distance = pick(better, distance, best_distance);
  }
  return best;
}

// ---- One pose, end to end.

/// A pose's outcome: status (a SampleStatus value), q as solve() sets it (zero when unreachable,
/// the first solution when invalid, the chosen one brought into the limits otherwise) and, for
/// a reachable or singular pose, the chosen configuration's DH-angle cosines c and sines s.
template <typename T>
struct PoseOutcome {
  T status, q[6], c[6], s[6];
};

/// The target of a pose (x, y, z, qw, qx, qy, qz) with a finite position and a quaternion of
/// norm > 1e-9 (the caller checks): the quaternion normalised, then Eigen's toRotationMatrix().
template <typename T>
[[gnu::always_inline]] inline void target_of(const T (&pose)[7], const T& quaternion_norm, Target<T>& t) {
  for (int i = 0; i < 3; ++i) t.p[i] = pose[i];
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

/// IK, selection and classification of a pose whose position is finite and whose quaternion has
/// a finite norm > 1e-9 (`norm`, from quaternion_norm(); the caller settles other poses).
template <typename T>
[[gnu::always_inline]] inline void configure(const T (&pose)[7], const T& norm, const IkModel& m, PoseOutcome<T>& out) {
  const T zero = splat<T>(0.0), one = splat<T>(1.0);
  Target<T> target;
  target_of(pose, norm, target);
  Slots<T> slots;
  inverse_kinematics(target, m, slots);
  const T chosen = select(slots, m);
  // The first valid slot (the per-pose list's solutions[0]) and the chosen slot's values.
  T first = splat<T>(-1.0);
  for (int k = 7; k >= 0; --k) first = pick(slots.valid[k], splat<T>(k), first);
  const T use = where_less(chosen, zero, first, chosen);
  for (int i = 0; i < 6; ++i) out.q[i] = out.c[i] = out.s[i] = zero;
  for (int k = 0; k < 8; ++k) {
    const T here = where_equal(use, splat<T>(k), one, zero);
    if (!any(here)) continue;
    for (int i = 0; i < 6; ++i) {
      out.q[i] = pick(here, slots.q[k][i], out.q[i]);
      out.c[i] = pick(here, slots.c[k][i], out.c[i]);
      out.s[i] = pick(here, slots.s[k][i], out.s[i]);
    }
  }
  const T is_chosen = where_less(chosen, zero, zero, one);
  // Brings q_i to its representative inside [lower, upper] (select() checked it exists).
  for (std::size_t i = 0; i < 6; ++i) {
    constexpr double tol = kHaptic6RAngleTolerance;
    T v = pick(is_chosen, out.q[i], zero);
    shift_by_turns(v, m.lower[i] - tol, false);
    shift_by_turns(v, m.upper[i] + tol, true);
    out.q[i] = pick(is_chosen, clamp_to(v, splat<T>(m.lower[i]), splat<T>(m.upper[i])), out.q[i]);
  }
  const T tol = splat<T>(m.singularity_tolerance);
  const T wrist = root(target.r[0][2] * target.r[0][2] + target.r[1][2] * target.r[1][2]);
  const T singular = where_less(magnitude(out.s[1]), tol, one,
                                where_less(magnitude(out.c[3]), tol, one, where_less(wrist, tol, one, zero)));
  const T reachable_status = pick(singular, splat<T>(static_cast<double>(SampleStatus::kSingular)),
                                  splat<T>(static_cast<double>(SampleStatus::kReachable)));
  out.status = where_less(first, zero, splat<T>(static_cast<double>(SampleStatus::kUnreachable)),
                          pick(is_chosen, reachable_status, splat<T>(static_cast<double>(SampleStatus::kInvalid))));
  // Unreachable: q zero (and no trig); invalid: the first solution's q (and no trig).
  const T has_trig = pick(is_chosen, one, zero);
  for (int i = 0; i < 6; ++i) {
    out.q[i] = where_less(first, zero, zero, out.q[i]);
    out.c[i] = pick(has_trig, out.c[i], zero);
    out.s[i] = pick(has_trig, out.s[i], zero);
  }
}

}  // namespace hapsyn::plugins::haptic6r_ik
