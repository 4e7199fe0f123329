#include "planar_square.hpp"

#include <hapsyn/error.hpp>

#include <cmath>
#include <string>

namespace hapsyn::plugins {
namespace {

constexpr const char* kName = "planar_square";

std::string show(double value) { return Json(value).dump(); }

}  // namespace

std::string planar_square_step_rule(const PlanarSquareOptions& o) {
  if (o.step > o.side) return "must be <= side (" + show(o.side) + ")";
  const double ratio = o.side / o.step;
  if (!(std::abs(ratio - std::round(ratio)) <= 1e-9 * ratio)) return "must divide side (" + show(o.side) + ") into whole steps";
  return "";
}

PlanarSquare::PlanarSquare(const PlanarSquareOptions& options) : options_(options) {
  // step <= side and divides it into whole steps: a declared rule (planar_square_step_rule).
  const double step = options_.step;
  const double per_axis = std::round(options_.side / step) + 1.0;
  if (per_axis * per_axis > static_cast<double>(kPlanarSquareMaxSamples)) {
    throw Error(kName, "options.step = " + show(step) + ": gives " + show(per_axis) + " x " +
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
    const double y = (2.0 * i - (n - 1)) / denominator * options_.side;
    for (int j = 0; j < n; ++j) {
      const Eigen::Index row = static_cast<Eigen::Index>(i) * n + j;
      set.poses(row, 0) = (2.0 * j - (n - 1)) / denominator * options_.side;
      set.poses(row, 1) = y;
    }
  }
  return set;
}

}  // namespace hapsyn::plugins
