#include "gii.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace hapsyn::plugins {

void Gii::singular_values(const TaskJointMatrix& m, double& sigma_min, double& sigma_max) {
  if (m.rows() == 2 && m.cols() == 2) {
    const double a = m(0, 0), b = m(0, 1), c = m(1, 0), d = m(1, 1);
    const double e = 0.5 * (a + d), f = 0.5 * (a - d), g = 0.5 * (c + b), h = 0.5 * (c - b);
    sigma_max = std::sqrt(e * e + h * h) + std::sqrt(f * f + g * g);
    sigma_min = sigma_max > 0.0 ? std::abs(a * d - b * c) / sigma_max : 0.0;
    if (sigma_min > sigma_max) sigma_min = sigma_max;  // rounding guard
    return;
  }
  if (m.rows() == 0 || m.cols() == 0) {
    sigma_min = sigma_max = 0.0;
    return;
  }
  const Eigen::JacobiSVD<TaskJointMatrix> svd(m);
  const auto& values = svd.singularValues();
  sigma_max = values(0);
  sigma_min = values(values.size() - 1);
}

void Gii::local(const SampleQuantities& q, double* out) const {
  singular_values(q.jacobian, out[0], out[1]);
}

std::vector<LocalValue> Gii::locals() const {
  return {LocalValue{"sigma_min_J", Reduction::kMin, ""}, LocalValue{"sigma_max_J", Reduction::kMax, ""}};
}

double Gii::combine(const double* reduced, int /*samples*/) const {
  const double den = reduced[1];
  if (!(den > 0.0) || !std::isfinite(den)) return 0.0;
  return reduced[0] / den;
}

}  // namespace hapsyn::plugins
