#pragma once
/// \file
/// The box scene: a rectangle (x, y) or box (x, y, z) [m] sampled on a regular grid including
/// its edges, optionally every sample with one fixed orientation (full 7-D poses).
#include <hapsyn/options.hpp>
#include <hapsyn/scene.hpp>

#include <array>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// Largest number of samples the scene builds (memory guard: at most 56 bytes per sample, 7-D).
constexpr long long kBoxMaxSamples = 2000000;

struct BoxOptions;
/// The rule relating step and size: "" when step is <= every side and divides it into whole steps
/// (relative tolerance 1e-9), else what is wrong.
std::string box_step_rule(const BoxOptions& o);
/// "" when `values` has one number per dimension, else what is wrong.
std::string one_per_dimension(const std::vector<double>& values, int dimension);

/// The options of box (`hapsyn describe box`).
struct BoxOptions {
  int dimension{};                  ///< 2 (rectangle) or 3 (box)
  std::vector<double> center{};     ///< dimension numbers [m]
  std::vector<double> size{};       ///< side lengths [m], dimension numbers, each > 0
  double step{};                    ///< grid spacing [m], > 0
  std::vector<double> orientation{};  ///< empty, or a unit quaternion [qw, qx, qy, qz] (3-D only)

  static void declare(OptionDeclarations<BoxOptions>& d) {
    d.describe(
        "A rectangle (dimension 2: coordinates x, y) or box (dimension 3: x, y, z) of side lengths `size` centred "
        "at `center`, sampled on a regular grid of spacing `step` including its edges: round(size/step) + 1 "
        "samples per axis, x fastest, then y, then z. With `orientation` (3-D only) every sample is the full pose "
        "x, y, z, qw, qx, qy, qz with that orientation. Metres.");
    d.add(&BoxOptions::dimension, "dimension", 2, "2: a rectangle in the (x, y) plane; 3: a box in (x, y, z).")
        .range(2, 3);
    d.add(&BoxOptions::center, "center", {0.0, 0.0}, "Centre of the rectangle or box; one number per dimension.")
        .min_size(2)
        .max_size(3)
        .unit("m");
    d.add(&BoxOptions::size, "size", {0.1, 0.1},
          "Side lengths along x, y (and z); one number per dimension, each > 0.")
        .greater_than(0)
        .min_size(2)
        .max_size(3)
        .unit("m");
    d.add(&BoxOptions::step, "step", 0.005,
          "Grid spacing; must divide every side into whole steps (relative tolerance 1e-9) and be <= every side.")
        .greater_than(0)
        .unit("m");
    d.add(&BoxOptions::orientation, "orientation", {},
          "Empty: positions only. Otherwise a unit quaternion [qw, qx, qy, qz] (norm 1 within 1e-6, normalized) "
          "given to every sample, which becomes the pose x, y, z, qw, qx, qy, qz; dimension 3 only.")
        .max_size(4);
    d.rule({"center", "dimension"}, "one number per dimension",
           [](const BoxOptions& o) { return one_per_dimension(o.center, o.dimension); });
    d.rule({"size", "dimension"}, "one number per dimension",
           [](const BoxOptions& o) { return one_per_dimension(o.size, o.dimension); });
    d.rule({"step", "size"}, "step <= every size[i] and divides it into whole steps", &box_step_rule);
  }
};

/// A rectangle or box of side lengths size [m] centred at center [m], sampled on a regular
/// grid of spacing step [m] including its edges: n_a = round(size_a / step) + 1 samples along
/// axis a, n_x n_y (n_z) in all, x fastest, then y, then z (sample ix + n_x (iy + n_y iz)).
/// Along each axis x_j = c + (2j - (n - 1)) / (2 (n - 1)) * size: the edges are exactly
/// c -+ size/2 up to the rounding of the sum, and the spacing is step to rounding.
/// Coordinates {"x", "y"}, {"x", "y", "z"} or, with an orientation, {"x", "y", "z", "qw", "qx",
/// "qy", "qz"}; unit "m". No per-sample attributes, no weights.
///
/// Thread safety: const methods are thread-safe; build() holds no state.
class Box final : public Scene {
 public:
  using Options = BoxOptions;

  /// \param options validated against the declarations (dimension 2 or 3, size and step > 0).
  /// \throws Error("box: options.<key> = <value>: <rule>") for what the declarations cannot
  ///         express: center or size without one number per dimension, an orientation that is
  ///         not 4 numbers, is given in 2-D or is not a unit quaternion (norm 1 within 1e-6), a
  ///         step that does not divide a side into whole steps (relative tolerance 1e-9) or is
  ///         larger than a side, or a grid of more than kBoxMaxSamples samples.
  explicit Box(const BoxOptions& options);

  /// Builds the grid. \throws Error when a per-sample attribute is requested (none exist).
  SampleSet build(const SceneRequest& request) const override;

  int dimension() const { return options_.dimension; }
  /// Samples along x, y, z (1 along z in 2-D).
  const std::array<int, 3>& per_axis() const { return per_axis_; }
  /// The orientation given to every sample, normalized; empty without one.
  const std::vector<double>& orientation() const { return orientation_; }
  long long sample_count() const {
    return static_cast<long long>(per_axis_[0]) * per_axis_[1] * per_axis_[2];
  }

 private:
  BoxOptions options_;
  std::array<int, 3> per_axis_{};
  std::vector<double> orientation_;
};

}  // namespace hapsyn::plugins
