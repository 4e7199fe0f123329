#pragma once
/// \file
/// Hand-built Chains for the IK tests and benchmark (no URDF / DH reader): planar 2R and 3R, a
/// Phantom-like 3R, a UR5-like 6R, the Fennel haptic 6R and a KUKA-iiwa-like 7R, each with its
/// natural IK task and a home posture. Test support only: allocates freely.
#include "chain_ik.hpp"

#include <cmath>
#include <string>
#include <vector>

namespace hapsyn::plugins::test_chains {

inline double deg(double x) { return x * 3.14159265358979323846 / 180.0; }

inline Eigen::Isometry3d translation(double x, double y, double z) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(x, y, z);
  return t;
}

inline Eigen::Isometry3d rotation(double angle, const Eigen::Vector3d& axis) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
  return t;
}

/// One standard DH row: theta = q + theta_offset [rad], d [m], a [m], alpha [rad].
struct DhRow {
  double theta_offset, d, a, alpha;
  double lower = -INFINITY, upper = INFINITY;
};

/// Tz(d) Tx(a) Rx(alpha): the part of a standard DH row after the joint's Rz(theta).
inline Eigen::Isometry3d dh_after_joint(const DhRow& r) {
  return translation(0, 0, r.d) * translation(r.a, 0, 0) * rotation(r.alpha, Eigen::Vector3d::UnitX());
}

/// A revolute chain from standard DH rows: O_i = (row i-1 after its joint) Rz(theta_offset_i),
/// axis z, T_tip = the last row after its joint.
inline Chain dh_chain(const std::vector<DhRow>& rows) {
  Chain c;
  Eigen::Isometry3d previous = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    ChainJoint j;
    j.name = "joint" + std::to_string(i + 1);
    j.origin = previous * rotation(rows[i].theta_offset, Eigen::Vector3d::UnitZ());
    j.lower = rows[i].lower;
    j.upper = rows[i].upper;
    c.joints.push_back(j);
    c.bodies.emplace_back();
    previous = dh_after_joint(rows[i]);
  }
  c.tip = previous;
  return c;
}

/// A revolute joint about `axis` at `origin`.
inline ChainJoint revolute(const Eigen::Isometry3d& origin, const Eigen::Vector3d& axis, double lower = -INFINITY,
                           double upper = INFINITY) {
  ChainJoint j;
  j.origin = origin;
  j.axis = axis;
  j.lower = lower;
  j.upper = upper;
  return j;
}

inline Chain make_chain(std::vector<ChainJoint> joints, const Eigen::Isometry3d& tip) {
  Chain c;
  for (std::size_t i = 0; i < joints.size(); ++i) {
    if (joints[i].name.empty()) joints[i].name = "joint" + std::to_string(i + 1);
  }
  c.joints = std::move(joints);
  c.bodies.resize(c.joints.size());
  c.tip = tip;
  return c;
}

/// Planar arm in the xy plane, joints about z, links along x; limits per joint (default none).
inline Chain planar(const std::vector<double>& links, const std::vector<std::pair<double, double>>& limits = {}) {
  std::vector<ChainJoint> joints;
  double previous = 0.0;
  for (std::size_t i = 0; i < links.size(); ++i) {
    ChainJoint j = revolute(translation(previous, 0, 0), Eigen::Vector3d::UnitZ());
    if (i < limits.size()) {
      j.lower = limits[i].first;
      j.upper = limits[i].second;
    }
    joints.push_back(j);
    previous = links[i];
  }
  return make_chain(joints, translation(previous, 0, 0));
}

constexpr double kPlanarL1 = 0.7, kPlanarL2 = 0.5;
inline Chain planar_2r() { return planar({kPlanarL1, kPlanarL2}); }
inline Chain planar_3r() { return planar({0.5, 0.4, 0.3}); }

/// Phantom-like 3R: yaw about z, shoulder and elbow about y (upper arm l1 and forearm l2 along
/// x at q = 0); the elbow's limits keep one elbow branch.
constexpr double kPhantomL1 = 0.215, kPhantomL2 = 0.17;
inline Chain phantom_3r() {
  return make_chain({revolute(Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitZ(), -1.0, 1.0),
                     revolute(Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitY(), -1.0, 1.2),
                     revolute(translation(kPhantomL1, 0, 0), Eigen::Vector3d::UnitY(), 0.2, 2.6)},
                    translation(kPhantomL2, 0, 0));
}

