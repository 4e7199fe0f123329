// Haptic6RModel per sample: the closed-form inverse kinematics, the selection of one solution,
// the classification, and solve() (IK, then the forward-chain kernels of haptic6r_chain.hpp).
//
// solve_sample() and inverse_kinematics_impl() are multiversioned (hapsyn/multiversion.hpp),
// each defined before its first call and next to its plain wrapper. A function they call runs
// the clone's instruction set only where it is inlined into the clone; an out-of-line call runs
// baseline code. So the IK's steps below are [[gnu::always_inline]] (they compile exactly as the
// one IK function did before it was split), the chain kernels too (haptic6r_chain.hpp), and
// select() and atan2_baseline() stay out-of-line calls, as they were: results are bit-identical.
#include "haptic6r.hpp"
#include "haptic6r_chain.hpp"

#include <hapsyn/fast_math.hpp>
#include <hapsyn/multiversion.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace hapsyn::plugins {

namespace {

constexpr double kPi = 3.14159265358979323846;
// acos/asin arguments this far past +-1 are rounding at the reach boundary, not a miss.
constexpr double kBoundaryTolerance = 1e-12;

// Into [-pi, pi). IK angles are sums of a few atan2 values (|angle| < 6 pi), so the common
// case is one comparison; floor() instead of fmod() keeps the per-sample loop cheap.
inline double wrap(double angle) {
  if (angle >= -kPi && angle < kPi) return angle;
  double r = angle - 2.0 * kPi * std::floor((angle + kPi) / (2.0 * kPi));
  if (r >= kPi) r -= 2.0 * kPi;
  if (r < -kPi) r += 2.0 * kPi;
  return r;
}

inline double norm2(double x, double y) { return std::sqrt(x * x + y * y); }

// fast::atan2 compiled for baseline CPUs and called out of line, in every clone: the yaw and
// theta4 of the IK come from it. That is what GCC 12 made of these three calls when the model was
// one file (it inlined the other nine atan2 of the IK into the AVX2/FMA clone, not these), and
// keeping it keeps the solutions bit-identical: inlined, the FMA-contracted polynomial moves
// theta3 by one ulp for about one pose in 10^4.
[[gnu::noinline]] double atan2_baseline(double y, double x) { return fast::atan2(y, x); }

// Rotation of one DH row from cos/sin of its angle (no trigonometric call).
inline void dh_rotation(double ct, double st, double ca, double sa, Eigen::Matrix3d& rot) {
  rot << ct, -st * ca, st * sa, st, ct * ca, -ct * sa, 0.0, sa, ca;
}

// ---- The IK in four steps. The eight branches (h sign, theta4 branch, elbow) share most of
// their work: flipping h flips x3 = e_z x h (yaw + pi), and the wrist centre o = w - L4
// cos(theta4) x3 depends only on the product of the two signs, so the planar 2R solve (three
// atan2) is done for two points only; rotations are built from the cosines and sines at hand,
// not from angles.

// Step 1: the wrist point w = p - L5 z_E, the unit axis hz of joints 4 and 5 (for h = +hz) and
// theta4's sine and |cosine|.
struct WristGeometry {
  Eigen::Vector3d approach;  // z_E, the roll axis
  Eigen::Vector3d w;
  Eigen::Vector3d hz;
  double s4 = 0.0, c4_abs = 0.0;
};

// \return false when the target has no solution (not a rotation, or w out of l4's reach).
[[gnu::always_inline]] inline bool wrist_geometry(const Eigen::Isometry3d& target, double L3, double L4, double L5,
                                                  WristGeometry& g) {
  const Eigen::Matrix3d& rot = target.linear();
  g.approach = rot.col(2);
  g.w = target.translation() - L5 * g.approach;
  // Axis of joints 4 and 5: horizontal and perpendicular to the roll axis.
  g.hz = Eigen::Vector3d(-g.approach.y(), g.approach.x(), 0.0);
  double n = g.hz.norm();
  if (n < 1e-12) {
    // Wrist axis vertical: h is free (a singular family); take the one normal to x_E so that
    // the solution stays finite and deterministic.
    g.hz = Eigen::Vector3d(-rot(1, 0), rot(0, 0), 0.0);
    n = g.hz.norm();
    if (n < 1e-12) return false;  // not a rotation
  }
  g.hz /= n;
  double s4 = (g.w.z() + L3) / L4;
  if (std::abs(s4) > 1.0 + kBoundaryTolerance) return false;
  s4 = std::clamp(s4, -1.0, 1.0);
  g.s4 = s4;
  g.c4_abs = std::sqrt(std::max(0.0, 1.0 - s4 * s4));
  return true;
}

// Step 2: the planar 2R solve (joints 1, 2) for the wrist centre of sign product k (0: +, 1: -).
struct PlanarSolution {
  bool valid = false;
  double c2 = 0.0, theta2 = 0.0, phi = 0.0, beta = 0.0;  // theta1 = phi -+ beta, theta2 = +-theta2
  double s2 = 0.0, cos_phi = 1.0, sin_phi = 0.0, cos_beta = 1.0, sin_beta = 0.0;
};

// `with_trig`: also the cosines and sines of the angles (for the chosen solution's frames).
[[gnu::always_inline]] inline void solve_planar(const WristGeometry& g, double L1, double L2, double L4, bool with_trig,
                                                std::array<PlanarSolution, 2>& planar) {
  const Eigen::Vector3d& w = g.w;
  const Eigen::Vector3d& hz = g.hz;
  const double c4_abs = g.c4_abs;
  for (int k = 0; k < 2; ++k) {
    const double c4x3 = (k == 0 ? c4_abs : -c4_abs) * L4;  // L4 c4 times the sign of x3
    const double ox = w.x() + c4x3 * hz.y(), oy = w.y() - c4x3 * hz.x();  // x3 = (-h_y, h_x, 0)
    double c2 = (ox * ox + oy * oy - L1 * L1 - L2 * L2) / (2.0 * L1 * L2);
    if (std::abs(c2) > 1.0 + kBoundaryTolerance) continue;
    c2 = std::clamp(c2, -1.0, 1.0);
    const double s2_abs = std::sqrt(std::max(0.0, 1.0 - c2 * c2));
    PlanarSolution& p = planar[static_cast<std::size_t>(k)];
    p.valid = true;
    p.c2 = c2;
    p.theta2 = fast::atan2(s2_abs, c2);
    p.phi = fast::atan2(oy, ox);
    p.beta = fast::atan2(L2 * s2_abs, L1 + L2 * c2);
    if (with_trig) {  // the same angles as cosines and sines, for the chosen solution's frames
      p.s2 = s2_abs;
      // Lengths of order 1 m: sqrt(x^2 + y^2) cannot overflow, and is several times cheaper than hypot.
      const double ro = norm2(ox, oy), rb = norm2(L1 + L2 * c2, L2 * s2_abs);
      if (ro > 0.0) {
        p.cos_phi = ox / ro;
        p.sin_phi = oy / ro;
      }
      if (rb > 0.0) {
        p.cos_beta = (L1 + L2 * c2) / rb;
        p.sin_beta = L2 * s2_abs / rb;
      }
    }
  }
}

// Step 3: the wrist angles theta5, theta6 for h = +hz and each theta4 branch b4. Flipping h and
// the theta4 branch together turns R_04 into R_04 Rx(pi) (x3 -> -x3, cos theta4 -> -cos
// theta4), which maps theta5 -> pi - theta5 and theta6 -> theta6 + pi: the h = -hz branches
// reuse these (two atan2 pairs instead of four).
struct WristAngles {
  double theta5[2] = {0.0, 0.0}, theta6[2] = {0.0, 0.0};
  double cos5[2] = {1.0, 1.0}, sin5[2] = {0.0, 0.0}, cos6[2] = {1.0, 1.0}, sin6[2] = {0.0, 0.0};
};

[[gnu::always_inline]] inline void solve_wrist(const Eigen::Matrix3d& rot, const WristGeometry& g,
                                               const std::array<double, 6>& ca, const std::array<double, 6>& sa,
                                               const std::array<PlanarSolution, 2>& planar, WristAngles& wrist) {
  const Eigen::Vector3d& hz = g.hz;
  const Eigen::Vector3d x_e = rot.col(0);
  Eigen::Matrix3d r3;
  dh_rotation(-hz.y(), hz.x(), ca[2], sa[2], r3);
  for (int b4 = 0; b4 < 2; ++b4) {
    if (!planar[static_cast<std::size_t>(b4)].valid) continue;  // used by (+hz, b4) and (-hz, 1 - b4) only
    Eigen::Matrix3d r4, r5;
    dh_rotation(b4 == 0 ? g.c4_abs : -g.c4_abs, g.s4, ca[3], sa[3], r4);
    const Eigen::Matrix3d r04 = r3 * r4;
    const Eigen::Vector3d a4 = r04.transpose() * g.approach;
    // z_5 in frame 4 is Rz(theta5) (0, -sin alpha5, cos alpha5) = (sin theta5, -cos theta5, 0).
    wrist.theta5[b4] = fast::atan2(a4.x(), -a4.y());
    const double n5 = norm2(a4.x(), a4.y());  // 1 up to rounding: the approach is normal to h
    wrist.cos5[b4] = n5 > 0.0 ? -a4.y() / n5 : 1.0;
    wrist.sin5[b4] = n5 > 0.0 ? a4.x() / n5 : 0.0;
    dh_rotation(wrist.cos5[b4], wrist.sin5[b4], ca[4], sa[4], r5);
    // theta6 from x_E in frame 5: (x_5 . x_E, y_5 . x_E).
    const Eigen::Vector3d x5 = r04 * r5.col(0), y5 = r04 * r5.col(1);
    wrist.theta6[b4] = fast::atan2(y5.dot(x_e), x5.dot(x_e));
    const double n6 = norm2(y5.dot(x_e), x5.dot(x_e));
    if (n6 > 0.0) {
      wrist.cos6[b4] = x5.dot(x_e) / n6;
      wrist.sin6[b4] = y5.dot(x_e) / n6;
    }
  }
}

// Step 4: the solutions of every valid branch, q = DH angles - theta offsets wrapped into
// [-pi, pi), and with `trig` their DH-angle cosines and sines by angle-sum identities on the
// vectors they came from. \return the count.
[[gnu::always_inline]] inline int assemble_solutions(const WristGeometry& g,
                                                     const std::array<PlanarSolution, 2>& planar,
                                                     const WristAngles& wrist, const std::array<double, 6>& offset,
                                                     std::array<Vector6d, 8>& solutions,
                                                     std::array<JointTrig, 8>* trig) {
  const Eigen::Vector3d& hz = g.hz;
  const double c4_abs = g.c4_abs, s4 = g.s4;
  const double yaw0 = atan2_baseline(hz.x(), -hz.y());
  const double theta4_branch[2] = {atan2_baseline(s4, c4_abs), atan2_baseline(s4, -c4_abs)};
  int count = 0;
  for (int hs = 0; hs < 2; ++hs) {
    const double yaw = hs == 0 ? yaw0 : yaw0 + kPi;
    for (int b4 = 0; b4 < 2; ++b4) {
      const PlanarSolution& p = planar[static_cast<std::size_t>(hs ^ b4)];
      if (!p.valid) continue;
      const double theta5 = hs == 0 ? wrist.theta5[b4] : kPi - wrist.theta5[1 - b4];
      const double theta6 = hs == 0 ? wrist.theta6[b4] : wrist.theta6[1 - b4] + kPi;
      for (int b2 = 0; b2 < 2; ++b2) {
        const double theta2 = b2 == 0 ? p.theta2 : -p.theta2;
        const double theta1 = b2 == 0 ? p.phi - p.beta : p.phi + p.beta;
        const double theta3 = yaw - theta1 - theta2;
        Vector6d& q = solutions[static_cast<std::size_t>(count++)];
        q << theta1, theta2, theta3, theta4_branch[b4], theta5, theta6;
        for (int i = 0; i < 6; ++i) q(i) = wrap(q(i) - offset[static_cast<std::size_t>(i)]);
        if (!trig) continue;
        JointTrig& t = (*trig)[static_cast<std::size_t>(count - 1)];
        const double sb = b2 == 0 ? -p.sin_beta : p.sin_beta;  // theta1 = phi + (-+beta)
        t.c[0] = p.cos_phi * p.cos_beta - p.sin_phi * sb;
        t.s[0] = p.sin_phi * p.cos_beta + p.cos_phi * sb;
        t.c[1] = p.c2;
        t.s[1] = b2 == 0 ? p.s2 : -p.s2;
        const double c12 = t.c[0] * t.c[1] - t.s[0] * t.s[1], s12 = t.s[0] * t.c[1] + t.c[0] * t.s[1];
        const double sign = hs == 0 ? 1.0 : -1.0;
        const double cy = -sign * hz.y(), sy = sign * hz.x();  // the yaw: x3 = e_z x h
        t.c[2] = cy * c12 + sy * s12;  // theta3 = yaw - (theta1 + theta2)
        t.s[2] = sy * c12 - cy * s12;
        t.c[3] = b4 == 0 ? c4_abs : -c4_abs;
        t.s[3] = s4;
        t.c[4] = hs == 0 ? wrist.cos5[b4] : -wrist.cos5[1 - b4];  // pi - theta5
        t.s[4] = hs == 0 ? wrist.sin5[b4] : wrist.sin5[1 - b4];
        t.c[5] = hs == 0 ? wrist.cos6[b4] : -wrist.cos6[1 - b4];  // theta6 + pi
        t.s[5] = hs == 0 ? wrist.sin6[b4] : -wrist.sin6[1 - b4];
      }
    }
  }
  return count;
}

}  // namespace

