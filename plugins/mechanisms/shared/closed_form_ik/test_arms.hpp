#pragma once
// Test and benchmark helper (not part of the library): the arms the closed_form_ik tests and
// benchmark use, as local joint frames (PoeChain::from_local_frames) built from standard DH rows
// (T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i); joint i turns about z of frame i-1).
#include "shared/closed_form_ik/poe_chain.hpp"

#include <cmath>
#include <vector>

namespace hapsyn::plugins::closed_form_ik::test_arms {

struct LocalFrames {
  std::vector<Eigen::Isometry3d> origins;
  std::vector<Eigen::Vector3d> axes;
  Eigen::Isometry3d tip = Eigen::Isometry3d::Identity();
  PoeChain poe() const { return PoeChain::from_local_frames(origins, axes, tip); }
};

inline Eigen::Isometry3d dh_link(double d, double a, double alpha) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translate(Eigen::Vector3d(0, 0, d));
  t.translate(Eigen::Vector3d(a, 0, 0));
  t.rotate(Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitX()));
  return t;
}

// Standard DH rows (d, a, alpha) of a 6R into local frames: joint 1 at the base origin.
inline LocalFrames from_dh(const std::vector<std::array<double, 3>>& rows) {
  LocalFrames f;
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
  for (const auto& r : rows) {
    f.origins.push_back(origin);
    f.axes.push_back(Eigen::Vector3d::UnitZ());
    origin = dh_link(r[0], r[1], r[2]);
  }
  f.tip = origin;
  return f;
}

/// UR5 (Universal Robots' published DH): axes 2, 3, 4 parallel.
inline LocalFrames ur5() {
  return from_dh({{{0.089159, 0.0, M_PI / 2}}, {{0.0, -0.425, 0.0}}, {{0.0, -0.39225, 0.0}},
                  {{0.10915, 0.0, M_PI / 2}}, {{0.09465, 0.0, -M_PI / 2}}, {{0.0823, 0.0, 0.0}}});
}

/// Puma 560 (Corke's standard DH) with a 0.1 m tool: spherical wrist.
inline LocalFrames puma() {
  return from_dh({{{0.0, 0.0, M_PI / 2}}, {{0.0, 0.4318, 0.0}}, {{0.15005, 0.0203, -M_PI / 2}},
                  {{0.4318, 0.0, M_PI / 2}}, {{0.0, 0.0, -M_PI / 2}}, {{0.1, 0.0, 0.0}}});
}

/// A general offset-wrist 6R: no parallel axes, only axes 5 and 6 meet (a5 = 0), all twists and
/// offsets irregular: the 1-D search family.
inline LocalFrames offset_wrist() {
  return from_dh({{{0.32, 0.05, 1.4}}, {{0.11, 0.41, 0.25}}, {{-0.06, 0.03, -1.2}},
                  {{0.37, 0.07, 1.0}}, {{0.09, 0.0, -1.3}}, {{0.08, 0.02, 0.3}}});
}

inline Eigen::Isometry3d xyz_rpy(double x, double y, double z, double roll, double pitch, double yaw) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translate(Eigen::Vector3d(x, y, z));
  t.rotate(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
           Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
  return t;
}

/// The haptic 6R of share/serial_chain/haptic6r.urdf (its joint origins and tool, numbers copied):
/// axes 1, 2, 3 parallel (SCARA), 4 || 5, 5 x 6.
inline LocalFrames haptic6r() {
  LocalFrames f;
  f.origins = {xyz_rpy(0, 0, 0, 0, 0, 0), xyz_rpy(0.45, 0, 0, 0, 0, 0), xyz_rpy(0.45, 0, 0, 0, 0, 0),
               xyz_rpy(0, 0, -0.65, 0, M_PI / 2, -M_PI / 2), xyz_rpy(0.55, 0, 0, 0, 0, 0),
               xyz_rpy(0, 0, 0, M_PI / 2, 0, 0)};
  f.axes.assign(6, Eigen::Vector3d::UnitZ());
  f.tip = xyz_rpy(0, 0, 0.15, 0, 0, 0);
  return f;
}

}  // namespace hapsyn::plugins::closed_form_ik::test_arms
