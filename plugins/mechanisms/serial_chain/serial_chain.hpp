#pragma once
/// \file
/// The serial_chain mechanism: a serial manipulator from a URDF file or a DH table
/// (chain_template.hpp), every model parameter a design variable, closed-form or numerical IK,
/// and the quantities the metrics need (chain.hpp). Conventions in docs/design.md, "serial
/// chains":
/// - A scene sample (x, y, z[, qw, qx, qy, qz]) in the scene frame S is the pose of the sample
///   frame P; the tip frame E must reach T_B^E = T_B^S T_S^P (T_E^P)^-1, with T_S^B from
///   base_xyz / base_rpy and T_E^P from tool_xyz / tool_rpy.
/// - The task Jacobian (SampleQuantities::jacobian) holds the rows the task matches, angular
///   rows first: pose 6 x n (omega, v), position 3 x n (v), position_axis 5 x n (two omega rows
///   orthogonal to the tip axis, then v); all in the base frame B, per joint rate.
/// - IK (option ik.solver): closed form (chain_closed_form_ik.hpp: every solution) for 6R chains
///   with the pose task whose axes form a supported family, and for 7R chains with a joint whose
///   locking leaves one (discretised: ik.redundant_joint, ik.redundant_steps), else numerical
///   (chain_ik.hpp).
/// - Classification: a solution inside the limits -> kReachable, or kSingular when the
///   scaled task Jacobian's sigma_min / sigma_max < singularity_tolerance; solutions only
///   outside the limits -> kInvalid; none -> kUnreachable. Never a NaN. The closed form proves
///   kInvalid and kUnreachable (it knows every solution); the numerical IK guesses them (kInvalid:
///   a run without limits converged and none with limits did; kUnreachable: no start converged).
/// - Demanded motion (kNeedJointVelocity / kNeedJointAcceleration / kNeedVelocityTorque, every
///   task, reachable samples only): the sample's twist and twist rate are those of P in S; they
///   are carried to E in B like the target (rotated by R_B^S; v_E = v_P + omega x r, a_E = a_P +
///   domega x r + omega x (omega x r) with r from P to E; r does not turn for a 3-coordinate
///   sample, which has no orientation), then given the task Jacobian's rows: pose all six,
///   position the v rows, position_axis (u1, u2) . omega and v. qdot solves J qdot = those rows
///   (LU, or minimum norm for a redundant chain), qddot solves J qddot = the rows of (twist_rate
///   - Jdot qdot), where for position_axis the angular part gains lambda (omega x a), lambda =
///   a . (omega_chain - omega), a the tip axis: the chain's spin about a is free, and the axis's
///   second derivative omega_dot x a + omega x (omega x a) is matched, not the spin's
///   (serial_chain_model.cpp). c = C(q, qdot) qdot by Newton-Euler on the bodies of the inertia
///   and gravity torque (hapsyn/chain_motion.hpp). Without a twist (solve() outside the
///   evaluator) these outputs are NaN.
#include "chain.hpp"
#include "chain_closed_form_ik.hpp"
#include "chain_ik.hpp"
#include "chain_template.hpp"
#include "linear_constraints.hpp"
#include "serial_chain_options.hpp"

#include <hapsyn/mechanism.hpp>
#include <hapsyn/mesh_drawing.hpp>

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn {
struct ActuatorTable;  // hapsyn/actuator_table.hpp
}  // namespace hapsyn

namespace hapsyn::plugins {

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// A sample's demanded motion carried to the tip point E in the base frame B (see the file
/// comment), rows (omega, v): what J qdot and J qddot + Jdot qdot must give.
struct DemandedMotion {
  Vector6d twist;       ///< [rad/s; m/s]
  Vector6d twist_rate;  ///< [rad/s^2; m/s^2]; NaN without a twist rate
};

/// What the plugin resolves once from its options: the chain file read, the actuator table,
/// the frames, the home posture, the constraints. Shared by every model (const).
struct SerialChainSetup {
  SerialChainOptions options;
  ChainTemplate chain_template;
  std::shared_ptr<const ActuatorTable> actuators;  ///< null without actuator_file
  IkTask task;
  IkSettings ik;
  bool first_found = false;                 ///< ik.selection == "first_found"
  /// The nominal chain got the closed-form IK (ik.solver auto or closed_form; see SerialChain::summary).
  bool closed_form = false;
  std::string solver_summary;               ///< "closed form (<geometry>)" or "numerical (...)"
  /// 7R closed form: the discretised joint (resolved at the nominal chain) and its steps.
  RedundantJointSettings redundancy;
  Eigen::Isometry3d base_from_scene;        ///< T_B^S
  Eigen::Isometry3d sample_to_tip;          ///< (T_E^P)^-1
  JointVector home;                         ///< [rad or m]
  double characteristic_length = 1.0;       ///< [m]
  int parameter_count = 0;                  ///< design layout: parameters, then size[n], gear[n]
  std::vector<LinearConstraint> constraints;
};

/// Per-thread scratch: the IK's and the previous sample's solution (the warm start).
struct SerialChainScratch final : MechanismScratch {
  IkScratch ik;
  ClosedFormScratch closed_form;
  ChainFrames frames;
  TaskJointMatrix geometric, task;
  std::uint64_t last_model = 0;  ///< id of the model `last_q` was solved with (warm start only; 0 = none)
  JointVector last_q;
};

/// The manipulator for one design. solve() is const, thread-safe and allocation-free.
class SerialChainModel final : public MechanismModel, public MeshDrawing {
 public:
  /// Builds the chain for a full design vector (see SerialChainSetup::parameter_count), and its
  /// closed-form IK when the nominal chain got one. A design whose axes leave the family (a freed
  /// origin angle, say) falls back to the numerical IK under ik.solver "auto".
  /// \throws Error("serial_chain", ...) under ik.solver "closed_form" for such a design, naming its geometry.
  SerialChainModel(const double* design, const SerialChainSetup& setup);

