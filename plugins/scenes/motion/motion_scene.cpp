#include "motion_scene.hpp"

#include "motion_recording.hpp"
#include "motion_signal.hpp"

#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/quantities.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace hapsyn::plugins {

namespace {
constexpr const char* kName = "motion";
// The lowest cut-off, as a fraction of the Nyquist frequency, the Butterworth low-pass is
// designed and run at (see the check in process()).
constexpr double kMinCutoffOfNyquist = 1e-4;

// Default of the max_samples option: the paper's 9 hours at 120 Hz are 3.9 million samples.
constexpr long long kMotionMaxSamples = 10000000;
using RowMatrix = SampleSet::RowMatrix;

const std::vector<std::vector<double>> kIdentityRows = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

Eigen::Vector3d vector3(const std::vector<double>& v) { return Eigen::Vector3d(v[0], v[1], v[2]); }

// One recording after steps 1-4 of the method (motion_scene.hpp), in the shoulder frame S.
struct Processed {
  Eigen::VectorXd time;  // [s] from the recording's start
  motion::MotionDerivatives d;
};
}  // namespace

void MotionOptions::declare(OptionDeclarations<MotionOptions>& d) {
  using O = MotionOptions;
  d.describe(
      "Recorded hand (palm) motion relative to the shoulder as samples, each with the twist and twist rate it "
      "demands (Fennel 2022, section VII-B). Reads hapsyn-motion CSV and BVH files (one file or a folder of them), "
      "resamples to a uniform rate, low-passes with a zero-phase Butterworth filter, differentiates twice "
      "(re-filtering after each derivative) and maps the poses into the manipulator base B as the human_arm scene "
      "does. Samples (x, y, z, qw, qx, qy, qz) [m]; attributes twist, twist_rate, time, shoulder_pose; groupings "
      "subject, activity, trajectory. Method and formats: plugins/scenes/motion/README.md, docs/design.md section 10.");
  d.add(&O::path, "path", "motion/synthetic/csv",
        "A recording (.csv in the hapsyn-motion format, or .bvh) or a folder of them (searched recursively; the first "
        "folder level below it names the subject): absolute, relative to the current directory, or to hapsyn's share "
        "directory. The default is the shipped SYNTHETIC data set (share/motion/README.md).");
  d.add(&O::bvh_shoulder_joint, "bvh_shoulder_joint", "RightArm",
        "BVH: the joint at the shoulder; the reference frame sits there, oriented like its parent (the torso side).");
  d.add(&O::bvh_hand_joint, "bvh_hand_joint", "RightHand", "BVH: the joint whose frame is the hand (palm).");
  d.add(&O::bvh_scale, "bvh_scale", 0.01, "BVH: metres per file unit (0.01 for centimetres, 0.0254 for inches).")
      .greater_than(0)
      .unit("m");
  d.add(&O::recording_rotation, "recording_rotation", kIdentityRows,
        "Rotation C from the recording's shoulder frame to the arm model's shoulder frame S, as 3 rows: "
        "p_S = C p_rec, R_P^S = C R_hand^rec H.")
      .size(3)
      .row_size(3);
  d.add(&O::hand_rotation, "hand_rotation", kIdentityRows,
        "Rotation H of the palm frame P in the recording's hand frame, as 3 rows (identity when the recording gives "
        "the palm frame itself).")
      .size(3)
      .row_size(3);
  d.add(&O::rate, "rate", 0.0,
        "Sampling rate the recordings are brought to; 0 keeps each recording's own rate (its median rate when the "
        "time stamps jitter). Resampling interpolates positions linearly and orientations by slerp.")
      .range(0, 100000)
      .unit("Hz");
  d.add(&O::filter, "filter", true,
        "Low-pass the pose and each derivative (zero-phase Butterworth). Off only for noise-free analytic data.");
  d.add(&O::cutoff, "cutoff", 5.0, "Cut-off frequency of the Butterworth low-pass (the paper: 5 Hz).")
      .greater_than(0)
      .unit("Hz");
  d.add(&O::filter_order, "filter_order", 4, "Order of the Butterworth low-pass (the paper: 4).").range(1, 10);
  d.add(&O::trim, "trim", 0.0,
        "Seconds dropped at both ends of every recording after filtering, where the filter and the one-sided "
        "derivatives have their edge error (about 1 / cutoff).")
      .range(0, 86400)
      .unit("s");
  d.add(&O::stride, "stride", 1, "Keep every stride-th sample after processing (a cheaper, coarser validation).")
      .range(1, 1000000);
  d.add(&O::max_samples, "max_samples", kMotionMaxSamples,
        "Largest number of samples all recordings together may give after resampling (10 million: 23 hours at "
        "120 Hz). Each recording's count is computed from its duration and rate before it is resampled or "
        "filtered, and a scene that would exceed it is refused before the work (a rate typo, or time stamps with a "
        "tiny step, would ask for billions). Raise it deliberately for more data.")
      .minimum(1);
  d.add(&O::x_S_B, "x_S_B", {0.0, 0.0, -0.61},
        "Shoulder position in the manipulator base frame B (as the human_arm scene; the paper: 0.61 m below joint 1).")
      .size(3)
      .unit("m");
  d.add(&O::C_S_B, "C_S_B", upright_shoulder_to_base_rows(),
        "Rotation from the shoulder frame S to B, as 3 rows: x_B = x_S_B + C_S_B x_S, as the human_arm scene. The "
        "default seats the user upright facing +x_B (the rest arm hangs along -z_B, gravity), the transpose of the "
        "paper's printed C_S^B (docs/design.md section 4.3).")
      .size(3)
      .row_size(3);
  d.add(&O::C_E_P, "C_E_P", {{0.0, 0.0, 1.0}, {0.0, -1.0, 0.0}, {1.0, 0.0, 0.0}},
        "Rotation from the end-effector frame E to the palm frame P, as 3 rows (as the human_arm scene).")
      .size(3)
      .row_size(3);
  d.add(&O::x_E_P, "x_E_P", {0.0, 0.0, 0.0},
        "End-effector position in the palm frame P; the twist is the one of this point.")
      .size(3)
      .unit("m");
}

