#pragma once
/// \file
/// The SCARA-like serial 6R haptic manipulator of Fennel, Zea, Hanebeck (IEEE ToH 2022) as a
/// hapsyn mechanism, with the reconstructed DH table of docs/design.md section 4 read from data.
///
/// Conventions:
/// - Standard DH, T_i = Rz(q_i + theta_offset_i) Tz(d_i) Tx(a_i) Rx(alpha_i); frame 0 = base B
///   (z up, joint 1 axis), frame 6 = end effector E (z_E = roll axis of joint 6). Structure:
///   a = (l1, l2, 0, l4, 0, 0), d = (0, 0, -l3, 0, 0, l5), alpha = (0, 0, 90, 0, 90, 0) deg.
/// - Design vector: l[0..4] = l1..l5 [m], s[0..5] joint sizes (1..3), r[0..5] gear codes (1..6).
/// - Scene sample: the end-effector target T_E^B as (x, y, z, qw, qx, qy, qz) [m] (human_arm).
/// - Twists, Jacobian rows and ellipsoid rows are ordered (omega, v); the Jacobian is the
///   geometric Jacobian of the point E in B [rad/s; m/s per rad/s].
/// - Inverse kinematics (closed form): the wrist point w = p - l5 z_E lies on axes 4-5's plane;
///   h = +-(e_z x z_E)/|e_z x z_E| is the axis of joints 4 and 5, theta4 from
///   sin(theta4) = (w_z + l3) / l4 (two branches), joint 3's axis from w - l4 cos(theta4) (e_z x h),
///   q1, q2 by the planar 2R law of cosines (two branches), q3 from the yaw of e_z x h, q5, q6
///   from the remaining rotation: up to 8 solutions, every one returned by inverse_kinematics().
/// - Selection (option "selection"): among the solutions inside the joint limits (tolerance
///   kHaptic6RAngleTolerance), "closest_to_home" takes the smallest sum of squared wrapped angle
///   differences to "home"; "elbow_left" / "elbow_right" first restrict to q2 >= 0 / q2 <= 0;
///   ties go to the lower solution index (deterministic).
/// - Classification: no solution -> kUnreachable; solutions but none in the limits (or branch)
///   -> kInvalid; the chosen one with |sin q2| (SCARA stretched), |sin(q4 + theta_offset4 + 90
///   deg)| = |cos theta4| (l4 vertical) or |e_z x z_E| (wrist axis vertical) below
///   singularity_tolerance -> kSingular (q filled, finite); else kReachable.
/// - Mass model (docs/design.md section 4): motor i a point mass motor_mass_factor * m(s_i) at the
///   origin of DH frame i-1 (on joint i's axis, carried by body i-1; motor 1 on the base has no
///   effect); links l1..l5 tubes of linear density link_density between consecutive DH origins
///   (l5 from the wrist point to E), outer diameter tube_outer_diameter, wall tube_wall; the end
///   effector a solid cylinder (ee_mass, ee_diameter, ee_length) centred at E, axis z_E.
///   Gravity -gravity e_z in B; gravity torque = the joint torque that holds the arm static.
/// - Demanded motion (kNeedJointVelocity / kNeedJointAcceleration / kNeedVelocityTorque, for a
///   reachable sample only): the sample's twist and twist rate are those of E in B (the scene
///   frame), rows (omega, v), like J. qdot = J^-1 twist, qddot = J^-1 (twist_rate - Jdot qdot)
///   (LU of the 6 x 6 J), c = C(q, qdot) qdot by Newton-Euler on the same bodies as H and the
///   gravity torque (hapsyn/chain_motion.hpp), so tau = H qddot + c + gravity is the full inverse
///   dynamics. Without a twist (solve() outside the evaluator) these outputs are NaN. Computed
///   only when asked for: the other flags run the same code as before.
#include <hapsyn/accel/mechanism_acceleration.hpp>
#include <hapsyn/actuator_table.hpp>
#include <hapsyn/mechanism.hpp>
#include <hapsyn/options.hpp>
#include <hapsyn/accel/lanes.hpp>
#include <hapsyn/accel/sample_block.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <memory>
#include <string>
#include <vector>

