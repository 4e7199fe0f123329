#pragma once
/// \file
/// The disc scene: the points of a regular grid through the centre that lie in a disc (x, y)
/// or ball (x, y, z) [m], optionally every sample with one fixed orientation (full 7-D poses).
#include <hapsyn/options.hpp>
#include <hapsyn/scene.hpp>

#include <string>
#include <vector>

namespace hapsyn::plugins {

/// Largest number of samples the scene builds (memory guard: at most 56 bytes per sample, 7-D).
constexpr long long kDiscMaxSamples = 2000000;

/// The options of disc (`hapsyn describe disc`).
struct DiscOptions {
  int dimension{};                    ///< 2 (disc) or 3 (ball)
  std::vector<double> center{};       ///< dimension numbers [m]
  double radius{};                    ///< [m], > 0
  double step{};                      ///< grid spacing [m], > 0
  std::vector<double> orientation{};  ///< empty, or a unit quaternion [qw, qx, qy, qz] (3-D only)

  static void declare(OptionDeclarations<DiscOptions>& d) {
    d.describe(
        "A disc (dimension 2: coordinates x, y) or ball (dimension 3: x, y, z) of radius `radius` centred at "
        "`center`: the points center + step (i, j[, k]), i, j, k whole numbers, at distance <= radius (relative "
        "tolerance 1e-9), x fastest, then y, then z. With `orientation` (3-D only) every sample is the full pose "
        "x, y, z, qw, qx, qy, qz with that orientation. Metres.");
    d.add(&DiscOptions::dimension, "dimension", 2, "2: a disc in the (x, y) plane; 3: a ball in (x, y, z).")
        .range(2, 3);
    d.add(&DiscOptions::center, "center", {0.0, 0.0},
          "Centre of the disc or ball, a grid point; one number per dimension.")
        .min_size(2)
        .max_size(3)
        .unit("m");
    d.add(&DiscOptions::radius, "radius", 0.05, "Radius; grid points on the boundary (within 1e-9 relative) count.")
        .greater_than(0)
        .unit("m");
    d.add(&DiscOptions::step, "step", 0.005,
          "Grid spacing; need not divide the radius. A step larger than the radius leaves the centre alone.")
        .greater_than(0)
        .unit("m");
    d.add(&DiscOptions::orientation, "orientation", {},
          "Empty: positions only. Otherwise a unit quaternion [qw, qx, qy, qz] (norm 1 within 1e-6, normalized) "
          "given to every sample, which becomes the pose x, y, z, qw, qx, qy, qz; dimension 3 only.")
        .max_size(4);
    d.rule({"center", "dimension"}, "one number per dimension", [](const DiscOptions& o) {
      return o.center.size() == static_cast<std::size_t>(o.dimension)
                 ? std::string()
                 : "must have " + std::to_string(o.dimension) + " numbers (one per dimension)";
    });
  }
};

/// The grid points c + step (i, j[, k]) (i, j, k whole numbers) with |(i, j[, k])| step <=
/// radius (1 + 1e-9), decided in whole numbers: i^2 + j^2 [+ k^2] <= (radius / step)^2
/// (1 + 1e-9)^2. Order: x fastest, then y, then z (rows of the grid from -K to K, K = the
/// largest whole number <= radius / step (1 + 1e-9)). The grid is symmetric about the centre:
/// c + k step and c - k step for every k, bit for bit mirror images when c = 0.
/// Coordinates {"x", "y"}, {"x", "y", "z"} or, with an orientation, {"x", "y", "z", "qw", "qx",
/// "qy", "qz"}; unit "m". No per-sample attributes, no weights.
///
/// Thread safety: const methods are thread-safe; build() holds no state.
class Disc final : public Scene {
 public:
  using Options = DiscOptions;

  /// \param options validated against the declarations (dimension 2 or 3, radius, step > 0).
  /// \throws Error("disc: options.<key> = <value>: <rule>") for what the declarations cannot
  ///         express: center without one number per dimension, an orientation that is not 4
  ///         numbers, is given in 2-D or is not a unit quaternion (norm 1 within 1e-6), or more
  ///         than kDiscMaxSamples samples (counted exactly, after a volume estimate refuses
  ///         grossly oversized grids without enumerating them).
  explicit Disc(const DiscOptions& options);

  /// Builds the samples. \throws Error when a per-sample attribute is requested (none exist).
  SampleSet build(const SceneRequest& request) const override;

  int dimension() const { return options_.dimension; }
  /// K: the grid runs from -K to K steps along each axis.
  int half_width() const { return half_width_; }
  long long sample_count() const { return samples_; }
  /// The orientation given to every sample, normalized; empty without one.
  const std::vector<double>& orientation() const { return orientation_; }

 private:
  /// The largest whole i >= 0 with i^2 <= m; -1 when m < 0.
  static int row_half_width(double m);
  DiscOptions options_;
  double bound_{};  // (radius / step)^2 (1 + 1e-9)^2: the bound on i^2 + j^2 [+ k^2]
  int half_width_{};
  long long samples_{};
  std::vector<double> orientation_;
};

}  // namespace hapsyn::plugins
