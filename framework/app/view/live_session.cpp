#include "live_session.hpp"

#include "motion_signal.hpp"
#include "replay_data.hpp"
#include "view_json.hpp"
#include "view_source.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/internal/maps.hpp>
#include <hapsyn/scene.hpp>

#include <cmath>
#include <sstream>

namespace hapsyn_cli {
namespace {

using hapsyn::Json;
namespace motion = hapsyn::plugins::motion;

constexpr hapsyn::Needs kRateNeeds = hapsyn::kNeedJointVelocity | hapsyn::kNeedJointAcceleration |
                                     hapsyn::kNeedVelocityTorque | hapsyn::kNeedInertia | hapsyn::kNeedGravity |
                                     hapsyn::kNeedActuatorLimits;
constexpr const char* kFeasibilityMetric = "motion_feasibility";

// A value for a message: its JSON, cut to a readable length.
std::string shown(const Json& value) {
  std::string text = value.dump();
  return text.size() > 60 ? text.substr(0, 57) + "..." : text;
}

[[noreturn]] void refuse(const std::string& field, const Json& value, const std::string& rule) {
  throw hapsyn::Error("live", "message." + field + " = " + shown(value) + ": " + rule);
}

// `value` (an element of `whole`, the field's value) as a finite number.
double finite_number(const Json& value, const std::string& field, const std::string& rule, const Json& whole) {
  if (!value.is_number() || !std::isfinite(value.get<double>())) refuse(field, whole, rule);
  return value.get<double>();
}

Eigen::Quaterniond orientation(const Json& value) {
  const std::string rule = "must be a unit quaternion [w, x, y, z] or a rotation matrix [[r11, r12, r13], [...], [...]]";
  if (!value.is_array() || (value.size() != 4 && value.size() != 3)) refuse("orientation", value, rule);
  if (value.size() == 4) {
    double c[4];
    for (std::size_t k = 0; k < 4; ++k) c[k] = finite_number(value[k], "orientation", rule, value);
    const Eigen::Quaterniond q(c[0], c[1], c[2], c[3]);
    if (!(std::abs(q.norm() - 1.0) <= 1e-3)) refuse("orientation", value, "a quaternion's norm must be 1 within 1e-3");
    return q.normalized();
  }
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i) {
    const Json& row = value[static_cast<std::size_t>(i)];
    if (!row.is_array() || row.size() != 3) refuse("orientation", value, rule);
    for (int j = 0; j < 3; ++j) r(i, j) = finite_number(row[static_cast<std::size_t>(j)], "orientation", rule, value);
  }
  const double off = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(off <= 1e-4) || !(r.determinant() > 0.0)) {
    refuse("orientation", value, "a rotation matrix must be orthonormal within 1e-4 with determinant +1");
  }
  return Eigen::Quaterniond(r).normalized();
}

std::vector<std::vector<double>> rows_of(const Json& options, const char* key) {
  return options.at(key).get<std::vector<std::vector<double>>>();
}

Eigen::Vector3d vector_of(const Json& options, const char* key) {
  const std::vector<double> v = options.at(key).get<std::vector<double>>();
  return Eigen::Vector3d(v.at(0), v.at(1), v.at(2));
}

Json vector_json(const double* v, int n) {
  Json out = Json::array();
  for (int i = 0; i < n; ++i) out.push_back(v[i]);
  return out;
}

// Parses and checks a message. \throws hapsyn::Error("live", ...) naming the field, its value
// and the rule.
void parse_live_message(std::string_view message, double& t, Eigen::Vector3d& position, Eigen::Quaterniond& rotation) {
  const Json doc = Json::parse(message.begin(), message.end(), nullptr, false);
  if (doc.is_discarded()) throw hapsyn::Error("live", "the message is not JSON: send {\"t\": s, \"position\": [x, y, z], \"orientation\": [w, x, y, z]}");
  if (!doc.is_object()) throw hapsyn::Error("live", "the message = " + shown(doc) + ": must be a JSON object {\"t\", \"position\", \"orientation\"}");
  for (const auto& item : doc.items()) {
    if (item.key() != "t" && item.key() != "position" && item.key() != "orientation") {
      refuse(item.key(), item.value(), "unknown key (known: t, position, orientation)");
    }
  }
  for (const char* key : {"t", "position", "orientation"}) {
    if (!doc.contains(key)) throw hapsyn::Error("live", std::string("message.") + key + ": missing (a message has t, position, orientation)");
  }
  t = finite_number(doc["t"], "t", "must be a finite number [s]", doc["t"]);
  const Json& p = doc["position"];
  if (!p.is_array() || p.size() != 3) refuse("position", p, "must be [x, y, z] [m]");
  for (std::size_t k = 0; k < 3; ++k) position[static_cast<Eigen::Index>(k)] = finite_number(p[k], "position", "must be 3 finite numbers [m]", p);
  rotation = orientation(doc["orientation"]);
}

}  // namespace