namespace hapsyn::plugins {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

/// Angle tolerance [rad] of joint-limit comparisons (a wrapped angle one ulp past a limit must
/// not drop a pose; docs/design.md section 6).
constexpr double kHaptic6RAngleTolerance = 1e-9;

/// A DH length: a constant [m] or +-one of the links l1..l5.
struct LinkRef {
  int link = -1;        ///< 0..4 for l1..l5, -1 for a constant
  double factor = 1.0;  ///< +1 or -1
  double value = 0.0;   ///< the constant [m] when link == -1
  double eval(const double* l) const { return link < 0 ? value : factor * l[link]; }
};

/// One DH row as read from the data file.
struct Haptic6RDhRow {
  double theta_offset = 0.0;  ///< [rad]
  double alpha = 0.0;         ///< [rad]
  LinkRef d, a;
};

/// The DH table file (share/haptic6r/fennel2022_dh.json).
struct Haptic6RDh {
  std::string file;
  std::array<Haptic6RDhRow, 6> rows;
};

/// Reads a DH table file. \throws Error("haptic6r", "<file>: <json path> = <value>: <rule>"),
/// also when the structure is not the one the closed-form IK serves.
Haptic6RDh read_haptic6r_dh(const std::string& path);
/// Resolves a data-file option: absolute, relative to the current directory, or to hapsyn's
/// share directory (source tree, then install tree). \throws Error naming the option.
std::string resolve_haptic6r_file(const std::string& option_name, const std::string& value);

struct Haptic6ROptions;
/// The rule relating joint_lower and joint_upper: "" when every joint_upper[i] >= joint_lower[i]
/// and the span is at most 360 deg (compared in radians, as the model compares), else what is wrong.
std::string haptic6r_joint_range_rule(const Haptic6ROptions& o);

/// Options of the mechanism, declared once (the plugin's schema is derived from them), as the
/// problem file gives them: data files by name, angles in degrees. Haptic6RSetup holds what the
/// model computes with.
struct Haptic6ROptions {
  std::string dh_file{};
  std::string actuator_file{};
  std::string selection{};            ///< "closest_to_home", "elbow_left" or "elbow_right"
  std::vector<double> home{};         ///< 6 angles [deg]
  std::vector<double> joint_lower{};  ///< 6 angles [deg]
  std::vector<double> joint_upper{};  ///< 6 angles [deg]
  double singularity_tolerance{};     ///< [-]
  double link_density{};              ///< tube linear density [kg/m]
  double tube_outer_diameter{};       ///< [m]
  double tube_wall{};                 ///< [m]
  double ee_mass{};                   ///< [kg]
  double ee_diameter{};               ///< [m]
  double ee_length{};                 ///< [m]
  double motor_mass_factor{};         ///< mounting structure allowance [-]
  double gravity{};                   ///< [m/s^2]

