#include "gii.hpp"

#include <hapsyn/error.hpp>

#include <hapsyn/accel/multiversion.hpp>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

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

namespace {
// singular_values()'s 2 x 2 closed form, lane by lane (the loop vectorises).
HAPSYN_MULTIVERSION_WIDE
void singular_values_2x2_block(const double (*m)[kBlockLanes], double* sigma_min, double* sigma_max) {
  for (int i = 0; i < kBlockLanes; ++i) {
    const double a = m[0][i], b = m[1][i], c = m[2][i], d = m[3][i];
    const double e = 0.5 * (a + d), f = 0.5 * (a - d), g = 0.5 * (c + b), h = 0.5 * (c - b);
    const double largest = std::sqrt(e * e + h * h) + std::sqrt(f * f + g * g);
    const double smallest = largest > 0.0 ? std::abs(a * d - b * c) / largest : 0.0;
    sigma_max[i] = largest;
    sigma_min[i] = smallest > largest ? largest : smallest;  // rounding guard
  }
}
}  // namespace

Gii::Gii(const GiiOptions& options)
    : rows_(options.rows == "translational" ? Rows::kTranslational
            : options.rows == "rotational"  ? Rows::kRotational
                                            : Rows::kAll),
      characteristic_length_(options.characteristic_length) {}

void Gii::local(const SampleQuantities& q, double* out) const {
  const auto& j = q.jacobian;
  // Angular rows come first and number rows - 3 (hapsyn/quantities.hpp's convention for task
  // Jacobians: (omega, v) for a 6-row J, none for a planar or positional one).
  const int angular = j.rows() > 3 ? static_cast<int>(j.rows()) - 3 : 0;
  if (angular == 0 && rows_ != Rows::kRotational) {
    singular_values(j, out[0], out[1]);
    return;
  }
  TaskJointMatrix m;
  switch (rows_) {
    case Rows::kTranslational:
      m = j.bottomRows(j.rows() - angular);
      break;
    case Rows::kRotational:
      if (angular == 0) {
        throw Error("gii", "options.rows = \"rotational\": the mechanism's Jacobian is " + std::to_string(j.rows()) + "x" +
                               std::to_string(j.cols()) + " with no angular rows");
      }
      m = j.topRows(angular);
      break;
    case Rows::kAll:
      if (!(characteristic_length_ > 0.0)) {
        throw Error("gii", "the mechanism's Jacobian is " + std::to_string(j.rows()) + "x" + std::to_string(j.cols()) +
                               " with " + std::to_string(angular) +
                               " angular rows [rad/s] and 3 linear rows [m/s]: set options.characteristic_length [m] "
                               "to compare them, or options.rows = \"translational\" / \"rotational\"");
      }
      m = j;
      m.topRows(angular) *= characteristic_length_;
      break;
  }
  singular_values(m, out[0], out[1]);
}

void Gii::local_block(const QuantityBlock& q, double* out) const {
  if (q.jacobian_rows != 2 || q.jacobian_cols != 2) {
    SampleQuantities one;
    one.jacobian.resize(q.jacobian_rows, q.jacobian_cols);
    double values[2];
    for (int lane = 0; lane < kBlockLanes; ++lane) {
      if (q.lane_status(lane) != SampleStatus::kReachable) continue;
      for (int r = 0; r < q.jacobian_rows; ++r) {
        for (int c = 0; c < q.jacobian_cols; ++c) one.jacobian(r, c) = q.jacobian[r * q.jacobian_cols + c][lane];
      }
      local(one, values);
      out[lane] = values[0];
      out[kBlockLanes + lane] = values[1];
    }
    return;
  }
  singular_values_2x2_block(q.jacobian, out, out + kBlockLanes);
}

std::vector<LocalValue> Gii::locals() const {
  return {LocalValue{"sigma_min_J", Reduction::kMin, ""}, LocalValue{"sigma_max_J", Reduction::kMax, ""}};
}

double Gii::combine(const double* reduced, int /*samples*/) const {
  const double den = reduced[1];
  if (!(den > 0.0) || !std::isfinite(den)) return 0.0;
  return reduced[0] / den;
}

double Gii::envelope_bound(const SampleEnvelope& envelope) const {
  if (rows_ != Rows::kAll || characteristic_length_ != 0.0) return std::numeric_limits<double>::infinity();
  return envelope.jacobian_inverse_condition_max;
}

bool Gii::combine_block(const double* reduced, int /*samples*/, double* out) const {
  // combine() per lane, written as selects so that the lanes compile to one vector.
  for (int lane = 0; lane < kBlockLanes; ++lane) {
    const double den = reduced[kBlockLanes + lane];
    const bool usable = den > 0.0 && den < std::numeric_limits<double>::infinity();
    out[lane] = usable ? reduced[lane] / (usable ? den : 1.0) : 0.0;
  }
  return true;
}

}  // namespace hapsyn::plugins
