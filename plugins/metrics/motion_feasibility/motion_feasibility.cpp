#include "motion_feasibility.hpp"

#include <cmath>

namespace hapsyn::plugins {

MotionFeasibility::MotionFeasibility(const MotionFeasibilityOptions& options) {
  const std::string& share = options.share;
  all_ = share == "all";
  velocity_ = all_ || share == "velocity";
  acceleration_ = all_ || share == "acceleration";
  // The value is the last local: reachable, the one share, or feasible for "all".
  value_local_ = static_cast<int>(locals().size()) - 1;
}

bool MotionFeasibility::velocity_within_limits(const SampleQuantities& q) {
  for (Eigen::Index i = 0; i < q.joint_velocity.size(); ++i) {
    if (!(std::abs(q.joint_velocity(i)) <= q.max_velocity(i))) return false;
  }
  return true;
}

bool MotionFeasibility::torque_within_limits(const SampleQuantities& q) {
  const Eigen::Index n = q.joint_acceleration.size();
  for (Eigen::Index i = 0; i < n; ++i) {
    // The full inverse dynamics, row by row: no temporary vector in the per-sample loop.
    double tau = q.velocity_torque(i) + q.gravity(i);
    for (Eigen::Index j = 0; j < n; ++j) tau += q.inertia(i, j) * q.joint_acceleration(j);
    if (!(std::abs(tau) <= q.max_torque(i))) return false;
  }
  return true;
}

void MotionFeasibility::local(const SampleQuantities& q, double* out) const {
  const bool reachable = q.status == SampleStatus::kReachable;
  int k = 0;
  out[k++] = reachable ? 1.0 : 0.0;
  const bool velocity = reachable && velocity_ && velocity_within_limits(q);
  const bool acceleration = reachable && acceleration_ && torque_within_limits(q);
  if (velocity_) out[k++] = velocity ? 1.0 : 0.0;
  if (acceleration_) out[k++] = acceleration ? 1.0 : 0.0;
  if (all_) out[k++] = velocity && acceleration ? 1.0 : 0.0;
}

Needs MotionFeasibility::needs() const {
  Needs needs = kNeedPose;
  if (velocity_) needs |= kNeedJointVelocity | kNeedActuatorLimits;
  if (acceleration_) {
    needs |= kNeedJointVelocity | kNeedJointAcceleration | kNeedVelocityTorque | kNeedInertia | kNeedGravity |
             kNeedActuatorLimits;
  }
  return needs;
}

std::vector<LocalValue> MotionFeasibility::locals() const {
  std::vector<LocalValue> locals{{"reachable", Reduction::kSum, ""}};
  if (velocity_) locals.push_back({"velocity_feasible", Reduction::kSum, ""});
  if (acceleration_) locals.push_back({"acceleration_feasible", Reduction::kSum, ""});
  if (all_) locals.push_back({"feasible", Reduction::kSum, ""});
  return locals;
}

double MotionFeasibility::combine(const double* reduced, int samples) const {
  return samples > 0 ? reduced[value_local_] / samples : 0.0;
}

}  // namespace hapsyn::plugins