  static void declare(OptionDeclarations<Haptic6ROptions>& d) {
    d.describe(
        "SCARA-like serial 6R haptic manipulator (Fennel, Zea, Hanebeck 2022; DH table reconstructed in docs/design.md "
        "section 4, read from dh_file). Design variables l (5, m), s (6 joint sizes 1..3), r (6 gear codes 1..6). "
        "Scene samples are end-effector poses (x, y, z, qw, qx, qy, qz) in the base frame B. Closed-form IK (up to 8 "
        "solutions), one picked by 'selection' within the joint limits.");
    d.add(&Haptic6ROptions::dh_file, "dh_file", "haptic6r/fennel2022_dh.json",
          "DH table: absolute, relative to the current directory, or to hapsyn's share directory.");
    d.add(&Haptic6ROptions::actuator_file, "actuator_file", "haptic6r/actuators_assumed.json",
          "Actuator table (f_qdot, f_tau, f_m); the shipped one is assumed (see share/haptic6r/README.md).");
    d.add(&Haptic6ROptions::selection, "selection", "closest_to_home",
          "Which IK solution is used: the admissible one closest to 'home' (sum of squared wrapped angle "
          "differences); elbow_left / elbow_right first keep only q2 >= 0 / q2 <= 0.")
        .one_of({"closest_to_home", "elbow_left", "elbow_right"});
    d.add(&Haptic6ROptions::home, "home", {0, 90, 0, 90, 90, 0}, "Reference configuration of the selection rule.")
        .size(6)
        .range(-720, 720)
        .unit("deg");
    d.add(&Haptic6ROptions::joint_lower, "joint_lower", {-180, -180, -180, 0, -180, -180},
          "Joint lower limits (q4 in [0, 180] keeps l4 on one side of joint 3's plane: one of each mirror pair).")
        .size(6)
        .range(-720, 720)
        .unit("deg");
    d.add(&Haptic6ROptions::joint_upper, "joint_upper", {180, 180, 180, 180, 180, 180},
          "Joint upper limits (span at most 360 deg).")
        .size(6)
        .range(-720, 720)
        .unit("deg");
    d.add(&Haptic6ROptions::singularity_tolerance, "singularity_tolerance", 1e-4,
          "A configuration with |sin q2|, |cos theta4| (l4 vertical) or the horizontal part of the roll axis below "
          "this is classified singular.")
        .minimum(0)
        .less_than(1);
    d.add(&Haptic6ROptions::link_density, "link_density", 4.0, "Linear density of the link tubes (the paper's 4 kg/m).")
        .minimum(0)
        .unit("kg/m");
    d.add(&Haptic6ROptions::tube_outer_diameter, "tube_outer_diameter", 0.1, "Outer diameter of the link tubes.")
        .minimum(0)
        .unit("m");
    d.add(&Haptic6ROptions::tube_wall, "tube_wall", 0.002,
          "Wall thickness of the link tubes (enters their inertia only).")
        .minimum(0)
        .unit("m");
    d.add(&Haptic6ROptions::ee_mass, "ee_mass", 0.5, "End-effector mass (solid cylinder centred at E, axis z_E).")
        .minimum(0)
        .unit("kg");
    d.add(&Haptic6ROptions::ee_diameter, "ee_diameter", 0.1, "End-effector cylinder diameter.").minimum(0).unit("m");
    d.add(&Haptic6ROptions::ee_length, "ee_length", 0.05, "End-effector cylinder length.").minimum(0).unit("m");
    d.add(&Haptic6ROptions::motor_mass_factor, "motor_mass_factor", 1.2,
          "Motor point mass = factor * table mass (the paper's +20 % for mountings).")
        .minimum(0);
    d.add(&Haptic6ROptions::gravity, "gravity", 9.81, "Gravitational acceleration, along -z of B.")
        .minimum(0)
        .unit("m/s^2");
    d.rule({"joint_upper", "joint_lower"}, "joint_lower[i] <= joint_upper[i] <= joint_lower[i] + 360",
           &haptic6r_joint_range_rule);
    d.rule({"tube_wall", "tube_outer_diameter"}, "tube_wall <= tube_outer_diameter / 2",
           [](const Haptic6ROptions& o) {
             return 2.0 * o.tube_wall > o.tube_outer_diameter
                        ? "must be <= tube_outer_diameter / 2 (" + std::to_string(o.tube_outer_diameter / 2) + ")"
                        : std::string();
           });
  }
};

/// The IK solution rule of the "selection" option.
enum class Haptic6RSelection { kClosestToHome, kElbowLeft, kElbowRight };

/// The options resolved for the model: the data files read, the angles in radians. Built once
/// per plugin object; every Haptic6RModel keeps a pointer to it.
struct Haptic6RSetup {
  Haptic6ROptions options;            ///< as declared (tolerance, mass model and gravity are read here)
  Haptic6RDh dh;
  ActuatorTable actuators;
  Haptic6RSelection selection{};  // set from the "selection" option
  Vector6d home;                      ///< [rad]
  Vector6d joint_lower, joint_upper;  ///< [rad]

