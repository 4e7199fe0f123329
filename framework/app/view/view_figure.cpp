#include "view_figure.hpp"

#include <hapsyn/error.hpp>

#include <cmath>
#include <string>

namespace hapsyn_cli {
namespace {

using hapsyn::Json;

[[noreturn]] void refuse(const std::string& key, const Json& value, const std::string& rule) {
  std::string shown = value.dump();
  if (shown.size() > 80) shown = shown.substr(0, 77) + "...";
  throw hapsyn::Error("view", "the scene's info.figure" + (key.empty() ? "" : "." + key) + " = " + shown + ": " + rule);
}

bool is_point(const Json& p) {
  if (!p.is_array() || p.size() != 3) return false;
  for (const Json& c : p) {
    if (!c.is_number() || !std::isfinite(c.get<double>())) return false;
  }
  return true;
}

Json checked_body_lines(const Json& figure) {
  const Json& lines = figure.contains("body_lines") ? figure["body_lines"] : Json();
  if (!lines.is_array()) refuse("body_lines", lines, "must be a list of polylines");
  for (const Json& line : lines) {
    if (!line.is_array()) refuse("body_lines", lines, "every polyline must be a list of [x, y, z] points");
    for (const Json& p : line) {
      if (!is_point(p)) refuse("body_lines", lines, "every point must be 3 finite numbers");
    }
  }
  return lines;
}

}  // namespace

Json figure_json(const hapsyn::SampleSet& samples, int sample) {
  const auto info = samples.info.find("figure");
  if (info == samples.info.end() || sample < 0) return nullptr;
  const Json& figure = *info;
  if (!figure.is_object()) refuse("", figure, "must be an object");
  const Json& name = figure.contains("arm_attribute") ? figure["arm_attribute"] : Json();
  if (!name.is_string()) refuse("arm_attribute", name, "must name a per-sample attribute");
  const auto arm = samples.attributes.find(name.get<std::string>());
  if (arm == samples.attributes.end()) refuse("arm_attribute", name, "the scene has no attribute of that name");
  if (arm->second.cols() < 6 || arm->second.cols() % 3 != 0) {
    refuse("arm_attribute", name, "its attribute must have 3 columns per joint (x, y, z), at least 2 joints");
  }
  const Json& joints = figure.contains("arm_joints") ? figure["arm_joints"] : Json();
  if (!joints.is_array() || static_cast<Eigen::Index>(joints.size()) * 3 != arm->second.cols()) {
    refuse("arm_joints", joints, "must name the attribute's " + std::to_string(arm->second.cols() / 3) + " joints");
  }
  const Json& centre = figure.contains("head_centre") ? figure["head_centre"] : Json();
  if (!is_point(centre)) refuse("head_centre", centre, "must be 3 finite numbers");
  const Json& radius = figure.contains("head_radius") ? figure["head_radius"] : Json();
  if (!radius.is_number() || !(radius.get<double>() >= 0.0) || !std::isfinite(radius.get<double>())) {
    refuse("head_radius", radius, "must be a finite number >= 0");
  }
  Json points = Json::array();
  for (Eigen::Index c = 0; c + 2 < arm->second.cols(); c += 3) {
    const auto row = arm->second.row(sample);
    if (!row.segment<3>(c).allFinite()) refuse("arm_attribute", name, "its values at the drawn sample must be finite");
    points.push_back({row(c), row(c + 1), row(c + 2)});
  }
  return {{"arm", points},
          {"arm_joints", joints},
          {"body_lines", checked_body_lines(figure)},
          {"head_centre", centre},
          {"head_radius", radius}};
}

}  // namespace hapsyn_cli
