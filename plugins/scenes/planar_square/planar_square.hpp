#pragma once
/// \file
/// The planar square scene of the five-bar study (Unal 2008): a regular grid of (x, y) [m]
/// samples covering a square centred at the scene origin.
#include <hapsyn/options.hpp>
#include <hapsyn/scene.hpp>

#include <string>

namespace hapsyn::plugins {

/// Largest number of samples the scene builds (memory guard: 16 bytes per sample).
constexpr long long kPlanarSquareMaxSamples = 2000000;  // 0.07 mm steps on a 100 mm square

struct PlanarSquareOptions;
/// The rule relating step and side: "" when step <= side and divides it into whole steps (relative
/// tolerance 1e-9), else what is wrong.
std::string planar_square_step_rule(const PlanarSquareOptions& o);

/// The options of planar_square (`hapsyn describe planar_square`).
struct PlanarSquareOptions {
  double side{};  ///< side length of the square [m], > 0
  double step{};  ///< grid spacing [m], > 0

  static void declare(OptionDeclarations<PlanarSquareOptions>& d) {
    d.describe(
        "A square of side `side` centred at (0, 0), sampled on a regular grid of spacing `step` including its "
        "edges: round(side/step) + 1 samples per axis, x fastest. Coordinates x, y in metres.");
    d.add(&PlanarSquareOptions::side, "side", 0.1,
          "Side length of the square. 0.1 m reproduces Unal 2008 Table 2 (the paper's printed w = 200 mm does not).")
        .greater_than(0)
        .unit("m");
    d.add(&PlanarSquareOptions::step, "step", 0.005,
          "Grid spacing; must divide side into whole steps (relative tolerance 1e-9) and be <= side. The paper "
          "uses 0.001 m.")
        .greater_than(0)
        .unit("m");
    d.rule({"step", "side"}, "step <= side and divides it into whole steps", &planar_square_step_rule);
  }
};

/// A square of side `side` [m] centred at (0, 0), sampled on a regular grid of spacing `step`
/// [m] including its edges: n = round(side / step) + 1 samples per axis, n^2 in all, in
/// row-major order with x fastest (sample i * n + j is (x_j, y_i)). Coordinates {"x", "y"},
/// unit "m". The grid is exactly symmetric: x_j = (2j - (n - 1)) / (2 (n - 1)) * side, so the
/// edges are exactly +-side/2 and x_{n-1-j} = -x_j bit for bit.
///
/// Thread safety: const methods are thread-safe; build() holds no state.
class PlanarSquare final : public Scene {
 public:
  using Options = PlanarSquareOptions;

  /// \param options validated against the declarations (side, step > 0).
  /// \throws Error("planar_square: options.step = ...: ...") for what the declarations cannot
  ///         express: step does not divide side into whole steps (relative tolerance 1e-9),
  ///         step > side, or the grid would exceed kPlanarSquareMaxSamples.
  explicit PlanarSquare(const PlanarSquareOptions& options);

  /// Builds the grid. \throws Error when a per-sample attribute is requested (none exist).
  SampleSet build(const SceneRequest& request) const override;

  double side() const { return options_.side; }  ///< side of the square [m]
  double step() const { return options_.step; }  ///< grid spacing [m]
  int per_axis() const { return per_axis_; }     ///< samples per axis, round(side / step) + 1

 private:
  PlanarSquareOptions options_;
  int per_axis_{};
};

}  // namespace hapsyn::plugins
