#include "planar_square.hpp"

#include <hapsyn/error.hpp>

#include <cmath>
#include <string>

namespace hapsyn::plugins {
namespace {

constexpr const char* kName = "planar_square";

std::string show(double value) { return Json(value).dump(); }

double positive_option(const Json& options, const char* key, double fallback) {
  const auto it = options.find(key);
  if (it == options.end()) return fallback;
  if (!it->is_number()) {
    throw Error(kName, std::string("options.") + key + " = " + it->dump() + ": must be a number");
  }
  const double value = it->get<double>();
  if (!std::isfinite(value) || !(value > 0.0)) {
    throw Error(kName, std::string("options.") + key + " = " + show(value) + ": must be finite and > 0");
  }
  return value;
}

}  // namespace

PlanarSquare::PlanarSquare(const Json& options) {
  if (!options.is_null()) {
    if (!options.is_object()) throw Error(kName, "options = " + options.dump() + ": must be an object");
    for (const auto& item : options.items()) {
      if (item.key() != "side" && item.key() != "step") {
        throw Error(kName, "options." + item.key() + ": unknown option (known: side, step)");
      }
    }
    side_ = positive_option(options, "side", side_);
    step_ = positive_option(options, "step", step_);
  }
  if (step_ > side_) {
    throw Error(kName, "options.step = " + show(step_) + ": must be <= side (" + show(side_) + ")");
  }
  const double ratio = side_ / step_;
  const double steps = std::round(ratio);
  if (!(std::abs(ratio - steps) <= 1e-9 * ratio)) {
    throw Error(kName, "options.step = " + show(step_) + ": must divide side (" + show(side_) +
                           ") into whole steps");
  }
  const double per_axis = steps + 1.0;
  if (per_axis * per_axis > static_cast<double>(kPlanarSquareMaxSamples)) {
    throw Error(kName, "options.step = " + show(step_) + ": gives " + show(per_axis) + " x " +
                           show(per_axis) + " samples; at most " +
                           std::to_string(kPlanarSquareMaxSamples) + " are allowed");
  }
  per_axis_ = static_cast<int>(per_axis);
}

SampleSet PlanarSquare::build(const SceneRequest& request) const {
  if (!request.attributes.empty()) {
    throw Error(kName, "per-sample attribute '" + request.attributes.front() +
                           "' requested: this scene provides none");
  }
  SampleSet set;
  set.coordinates = {"x", "y"};
  set.unit = "m";
  const int n = per_axis_;
  set.poses.resize(static_cast<Eigen::Index>(n) * n, 2);
  const double denominator = 2.0 * (n - 1);
  for (int i = 0; i < n; ++i) {
    const double y = (2.0 * i - (n - 1)) / denominator * side_;
    for (int j = 0; j < n; ++j) {
      const Eigen::Index row = static_cast<Eigen::Index>(i) * n + j;
      set.poses(row, 0) = (2.0 * j - (n - 1)) / denominator * side_;
      set.poses(row, 1) = y;
    }
  }
  return set;
}

}  // namespace hapsyn::plugins
