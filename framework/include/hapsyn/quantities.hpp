#pragma once
/// \file
/// What a metric may ask of a mechanism at one task-space sample, and the fixed-capacity
/// storage a mechanism fills (no heap allocation in the per-sample loop).
#include <Eigen/Core>
#include <cstdint>
#include <string>

namespace hapsyn {

struct SampleSet;

/// Quantities computed at a sample, as bit flags. Pose (the inverse kinematics and its
/// classification) is always computed; everything else only when some metric asks for it.
enum Need : std::uint32_t {
  kNeedPose = 0,
  kNeedJacobian = 1u << 0,        ///< task Jacobian J (task velocity = J * actuator rates)
  kNeedInertia = 1u << 1,         ///< joint-space inertia D (actuated coordinates)
  kNeedEffectiveMass = 1u << 2,   ///< end-effector effective mass M = J^-T D J^-1
  kNeedGravity = 1u << 3,         ///< gravity torque at the actuators
  kNeedActuatorLimits = 1u << 4,  ///< actuator velocity / torque limits
  /// Joint rates qdot [rad/s or m/s] that realise the sample's demanded twist
  /// (SampleQuantities::twist): J qdot = twist in the task rows (least squares / minimum norm
  /// when J is not square). A mechanism whose J is in another frame or at another point than
  /// the scene's pose carries the twist there first (serial_chain: base frame, tip point). The
  /// scene must provide the "twist" attribute. hapsyn/chain_motion.hpp has the building blocks
  /// for serial chains (Jdot qdot, C(q, qdot) qdot, the allocation-free solve).
  kNeedJointVelocity = 1u << 5,
  /// Joint accelerations qddot that realise the demanded twist rate at those rates:
  /// J qddot = twist_rate - Jdot qdot (same rule). Implies kNeedJointVelocity; the scene must
  /// provide "twist_rate" too.
  kNeedJointAcceleration = 1u << 6,
  /// Velocity-dependent joint torque c(q, qdot) = C(q, qdot) qdot [N m or N] at the rates of
  /// kNeedJointVelocity (Coriolis and centrifugal terms), so that the full inverse dynamics is
  /// tau = inertia * qddot + velocity_torque + gravity. Implies kNeedJointVelocity.
  kNeedVelocityTorque = 1u << 7,
};
using Needs = std::uint32_t;

/// Classification of one sample for one design.
enum class SampleStatus : std::uint8_t {
  kReachable = 0,    ///< valid configuration, quantities filled
  kUnreachable = 1,  ///< outside the reachable set (no IK solution)
  kSingular = 2,     ///< reachable but at or too near a singularity
  kInvalid = 3,      ///< a solution exists but violates the working mode / joint limits
};
const char* to_string(SampleStatus status);

/// The names of the flags in `needs`, comma-separated ("jacobian, inertia"), for messages.
std::string need_names(Needs needs);

/// The scene attributes that carry a sample's demanded motion (6 columns each, in the scene
/// frame at the pose's point, rows (omega, v) like every twist in hapsyn): "twist" = (omega
/// [rad/s], v [m/s]) and "twist_rate" = (d omega/dt [rad/s^2], dv/dt [m/s^2]).
constexpr const char* kTwistAttribute = "twist";
constexpr const char* kTwistRateAttribute = "twist_rate";

/// Largest matrix a mechanism may fill (6-DOF spatial). Fixed capacity => no allocation.
constexpr int kMaxDof = 8;
constexpr int kMaxTask = 6;
using JointVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxDof, 1>;
using TaskJointMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxTask, kMaxDof>;
using JointMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxDof, kMaxDof>;
using TaskMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxTask, kMaxTask>;
/// A per-sample scene attribute: one row per sample (the type of SampleSet::attributes' values).
using AttributeMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Everything a mechanism computes at one sample. Only the members requested by Needs are
/// meaningful; the others keep whatever they held.
struct SampleQuantities {
  SampleStatus status = SampleStatus::kUnreachable;
  /// Set by the evaluator before the mechanism's solve(): the sample's index in `scene`, so a
  /// mechanism or metric can read the scene (its dimension) and the sample's attributes (e.g.
  /// the human's M_v). -1 / null outside the evaluator.
  int sample = -1;
  const SampleSet* scene = nullptr;
  /// Set by the evaluator before each metric's local(): the scene attributes that metric lists
  /// in scene_attributes(), in that order (an entry is null when the scene lacks it), resolved
  /// once per study so that the per-sample loop does no lookup by name. Null outside the evaluator.
  const AttributeMatrix* const* attributes = nullptr;
  int attribute_count = 0;
  /// Row of the current sample in the calling metric's k-th scene attribute, or null when the
  /// evaluator did not resolve it (then look it up by name in scene->attributes).
  const double* attribute_row(int k) const {
    if (!attributes || k < 0 || k >= attribute_count || sample < 0) return nullptr;
    const AttributeMatrix* m = attributes[k];
    return m && sample < m->rows() ? m->row(sample).data() : nullptr;
  }
  /// Set by the evaluator before solve() when the scene carries the demanded motion (see
  /// kTwistAttribute): the sample's twist (omega, v) and twist rate, 6 values each, in the scene
  /// frame; null otherwise. A mechanism reads them for kNeedJointVelocity / kNeedJointAcceleration.
  const double* twist = nullptr;
  const double* twist_rate = nullptr;
  JointVector q;                  ///< joint angles of the chosen configuration [rad]
  TaskJointMatrix jacobian;       ///< J: task velocity [m/s] per actuator rate [rad/s]
  JointMatrix inertia;            ///< D [kg m^2] in actuated coordinates
  TaskMatrix effective_mass;      ///< M = J^-T D J^-1 [kg]
  JointVector gravity;            ///< gravity torque [N m]
  JointVector max_velocity;       ///< actuator velocity limits [rad/s]
  JointVector max_torque;         ///< actuator torque limits [N m]
  JointVector joint_velocity;     ///< qdot realising `twist` [rad/s or m/s] (kNeedJointVelocity)
  JointVector joint_acceleration; ///< qddot realising `twist_rate` (kNeedJointAcceleration)
  JointVector velocity_torque;    ///< C(q, qdot) qdot [N m or N] (kNeedVelocityTorque)
};

}  // namespace hapsyn
