#pragma once
/// \file
/// The global dynamic index (Stocco et al. 1998; Unal 2008 eq. 2), a worst-case metric:
///   GDI = min over samples 1 / (1 + sigma_max(M)) = 1 / (1 + max over samples sigma_max(M)),
/// M = J^-T D J^-1 the effective mass at the end effector [kg].
#include <hapsyn/accel/metric_acceleration.hpp>
#include <hapsyn/metric.hpp>

#include <vector>

namespace hapsyn::plugins {

/// The "gdi" metric. It has no options (no Options type): the framework default-constructs it.
/// Local: sigma_max_M [kg] (reduced by max); combine = 1 / (1 + reduced[0]).
/// Thread safety: stateless; every method is const and thread-safe; local() never allocates.
class Gdi final : public Metric, public MetricAcceleration {
 public:
  /// out[0] = sigma_max(M) of q.effective_mass [kg].
  void local(const SampleQuantities& q, double* out) const override;
  Needs needs() const { return kNeedEffectiveMass; }
  MetricSpecs specs() const override { return {needs(), {}}; }
  const MetricAcceleration* acceleration() const override { return this; }

  std::vector<LocalValue> locals() const override;
  /// 1 / (1 + reduced[0]) [-]; 0 for an infinite reduced[0].
  double combine(const double* reduced, int samples) const override;
  bool combine_block(const double* reduced, int samples, double* out) const override;
  /// The block path: largest_singular_value() per lane (2 x 2: its closed form, vectorised).
  bool has_local_block() const override { return true; }
  void local_block(const QuantityBlock& q, double* out) const override;

  /// Block bound (docs/design.md section 13.5): GDI over the whole scene is at most
  /// 1 / (1 + sigma_max(M)) at any one sample, so 1 / (1 + effective_mass_sigma_max_min) bounds
  /// it (1 when the envelope says nothing about M: no bound below 1 is known).
  double envelope_bound(const SampleEnvelope& envelope) const override;
  /// Largest singular value of a matrix. 2 x 2: closed form
  /// sqrt(E^2 + H^2) + sqrt(F^2 + G^2) with E = (a + d)/2, F = (a - d)/2, G = (c + b)/2,
  /// H = (c - b)/2 (never NaN for finite input); other shapes: Eigen::JacobiSVD (fixed
  /// capacity, no allocation); empty: 0.
  static double largest_singular_value(const TaskMatrix& matrix);
};

}  // namespace hapsyn::plugins
