#pragma once
/// \file
/// A serial kinematic chain with numbers only (no names of files or parameters): the model the
/// `serial_chain` mechanism builds per design, and what its kinematics, dynamics and inverse
/// kinematics work on. URDF and DH tables are turned into it by chain_template.hpp.
///
/// Conventions (docs/design.md, "serial chains"):
/// - T_base_tip(q) = O_1 M_1(q_1) O_2 M_2(q_2) ... O_n M_n(q_n) T_tip, where O_i is joint i's
///   fixed origin (the pose of joint frame i at q_i = 0 in joint frame i-1, or in the base frame
///   for i = 1), M_i the joint's motion about / along its unit axis (in joint frame i), T_tip
///   the fixed pose of the tip frame in joint frame n.
/// - Body i moves with joint i (is rigidly attached to joint frame i); its inertial data are in
///   joint frame i. The base carries no dynamics.
/// - Twists and Jacobian rows are ordered (omega, v): the geometric Jacobian of the tip point in
///   the base frame [rad/s; m/s per joint rate].
/// - Units SI: m, rad, kg, kg m^2; a prismatic joint's coordinate is in m.
#include <hapsyn/chain_motion.hpp>
#include <hapsyn/quantities.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// Most joints a serial chain may have (the 2 to 7 DOF; kMaxDof bounds SampleQuantities).
constexpr int kMaxChainJoints = 7;

enum class ChainJointType { kRevolute, kPrismatic };

/// One moving joint of a chain.
struct ChainJoint {
  std::string name;                                       ///< for messages and columns
  ChainJointType type = ChainJointType::kRevolute;
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  ///< O_i (see the file comment)
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();          ///< unit, in joint frame i
  double lower = -INFINITY, upper = INFINITY;  ///< position limits [rad or m]; infinite when unlimited
  double max_velocity = 0.0;  ///< [rad/s or m/s]; 0 = not given
  double max_effort = 0.0;    ///< [N m or N]; 0 = not given
};

/// The rigid body moving with one joint.
struct ChainBody {
  double mass = 0.0;                                    ///< [kg], >= 0
  Eigen::Vector3d com = Eigen::Vector3d::Zero();        ///< centre of mass in joint frame i [m]
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();    ///< about the com, joint frame i axes [kg m^2]
};

/// A serial chain with numbers: what one design of a serial_chain mechanism is.
struct Chain {
  std::vector<ChainJoint> joints;  ///< n = 1..kMaxChainJoints moving joints, base to tip
  std::vector<ChainBody> bodies;   ///< n bodies, body i moving with joint i
  Eigen::Isometry3d tip = Eigen::Isometry3d::Identity();  ///< T_tip (see the file comment)
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);  ///< in the base frame [m/s^2]

  int dof() const { return static_cast<int>(joints.size()); }
};

/// Joint positions of a chain (fixed capacity: no allocation).
using ChainVector = JointVector;

/// The frames of one configuration (fixed capacity: no allocation).
struct ChainFrames {
  /// joint[i] = pose of joint frame i in the base frame, after joint i's motion (i < n).
  std::array<Eigen::Isometry3d, kMaxChainJoints> joint;
  Eigen::Isometry3d tip = Eigen::Isometry3d::Identity();  ///< T_base_tip(q)
};

/// Forward kinematics. \param q n joint positions. Allocation-free.
void chain_frames(const Chain& chain, const double* q, ChainFrames& out);

/// Geometric Jacobian (6 x n, rows omega then v) of the tip point in the base frame, from the
/// frames of chain_frames. Allocation-free.
void chain_jacobian(const Chain& chain, const ChainFrames& frames, TaskJointMatrix& jacobian);

/// Whether sigma_min > tolerance sigma_max for a (task) Jacobian: the SVD's answer, reached for a
/// square matrix far from a singularity through an LU instead (|J|_F |J^-1|_F tolerance < 1
/// suffices). Allocation-free.
bool chain_well_conditioned(const TaskJointMatrix& jacobian, double tolerance);

/// Joint-space inertia H (n x n, symmetric, [kg m^2 / kg m / kg]) by composite rigid bodies,
/// from the frames of chain_frames. Allocation-free.
void chain_inertia(const Chain& chain, const ChainFrames& frames, JointMatrix& inertia);

/// Gravity torque tau_g (n): the joint torques [N m or N] that hold the chain static against
/// chain.gravity (tau_g = -sum_i J_com_i^T m_i g). Allocation-free.
void chain_gravity(const Chain& chain, const ChainFrames& frames, JointVector& gravity);

/// The joints at the frames of chain_frames for hapsyn/chain_motion.hpp (n values): joint i's
/// axis in the base frame through joint frame i's origin (after its motion). Allocation-free.
void chain_world_joints(const Chain& chain, const ChainFrames& frames, WorldJoint* out);

/// The bodies (n values) in the base frame at the frames of chain_frames: the same mass model as
/// chain_inertia and chain_gravity, so that tau = H qddot + velocity_torque + gravity holds.
void chain_world_bodies(const Chain& chain, const ChainFrames& frames, WorldBody* out);

}  // namespace hapsyn::plugins
