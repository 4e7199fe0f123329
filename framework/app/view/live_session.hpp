#pragma once
// The virtual prototype's live mode (`hapsyn view`, WebSocket /live): a tracker bridge sends
// the hand pose with a time stamp, one JSON message per pose; each is answered with a frame of
// the study's mechanism at that pose: its joint values and drawing, and per joint the rate and
// torque against the actuator limits, from the derivatives of the stream filtered as the motion
// scene filters a recording (motion_signal.hpp: differentiate).
#include <hapsyn/json.hpp>
#include <hapsyn/mechanism.hpp>
#include <hapsyn/problem.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <deque>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace hapsyn_cli {

struct ViewSource;

/// What every live connection of one study shares, immutable: the study's mechanism built at the
/// design, the motion scene's frame mapping and filter (its resolved options).
class LiveModel {
 public:
  /// Largest number of poses a connection keeps for the derivatives (the newest ones).
  static constexpr int kMaxWindow = 512;
  /// Seconds of the stream the derivatives are computed over (the newest poses; at most
  /// kMaxWindow of them).
  static constexpr double kWindowSeconds = 2.0;

  /// \throws nothing for a study without a motion scene: unavailable() then says why.
  explicit LiveModel(std::shared_ptr<const ViewSource> source);
  /// "" when live frames can be computed, else why not (a study without a motion scene).
  const std::string& unavailable() const { return unavailable_; }
  /// Where the arm model's shoulder frame S sits in the base B (x_B = x_S_B + C_S_B x_S): the
  /// page places the study around a headset's user with it. {"C_S_B": 3 rows, "x_S_B": [m]};
  /// null when unavailable.
  hapsyn::Json shoulder_frame() const;

 private:
  friend class LiveSession;
  std::shared_ptr<const ViewSource> source_;
  std::string unavailable_;
  std::unique_ptr<const hapsyn::MechanismModel> model_;
  hapsyn::Needs rate_needs_ = 0;    // what the bars need, when the mechanism provides it
  Eigen::Matrix3d recording_rotation_, hand_rotation_, C_S_B_, C_E_P_;
  Eigen::Vector3d x_S_B_, x_E_P_;
  bool filter_ = true;
  int filter_order_ = 4;
  double cutoff_ = 5.0;
};

/// One connection's state: the newest poses of its stream, the mechanism's scratch.
///
/// The message (JSON text, at most ServerSettings::max_message_bytes):
///   {"t": seconds, "position": [x, y, z], "orientation": [w, x, y, z] or [[r11, r12, r13], ...]}
/// the palm pose [m] in the frame the study's recordings use (mapped by the motion scene's
/// recording_rotation and hand_rotation into the arm model's shoulder frame S, then into the
/// base B by C_S_B, x_S_B, C_E_P, x_E_P, as the scene maps a recording); t strictly increasing
/// within a connection. The quaternion's norm must be 1 within 1e-3 (it is normalised), a matrix
/// a rotation within 1e-4 (as the recording readers accept).
///
/// The frame: {"t", "status", "q" (null unless reachable), "segments": [{"name", "points"}],
/// "position" (the end-effector target in B), "qdot_ratio", "tau_ratio" (|qdot|/limit,
/// |tau|/limit per joint with tau = H qddot + C qdot + g; null until the window holds enough
/// poses for the filter, or when not reachable), "feasible" (1 when every motion_feasibility
/// per-sample value is 1, 0 otherwise, null without rates or that metric), "checks" (those
/// values by samples.csv column name), "rates" (how they were obtained, or why there are none)}.
/// The pose itself is used as received (the arm follows the hand without the filter's delay or
/// edge error); its velocity and acceleration are those of differentiate() over the window,
/// taken at its newest sample, where the zero-phase filter has its end effect (motion_scene.hpp).
/// A bad message gets {"error": "live: ..."} naming the field, its value and the rule; the
/// connection's state is unchanged by it.
class LiveSession {
 public:
  explicit LiveSession(const LiveModel& model);
  /// The frame answering one text message (an error frame for a bad one; `is_frame` tells
  /// which). Never throws for bad input; allocates (a frame is a JSON document).
  std::string answer(std::string_view message, bool* is_frame = nullptr);

 private:
  struct Pose {
    double t;
    Eigen::Vector3d position;     // palm, in S
    Eigen::Quaterniond rotation;  // palm, in S
  };
  hapsyn::Json frame(const Pose& pose);
  // The filtered twist and twist rate of the window's newest pose in B; false (and why) when
  // the window is too short.
  bool rates(double* twist, double* twist_rate, std::string& how) const;

  const LiveModel& model_;
  std::unique_ptr<hapsyn::MechanismScratch> scratch_;
  hapsyn::SampleSet one_;  // the current pose as a one-sample scene (for solve and segments)
  std::deque<Pose> window_;
  std::vector<double> locals_;
};

}  // namespace hapsyn_cli