MotionScene::MotionScene(const MotionOptions& options) : options_(options) {
  path_ = find_data_path(kName, "path", options.path);
  recording_rotation_ = rotation_option(options.recording_rotation, "recording_rotation", kName);
  hand_rotation_ = rotation_option(options.hand_rotation, "hand_rotation", kName);
  C_S_B_ = rotation_option(options.C_S_B, "C_S_B", kName);
  C_E_P_ = rotation_option(options.C_E_P, "C_E_P", kName);
  x_S_B_ = vector3(options.x_S_B);
  x_E_P_ = vector3(options.x_E_P);
}

namespace {

// Step 1: the recording in S (positions and orientations as rows).
void to_shoulder_frame(motion::Recording& r, const Eigen::Matrix3d& c, const Eigen::Matrix3d& h) {
  for (Eigen::Index i = 0; i < r.position.rows(); ++i) {
    r.position.row(i) = (c * r.position.row(i).transpose()).transpose();
    const Eigen::Quaterniond q(r.quaternion(i, 0), r.quaternion(i, 1), r.quaternion(i, 2), r.quaternion(i, 3));
    const Eigen::Quaterniond mapped(c * q.normalized().toRotationMatrix() * h);
    r.quaternion.row(i) << mapped.w(), mapped.x(), mapped.y(), mapped.z();
  }
}

// Steps 2-4 for one recording.
// `before`: the samples of the recordings processed before this one (the max_samples budget).
Processed process(const motion::Recording& r, const MotionOptions& o, const Eigen::Matrix3d& c,
                  const Eigen::Matrix3d& h, long long before) {
  motion::Recording s = r;
  to_shoulder_frame(s, c, h);
  const bool uniform = motion::is_uniform(s.time);
  // A uniform recording's rate is its grid's (the median of rounded steps would be off by the
  // rounding: 4e-5 at 6 decimals and 120 Hz, scaling every derivative by as much).
  const double own_rate = uniform ? 1.0 / motion::mean_step(s.time) : motion::median_rate(s.time);
  const double rate = o.rate > 0.0 ? o.rate : own_rate;
  // The samples this recording gives, decided before any of them is made: a rate typo or time
  // stamps with a tiny step would ask for billions of samples (and memory to match).
  const double duration = s.time(s.time.size() - 1) - s.time(0);
  const bool resampling = !uniform || o.rate > 0.0;
  const double samples = resampling ? duration * rate + 1.0 : static_cast<double>(s.time.size());
  if (!(samples + static_cast<double>(before) <= static_cast<double>(o.max_samples))) {
    std::ostringstream m;
    m << r.file << ": ";
    if (resampling) {
      m << "resampling " << duration << " s at " << rate << " Hz" << (o.rate > 0.0 ? " (options.rate)" : " (its median rate)")
        << " gives " << samples << " samples";
    } else {
      m << samples << " samples";
    }
    if (before > 0) m << ", with the " << before << " of the recordings before it";
    m << ": more than options.max_samples = " << o.max_samples << " ("
      << (o.rate > 0.0 ? "lower options.rate" : "check the time stamps") << ", or raise max_samples deliberately)";
    throw Error(kName, m.str());
  }
  Eigen::VectorXd time = uniform ? Eigen::VectorXd::LinSpaced(s.time.size(), s.time(0), s.time(s.time.size() - 1))
                                 : s.time;
  Eigen::MatrixXd position = s.position, quaternion = s.quaternion;
  if (!uniform || o.rate > 0.0) {
    const motion::Uniform u = motion::resample(s.time, s.position, s.quaternion, rate);
    time = u.time;
    position = u.positions;
    quaternion = u.quaternions;
  }
  if (o.filter && !(o.cutoff < rate / 2.0)) {
    std::ostringstream m;
    m << "options.cutoff = " << o.cutoff << " Hz: must be below half the sampling rate of " << r.file << " ("
      << rate << " Hz)";
    throw Error(kName, m.str());
  }
  // A cut-off far below the Nyquist frequency puts the filter's poles within ~1e-4 of 1, where
  // the design and the filtering lose their accuracy in double precision: the output looks
  // smooth and is wrong (time stamps in ns read as s gave a 1 GHz "recording" and velocities
  // off by 10^3). Such a rate is far from any motion capture's anyway.
  if (o.filter && o.cutoff < kMinCutoffOfNyquist * rate / 2.0) {
    std::ostringstream m;
    m << "options.cutoff = " << o.cutoff << " Hz is " << o.cutoff / (rate / 2.0) << " of the Nyquist frequency of "
      << r.file << " (sampled at " << rate << " Hz" << (o.rate > 0.0 ? ", options.rate" : "")
      << "): the low-pass is accurate down to " << kMinCutoffOfNyquist
      << " of it; check the time stamps (in seconds, or as its time_unit line says), lower options.rate or raise options.cutoff";
    throw Error(kName, m.str());
  }
  const std::vector<motion::SecondOrderSection> sos =
      o.filter ? motion::butterworth_lowpass(o.filter_order, o.cutoff, rate) : std::vector<motion::SecondOrderSection>{};
  const Eigen::Index needed = std::max<Eigen::Index>(o.filter ? motion::filtfilt_min_samples(sos) : 3, 3);
  const Eigen::Index trimmed = static_cast<Eigen::Index>(std::floor(o.trim * rate + 1e-9));
  if (time.size() < needed + 2 * trimmed) {
    std::ostringstream m;
    m << r.file << ": " << time.size() << " samples at " << rate << " Hz (" << (time.size() - 1) / rate
      << " s): the filter and derivatives need at least " << needed << " samples"
      << (trimmed > 0 ? " plus " + std::to_string(2 * trimmed) + " trimmed (trim = " + std::to_string(o.trim) + " s)"
                      : std::string());
    throw Error(kName, m.str());
  }
  Processed p;
  p.d = motion::differentiate(position, quaternion, rate, sos);
  p.time = time.array() - time(0);
  // Step 4: trim both ends, then keep every stride-th sample.
  const Eigen::Index first = trimmed, count = time.size() - 2 * trimmed;
  std::vector<Eigen::Index> keep;
  for (Eigen::Index i = 0; i < count; i += o.stride) keep.push_back(first + i);
  const auto pick = [&](const Eigen::MatrixXd& m) {
    Eigen::MatrixXd out(static_cast<Eigen::Index>(keep.size()), m.cols());
    for (std::size_t k = 0; k < keep.size(); ++k) out.row(static_cast<Eigen::Index>(k)) = m.row(keep[k]);
    return out;
  };
  Eigen::MatrixXd t = pick(p.time);
  p.time = t.col(0);
  p.d.position = pick(p.d.position);
  p.d.velocity = pick(p.d.velocity);
  p.d.acceleration = pick(p.d.acceleration);
  p.d.quaternion = pick(p.d.quaternion);
  p.d.angular_velocity = pick(p.d.angular_velocity);
  p.d.angular_acceleration = pick(p.d.angular_acceleration);
  return p;
}

// Labels of the groupings, with a label's index kept by first appearance (deterministic).
struct Labels {
  SampleGrouping grouping;
  std::map<std::string, int> index;
  int of(const std::string& label) {
    const auto [it, fresh] = index.emplace(label, static_cast<int>(grouping.labels.size()));
    if (fresh) grouping.labels.push_back(label);
    return it->second;
  }
};

}  // namespace