LiveModel::LiveModel(std::shared_ptr<const ViewSource> source) : source_(std::move(source)) {
  const hapsyn::Problem& problem = *source_->study.problem;
  const Json& scene = source_->study.resolved["scene"];
  if (scene.value("plugin", std::string()) != "motion") {
    unavailable_ = "the study's scene is not a motion scene: live frames need its frames and filter";
    return;
  }
  const Json& o = scene["options"];
  recording_rotation_ = hapsyn::rotation_option(rows_of(o, "recording_rotation"), "recording_rotation", "motion");
  hand_rotation_ = hapsyn::rotation_option(rows_of(o, "hand_rotation"), "hand_rotation", "motion");
  C_S_B_ = hapsyn::rotation_option(rows_of(o, "C_S_B"), "C_S_B", "motion");
  C_E_P_ = hapsyn::rotation_option(rows_of(o, "C_E_P"), "C_E_P", "motion");
  x_S_B_ = vector_of(o, "x_S_B");
  x_E_P_ = vector_of(o, "x_E_P");
  filter_ = o.at("filter").get<bool>();
  filter_order_ = o.at("filter_order").get<int>();
  cutoff_ = o.at("cutoff").get<double>();
  model_ = problem.mechanism().build(source_->design.data());
  const hapsyn::Needs provided = problem.mechanism().specs().provides;
  rate_needs_ = (provided & kRateNeeds) == kRateNeeds ? kRateNeeds : 0;
}

hapsyn::Json LiveModel::shoulder_frame() const {
  if (!unavailable_.empty()) return nullptr;
  Json rows = Json::array();
  for (int i = 0; i < 3; ++i) rows.push_back({C_S_B_(i, 0), C_S_B_(i, 1), C_S_B_(i, 2)});
  return {{"C_S_B", rows}, {"x_S_B", {x_S_B_.x(), x_S_B_.y(), x_S_B_.z()}}};
}

LiveSession::LiveSession(const LiveModel& model) : model_(model) {
  if (!model_.unavailable().empty()) return;
  scratch_ = model_.source_->study.problem->mechanism().make_scratch();
  one_.coordinates = {"x", "y", "z", "qw", "qx", "qy", "qz"};
  one_.unit = "m";
  one_.poses.setZero(1, 7);
  one_.attributes[hapsyn::kTwistAttribute].setZero(1, 6);
  one_.attributes[hapsyn::kTwistRateAttribute].setZero(1, 6);
}

std::string LiveSession::answer(std::string_view message, bool* is_frame) {
  if (is_frame) *is_frame = false;
  try {
    if (!model_.unavailable().empty()) throw hapsyn::Error("live", model_.unavailable());
    double t = 0.0;
    Eigen::Vector3d position;
    Eigen::Quaterniond rotation;
    parse_live_message(message, t, position, rotation);
    if (!window_.empty() && !(t > window_.back().t)) {
      std::ostringstream m;
      m.precision(17);
      m << "message.t = " << t << " after " << window_.back().t << ": time stamps must increase within a connection "
        << "(reconnect to start a new stream)";
      throw hapsyn::Error("live", m.str());
    }
    // Into S as the motion scene maps a recording: p_S = C p, R_P^S = C R H.
    const Pose pose{t, model_.recording_rotation_ * position,
                    Eigen::Quaterniond(model_.recording_rotation_ * rotation.toRotationMatrix() * model_.hand_rotation_)};
    window_.push_back(pose);
    while (static_cast<int>(window_.size()) > LiveModel::kMaxWindow ||
           (window_.size() > 1 && window_.back().t - window_.front().t > LiveModel::kWindowSeconds)) {
      window_.pop_front();
    }
    std::string text = frame(pose).dump();
    if (is_frame) *is_frame = true;
    return text;
  } catch (const hapsyn::Error& e) {
    return Json{{"error", e.what()}}.dump();
  }
}

