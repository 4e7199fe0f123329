#include "box.hpp"

#include <hapsyn/error.hpp>

#include <cmath>
#include <string>

namespace hapsyn::plugins {
namespace {

constexpr const char* kName = "box";
constexpr const char* kAxes[3] = {"x", "y", "z"};

std::string show(const Json& value) { return value.dump(); }

}  // namespace

std::string one_per_dimension(const std::vector<double>& values, int dimension) {
  if (values.size() == static_cast<std::size_t>(dimension)) return "";
  return "must have " + std::to_string(dimension) + " numbers (one per dimension)";
}

std::string box_step_rule(const BoxOptions& o) {
  for (std::size_t a = 0; a < o.size.size(); ++a) {
    const double side = o.size[a];
    const std::string side_name = "size[" + std::to_string(a) + "] (" + show(Json(side)) + ")";
    if (o.step > side) return "must be <= " + side_name;
    const double ratio = side / o.step;
    if (!(std::abs(ratio - std::round(ratio)) <= 1e-9 * ratio)) return "must divide " + side_name + " into whole steps";
  }
  return "";
}

Box::Box(const BoxOptions& options) : options_(options) {
  // center and size have one number per dimension and step divides every side: declared rules.
  const int dim = options_.dimension;
  const std::size_t n = static_cast<std::size_t>(dim);
  orientation_ = orientation_option(options_.orientation, dim, kName);
  const double step = options_.step;
  // Counted in double: a product of per-axis counts cannot overflow before it is compared.
  double samples = 1.0;
  per_axis_ = {1, 1, 1};
  for (std::size_t a = 0; a < n; ++a) samples *= std::round(options_.size[a] / step) + 1.0;
  if (samples > static_cast<double>(kBoxMaxSamples)) {
    std::string grid;
    for (std::size_t a = 0; a < n; ++a) {
      grid += (a ? " x " : "") + show(Json(std::round(options_.size[a] / step) + 1.0));
    }
    throw Error(kName, "options.step = " + show(Json(step)) + ": gives " + grid + " samples; at most " +
                           std::to_string(kBoxMaxSamples) + " are allowed");
  }
  // Each count is now <= kBoxMaxSamples: it fits an int.
  for (std::size_t a = 0; a < n; ++a) per_axis_[a] = static_cast<int>(std::round(options_.size[a] / step)) + 1;
}

SampleSet Box::build(const SceneRequest& request) const {
  if (!request.attributes.empty()) {
    throw Error(kName, "per-sample attribute '" + request.attributes.front() +
                           "' requested: this scene provides none");
  }
  const int dim = options_.dimension;
  SampleSet set;
  for (int a = 0; a < dim; ++a) set.coordinates.push_back(kAxes[a]);
  if (!orientation_.empty()) set.coordinates.insert(set.coordinates.end(), {"qw", "qx", "qy", "qz"});
  set.unit = "m";
  const Eigen::Index columns = static_cast<Eigen::Index>(set.coordinates.size());
  set.poses.resize(static_cast<Eigen::Index>(sample_count()), columns);
  // The abscissae of each axis once; the symmetric formula keeps the edges at c -+ size/2.
  std::array<std::vector<double>, 3> axis;
  for (int a = 0; a < dim; ++a) {
    const int n = per_axis_[static_cast<std::size_t>(a)];
    const double c = options_.center[static_cast<std::size_t>(a)], side = options_.size[static_cast<std::size_t>(a)];
    const double denominator = 2.0 * (n - 1);
    for (int j = 0; j < n; ++j) axis[static_cast<std::size_t>(a)].push_back(c + (2.0 * j - (n - 1)) / denominator * side);
  }
  Eigen::Index row = 0;
  for (int iz = 0; iz < per_axis_[2]; ++iz) {
    for (int iy = 0; iy < per_axis_[1]; ++iy) {
      for (int ix = 0; ix < per_axis_[0]; ++ix, ++row) {
        set.poses(row, 0) = axis[0][static_cast<std::size_t>(ix)];
        set.poses(row, 1) = axis[1][static_cast<std::size_t>(iy)];
        if (dim == 3) set.poses(row, 2) = axis[2][static_cast<std::size_t>(iz)];
        for (std::size_t k = 0; k < orientation_.size(); ++k) set.poses(row, 3 + static_cast<Eigen::Index>(k)) = orientation_[k];
      }
    }
  }
  set.info = {{"per_axis", std::vector<int>(per_axis_.begin(), per_axis_.begin() + dim)}, {"samples", sample_count()}};
  return set;
}

}  // namespace hapsyn::plugins
