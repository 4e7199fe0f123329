#include "planar_square.hpp"

#include <hapsyn/error.hpp>

#include <cmath>
#include <string>

namespace hapsyn::plugins {
namespace {

constexpr const char* kName = "planar_square";

std::string show(double value) { return Json(value).dump(); }

}  // namespace

PlanarSquare::PlanarSquare(const PlanarSquareOptions& options) : options_(options) {
  const double side = options_.side, step = options_.step;
  if (step > side) {
    throw Error(kName, "options.step = " + show(step) + ": must be <= side (" + show(side) + ")");
  }
  const double ratio = side / step;
  const double steps = std::round(ratio);
  if (!(std::abs(ratio - steps) <= 1e-9 * ratio)) {
    throw Error(kName, "options.step = " + show(step) + ": must divide side (" + show(side) +
                           ") into whole steps");
  }
  const double per_axis = steps + 1.0;
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