bool LiveSession::rates(double* twist, double* twist_rate, std::string& how) const {
  const Eigen::Index n = static_cast<Eigen::Index>(window_.size());
  if (n < 3) {
    how = "waiting: " + std::to_string(n) + " pose(s), the derivatives need 3 or more";
    return false;
  }
  Eigen::VectorXd time(n);
  Eigen::MatrixXd position(n, 3), quaternion(n, 4);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Pose& p = window_[static_cast<std::size_t>(i)];
    time(i) = p.t;
    position.row(i) = p.position.transpose();
    quaternion.row(i) << p.rotation.w(), p.rotation.x(), p.rotation.y(), p.rotation.z();
  }
  // As the scene: a uniform stream's rate is its grid's, another is resampled at its median rate.
  const bool uniform = motion::is_uniform(time);
  const double rate = uniform ? 1.0 / motion::mean_step(time) : motion::median_rate(time);
  if (model_.filter_ && !(model_.cutoff_ < rate / 2.0)) {
    how = "none: the stream's rate " + std::to_string(rate) + " Hz is not above twice the filter's cut-off " +
          std::to_string(model_.cutoff_) + " Hz";
    return false;
  }
  const std::vector<motion::SecondOrderSection> sos =
      model_.filter_ ? motion::butterworth_lowpass(model_.filter_order_, model_.cutoff_, rate)
                     : std::vector<motion::SecondOrderSection>{};
  if (!uniform) {
    motion::Uniform u = motion::resample(time, position, quaternion, rate);
    position = std::move(u.positions);
    quaternion = std::move(u.quaternions);
  }
  const Eigen::Index needed = std::max<Eigen::Index>(3, motion::filtfilt_min_samples(sos));
  if (position.rows() < needed) {
    how = "waiting: " + std::to_string(position.rows()) + " of the " + std::to_string(needed) +
          " poses the filter needs";
    return false;
  }
  const motion::MotionDerivatives d = motion::differentiate(position, quaternion, rate, sos);
  const Eigen::Index k = d.position.rows() - 1;
  const Eigen::Quaterniond q(d.quaternion(k, 0), d.quaternion(k, 1), d.quaternion(k, 2), d.quaternion(k, 3));
  // The twist of E in B and its rate, as the motion scene maps them (motion_scene.hpp, step 5).
  const Eigen::Vector3d r_E = q.toRotationMatrix() * model_.x_E_P_;
  const Eigen::Vector3d w = d.angular_velocity.row(k).transpose(), al = d.angular_acceleration.row(k).transpose();
  const Eigen::Matrix3d& C = model_.C_S_B_;
  Eigen::Map<Eigen::Matrix<double, 6, 1>> tw(twist), tr(twist_rate);
  tw.head<3>() = C * w;
  tw.tail<3>() = C * (d.velocity.row(k).transpose() + w.cross(r_E));
  tr.head<3>() = C * al;
  tr.tail<3>() = C * (d.acceleration.row(k).transpose() + al.cross(r_E) + w.cross(w.cross(r_E)));
  std::ostringstream m;
  m << "filtered over the last " << position.rows() << " poses at " << rate << " Hz"
    << (uniform ? "" : " (resampled)");
  how = m.str();
  return true;
}

Json LiveSession::frame(const Pose& p) {
  const hapsyn::Problem& problem = *model_.source_->study.problem;
  // The end-effector target in B, as the motion scene maps a pose (motion_scene.hpp, step 5).
  const Eigen::Vector3d r_E = p.rotation.toRotationMatrix() * model_.x_E_P_;
  const Eigen::Vector3d x = model_.x_S_B_ + model_.C_S_B_ * (p.position + r_E);
  Eigen::Quaterniond target = Eigen::Quaterniond(model_.C_S_B_) * p.rotation * Eigen::Quaterniond(model_.C_E_P_);
  target.normalize();
  if (target.w() < 0.0) target.coeffs() = -target.coeffs();
  one_.poses.row(0) << x.x(), x.y(), x.z(), target.w(), target.x(), target.y(), target.z();
  double* twist = one_.attributes[hapsyn::kTwistAttribute].row(0).data();
  double* twist_rate = one_.attributes[hapsyn::kTwistRateAttribute].row(0).data();
  std::string how;
  const bool with_rates = model_.rate_needs_ != 0 && rates(twist, twist_rate, how);
  if (model_.rate_needs_ == 0) how = "none: the mechanism does not compute joint rates and dynamics";

  hapsyn::SampleQuantities q;
  q.sample = 0;
  q.scene = &one_;
  q.twist = with_rates ? twist : nullptr;
  q.twist_rate = with_rates ? twist_rate : nullptr;
  model_.model_->solve(one_.pose(0), with_rates ? model_.rate_needs_ : hapsyn::kNeedPose, *scratch_, q);
  const bool reachable = q.status == hapsyn::SampleStatus::kReachable;
  const int joints = static_cast<int>(q.q.size());

  Json frame = {{"t", p.t}, {"status", hapsyn::to_string(q.status)}, {"position", {x.x(), x.y(), x.z()}}, {"rates", how}};
  frame["q"] = reachable ? vector_json(q.q.data(), joints) : Json(nullptr);
  frame["segments"] = segments_json(model_.model_->segments(one_, 0, *scratch_));
  frame["qdot_ratio"] = nullptr;
  frame["tau_ratio"] = nullptr;
  frame["feasible"] = nullptr;
  frame["checks"] = Json::object();
  if (!with_rates) return frame;
  if (reachable) {
    std::vector<double> qdot(static_cast<std::size_t>(joints)), tau(static_cast<std::size_t>(joints));
    limit_ratios(q, qdot.data(), tau.data());
    frame["qdot_ratio"] = qdot;
    frame["tau_ratio"] = tau;
  }
  // The motion_feasibility metrics' own per-sample values at this pose.
  const std::vector<std::string> columns = hapsyn::local_columns(problem);
  std::size_t c = 0;
  bool any = false, feasible = true;
  for (const hapsyn::MetricEntry& m : problem.metrics()) {
    const std::size_t count = m.metric->locals().size();
    if (m.plugin == kFeasibilityMetric) {
      locals_.assign(count, 0.0);
      m.metric->local(q, locals_.data());
      for (std::size_t k = 0; k < count; ++k) {
        frame["checks"][columns[c + k]] = locals_[k];
        feasible = feasible && locals_[k] == 1.0;
      }
      any = true;
    }
    c += count;
  }
  if (any) frame["feasible"] = feasible ? 1 : 0;
  return frame;
}

}  // namespace hapsyn_cli