  /// Reads the data files and converts the angles; checks what the declarations cannot
  /// express: the files (they must exist and hold a valid table), joint_upper[i] >=
  /// joint_lower[i] with a span of at most 360 deg, and tube_wall <= tube_outer_diameter / 2.
  /// \param options validated options (Haptic6ROptions::declare)
  /// \throws Error("haptic6r: options.<key> = <value>: <rule>"), or naming the data file.
  static Haptic6RSetup from_options(const Haptic6ROptions& options);
};

/// cos and sin of the six DH angles theta_i = q_i + theta_offset_i of one configuration.
struct JointTrig {
  std::array<double, 6> c{}, s{};
};

/// One rigid body of the mass model, in its DH frame i (i = 1..6).
struct Haptic6RBody {
  double mass = 0.0;                                      ///< [kg]
  Eigen::Vector3d com = Eigen::Vector3d::Zero();          ///< centre of mass in frame i [m]
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();      ///< about the com, frame i axes [kg m^2]
};

namespace haptic6r_ik {
/// The design's numbers the IK and the selection read (from Haptic6RModel and its setup); set
/// by rebuild(), read by the IK templates of haptic6r_ik.hpp for every pose.
struct IkModel {
  double L1 = 0.0, L2 = 0.0, L3 = 0.0, L4 = 0.0, L5 = 0.0;  // a1, a2, -d3, a4, d6 [m]
  double inverse_L4 = 0.0, inverse_2L1L2 = 0.0;             // 1 / L4, 1 / (2 L1 L2) [1/m, 1/m^2]
  std::array<double, 6> ca{}, sa{}, offset{};               // cos, sin alpha_i; theta_offset_i [rad]
  std::array<double, 6> lower{}, upper{}, home{};            // joint limits and home [rad]
  // At least as many turns as admissible()'s first and second loops take for a wrapped angle in
  // [-pi, pi] (the block kernel takes this many conditional turns instead of the loops).
  std::array<int, 6> turns_up{}, turns_down{};
  // Whether [lower, upper] holds all of [-pi, pi] (a wrapped angle is then inside unless NaN).
  std::array<bool, 6> full_turn{};
  // Whether |theta_offset_i| <= 3 pi / 4 and |home_i| <= pi: the IK's angles minus the offset
  // (all but theta3's) and a wrapped angle minus home then lie within [-3 pi, 3 pi), and
  // haptic6r_ik::wrap_near() wraps them with two selections, the same value as wrap().
  std::array<bool, 6> near_offset{}, near_home{};
  Haptic6RSelection selection = Haptic6RSelection::kClosestToHome;
  double singularity_tolerance = 0.0;
};
}  // namespace haptic6r_ik

/// The manipulator for one design. Immutable after rebuild(); solve() is const, thread-safe
/// and allocation-free.
class Haptic6RModel final : public MechanismModel {
 public:
  Haptic6RModel() = default;
  /// (Re)builds for a design vector (l[5], s[6], r[6]) without allocating. The model keeps a
  /// pointer to `setup`, which must outlive it.
  /// \throws Error for a non-finite or non-positive length, or a size / code out of range.
  void rebuild(const double* design, const Haptic6RSetup& setup);

