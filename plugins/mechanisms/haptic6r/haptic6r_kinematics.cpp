// Haptic6RModel per sample: the closed-form inverse kinematics, the selection of one solution
// and the classification (the templates of haptic6r_ik.hpp at T = double, which the block
// kernel runs at T = Lanes), and solve() (IK, then the forward-chain kernels of
// haptic6r_chain.hpp).
//
// solve_sample() and inverse_kinematics_impl() are multiversioned (hapsyn/accel/multiversion.hpp),
// each defined before its first call and next to its plain wrapper. The templates they call are
// [[gnu::always_inline]], so every clone runs its own instruction set throughout.
#include "haptic6r.hpp"
#include "haptic6r_chain.hpp"
#include "haptic6r_ik.hpp"

#include <hapsyn/accel/multiversion.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace hapsyn::plugins {

void Haptic6RModel::ik_model(haptic6r_ik::IkModel& m) const {
  m.L1 = a_[0];
  m.L2 = a_[1];
  m.L3 = -d_[2];
  m.L4 = a_[3];
  m.L5 = d_[5];
  m.inverse_L4 = 1.0 / m.L4;
  m.inverse_2L1L2 = 1.0 / (2.0 * m.L1 * m.L2);
  m.ca = ca_;
  m.sa = sa_;
  m.offset = offset_;
  const Haptic6RSetup& o = *setup_;
  for (std::size_t i = 0; i < 6; ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    m.lower[i] = o.joint_lower(k);
    m.upper[i] = o.joint_upper(k);
    m.home[i] = o.home(k);
    // The first loop lifts an angle >= -pi by 2 pi until it reaches lower - tol, the second
    // lowers one <= pi until it is at most lower + 2 pi - tol; one turn more for the rounding
    // of the repeated additions.
    const double up = std::ceil((m.lower[i] + haptic6r_ik::kPi) / (2.0 * haptic6r_ik::kPi)),
                 down = std::ceil((haptic6r_ik::kPi - m.lower[i]) / (2.0 * haptic6r_ik::kPi)) - 1.0;
    m.turns_up[i] = static_cast<int>(std::max(0.0, up)) + 1;
    m.turns_down[i] = static_cast<int>(std::max(0.0, down)) + 1;
    m.full_turn[i] = m.lower[i] <= -haptic6r_ik::kPi && m.upper[i] >= haptic6r_ik::kPi;
    m.near_offset[i] = std::abs(m.offset[i]) <= 0.75 * haptic6r_ik::kPi;
    m.near_home[i] = std::abs(m.home[i]) <= haptic6r_ik::kPi;
  }
  m.selection = o.selection;
  m.singularity_tolerance = o.options.singularity_tolerance;
}

HAPSYN_MULTIVERSION
int Haptic6RModel::inverse_kinematics_impl(const Eigen::Isometry3d& target, std::array<Vector6d, 8>& solutions,
                                           std::array<JointTrig, 8>* trig) const {
  const haptic6r_ik::IkModel& m = ik_;
  haptic6r_ik::Target<double> t;
  for (int r = 0; r < 3; ++r) {
    t.p[r] = target.translation()(r);
    for (int c = 0; c < 3; ++c) t.r[r][c] = target.linear()(r, c);
  }
  haptic6r_ik::Slots slots;
  haptic6r_ik::inverse_kinematics(t, m, slots);
  int count = 0;
  for (int k = 0; k < 8; ++k) {
    if (!slots.valid[k]) continue;
    for (int i = 0; i < 6; ++i) {
      solutions[static_cast<std::size_t>(count)](i) = slots.q[k][i];
      if (!trig) continue;
      (*trig)[static_cast<std::size_t>(count)].c[static_cast<std::size_t>(i)] = slots.c[k][i];
      (*trig)[static_cast<std::size_t>(count)].s[static_cast<std::size_t>(i)] = slots.s[k][i];
    }
    ++count;
  }
  return count;
}

int Haptic6RModel::select(const std::array<Vector6d, 8>& solutions, int count) const {
  const haptic6r_ik::IkModel& m = ik_;
  haptic6r_ik::Slots slots;
  for (int k = 0; k < 8; ++k) {
    slots.valid[k] = k < count;
    for (int i = 0; i < 6; ++i) slots.q[k][i] = k < count ? solutions[static_cast<std::size_t>(k)](i) : 0.0;
  }
  return haptic6r_ik::select(slots, m);
}

// The first half of solve(): IK, selection and classification of the pose. Sets q (zero when
// unreachable, the first solution when invalid, the chosen one in the limits otherwise) and,
// for kReachable and kSingular, the chosen configuration's DH-angle cosines and sines.
[[gnu::always_inline]] inline SampleStatus Haptic6RModel::configure(const double* pose, Vector6d& q,
                                                                   JointTrig& chosen_trig) const {
  double p[7];
  for (int i = 0; i < 7; ++i) p[i] = pose[i];
  const double norm = haptic6r_ik::quaternion_norm(p);
  if (!(norm > 1e-9) || !std::isfinite(norm) || !std::isfinite(p[0] + p[1] + p[2])) {
    q.setZero();
    return SampleStatus::kUnreachable;
  }
  const haptic6r_ik::IkModel& m = ik_;
  haptic6r_ik::PoseOutcome o;
  haptic6r_ik::configure(p, norm, m, o);
  for (std::size_t i = 0; i < 6; ++i) {
    q(static_cast<Eigen::Index>(i)) = o.q[i];
    chosen_trig.c[i] = o.c[i];
    chosen_trig.s[i] = o.s[i];
  }
  return o.status;
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
    haptic6r_chain::chain_from(trig, d_, a_, f);
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
