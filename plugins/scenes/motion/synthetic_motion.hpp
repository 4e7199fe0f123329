#pragma once
/// \file
/// Synthetic human arm motion: activities of daily living (reaching, wiping, lifting, drinking,
/// side_reach)
/// performed by the 7-DOF arm of Fennel et al. 2022 (the shared arm model,
/// shared/human_arm_model/human_arm_model.hpp), written in the
/// "hapsyn-motion" CSV format and as BVH. The data are made, not recorded: joint-space keyframes
/// with per-subject perturbations, joined by quintic (minimum-jerk) rest-to-rest segments whose
/// durations keep every joint below a fraction of Table II's maximal velocity and acceleration,
/// sampled at a fixed rate (optionally with time-stamp jitter), plus Gaussian measurement noise.
/// Everything is deterministic in the seed (own splitmix64 generator and Box-Muller transform).
///
/// Frames as in human_arm_model.hpp: S the shoulder (DH frame 0: x lateral to the right, y up, z
/// backwards for the right arm at q = 0 hanging down), P the palm (DH frame 7). Twists are ordered
/// (omega, v) and expressed in S. Units: s, m, rad (degrees only where named so).
#include "shared/human_arm_model/human_arm_model.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace hapsyn::plugins::motion {

/// A joint path through keyframes, joined by quintic rest-to-rest segments
/// q(s) = q_i + (q_{i+1} - q_i)(10 s^3 - 15 s^4 + 6 s^5), s = (t - t_i)/T_i: velocity and
/// acceleration are zero at every keyframe, each segment is monotone per joint (so it stays
/// between its keyframes), peak |qdot| = 1.875 |dq|/T, peak |qddot| = 5.7735 |dq|/T^2.
struct QuinticPath {
  std::vector<Vector7d> keyframes;  ///< [rad], one more than durations (a repeated keyframe is a hold)
  std::vector<double> durations;    ///< [s], each > 0

  /// Total duration [s].
  double duration() const;
  /// Start times [s] of the segments plus the end: durations.size() + 1 values from 0.
  std::vector<double> boundaries() const;
  /// Position [rad], velocity [rad/s], acceleration [rad/s^2] at time t [s]; before 0 and after
  /// duration() the path rests at its first / last keyframe. Any output pointer may be null.
  void evaluate(double t, Vector7d* q, Vector7d* qdot, Vector7d* qddot) const;
};

/// The generator's knobs; the defaults made share/motion/synthetic/.
struct SyntheticOptions {
  std::uint64_t seed = 2022;
  int subjects = 6;                    ///< S01, S02, ...
  double duration_s = 10;              ///< [s] target length of each activity (longer only if the speed limits need it)
  double rate_hz = 120;                ///< [Hz] sampling rate
  double position_noise_m = 0.5e-3;    ///< [m] Gaussian sigma per axis
  double orientation_noise_deg = 0.2;  ///< [deg] Gaussian sigma per axis of a rotation vector
  double speed_fraction = 0.5;         ///< peak |qdot|, |qddot| <= fraction * Table II maxima, in (0, 1]
  double time_jitter_s = 1e-3;         ///< [s] uniform +- jitter of the time stamps of jittered subjects
  int first_jittered_subject = 5;      ///< 1-based: subjects from this one on have jittered time stamps
  double keyframe_sigma_deg = 3;       ///< [deg] per-subject Gaussian perturbation of each keyframe joint (cut at 2 sigma)
  double keyframe_margin_deg = 5;      ///< [deg] keyframes stay this far inside the joint limits
};

