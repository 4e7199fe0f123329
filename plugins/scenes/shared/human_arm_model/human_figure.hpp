#pragma once
/// \file
/// What a viewer draws of the human whose arm a scene models: the arm as a polyline through the
/// shoulder, elbow, wrist centre and palm at a configuration, and a rigid proxy of the rest of
/// the body (torso outline and a head sphere) seated at the shoulder. Everything in the shoulder
/// frame S (x_S lateral, y_S up, z_S backwards; see human_arm_model.hpp), lengths in m.
///
/// The proxy is anthropometry, not data: segment lengths as fractions of body height H (Drillis
/// and Contini, 1966, as tabulated by Winter, "Biomechanics and Motor Control of Human Movement",
/// fig. 4.1), with H taken from the arm file's upper arm (0.186 H). It is for looking at, never
/// for computing: no metric reads it.
#include "shared/human_arm_model/human_arm_model.hpp"

#include <Eigen/Core>

#include <array>
#include <vector>

namespace hapsyn::plugins {

/// The arm's polyline: shoulder (the origin of S), elbow, wrist centre, palm, in S.
using ArmPoints = std::array<Eigen::Vector3d, 4>;

/// The arm's points at joint angles q [rad] (the origins of DH frames 0, 3, 5 and 7, which the
/// arm file's checked structure puts at the shoulder, the elbow, the wrist centre and the palm).
ArmPoints arm_points(const HumanArm& arm, const Vector7d& q);

/// The rest of the body, for drawing.
struct HumanBodyProxy {
  double height = 0.0;                              ///< H [m] the proportions are scaled by
  std::vector<std::vector<Eigen::Vector3d>> lines;  ///< polylines: shoulder girdle, torso outline, neck
  Eigen::Vector3d head_centre = Eigen::Vector3d::Zero();
  double head_radius = 0.0;
};

/// The body proxy of the arm's owner, in S: the other shoulder medial of this one (at -x_S for a
/// right arm, +x_S for a left arm: the arm file's "side"), the hips below the shoulders (-y_S),
/// the head above the shoulders' midpoint.
HumanBodyProxy body_proxy(const HumanArm& arm);

}  // namespace hapsyn::plugins