SampleSet MotionScene::build(const SceneRequest& request) const {
  for (const std::string& a : request.attributes) {
    if (a != kTwistAttribute && a != kTwistRateAttribute && a != "time" && a != "shoulder_pose") {
      throw Error(kName, "attribute '" + a + "' is not provided (motion provides twist, twist_rate, time, shoulder_pose)");
    }
  }
  motion::BvhOptions bvh;
  bvh.shoulder_joint = options_.bvh_shoulder_joint;
  bvh.hand_joint = options_.bvh_hand_joint;
  bvh.scale = options_.bvh_scale;
  const std::vector<motion::Recording> recordings = motion::read_recordings(path_, bvh);

  std::vector<Processed> processed;
  Eigen::Index total = 0;
  for (const motion::Recording& r : recordings) {
    processed.push_back(process(r, options_, recording_rotation_, hand_rotation_, static_cast<long long>(total)));
    total += processed.back().time.size();
  }

  SampleSet set;
  set.coordinates = {"x", "y", "z", "qw", "qx", "qy", "qz"};
  set.unit = "m";
  set.poses.resize(total, 7);
  RowMatrix twist(total, 6), rate(total, 6), time(total, 1), shoulder(total, 7);
  Labels subject{{"subject", {}, {}}, {}}, activity{{"activity", {}, {}}, {}}, trajectory{{"trajectory", {}, {}}, {}};
  const Eigen::Quaterniond q_S_B(C_S_B_), q_E_P(C_E_P_);
  Json per_recording = Json::array();
  Eigen::Index row = 0;
  for (std::size_t k = 0; k < recordings.size(); ++k) {
    const motion::Recording& r = recordings[k];
    const Processed& p = processed[k];
    std::string label = r.subject + "/" + r.activity;
    if (trajectory.index.count(label)) label = r.file;  // two recordings of one subject and activity
    const int s = subject.of(r.subject), a = activity.of(r.activity), t = trajectory.of(label);
    for (Eigen::Index i = 0; i < p.time.size(); ++i, ++row) {
      const motion::MotionDerivatives& d = p.d;
      const Eigen::Quaterniond q_P_S(d.quaternion(i, 0), d.quaternion(i, 1), d.quaternion(i, 2), d.quaternion(i, 3));
      const Eigen::Matrix3d R = q_P_S.toRotationMatrix();
      const Eigen::Vector3d r_E = R * x_E_P_;  // palm -> E, in S
      const Eigen::Vector3d w = d.angular_velocity.row(i).transpose(), al = d.angular_acceleration.row(i).transpose();
      const Eigen::Vector3d x = x_S_B_ + C_S_B_ * (d.position.row(i).transpose() + r_E);
      Eigen::Quaterniond q = q_S_B * q_P_S * q_E_P;
      q.normalize();
      if (q.w() < 0.0) q.coeffs() = -q.coeffs();
      set.poses.row(row) << x.x(), x.y(), x.z(), q.w(), q.x(), q.y(), q.z();
      twist.row(row).head<3>() = (C_S_B_ * w).transpose();
      twist.row(row).tail<3>() = (C_S_B_ * (d.velocity.row(i).transpose() + w.cross(r_E))).transpose();
      rate.row(row).head<3>() = (C_S_B_ * al).transpose();
      rate.row(row).tail<3>() =
          (C_S_B_ * (d.acceleration.row(i).transpose() + al.cross(r_E) + w.cross(w.cross(r_E)))).transpose();
      time(row, 0) = p.time(i);
      shoulder.row(row) << d.position.row(i), d.quaternion.row(i);
      subject.grouping.of_sample.push_back(s);
      activity.grouping.of_sample.push_back(a);
      trajectory.grouping.of_sample.push_back(t);
    }
    per_recording.push_back({{"file", r.file}, {"trajectory", label}, {"samples", p.time.size()},
                             {"recorded_samples", r.time.size()}, {"duration_s", p.time.size() ? p.time(p.time.size() - 1) : 0.0}});
  }
  set.attributes[kTwistAttribute] = std::move(twist);
  set.attributes[kTwistRateAttribute] = std::move(rate);
  set.attributes["time"] = std::move(time);
  set.attributes["shoulder_pose"] = std::move(shoulder);
  set.groups = {std::move(subject.grouping), std::move(activity.grouping), std::move(trajectory.grouping)};
  set.info = {{"path", path_},
              {"recordings", per_recording.size()},
              {"samples", total},
              {"filter", options_.filter ? Json{{"type", "butterworth, zero-phase"}, {"order", options_.filter_order},
                                                {"cutoff_hz", options_.cutoff}}
                                         : Json("none")},
              {"per_recording", per_recording}};
  return set;
}

}  // namespace hapsyn::plugins
