#pragma once
/// \file
/// The global isotropy index (Stocco et al. 1998; Unal 2008 eq. 1), a worst-case metric:
///   GII = min over samples sigma_min(J) / max over samples sigma_max(J),
/// J the mechanism's task Jacobian (task velocity per actuator rate).
#include <hapsyn/metric.hpp>

#include <vector>

namespace hapsyn::plugins {

/// The "gii" metric. It has no options (no Options type): the framework default-constructs it.
/// Locals: sigma_min_J (reduced by min) and sigma_max_J (reduced by max), in
/// the Jacobian's units (m/rad for the five-bar); combine = reduced[0] / reduced[1] [-].
/// Thread safety: stateless; every method is const and thread-safe; local() never allocates.
class Gii final : public Metric {
 public:
  /// out[0] = sigma_min(J), out[1] = sigma_max(J) of q.jacobian.
  void local(const SampleQuantities& q, double* out) const override;
  Needs needs() const override { return kNeedJacobian; }
  std::vector<LocalValue> locals() const override;
  /// reduced[0] / reduced[1]; 0 when reduced[1] is not a positive finite number.
  double combine(const double* reduced, int samples) const override;

  /// Smallest and largest singular values of a matrix. 2 x 2: closed form,
  /// sigma_max = sqrt(E^2 + H^2) + sqrt(F^2 + G^2) with E = (a + d)/2, F = (a - d)/2,
  /// G = (c + b)/2, H = (c - b)/2, and sigma_min = |ad - bc| / sigma_max (0 for the zero
  /// matrix): never NaN for finite input, exact zeros for rank-deficient integer-like input.
  /// Other shapes: Eigen::JacobiSVD (fixed capacity, no allocation). Empty: both 0.
  static void singular_values(const TaskJointMatrix& matrix, double& sigma_min, double& sigma_max);
};

}  // namespace hapsyn::plugins
