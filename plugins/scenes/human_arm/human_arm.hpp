#pragma once
/// \file
/// The 7-DOF human arm of Fennel et al. (IEEE ToH 2022, section V, Table II) and the scene of
/// palm poses it can reach: the arm model (loaded from a JSON arm file in share/human_arm/),
/// its forward kinematics, Jacobian, manipulability and closed-form inverse kinematics for a
/// given joint-3 angle, the orientation set, the position lattice, the scene and its disk cache.
///
/// Frames: S is the shoulder (DH frame 0), P the palm (DH frame 7), B the manipulator base and E
/// its end effector. Twists are ordered (omega, v). Angles are in rad, lengths in m, joint
/// velocities in rad/s, joint accelerations in rad/s^2 (the arm file holds degrees; they are
/// converted once on load).
#include <hapsyn/json.hpp>
#include <hapsyn/scene.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace hapsyn::plugins {

using Vector7d = Eigen::Matrix<double, 7, 1>;
using Matrix67d = Eigen::Matrix<double, 6, 7>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// One standard DH row: T = Rz(q + theta_offset) Tz(d) Tx(a) Rx(alpha).
struct DhRow {
  double theta_offset = 0.0;  ///< [rad]
  double d = 0.0;             ///< [m]
  double a = 0.0;             ///< [m]
  double alpha = 0.0;         ///< [rad]
};

/// Tolerance [rad] with which joint limits are compared: an angle that lands within it outside a
/// limit (rounding, wrapping an exact 80 deg) is clamped onto the limit instead of being dropped.
constexpr double kJointLimitTolerance = 1e-9;

/// A human arm as data: 7 revolute joints with limits, velocity and acceleration maxima.
struct HumanArmData {
  std::string name;    ///< e.g. "fennel2022_right_arm"
  std::string side;    ///< "right" or "left" (informative)
  std::string source;  ///< where the numbers come from
  std::string file;    ///< path it was loaded from ("" when parsed from memory)
  Json document;       ///< the parsed arm file (part of the scene cache key)
  std::array<DhRow, 7> dh;
  Vector7d lower, upper;         ///< joint limits [rad]
  Vector7d velocity_max;         ///< maximal joint velocities [rad/s]
  Vector7d acceleration_max;     ///< maximal joint accelerations [rad/s^2]
  std::vector<std::pair<std::string, double>> segments;  ///< named segment lengths [m]
};

/// Parses and validates an arm document. \param label the file name used in messages.
/// \throws Error("human_arm", "<label>: <json path> = <value>: <rule>") for a missing or
///         mistyped key, a non-finite number, lower > upper, a non-positive maximum or segment,
///         an unknown segment name, or a DH structure the closed-form IK cannot handle (it needs
///         a spherical shoulder at the origin, an elbow on the upper-arm axis, a spherical wrist:
///         a_1..a_6 = 0, d_1 = d_2 = d_4 = d_6 = 0, d_3 != 0, d_5 != 0, and sin(alpha_1),
///         sin(alpha_3) sin(alpha_4), sin(alpha_5) sin(alpha_6) bounded away from 0).
HumanArmData parse_human_arm(const Json& document, const std::string& label);

/// Reads and parses an arm file. \throws Error("human_arm", "<file>: ...") also when the file
/// cannot be read or is not JSON.
HumanArmData load_human_arm(const std::string& path);

/// Resolves an arm_file option: an absolute path as is; a relative path against the current
/// directory when it exists there, else against the share directory (installed or source tree).
/// "" means the shipped fennel2022_right_arm.json. \throws Error when no candidate exists.
std::string resolve_arm_file(const std::string& option);

/// One IK solution for a fixed joint-3 angle.
struct ArmIkSolution {
  Vector7d q;  ///< joint angles [rad], inside the limits
};

/// Kinematics of a HumanArmData (immutable; all methods are const and thread-safe).
class HumanArm {
 public:
  explicit HumanArm(HumanArmData data);

  const HumanArmData& data() const { return data_; }
  /// Upper bound [m] on the distance of the palm from the shoulder (|d_3| + |d_5| + |(a_7, d_7)|).
  double reach() const { return reach_; }

  /// Palm pose in S for joint angles q [rad].
  Eigen::Isometry3d forward(const Vector7d& q) const;
  /// Geometric Jacobian [(rad/s, m/s) per rad/s] of the palm in S, rows (omega, v).
  Matrix67d jacobian(const Vector7d& q) const;
  /// Yoshikawa's manipulability sqrt(det(J J^T)) (>= 0, never NaN).
  double manipulability(const Vector7d& q) const;

  /// All IK solutions for the palm pose (R [rotation S->P], p [m], both in S) with joint 3 at
  /// q3 [rad], inside the joint limits (kJointLimitTolerance; angles are wrapped to the limit
  /// range and clamped onto it). At most 8 (2 elbow x 2 shoulder x 2 wrist branches); returns
  /// their count. Degenerate branches (wrist centre on axis 1, wrist singular) pick the free
  /// angle at the middle of its limits, so the result is always finite.
  int solve(const Eigen::Matrix3d& R, const Eigen::Vector3d& p, double q3, ArmIkSolution out[8]) const;

