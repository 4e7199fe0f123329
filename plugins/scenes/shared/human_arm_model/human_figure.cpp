#include "shared/human_arm_model/human_figure.hpp"

#include <cmath>

namespace hapsyn::plugins {
namespace {

// Fractions of body height H (Drillis and Contini; Winter, fig. 4.1).
constexpr double kUpperArm = 0.186;       // shoulder to elbow
constexpr double kShoulderWidth = 0.259;  // between the shoulder joints
constexpr double kHipWidth = 0.191;       // between the hip joints
constexpr double kShoulderToHip = 0.288;  // shoulder height 0.818 H, hip height 0.530 H
constexpr double kNeck = 0.052;           // shoulder height to chin (0.870 H)
constexpr double kHeadRadius = 0.065;     // half the chin-to-crown height (0.130 H)

}  // namespace

ArmPoints arm_points(const HumanArm& arm, const Vector7d& q) {
  const std::array<Eigen::Vector3d, 8> o = arm.frame_origins(q);
  return {o[0], o[3], o[5], o[7]};
}

HumanBodyProxy body_proxy(const HumanArm& arm) {
  HumanBodyProxy body;
  body.height = std::abs(arm.data().dh[2].d) / kUpperArm;
  const double H = body.height;
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  // The medial direction points from this shoulder to the other one.
  const Eigen::Vector3d medial = (arm.data().side == "left" ? 1.0 : -1.0) * Eigen::Vector3d::UnitX();
  const Eigen::Vector3d shoulder = Eigen::Vector3d::Zero();
  const Eigen::Vector3d other = shoulder + kShoulderWidth * H * medial;
  const Eigen::Vector3d middle = 0.5 * (shoulder + other);
  const Eigen::Vector3d pelvis = middle - kShoulderToHip * H * up;
  const Eigen::Vector3d hip_offset = 0.5 * kHipWidth * H * medial;
  body.lines.push_back({shoulder, other});
  body.lines.push_back({shoulder, pelvis - hip_offset, pelvis + hip_offset, other});
  const Eigen::Vector3d chin = middle + kNeck * H * up;
  body.lines.push_back({middle, chin});
  body.head_radius = kHeadRadius * H;
  body.head_centre = chin + body.head_radius * up;
  return body;
}

}  // namespace hapsyn::plugins
