#pragma once
/// \file
/// The planar square scene of the five-bar study (Unal 2008): a regular grid of (x, y) [m]
/// samples covering a square centred at the scene origin.
#include <hapsyn/json.hpp>
#include <hapsyn/scene.hpp>

namespace hapsyn::plugins {

/// Largest number of samples the scene builds (memory guard: 16 bytes per sample).
constexpr long long kPlanarSquareMaxSamples = 2000000;  // 0.07 mm steps on a 100 mm square

/// A square of side `side` [m] centred at (0, 0), sampled on a regular grid of spacing `step`
/// [m] including its edges: n = round(side / step) + 1 samples per axis, n^2 in all, in
/// row-major order with x fastest (sample i * n + j is (x_j, y_i)). Coordinates {"x", "y"},
/// unit "m". The grid is exactly symmetric: x_j = (2j - (n - 1)) / (2 (n - 1)) * side, so the
/// edges are exactly +-side/2 and x_{n-1-j} = -x_j bit for bit.
///
/// Thread safety: const methods are thread-safe; build() holds no state.
class PlanarSquare final : public Scene {
 public:
  /// \param options {"side": [m], "step": [m]} (missing keys take the schema's defaults
  ///        0.1 and 0.005).
  /// \throws Error("planar_square: options.step = ...: ...") when step does not divide side
  ///         into whole steps (relative tolerance 1e-9), step > side, or the grid would exceed
  ///         kPlanarSquareMaxSamples.
  explicit PlanarSquare(const Json& options);

  /// Builds the grid. \throws Error when a per-sample attribute is requested (none exist).
  SampleSet build(const SceneRequest& request) const override;

  double side() const { return side_; }  ///< side of the square [m]
  double step() const { return step_; }  ///< grid spacing [m]
  int per_axis() const { return per_axis_; }  ///< samples per axis, round(side / step) + 1

 private:
  double side_ = 0.1;
  double step_ = 0.005;
  int per_axis_ = 21;
};

}  // namespace hapsyn::plugins