HAPSYN_MULTIVERSION
int Haptic6RModel::inverse_kinematics_impl(const Eigen::Isometry3d& target, std::array<Vector6d, 8>& solutions,
                                           std::array<JointTrig, 8>* trig) const {
  const double L1 = a_[0], L2 = a_[1], L3 = -d_[2], L4 = a_[3], L5 = d_[5];
  WristGeometry g;
  if (!wrist_geometry(target, L3, L4, L5, g)) return 0;
  std::array<PlanarSolution, 2> planar;
  solve_planar(g, L1, L2, L4, trig != nullptr, planar);
  WristAngles wrist;
  solve_wrist(target.linear(), g, ca_, sa_, planar, wrist);
  return assemble_solutions(g, planar, wrist, offset_, solutions, trig);
}

int Haptic6RModel::select(const std::array<Vector6d, 8>& solutions, int count) const {
  const Haptic6RSetup& o = *setup_;
  int best = -1;
  double best_distance = std::numeric_limits<double>::infinity();
  for (int k = 0; k < count; ++k) {
    const Vector6d& q = solutions[static_cast<std::size_t>(k)];
    bool inside = true;
    for (int i = 0; i < 6 && inside; ++i) {
      if (q(i) >= o.joint_lower(i) && q(i) <= o.joint_upper(i)) continue;  // the common case
      // The representative of q_i in [lower, lower + 2 pi) must not exceed upper (with tolerance).
      double v = q(i);
      while (v < o.joint_lower(i) - kHaptic6RAngleTolerance) v += 2.0 * kPi;
      while (v > o.joint_lower(i) + 2.0 * kPi - kHaptic6RAngleTolerance) v -= 2.0 * kPi;
      if (v < o.joint_lower(i) - kHaptic6RAngleTolerance) v += 2.0 * kPi;
      inside = v <= o.joint_upper(i) + kHaptic6RAngleTolerance;
    }
    if (!inside) continue;
    if (o.selection == Haptic6RSelection::kElbowLeft && q(1) < -kHaptic6RAngleTolerance) continue;
    if (o.selection == Haptic6RSelection::kElbowRight && q(1) > kHaptic6RAngleTolerance) continue;
    double distance = 0.0;
    for (int i = 0; i < 6; ++i) {
      const double e = wrap(q(i) - o.home(i));
      distance += e * e;
    }
    if (distance < best_distance) {
      best_distance = distance;
      best = k;
    }
  }
  return best;
}