  void solve(const double* pose, Needs needs, MechanismScratch& scratch,
             SampleQuantities& out) const override;
  /// Drawn in B (the scene frame): "links", the polyline o_0 -> (o_0 + d_1 z_0) -> o_1 -> ... ->
  /// o_6 = E through the DH origins (each row's d along z_{i-1}, then its a along x_i), at the
  /// configuration solve() picks. Empty for an unreachable or invalid sample.
  std::vector<Segment> segments(const SampleSet& scene, int sample, MechanismScratch& scratch) const override;
  /// The block kernel (docs/design.md section 14): the IK, selection and classification of every
  /// lane at once with the same outcome as solve() (the same statuses), then the Jacobian,
  /// inertia and gravity torque of every lane at once (haptic6r_block.cpp); agreement with solve() to 1e-12 relative. Serves
  /// needs within kNeedPose | kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits
  /// (Haptic6R::solves_blocks).
  void solve_block(const PoseBlock& poses, Needs needs, MechanismScratch& scratch, QuantityBlock& out) const;
  /// The first half of solve() for one pose: its status, q as solve() sets it, and for a
  /// reachable or singular pose the chosen configuration's DH-angle cosines and sines.
  SampleStatus configuration(const double* pose, Vector6d& q, JointTrig& trig) const;

  /// Every closed-form IK solution of the target (joint limits ignored), q [rad] wrapped into
  /// [-pi, pi). \return the count (0..8); solutions[0..count). With `trig`, also each solution's
  /// DH-angle cosines and sines (from the IK's own vectors: no trigonometric calls).
  int inverse_kinematics(const Eigen::Isometry3d& target, std::array<Vector6d, 8>& solutions,
                         std::array<JointTrig, 8>* trig = nullptr) const;
  /// Index into solutions of the one the selection rule picks, -1 when none is admissible.
  int select(const std::array<Vector6d, 8>& solutions, int count) const;
  /// Forward kinematics: frames[i] = T_0i (i = 0..6), frames[6] = T_E^B.
  void frames(const Vector6d& q, std::array<Eigen::Isometry3d, 7>& out) const;
  Eigen::Isometry3d forward(const Vector6d& q) const;
  /// Geometric Jacobian of E in B, rows (omega, v).
  Matrix6d jacobian(const Vector6d& q) const;
  /// Joint-space inertia H [kg m^2] (composite rigid bodies) and gravity torque [N m]; either
  /// pointer may be null.
  void dynamics(const Vector6d& q, Matrix6d* inertia, Vector6d* gravity) const;

  /// Jacobian, inertia and gravity at q from one forward pass (what solve() computes for a
  /// reachable sample); any pointer may be null.
  void quantities(const Vector6d& q, Matrix6d* jacobian, Matrix6d* inertia, Vector6d* gravity) const;
  /// quantities() for up to kBlockLanes configurations at once, one per SIMD lane: lane i of
  /// `out` holds the Jacobian, inertia, gravity torque and actuator limits (those in `needs`) at
  /// q[i], i < count (status kReachable; later lanes kUnreachable). Agreement with quantities()
  /// to 1e-12 relative. \throws Error("haptic6r: quantities_block: count = ...") unless
  /// 1 <= count <= kBlockLanes.
  void quantities_block(const Vector6d* q, int count, Needs needs, QuantityBlock& out) const;

  const std::array<Haptic6RBody, 6>& bodies() const { return bodies_; }
  const Vector6d& max_velocity() const { return max_velocity_; }  ///< [rad/s]
  const Vector6d& max_torque() const { return max_torque_; }      ///< [N m]
  const std::array<double, 5>& links() const { return l_; }       ///< l1..l5 [m]
  /// DH row i evaluated for this design: (theta_offset [rad], d [m], a [m], alpha [rad]).
  Eigen::Vector4d dh_row(int i) const;
  const Haptic6RSetup& setup() const { return *setup_; }