  void solve(const double* pose, Needs needs, MechanismScratch& scratch, SampleQuantities& out) const override;
  /// Drawn in the scene frame S: "links", the polyline from the base origin through every joint
  /// frame's origin to the tip, then to the tool point P when the tool frame moves it, at the
  /// configuration solve() picks (T_S^B applied to the frames of chain_frames). Empty for an
  /// unreachable sample or one out of the joint limits.
  std::vector<Segment> segments(const SampleSet& scene, int sample, MechanismScratch& scratch) const override;
  /// A URDF's mesh visuals (ChainTemplate::meshes) in the scene frame S at the configuration
  /// segments() draws: T_S^B times the carrying joint frame times mesh_pose_in_body
  /// (serial_chain_meshes.cpp). Empty when segments() is, or the file has no drawable mesh.
  std::vector<MeshVisual> mesh_visuals(const SampleSet& scene, int sample, MechanismScratch& scratch) const override;
  /// ChainTemplate::meshes().warnings.
  std::vector<std::string> mesh_warnings() const override;

  const Chain& chain() const { return chain_; }
  /// Whether this design's samples are solved in closed form.
  bool closed_form() const { return closed_form_ != nullptr; }
  const JointVector& max_velocity() const { return max_velocity_; }  ///< [rad/s or m/s]
  const JointVector& max_torque() const { return max_torque_; }      ///< [N m or N]
  /// T_B^E wanted for a scene sample (dimension 3 or 7).
  Eigen::Isometry3d target(const double* pose, int dimension) const;
  /// The sample's twist (and twist rate, may be null), 6 values each of P in S, as a motion of
  /// E in B for the target `goal` = target(pose, dimension). Allocation-free.
  DemandedMotion demanded_motion(const double* pose, int dimension, const Eigen::Isometry3d& goal, const double* twist,
                                 const double* twist_rate) const;
  /// position_axis: what the angular acceleration must gain for the tip axis `axis` (unit, B)
  /// to follow the demanded one to second order when the chain's angular velocity
  /// `omega_chain` differs from the demanded `omega` by a spin about the axis:
  /// (axis . (omega_chain - omega)) (omega x axis).
  static Eigen::Vector3d axis_rate_term(const Eigen::Vector3d& axis, const Eigen::Vector3d& omega,
                                        const Eigen::Vector3d& omega_chain);

 private:
  /// The chain's frames at the configuration the IK gives `sample` (what segments() and
  /// mesh_visuals() draw); false when the sample is unreachable or reachable only outside the limits.
  bool drawn_frames(const SampleSet& scene, int sample, MechanismScratch& scratch, ChainFrames& frames) const;
  void fill_quantities(const ChainFrames& frames, const TaskJointMatrix& jacobian, Needs needs,
                       SampleQuantities& out) const;
  // kNeedJointVelocity, kNeedJointAcceleration, kNeedVelocityTorque at s.frames, s.task and
  // s.geometric of a reachable sample.
  void fill_motion(const double* pose, int dimension, const Eigen::Isometry3d& goal, SerialChainScratch& s,
                   Needs needs, SampleQuantities& out) const;

  const SerialChainSetup* setup_;
  std::uint64_t id_;  ///< unique per model, for the warm start (an address may be reused)
  Chain chain_;
  std::unique_ptr<const ChainClosedFormIk> closed_form_;  ///< null: the numerical IK
  JointVector max_velocity_, max_torque_;
  std::vector<double> mesh_parameters_;  ///< the design's chain parameters, kept only when there are meshes
};

/// The "serial_chain" mechanism plugin.
class SerialChain final : public Mechanism {
 public:
  using Options = SerialChainOptions;
  /// Reads the chain file and the actuator table and checks the relations between options.
  /// \throws Error("serial_chain", ...) naming the option or the file, the value and the rule.
  explicit SerialChain(const SerialChainOptions& options);

  std::unique_ptr<const MechanismModel> build(const double* design) const override;
  std::unique_ptr<MechanismScratch> make_scratch() const override;
  /// Every parameter of the chain file (fixed at its value unless the design section frees
  /// it), then size and gear (n integer codes each) when an actuator table is given.
  std::vector<VariableDecl> variables() const override;
  std::vector<ConstraintDecl> constraints() const override;
  void evaluate_constraints(const double* design, const SampleSet& scene, double* g) const override;
  /// 3 coordinates (x, y, z) for the position task, 7 (x, y, z, qw, qx, qy, qz) for any task.
  void check_scene(const SampleSet& scene) const override;
  /// Jacobian, inertia, effective mass, gravity, joint velocity, joint acceleration, velocity
  /// torque; actuator limits when a table is given or the file gives every joint's velocity and
  /// effort limits.
  Needs provides() const;
  MechanismSpecs specs() const override { return {provides(), summary()}; }
  /// "N moving joints base -> tip: name (revolute), ...[; folded: link, link -> body_link]...;
  /// task T; IK selection S; IK solver closed form (<ChainGeometry::describe()>)" or "...; IK
  /// solver numerical (<why>)". One "folded" part per body of ChainTemplate::folded_links().
  std::string summary() const;

  const SerialChainSetup& setup() const { return *setup_; }

 private:
  std::shared_ptr<const SerialChainSetup> setup_;
};

}  // namespace hapsyn::plugins