namespace {
// Brings q_i to the representative inside [lower, upper] (select() checked it exists).
void into_limits(Vector6d& q, const Haptic6RSetup& o) {
  for (int i = 0; i < 6; ++i) {
    double v = q(i);
    while (v < o.joint_lower(i) - kHaptic6RAngleTolerance) v += 2.0 * kPi;
    while (v > o.joint_upper(i) + kHaptic6RAngleTolerance) v -= 2.0 * kPi;
    q(i) = std::clamp(v, o.joint_lower(i), o.joint_upper(i));
  }
}
}  // namespace

// The first half of solve(): IK, selection and classification of the pose. Sets q (zero when
// unreachable, the first solution when invalid, the chosen one in the limits otherwise) and,
// for kReachable and kSingular, the chosen configuration's DH-angle cosines and sines.
[[gnu::always_inline]] inline SampleStatus Haptic6RModel::configure(const double* pose, Vector6d& q,
                                                                   JointTrig& chosen_trig) const {
  Eigen::Quaterniond quat(pose[3], pose[4], pose[5], pose[6]);
  const double qn = quat.norm();
  if (!(qn > 1e-9) || !std::isfinite(qn) || !std::isfinite(pose[0] + pose[1] + pose[2])) {
    q.setZero();
    return SampleStatus::kUnreachable;
  }
  quat.coeffs() /= qn;
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
  target.linear() = quat.toRotationMatrix();
  target.translation() = Eigen::Vector3d(pose[0], pose[1], pose[2]);
  std::array<Vector6d, 8> solutions;
  std::array<JointTrig, 8> trig;
  const int count = inverse_kinematics_impl(target, solutions, &trig);
  if (count == 0) {
    q.setZero();
    return SampleStatus::kUnreachable;
  }
  const int chosen = select(solutions, count);
  if (chosen < 0) {
    q = solutions[0];
    return SampleStatus::kInvalid;
  }
  q = solutions[static_cast<std::size_t>(chosen)];
  into_limits(q, *setup_);
  const double tol = setup_->options.singularity_tolerance;
  const Eigen::Vector3d& approach = target.linear().col(2);
  const double wrist = norm2(approach.x(), approach.y());
  chosen_trig = trig[static_cast<std::size_t>(chosen)];
  const double sin2 = chosen_trig.s[1];
  const double cos4 = chosen_trig.c[3];  // l4 vertical when cos(theta4) = 0
  if (std::abs(sin2) < tol || std::abs(cos4) < tol || wrist < tol) return SampleStatus::kSingular;
  return SampleStatus::kReachable;
}

