#pragma once
/// \file
/// The global isotropy index (Stocco et al. 1998; Unal 2008 eq. 1), a worst-case metric:
///   GII = min over samples sigma_min(J) / max over samples sigma_max(J),
/// J the mechanism's task Jacobian (task velocity per actuator rate).
#include <hapsyn/accel/metric_acceleration.hpp>
#include <hapsyn/metric.hpp>
#include <hapsyn/options.hpp>

#include <string>
#include <vector>

namespace hapsyn::plugins {

/// Options of gii: which rows of a Jacobian that mixes angular and linear rows it uses.
struct GiiOptions {
  std::string rows{};
  double characteristic_length{};

  static void declare(OptionDeclarations<GiiOptions>& d) {
    d.describe(
        "Global isotropy index GII = min sigma_min(J) / max sigma_max(J) over the scene (Stocco 1998, Unal 2008 eq. 1). "
        "A Jacobian with more than 3 rows has its angular rows first (rows - 3 of them: a 6-row J is (omega, v)), "
        "whose units differ from the linear rows': use both scaled by a characteristic length, or one part alone "
        "(docs/design.md, serial chains).");
    d.add(&GiiOptions::rows, "rows", "all",
          "Rows of J used: all (angular rows times characteristic_length, which a mixed J requires), the linear "
          "(translational) rows only, or the angular (rotational) rows only.")
        .one_of({"all", "translational", "rotational"});
    d.add(&GiiOptions::characteristic_length, "characteristic_length", 0.0,
          "Length L that turns an angular row [rad/s per rate] into a velocity [m/s per rate]: the rows used are "
          "(L omega, v). 0: not set; then a J with angular rows and rows = all is refused at the first sample.")
        .minimum(0)
        .unit("m");
  }
};

/// The "gii" metric. Default-constructed (as in tests) it has the declared defaults: every row
/// of J, no characteristic length (fine for the five-bar's 2 x 2 J, which has no angular rows).
/// Locals: sigma_min_J (reduced by min) and sigma_max_J (reduced by max), in
/// the Jacobian's units (m/rad for the five-bar); combine = reduced[0] / reduced[1] [-].
/// Thread safety: stateless; every method is const and thread-safe; local() never allocates.
class Gii final : public Metric, public MetricAcceleration {
 public:
  using Options = GiiOptions;
  Gii() = default;
  /// \param options validated (GiiOptions::declare), defaults filled.
  explicit Gii(const GiiOptions& options);
  /// out[0] = sigma_min(J), out[1] = sigma_max(J) of q.jacobian (the rows `rows` selects).
  /// \throws Error("gii: ...") when J has angular rows, rows = all and no characteristic_length,
  ///         or rows = rotational and J has no angular rows (the first sample stops the study).
  void local(const SampleQuantities& q, double* out) const override;
  Needs needs() const { return kNeedJacobian; }
  MetricSpecs specs() const override { return {needs(), {}}; }
  const MetricAcceleration* acceleration() const override { return this; }

  std::vector<LocalValue> locals() const override;
  /// The block path: the 2 x 2 closed form of singular_values() per lane (other shapes: local()
  /// per lane). Not for rows = rotational (which local() refuses on J without angular rows).
  bool has_local_block() const override { return rows_ != Rows::kRotational; }
  void local_block(const QuantityBlock& q, double* out) const override;
  /// reduced[0] / reduced[1]; 0 when reduced[1] is not a positive finite number.
  double combine(const double* reduced, int samples) const override;
  bool combine_block(const double* reduced, int samples, double* out) const override;

  /// Block bound (docs/design.md section 13.5): GII over the whole scene is at most
  /// sigma_min(J) / sigma_max(J) at any one sample, so the envelope's
  /// jacobian_inverse_condition_max bounds it. Only when J is used as the mechanism returns it
  /// (rows = all, no characteristic_length); +inf otherwise.
  double envelope_bound(const SampleEnvelope& envelope) const override;
  /// Smallest and largest singular values of a matrix. 2 x 2: closed form,
  /// sigma_max = sqrt(E^2 + H^2) + sqrt(F^2 + G^2) with E = (a + d)/2, F = (a - d)/2,
  /// G = (c + b)/2, H = (c - b)/2, and sigma_min = |ad - bc| / sigma_max (0 for the zero
  /// matrix): never NaN for finite input, exact zeros for rank-deficient integer-like input.
  /// Other shapes: Eigen::JacobiSVD (fixed capacity, no allocation). Empty: both 0.
  static void singular_values(const TaskJointMatrix& matrix, double& sigma_min, double& sigma_max);

 private:
  enum class Rows { kAll, kTranslational, kRotational };
  Rows rows_ = Rows::kAll;
  double characteristic_length_ = 0.0;
};

}  // namespace hapsyn::plugins