  /// The grid of joint-3 values: `steps` equidistant values from lower to upper limit
  /// inclusive (steps = 1: the middle).
  std::vector<double> joint3_grid(int steps) const;

  /// The scene's IK: solve() over the joint-3 grid, keeping the solution of highest
  /// manipulability (the first in grid/branch order on ties). \returns false when unreachable.
  bool best(const Eigen::Matrix3d& R, const Eigen::Vector3d& p, const std::vector<double>& q3_grid,
            Vector7d* q, double* manipulability) const;

 private:
  HumanArmData data_;
  double reach_ = 0.0;
  Eigen::Vector3d palm_offset_;  // palm -> wrist centre offset in P: w = p - R * palm_offset_
};

/// M = U S from the SVD of J diag(scale) (J 6x7): the principal axes of the ellipsoid, columns
/// in descending singular-value order, each column's sign fixed so that its entry of largest
/// magnitude is positive (the SVD leaves it free). Used for M_v (scale = qdot_max) and M_a
/// (scale = qddot_max), section V-C.
Matrix6d ellipsoid_axes(const Matrix67d& J, const Vector7d& scale);

/// The orientation set: n unit quaternions (w, x, y, z) with w >= 0, near-uniform on SO(3).
/// A generalized Fibonacci grid in [0,1)^3, u_i = ((i + 1/2)/n, frac(i/phi), frac(i/phi^2)) with
/// phi the plastic number (the real root of x^3 = x + 1), mapped to the hemisphere by the
/// volume-preserving (constant Jacobian determinant) Hopf map
/// q = (sqrt(u1) cos(pi (u3 - 1/2)), sqrt(1 - u1) sin(2 pi u2), sqrt(1 - u1) cos(2 pi u2),
///      sqrt(u1) sin(pi (u3 - 1/2))).
std::vector<Eigen::Quaterniond> orientation_set(int n);

/// Lattice coordinates along one axis: k * step for k = -m..m, m = floor(extent/step + 1e-9).
std::vector<double> lattice_axis(double step, double extent);

/// Resolved options of the scene (see schema.json).
struct HumanArmSceneOptions {
  std::string arm_file;          ///< resolved absolute path
  double lattice_step = 0.1;     ///< [m]
  double lattice_extent = 0.7;   ///< [m], cube of +-extent around the shoulder
  int orientations = 505;
  int joint3_steps = 17;
  Eigen::Vector3d x_S_B{0.0, 0.0, -0.61};  ///< shoulder position in B [m]
  Eigen::Matrix3d C_S_B;                   ///< rotation S -> B
  Eigen::Matrix3d C_E_P;                   ///< rotation E -> P
  Eigen::Vector3d x_E_P{0.0, 0.0, 0.0};    ///< end-effector position in P [m]
  bool cache = true;
  std::string cache_directory;  ///< "" = $XDG_CACHE_HOME/hapsyn or ~/.cache/hapsyn
  int threads = 0;              ///< 0 = all cores
};

/// Parses scene options (defaults for missing keys). \throws Error("human_arm", "options.<key>
/// = <value>: <rule>") for unknown keys, wrong types, non-positive steps, non-rotations.
HumanArmSceneOptions parse_human_arm_scene_options(const Json& options);

/// The human_arm scene: the reachable palm poses of the arm on lattice x orientation set.
///
/// Samples are ordered by lattice point (x fastest, then y, then z, in S) and orientation index.
/// poses row = the end-effector target T_E^B = T_S^B T_P^S T_E^P as (x, y, z, qw, qx, qy, qz)
/// [m] with qw >= 0 (the palm pose in B when C_E^P = I, x_E^P = 0). Attributes: "shoulder_pose"
/// (7: palm position [m] and quaternion in S), "human_q" (7, rad), "manipulability" (1),
/// "lattice_index" (1), and on request "M_v", "M_a" (36 each, row-major 6x6 in B at E).
class HumanArmScene final : public Scene {
 public:
  explicit HumanArmScene(const Json& options);
  SampleSet build(const SceneRequest& request) const override;

  const HumanArm& arm() const { return arm_; }
  const HumanArmSceneOptions& options() const { return options_; }
  /// The text every cached file must carry to be used: options, arm document, format versions.
  std::string cache_key(bool ellipsoids) const;
  /// The cache file for that key ("" when caching is off or no cache directory is known).
  std::string cache_file(bool ellipsoids) const;

 private:
  HumanArmSceneOptions options_;
  HumanArm arm_;
};

/// 64-bit FNV-1a of bytes (cache file names and payload checksums).
std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t seed = 1469598103934665603ULL);

}  // namespace hapsyn::plugins
