#pragma once
/// \file
/// The "motion" scene: recorded (or synthetic) trajectories of the hand relative to the
/// shoulder as task-space samples, each with the twist and twist rate it demands of a
/// manipulator (Fennel, Zea, Hanebeck 2022, section VII-B: the validation on human motion).
///
/// Method, per recording (docs/design.md, section 10):
///  1. read (motion_recording.hpp: the hapsyn-motion CSV or BVH), map into the shoulder frame S
///     of the human arm model: p_S = C p_rec, R_P^S = C R_hand^rec H (C = recording_rotation,
///     H = hand_rotation);
///  2. resample to a uniform rate (slerp for orientations) when the time stamps are not uniform
///     within 1e-3 sampling intervals of the uniform grid (motion::is_uniform), or when the
///     option `rate` asks for another rate;
///  3. differentiate (motion_signal.hpp: differentiate): zero-phase Butterworth low-pass
///     (order `filter_order`, `cutoff`) of the pose, numerical derivative, the same filter again
///     after each differentiation; angular velocity and acceleration from the filtered rotation;
///  4. drop `trim` seconds at both ends (where the filter's edge error lives), keep every
///     `stride`-th sample;
///  5. map to the manipulator: the end-effector target T_E^B = T_S^B T_P^S T_E^P, exactly as
///     the human_arm scene does, and the twist of the point E in B, rows (omega, v):
///     omega_B = C_S^B omega_S, v_E = C_S^B (v_P + omega_S x r), r = R_P^S x_E^P, and its rate
///     (d omega_B/dt, a_E = C_S^B (a_P + alpha_S x r + omega_S x (omega_S x r))).
/// Samples: (x, y, z, qw, qx, qy, qz) [m] with qw >= 0. Attributes: twist and twist_rate
/// (hapsyn/quantities.hpp: kTwistAttribute, kTwistRateAttribute), time [s] (from the start of
/// the recording), shoulder_pose (7: palm position [m] and quaternion in S). Groupings:
/// subject, activity, trajectory ("<subject>/<activity>", or the file's relative path when two
/// recordings share that).
#include <hapsyn/options.hpp>
#include <hapsyn/scene.hpp>

#include <Eigen/Core>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// The options of the motion scene, declared once (`hapsyn describe motion`).
struct MotionOptions {
  std::string path;
  std::string bvh_shoulder_joint, bvh_hand_joint;
  double bvh_scale{};
  std::vector<std::vector<double>> recording_rotation, hand_rotation;
  double rate{}, cutoff{}, trim{};
  int filter_order{}, stride{};
  long long max_samples{};  ///< >= 1: samples of all recordings together, after resampling
  bool filter{};
  std::vector<double> x_S_B;
  std::vector<std::vector<double>> C_S_B, C_E_P;
  std::vector<double> x_E_P;

  static void declare(OptionDeclarations<MotionOptions>& d);
};

/// The motion scene. Built once per study; build() reads and processes every recording.
class MotionScene final : public Scene {
 public:
  using Options = MotionOptions;
  /// Checks what the declarations cannot: the path exists, the rotations are rotations.
  /// \throws Error("motion: options.<key> = <value>: <rule>")
  explicit MotionScene(const MotionOptions& options);
  /// \throws Error("motion: <file>[:<line>]: <what>: <rule>") for an unusable recording
  ///         (see motion_recording.hpp), one too short for the filter or the trim, or a
  ///         requested attribute it does not provide.
  SampleSet build(const SceneRequest& request) const override;

 private:
  MotionOptions options_;
  std::string path_;  // resolved
  Eigen::Matrix3d recording_rotation_, hand_rotation_, C_S_B_, C_E_P_;
  Eigen::Vector3d x_S_B_, x_E_P_;
};

}  // namespace hapsyn::plugins
