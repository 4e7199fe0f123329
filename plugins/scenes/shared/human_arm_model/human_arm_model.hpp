#pragma once
/// \file
/// The 7-DOF human arm of Fennel et al. (IEEE ToH 2022, section V, Table II) as a model, shared
/// by the human_arm scene and the motion scene (plugins/scenes/shared/human_arm_model/README.md):
/// the arm file (loaded from a JSON arm file in share/human_arm/), the arm's forward kinematics,
/// Jacobian, manipulability, closed-form inverse kinematics for a given joint-3 angle, and the
/// principal axes of its velocity and acceleration ellipsoids.
///
/// Frames: S is the shoulder (DH frame 0), P the palm (DH frame 7). Twists are ordered
/// (omega, v). Angles are in rad, lengths in m, joint velocities in rad/s, joint accelerations in
/// rad/s^2 (the arm file holds degrees; they are converted once on load).
#include <hapsyn/json.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <string>
#include <utility>
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

/// Largest arm file read [bytes]: an arm file is a few kB.
constexpr std::uint64_t kHumanArmMaxArmFileBytes = 16u << 20;

/// Reads and parses an arm file. \throws Error("human_arm", "<file>: ...") when it is not JSON;
/// Error("human_arm: cannot read arm file <file>: ...") when it cannot be read;
/// Error("human_arm: arm file <file> is not a regular file (...)") for a FIFO, device or
/// directory; Error("human_arm: arm file <file> is <n> bytes, more than the ...") beyond
/// kHumanArmMaxArmFileBytes.
HumanArmData load_human_arm(const std::string& path);

/// The default arm file, relative to hapsyn's share directory: Table II of the paper.
constexpr const char* kHumanArmDefaultArmFile = "human_arm/fennel2022_right_arm.json";

/// Resolves an arm_file option: an absolute path as is; a relative path against the current
/// directory when it exists there, else against the share directory (installed or source tree).
/// "" means kHumanArmDefaultArmFile (the shipped fennel2022_right_arm.json).
/// \throws Error("human_arm", "options.arm_file = \"...\": no such file ...") when no candidate exists.
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
  /// The origins of DH frames 0 (the shoulder) to 7 (the palm) in S for joint angles q [rad]
  /// [m]; the last is forward(q)'s translation.
  std::array<Eigen::Vector3d, 8> frame_origins(const Vector7d& q) const;
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

}  // namespace hapsyn::plugins
