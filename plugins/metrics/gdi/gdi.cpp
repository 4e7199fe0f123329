#include "gdi.hpp"

#include <Eigen/SVD>
#include <cmath>

namespace hapsyn::plugins {

double Gdi::largest_singular_value(const TaskMatrix& m) {
  if (m.rows() == 2 && m.cols() == 2) {
    const double a = m(0, 0), b = m(0, 1), c = m(1, 0), d = m(1, 1);
    const double e = 0.5 * (a + d), f = 0.5 * (a - d), g = 0.5 * (c + b), h = 0.5 * (c - b);
    return std::sqrt(e * e + h * h) + std::sqrt(f * f + g * g);
  }
  if (m.rows() == 0 || m.cols() == 0) return 0.0;
  const Eigen::JacobiSVD<TaskMatrix> svd(m);
  return svd.singularValues()(0);
}

void Gdi::local(const SampleQuantities& q, double* out) const {
  out[0] = largest_singular_value(q.effective_mass);
}

std::vector<LocalValue> Gdi::locals() const { return {LocalValue{"sigma_max_M", Reduction::kMax, "kg"}}; }

double Gdi::combine(const double* reduced, int /*samples*/) const { return 1.0 / (1.0 + reduced[0]); }

}  // namespace hapsyn::plugins