/// UR5-like 6R from Universal Robots' published DH; limits +-2 pi (continuous joints).
inline Chain ur5() {
  const double l = 2.0 * 3.14159265358979323846;
  return dh_chain({{0, 0.089159, 0, deg(90), -l, l},
                   {0, 0, -0.425, 0, -l, l},
                   {0, 0, -0.39225, 0, -l, l},
                   {0, 0.10915, 0, deg(90), -l, l},
                   {0, 0.09465, 0, deg(-90), -l, l},
                   {0, 0.0823, 0, 0, -l, l}});
}

/// The Fennel haptic 6R (standard DH; q = theta - theta_offset), joint 4 in [0, 180] deg.
constexpr double kFennelL[5] = {0.45, 0.45, 0.65, 0.55, 0.15};
inline Chain fennel_6r() {
  const double* l = kFennelL;
  const double lo = deg(-180), hi = deg(180);
  return dh_chain({{0, 0, l[0], 0, lo, hi},
                   {0, 0, l[1], 0, lo, hi},
                   {0, -l[2], 0, deg(90), lo, hi},
                   {deg(-90), 0, l[3], 0, deg(0), deg(180)},
                   {0, 0, 0, deg(90), lo, hi},
                   {0, l[4], 0, 0, lo, hi}});
}

/// KUKA-iiwa-14-like 7R: axes z, y, z, -y, z, y, z along a vertical column, its joint limits.
inline Chain iiwa_7r() {
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ(), y = Eigen::Vector3d::UnitY();
  return make_chain({revolute(translation(0, 0, 0.1575), z, deg(-170), deg(170)),
                     revolute(translation(0, 0, 0.2025), y, deg(-120), deg(120)),
                     revolute(translation(0, 0, 0.2045), z, deg(-170), deg(170)),
                     revolute(translation(0, 0, 0.2155), -y, deg(-120), deg(120)),
                     revolute(translation(0, 0, 0.1845), z, deg(-170), deg(170)),
                     revolute(translation(0, 0, 0.2155), y, deg(-120), deg(120)),
                     revolute(translation(0, 0, 0.081), z, deg(-175), deg(175))},
                    translation(0, 0, 0.045));
}

/// SCARA-like RRPR: two yaw joints (links 0.4, 0.3 m), a vertical prismatic joint in
/// [-0.25, 0] m, a yaw wrist: 4 DOF reaching x, y, z and yaw (full pose: 6 consistent rows).
inline Chain scara_rrpr() {
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  ChainJoint slide = revolute(translation(0.3, 0, 0), z, -0.25, 0.0);
  slide.type = ChainJointType::kPrismatic;
  return make_chain({revolute(translation(0, 0, 0.3), z, deg(-150), deg(150)),
                     revolute(translation(0.4, 0, 0), z, deg(-140), deg(140)), slide,
                     revolute(Eigen::Isometry3d::Identity(), z)},
                    translation(0, 0, -0.05));
}

/// A chain, the task it is solved for and its home posture.
struct TestChain {
  std::string name;
  Chain chain;
  IkTask task;
  std::vector<double> home;
};

inline IkTask position_task() { return IkTask{true, IkTask::Orientation::kNone, 2}; }
inline IkTask full_task() { return IkTask{true, IkTask::Orientation::kFull, 2}; }
inline IkTask axis_task(int axis = 2) { return IkTask{true, IkTask::Orientation::kAxis, axis}; }

/// Every test chain with its natural task (3R: position; 6R / 7R: full pose; planar 3R and
/// SCARA: full pose, an over-determined but consistent task).
inline std::vector<TestChain> all_chains() {
  return {{"planar_2r", planar_2r(), position_task(), {0.3, 1.0}},
          {"planar_3r", planar_3r(), full_task(), {0.3, 0.8, 0.6}},
          {"phantom_3r", phantom_3r(), position_task(), {0.0, 0.3, 1.2}},
          {"ur5", ur5(), full_task(), {0.0, -1.2, 1.5, -1.9, -1.57, 0.0}},
          {"fennel_6r", fennel_6r(), full_task(), {0.0, deg(90), 0.0, deg(90), deg(90), 0.0}},
          {"iiwa_7r", iiwa_7r(), full_task(), {0.0, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0}},
          {"scara_rrpr", scara_rrpr(), full_task(), {0.0, 0.5, -0.1, 0.0}}};
}

}  // namespace hapsyn::plugins::test_chains
