#include "disc.hpp"

#include <hapsyn/error.hpp>

#include <cmath>
#include <string>

namespace hapsyn::plugins {
namespace {

constexpr const char* kName = "disc";
constexpr double kPi = 3.14159265358979323846;

std::string show(const Json& value) { return value.dump(); }

}  // namespace

int Disc::row_half_width(double m) {
  if (m < 0.0) return -1;
  // sqrt may round either way: settle the whole number exactly.
  long long i = static_cast<long long>(std::floor(std::sqrt(m)));
  while (static_cast<double>(i + 1) * static_cast<double>(i + 1) <= m) ++i;
  while (i > 0 && static_cast<double>(i) * static_cast<double>(i) > m) --i;
  return static_cast<int>(i);
}

Disc::Disc(const DiscOptions& options) : options_(options) {
  // center has one number per dimension: a declared rule.
  const int dim = options_.dimension;
  orientation_ = orientation_option(options_.orientation, dim, kName);
  const double step = options_.step;
  const double reach = options_.radius / step * (1.0 + 1e-9);  // in steps, with the boundary tolerance
  const std::string too_many = "options.step = " + show(Json(step)) + ": gives ";
  const std::string cap = "; at most " + std::to_string(kDiscMaxSamples) + " are allowed";
  // The area or volume in steps estimates the count to a few per cent once it nears the cap;
  // a grid estimated at twice the cap is refused before it is enumerated (or K overflows).
  const double estimate = dim == 2 ? kPi * reach * reach : 4.0 / 3.0 * kPi * reach * reach * reach;
  if (!(estimate <= 2.0 * static_cast<double>(kDiscMaxSamples))) {
    throw Error(kName, too_many + "about " + show(Json(std::round(estimate))) + " samples (radius / step = " +
                           show(Json(options_.radius / step)) + ")" + cap);
  }
  bound_ = reach * reach;
  half_width_ = row_half_width(bound_);
  // Exact count, one grid row at a time: O(K) rows in 2-D, O(K^2) in 3-D.
  const int k = half_width_;
  samples_ = 0;
  for (int z = dim == 3 ? -k : 0; z <= (dim == 3 ? k : 0); ++z) {
    for (int y = -k; y <= k; ++y) {
      const int half = row_half_width(bound_ - static_cast<double>(y) * y - static_cast<double>(z) * z);
      if (half >= 0) samples_ += 2LL * half + 1;
    }
  }
  if (samples_ > kDiscMaxSamples) {
    throw Error(kName, too_many + std::to_string(samples_) + " samples (radius / step = " +
                           show(Json(options_.radius / step)) + ")" + cap);
  }
}

SampleSet Disc::build(const SceneRequest& request) const {
  if (!request.attributes.empty()) {
    throw Error(kName, "per-sample attribute '" + request.attributes.front() +
                           "' requested: this scene provides none");
  }
  const int dim = options_.dimension;
  const double step = options_.step;
  const std::vector<double>& c = options_.center;
  SampleSet set;
  set.coordinates = {"x", "y"};
  if (dim == 3) set.coordinates.push_back("z");
  if (!orientation_.empty()) set.coordinates.insert(set.coordinates.end(), {"qw", "qx", "qy", "qz"});
  set.unit = "m";
  set.poses.resize(static_cast<Eigen::Index>(samples_), static_cast<Eigen::Index>(set.coordinates.size()));
  const int k = half_width_;
  Eigen::Index row = 0;
  for (int z = dim == 3 ? -k : 0; z <= (dim == 3 ? k : 0); ++z) {
    for (int y = -k; y <= k; ++y) {
      const int half = row_half_width(bound_ - static_cast<double>(y) * y - static_cast<double>(z) * z);
      for (int x = -half; x <= half; ++x, ++row) {
        // c + i step (not c - K step + ...): the grid passes through the centre exactly.
        set.poses(row, 0) = c[0] + x * step;
        set.poses(row, 1) = c[1] + y * step;
        if (dim == 3) set.poses(row, 2) = c[2] + z * step;
        for (std::size_t q = 0; q < orientation_.size(); ++q) set.poses(row, 3 + static_cast<Eigen::Index>(q)) = orientation_[q];
      }
    }
  }
  set.info = {{"half_width", half_width_}, {"samples", samples_}};
  return set;
}

}  // namespace hapsyn::plugins
