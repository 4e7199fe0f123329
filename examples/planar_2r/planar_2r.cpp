#include "planar_2r.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace planar_2r_example {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

void check_length(const char* name, double value) {
  if (!(std::isfinite(value) && value > 0.0)) {
    throw hapsyn::Error("planar_2r", std::string("design ") + name + " = " + hapsyn::Json(value).dump() +
                                         ": must be finite and > 0");
  }
}

}  // namespace

Planar2RModel::Planar2RModel(double l1, double l2, const Planar2ROptions& options)
    : l1_(l1),
      l2_(l2),
      q2_sign_(options.q2_sign == "negative" ? -1.0 : 1.0),
      singularity_tolerance_(options.singularity_tolerance) {
  check_length("l1", l1);
  check_length("l2", l2);
}

void Planar2RModel::forward(double q1, double q2, double* xy) const {
  xy[0] = l1_ * std::cos(q1) + l2_ * std::cos(q1 + q2);
  xy[1] = l1_ * std::sin(q1) + l2_ * std::sin(q1 + q2);
}

void Planar2RModel::jacobian(double q1, double q2, hapsyn::TaskJointMatrix& j) const {
  const double s1 = std::sin(q1), c1 = std::cos(q1), s12 = std::sin(q1 + q2), c12 = std::cos(q1 + q2);
  j.resize(2, 2);
  j << -l1_ * s1 - l2_ * s12, -l2_ * s12, l1_ * c1 + l2_ * c12, l2_ * c12;
}

void Planar2RModel::solve(const double* pose, hapsyn::Needs needs, hapsyn::MechanismScratch& /*scratch*/,
                          hapsyn::SampleQuantities& out) const {
  const double x = pose[0], y = pose[1];
  const double r2 = x * x + y * y;
  double c2 = (r2 - l1_ * l1_ - l2_ * l2_) / (2.0 * l1_ * l2_);
  // A sample on the reach boundary may compute |c2| a few ulps above 1: rounding, not out of reach.
  const double rounding = 8.0 * kEps * (r2 + l1_ * l1_ + l2_ * l2_) / (2.0 * l1_ * l2_);
  if (!(std::abs(c2) <= 1.0 + rounding)) {
    out.status = hapsyn::SampleStatus::kUnreachable;
    return;
  }
  c2 = std::clamp(c2, -1.0, 1.0);
  const double s2 = q2_sign_ * std::sqrt((1.0 - c2) * (1.0 + c2));
  const double q2 = std::atan2(s2, c2);
  const double q1 = std::atan2(y, x) - std::atan2(l2_ * s2, l1_ + l2_ * c2);
  out.q.resize(2);
  out.q << q1, q2;
  out.status = std::abs(s2) < singularity_tolerance_ ? hapsyn::SampleStatus::kSingular
                                                     : hapsyn::SampleStatus::kReachable;
  if (needs & hapsyn::kNeedJacobian) jacobian(q1, q2, out.jacobian);
}

std::vector<hapsyn::Segment> Planar2RModel::segments(const hapsyn::SampleSet& scene, int sample,
                                                    hapsyn::MechanismScratch& scratch) const {
  hapsyn::SampleQuantities q;
  solve(scene.pose(sample), hapsyn::kNeedPose, scratch, q);
  if (q.status == hapsyn::SampleStatus::kUnreachable) return {};
  const Eigen::Vector3d elbow(l1_ * std::cos(q.q[0]), l1_ * std::sin(q.q[0]), 0.0);
  const Eigen::Vector3d tip(scene.pose(sample)[0], scene.pose(sample)[1], 0.0);
  return {hapsyn::Segment{"links", {Eigen::Vector3d::Zero(), elbow, tip}}};
}

std::unique_ptr<const hapsyn::MechanismModel> Planar2R::build(const double* design) const {
  return std::make_unique<const Planar2RModel>(design[0], design[1], options_);
}

std::vector<hapsyn::VariableDecl> Planar2R::variables() const {
  const auto link = [](const char* name, const char* description) {
    hapsyn::VariableDecl v;
    v.name = name;
    v.description = description;
    v.unit = "m";
    v.default_lower = {0.05};
    v.default_upper = {0.5};
    v.hard_lower = {1e-4};
    v.hard_upper = {10.0};
    return v;
  };
  return {link("l1", "length of link 1 (base to elbow)"), link("l2", "length of link 2 (elbow to end effector)")};
}

void Planar2R::check_scene(const hapsyn::SampleSet& scene) const {
  if (scene.dimension() != 2) {
    throw hapsyn::Error("planar_2r", "scene samples have " + std::to_string(scene.dimension()) +
                                         " coordinates: the arm serves planar scenes of (x, y) [m] samples");
  }
  if (scene.size() == 0) throw hapsyn::Error("planar_2r", "scene has no samples");
}

}  // namespace planar_2r_example
