#include "gdi.hpp"

#include <hapsyn/accel/multiversion.hpp>

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

namespace {
// largest_singular_value()'s 2 x 2 closed form, lane by lane (the loop vectorises).
HAPSYN_MULTIVERSION_WIDE
void largest_singular_value_2x2_block(const double (*m)[kBlockLanes], double* out) {
  for (int i = 0; i < kBlockLanes; ++i) {
    const double a = m[0][i], b = m[1][i], c = m[2][i], d = m[3][i];
    const double e = 0.5 * (a + d), f = 0.5 * (a - d), g = 0.5 * (c + b), h = 0.5 * (c - b);
    out[i] = std::sqrt(e * e + h * h) + std::sqrt(f * f + g * g);
  }
}
}  // namespace

void Gdi::local_block(const QuantityBlock& q, double* out) const {
  const int n = q.effective_mass_size;
  if (n == 2) {
    largest_singular_value_2x2_block(q.effective_mass, out);
    return;
  }
  TaskMatrix m(n, n);
  for (int lane = 0; lane < kBlockLanes; ++lane) {
    if (q.lane_status(lane) != SampleStatus::kReachable) continue;
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) m(r, c) = q.effective_mass[r * n + c][lane];
    }
    out[lane] = largest_singular_value(m);
  }
}

std::vector<LocalValue> Gdi::locals() const { return {LocalValue{"sigma_max_M", Reduction::kMax, "kg"}}; }

double Gdi::combine(const double* reduced, int /*samples*/) const { return 1.0 / (1.0 + reduced[0]); }

double Gdi::envelope_bound(const SampleEnvelope& envelope) const {
  return 1.0 / (1.0 + envelope.effective_mass_sigma_max_min);
}

bool Gdi::combine_block(const double* reduced, int /*samples*/, double* out) const {
  for (int lane = 0; lane < kBlockLanes; ++lane) out[lane] = 1.0 / (1.0 + reduced[lane]);
  return true;
}

}  // namespace hapsyn::plugins