 private:
  // The bodies of solve(), inverse_kinematics() and quantities(), compiled for AVX2/FMA and
  // baseline CPUs (hapsyn/accel/multiversion.hpp: GCC cannot multiversion the virtual solve(), and
  // clang exports no plain symbol for a multiversioned function). Each is defined in the file
  // of its wrapper: solve_sample and inverse_kinematics_impl in haptic6r_kinematics.cpp,
  // quantities_impl in haptic6r_dynamics.cpp.
  void solve_sample(const double* pose, Needs needs, SampleQuantities& out) const;
  SampleStatus configuration_impl(const double* pose, Vector6d& q, JointTrig& trig) const;
  SampleStatus configure(const double* pose, Vector6d& q, JointTrig& trig) const;  // inlined into both
  // The block kernels on lanes type L, inlined into each instruction set's entry
  // (hapsyn/accel/vector_dispatch.hpp); defined in haptic6r_block.cpp.
  template <class L>
  void solve_block_lanes(const PoseBlock& poses, Needs needs, QuantityBlock& out) const;
  template <class L>
  void quantities_block_lanes(const Vector6d* q, int count, Needs needs, QuantityBlock& out) const;
  template <class L>
  void fill_block(const L* cosine, const L* sine, const L& reachable, Needs needs, QuantityBlock& out) const;
  int inverse_kinematics_impl(const Eigen::Isometry3d& target, std::array<Vector6d, 8>& solutions,
                              std::array<JointTrig, 8>* trig) const;
  void quantities_impl(const Vector6d& q, Matrix6d* jacobian, Matrix6d* inertia, Vector6d* gravity) const;
  void ik_model(haptic6r_ik::IkModel& m) const;  // fills ik_ (in rebuild())

  const Haptic6RSetup* setup_ = nullptr;
  std::array<double, 5> l_{};
  std::array<double, 6> d_{}, a_{}, offset_{}, ca_{}, sa_{};
  std::array<Haptic6RBody, 6> bodies_;
  haptic6r_ik::IkModel ik_;  // the numbers the IK reads: once per design, not once per pose
  Vector6d max_velocity_ = Vector6d::Zero(), max_torque_ = Vector6d::Zero();
};

/// The "haptic6r" mechanism plugin.
class Haptic6R final : public Mechanism, public MechanismAcceleration {
 public:
  using Options = Haptic6ROptions;
  /// Reads the data files (see Haptic6RSetup::from_options, which throws).
  /// \param options validated options (Haptic6ROptions::declare), defaults filled.
  explicit Haptic6R(const Haptic6ROptions& options) : setup_(Haptic6RSetup::from_options(options)) {}

  std::unique_ptr<const MechanismModel> build(const double* design) const override;
  const MechanismModel* build_in(const double* design, MechanismScratch& scratch) const override;
  std::unique_ptr<MechanismScratch> make_scratch() const override;
  /// l (5, m), s (6, integer sizes 1..3), r (6, integer gear codes 1..6).
  std::vector<VariableDecl> variables() const override;
  /// "s_monotone_1".."s_monotone_5": g_i = s_{i+1} - s_i <= 0.
  std::vector<ConstraintDecl> constraints() const override;
  void evaluate_constraints(const double* design, const SampleSet& scene, double* g) const override;
  /// Requires 7 pose coordinates (x, y, z, qw, qx, qy, qz).
  void check_scene(const SampleSet& scene) const override;
  /// kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits | kNeedJointVelocity |
  /// kNeedJointAcceleration | kNeedVelocityTorque.
  Needs provides() const;
  MechanismSpecs specs() const override { return {provides(), {}}; }
  const MechanismAcceleration* acceleration() const override { return this; }
  /// The block kernel of `model` (a Haptic6RModel this mechanism built).
  void solve_block(const MechanismModel& model, const PoseBlock& poses, Needs needs, MechanismScratch& scratch,
                   QuantityBlock& out) const override {
    static_cast<const Haptic6RModel&>(model).solve_block(poses, needs, scratch, out);
  }

  /// True for needs within kNeedPose | kNeedJacobian | kNeedInertia | kNeedGravity |
  /// kNeedActuatorLimits (Haptic6RModel::solve_block); the demanded motion stays per sample.
  bool solves_blocks(Needs needs) const override;

  const Haptic6RSetup& setup() const { return setup_; }

 private:
  Haptic6RSetup setup_;
};

}  // namespace hapsyn::plugins