HAPSYN_MULTIVERSION
SampleStatus Haptic6RModel::configuration_impl(const double* pose, Vector6d& q, JointTrig& trig) const {
  return configure(pose, q, trig);
}

// Other translation units call this plain wrapper (clang exports no plain symbol for the
// multiversioned body).
SampleStatus Haptic6RModel::configuration(const double* pose, Vector6d& q, JointTrig& trig) const {
  return configuration_impl(pose, q, trig);
}

HAPSYN_MULTIVERSION
void Haptic6RModel::solve_sample(const double* pose, Needs needs, SampleQuantities& out) const {
  Vector6d q;
  JointTrig trig;
  out.status = configure(pose, q, trig);
  out.q = q;
  if (out.status != SampleStatus::kReachable) return;
  constexpr Needs kMotion = kNeedJointVelocity | kNeedJointAcceleration | kNeedVelocityTorque;
  if (needs & (kNeedJacobian | kNeedInertia | kNeedGravity | kMotion)) {
    haptic6r_chain::Chain f;
    haptic6r_chain::chain_from(trig, d_, a_, ca_, sa_, f);
    if (needs & kNeedJacobian) {
      out.jacobian.resize(6, 6);
      haptic6r_chain::jacobian_from(f, out.jacobian);
    }
    if (needs & (kNeedInertia | kNeedGravity)) {
      // Straight into the fixed-capacity outputs: no 6x6 temporaries to copy.
      if (needs & kNeedInertia) out.inertia.resize(6, 6);
      if (needs & kNeedGravity) out.gravity.resize(6);
      haptic6r_chain::dynamics_from(f, bodies_, setup_->options.gravity,
                                    (needs & kNeedInertia) ? &out.inertia : nullptr,
                                    (needs & kNeedGravity) ? &out.gravity : nullptr);
    }
    if (needs & kMotion) haptic6r_chain::joint_motion(f, bodies_, needs, out);
  }
  if (needs & kNeedActuatorLimits) {
    out.max_velocity = max_velocity_;
    out.max_torque = max_torque_;
  }
}

// The public entry points call the multiversioned bodies (defined above: clang refuses to
// multiversion a function already called, and other translation units must see plain symbols).
int Haptic6RModel::inverse_kinematics(const Eigen::Isometry3d& target, std::array<Vector6d, 8>& solutions,
                                      std::array<JointTrig, 8>* trig) const {
  return inverse_kinematics_impl(target, solutions, trig);
}

void Haptic6RModel::solve(const double* pose, Needs needs, MechanismScratch&, SampleQuantities& out) const {
  solve_sample(pose, needs, out);
}

}  // namespace hapsyn::plugins
