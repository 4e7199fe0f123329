// planar_disc: an example hapsyn scene plugin built out of tree (see README.md).
//
// The samples are the points of a regular square grid of spacing `step` [m] that lie in a disc
// of radius `radius` [m] centred at `centre` [m]: centre + (i step, j step) for the integers i, j
// with (i step)^2 + (j step)^2 <= radius^2 (points on the circle included, to a relative 1e-9).
// Row-major order, x fastest, from the bottom row up; coordinates {"x", "y"}, unit "m".
#include <hapsyn/error.hpp>
#include <hapsyn/plugin.hpp>

#include <cmath>
#include <string>
#include <vector>

namespace planar_disc_example {

/// The options, declared once: the framework derives the schema from this (`hapsyn describe
/// planar_disc`), checks the problem file against it and fills the struct before the
/// constructor runs. Member initialisers stay `{}`: the declared default is the only one.
struct PlanarDiscOptions {
  double radius{};             ///< [m], > 0
  double step{};               ///< [m], > 0
  std::vector<double> centre;  ///< (x, y) [m]

  static void declare(hapsyn::OptionDeclarations<PlanarDiscOptions>& d) {
    d.describe(
        "A disc of radius `radius` centred at `centre`, sampled on a regular square grid of spacing `step` whose "
        "origin is the centre: the grid points within the disc (its circle included), row-major with x fastest. "
        "Coordinates x, y in metres.");
    d.add(&PlanarDiscOptions::radius, "radius", 0.05, "Radius of the disc").greater_than(0).unit("m");
    d.add(&PlanarDiscOptions::step, "step", 0.01, "Grid spacing").greater_than(0).unit("m");
    d.add(&PlanarDiscOptions::centre, "centre", {0.0, 0.0}, "Centre of the disc (x, y) in the scene frame")
        .size(2)
        .unit("m");
  }
};

/// Largest number of grid points per axis (a memory guard: 2001^2 points = 64 MB of poses).
constexpr double kMaxPerAxis = 2001.0;

/// The "planar_disc" scene. Thread safety: immutable after construction; build() is const.
class PlanarDisc final : public hapsyn::Scene {
 public:
  using Options = PlanarDiscOptions;

  /// \param options validated against the declarations (radius, step > 0; centre of size 2).
  /// \throws hapsyn::Error("planar_disc: options.step = ...: ...") when the grid would have more
  ///         than kMaxPerAxis points per axis: a rule on two options that no single
  ///         declaration can express.
  explicit PlanarDisc(const PlanarDiscOptions& options) : options_(options) {
    const double per_axis = 2.0 * std::floor(options_.radius / options_.step + 1e-9) + 1.0;
    if (per_axis > kMaxPerAxis) {
      throw hapsyn::Error("planar_disc", "options.step = " + hapsyn::Json(options_.step).dump() + ": gives " +
                                             hapsyn::Json(per_axis).dump() + " grid points per axis for radius " +
                                             hapsyn::Json(options_.radius).dump() + "; at most 2001 are allowed");
    }
  }

  /// Builds the samples. \throws hapsyn::Error when a per-sample attribute is requested (none exist).
  hapsyn::SampleSet build(const hapsyn::SceneRequest& request) const override {
    if (!request.attributes.empty()) {
      throw hapsyn::Error("planar_disc", "per-sample attribute '" + request.attributes.front() +
                                             "' requested: this scene provides none");
    }
    // Whole steps to the rim; a point exactly on the circle (radius a multiple of step) is kept
    // despite rounding in radius / step.
    const double ratio = options_.radius / options_.step;
    const int m = static_cast<int>(std::floor(ratio + 1e-9));
    const double limit = ratio * ratio * (1.0 + 1e-9);
    std::vector<double> xy;
    for (int j = -m; j <= m; ++j) {
      for (int i = -m; i <= m; ++i) {
        if (static_cast<double>(i) * i + static_cast<double>(j) * j > limit) continue;
        xy.push_back(options_.centre[0] + i * options_.step);
        xy.push_back(options_.centre[1] + j * options_.step);
      }
    }
    hapsyn::SampleSet set;
    set.coordinates = {"x", "y"};
    set.unit = "m";
    const Eigen::Index n = static_cast<Eigen::Index>(xy.size() / 2);
    set.poses = Eigen::Map<const hapsyn::SampleSet::RowMatrix>(xy.data(), n, 2);
    set.info = {{"samples", static_cast<long long>(n)}, {"grid_points_per_axis", 2 * m + 1}};
    return set;
  }

 private:
  PlanarDiscOptions options_;
};

}  // namespace planar_disc_example

HAPSYN_SCENE_PLUGIN(planar_disc_example::PlanarDisc, "planar_disc", "1.0.0",
                    "Disc of (x, y) samples on a regular square grid centred at its centre")