/// One subject performing one activity: the exact (noise-free) motion and what a tracker would
/// have measured. All matrices have one row per sample.
struct SyntheticTrajectory {
  std::string subject;   ///< "S01", ...
  std::string activity;  ///< "reaching", "wiping", "lifting", "drinking", "side_reach"
  double arm_scale = 1;  ///< segment-length factor of this subject's arm (scaled_arm)
  bool jittered = false; ///< time stamps jittered around the nominal 1/rate_hz grid
  double rate_hz = 120;  ///< [Hz] nominal sampling rate (the BVH frame time is its inverse)
  QuinticPath path;      ///< the joint path the samples were taken from
  Eigen::VectorXd time;             ///< [s], strictly increasing, first 0
  Eigen::MatrixXd q, qdot, qddot;   ///< n x 7 [rad, rad/s, rad/s^2]
  Eigen::MatrixXd position;         ///< n x 3 palm position in S [m], noise-free
  Eigen::MatrixXd quaternion;       ///< n x 4 (w, x, y, z), rotation P -> S, noise-free, sign continuous (first w >= 0)
  Eigen::MatrixXd twist;            ///< n x 6 exact palm twist in S, (omega, v) = J(q) qdot [rad/s, m/s]
  Eigen::MatrixXd twist_rate;       ///< n x 6 (omega_dot, a) = J qddot + Jdot qdot [rad/s^2, m/s^2]
  Eigen::MatrixXd noisy_position;   ///< n x 3 [m]: position + N(0, sigma_p^2 I)
  Eigen::MatrixXd noisy_quaternion; ///< n x 4: Exp(r) R with r ~ N(0, sigma_r^2 I) in S, sign continuous
};

/// The activities, in the order make_synthetic_motion produces them.
std::vector<std::string> synthetic_activities();

/// Segment-length factor of subject `index` (0-based), uniform in [0.90, 1.10], from the seed only.
double subject_arm_scale(std::uint64_t seed, int index);

/// The arm with every DH length d, a and every named segment multiplied by `scale` (> 0); the
/// name gets a " x<scale>" suffix. Angles, limits and maxima are unchanged.
HumanArmData scaled_arm(const HumanArmData& arm, double scale);

/// All subjects x all activities (subject-major). Subject i uses scaled_arm(arm,
/// subject_arm_scale(seed, i)); each (subject, activity) draws from its own random streams, so a
/// trajectory does not depend on how many subjects are made. \throws Error("motion", ...) on
/// options out of range (subjects < 1, non-positive duration or rate, negative noise, speed
/// fraction outside (0, 1], jitter >= half the sampling period).
std::vector<SyntheticTrajectory> make_synthetic_motion(const HumanArmData& arm, const SyntheticOptions& options);

/// The trajectory played k times faster (k > 0): time / k, qdot * k, qddot * k^2, twist * k,
/// twist_rate * k^2, path durations / k, rate_hz * k; poses unchanged. \throws Error("motion", ...) for k <= 0.
SyntheticTrajectory speed_up(const SyntheticTrajectory& trajectory, double k);

/// The "hapsyn-motion 1" CSV text of the noisy poses: header lines `# hapsyn-motion 1`,
/// `# subject: `, `# activity: `, `# unit: m`, `# time_unit: s`, the column row
/// `time,x,y,z,qw,qx,qy,qz`, then one row per sample (time and position 6 decimals, quaternion 7).
std::string motion_csv(const SyntheticTrajectory& trajectory);

/// The fixed rotation from the BVH torso frame (Y up, the subject facing +Z, X to the subject's
/// left) to S: v_S = C v_bvh. It is diag(-1, 1, -1).
Eigen::Matrix3d bvh_recording_rotation();

/// Size of a BVH unit [m] in motion_bvh's output (centimetres).
constexpr double kBvhUnit = 0.01;

/// The BVH text of the noisy poses (units cm, frame time 1/rate of the nominal grid; the poses of
/// a jittered subject are those at its jittered times). Skeleton Hips (6 channels, constant) ->
/// Spine -> RightShoulder (zero rotations) -> RightArm (shoulder: DH joints 1-3) -> RightForeArm
/// (elbow: joint 4) -> RightHand (6 channels: its position channels absorb the wrist's palm
/// offset and the position noise) -> End Site; rotation channels Zrotation Xrotation Yrotation.
/// RightHand's global frame expressed in the shoulder frame (origin RightArm, axes of
/// RightShoulder) is (C^T p / kBvhUnit, C^T R) for the noisy palm pose (p, R) in S.
/// \param arm_of_subject the scaled arm the trajectory was made with (segment OFFSETs).
std::string motion_bvh(const SyntheticTrajectory& trajectory, const HumanArmData& arm_of_subject);

/// Z-X-Y Euler angles [rad] (a, b, c) with R = Rz(a) Rx(b) Ry(c), b in [-pi/2, pi/2]; exact to
/// rounding also at and near gimbal lock (cos b = 0, where only a + c or a - c is determined).
Eigen::Vector3d euler_zxy(const Eigen::Matrix3d& R);

}  // namespace hapsyn::plugins::motion
