#include "coverage.hpp"

#include <hapsyn/scene.hpp>

#include <hapsyn/error.hpp>
#include <hapsyn/accel/multiversion.hpp>

#include <algorithm>
#include <cmath>

namespace hapsyn::plugins {

namespace {
constexpr const char* kName = "coverage";

// Gaussian elimination with partial pivoting on row-major copies (see solve_jacobian).
template <int Cols>
[[gnu::always_inline]] inline bool eliminate(const Coverage::Matrix6& jacobian, Eigen::Matrix<double, 6, Cols>& x) {
  // Row-major working copies: every elimination step is a contiguous row update.
  Eigen::Matrix<double, 6, 6, Eigen::RowMajor> a = jacobian;
  Eigen::Matrix<double, 6, Cols, Eigen::RowMajor> b = x;
  for (int k = 0; k < 6; ++k) {
    int pivot = k;
    for (int i = k + 1; i < 6; ++i) {
      if (std::abs(a(i, k)) > std::abs(a(pivot, k))) pivot = i;
    }
    if (a(pivot, k) == 0.0) return false;
    if (pivot != k) {
      a.row(k).swap(a.row(pivot));
      b.row(k).swap(b.row(pivot));
    }
    const double inverse_pivot = 1.0 / a(k, k);
    for (int i = k + 1; i < 6; ++i) {
      const double factor = a(i, k) * inverse_pivot;
      if (factor == 0.0) continue;
      a.row(i) -= factor * a.row(k);
      b.row(i) -= factor * b.row(k);
    }
  }
  for (int k = 5; k >= 0; --k) {
    for (int c = k + 1; c < 6; ++c) b.row(k) -= a(k, c) * b.row(c);
    b.row(k) *= 1.0 / a(k, k);
  }
  x = b;
  return true;
}

// min(1, min_i limit_i / (max_j |M_ij| + extra_i)), never NaN: a zero denominator leaves 1, a
// non-finite one (singular solve) gives 0.
template <typename Derived>
[[gnu::always_inline]] inline double ratio_eta(const Eigen::MatrixBase<Derived>& m, const Coverage::Vector6& limit, const Coverage::Vector6* extra) {
  double eta = 1.0;
  for (int i = 0; i < 6; ++i) {
    double need = m.row(i).cwiseAbs().maxCoeff();
    if (extra) need += std::abs((*extra)(i));
    if (!std::isfinite(need)) return 0.0;
    if (need * eta > limit(i)) eta = limit(i) / need;
  }
  return eta;
}
}  // namespace

namespace {
// Multiversioned here, not on the public static members: clang exports no plain symbol for a
// multiversioned function, which other translation units (tests, benchmarks) call.
HAPSYN_MULTIVERSION
bool eliminate6(const Coverage::Matrix6& jacobian, Eigen::Matrix<double, 6, 6>& x) { return eliminate(jacobian, x); }

HAPSYN_MULTIVERSION
bool eliminate12(const Coverage::Matrix6& jacobian, Eigen::Matrix<double, 6, 12>& x) { return eliminate(jacobian, x); }
}  // namespace

bool Coverage::solve_jacobian(const Matrix6& jacobian, Eigen::Matrix<double, 6, 6>& x) { return eliminate6(jacobian, x); }

bool Coverage::solve_jacobian(const Matrix6& jacobian, Eigen::Matrix<double, 6, 12>& x) { return eliminate12(jacobian, x); }

Coverage::Coverage(const CoverageOptions& options) : options_(options) {
  for (std::size_t i = 0; i < options_.terms.size(); ++i) {
    const std::string& term = options_.terms[i];
    // The declared one_of leaves exactly these four names.
    bool& flag = term == "pose"           ? pose_
                 : term == "velocity"     ? velocity_
                 : term == "acceleration" ? acceleration_
                                          : force_;
    flag = true;  // a repeated term is refused by a declared rule
  }
}

Needs Coverage::needs() const {
  Needs n = kNeedPose;
  if (velocity_) n |= kNeedJacobian | kNeedActuatorLimits;
  if (acceleration_) n |= kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits;
  if (force_) n |= kNeedJacobian | kNeedGravity | kNeedActuatorLimits;
  return n;
}

std::vector<std::string> Coverage::scene_attributes() const {
  std::vector<std::string> a;
  if (velocity_) a.push_back("M_v");
  if (acceleration_) a.push_back("M_a");
  return a;
}

std::vector<LocalValue> Coverage::locals() const {
  std::vector<LocalValue> l = {{"reach_h", Reduction::kSum, ""}, {"reach_m", Reduction::kSum, ""}};
  if (velocity_) l.push_back({"eta_v", Reduction::kSum, ""});
  if (acceleration_) l.push_back({"eta_a", Reduction::kSum, ""});
  if (force_) l.push_back({"eta_f", Reduction::kSum, ""});
  return l;
}

double Coverage::eta_velocity(const Matrix6& jacobian, const Matrix6& m_v, const Vector6& max_velocity) {
  Matrix6 a = m_v;
  if (!solve_jacobian(jacobian, a)) return 0.0;
  return ratio_eta(a, max_velocity, nullptr);
}

double Coverage::eta_acceleration(const Matrix6& jacobian, const Matrix6& inertia, const Vector6& gravity,
                                  const Matrix6& m_a, const Vector6& max_torque) {
  Matrix6 x = m_a;
  if (!solve_jacobian(jacobian, x)) return 0.0;
  const Matrix6 b = inertia.lazyProduct(x);
  return ratio_eta(b, max_torque, &gravity);
}

double Coverage::eta_force(const Matrix6& jacobian, const Vector6& gravity, const Vector6& max_torque, double m_max,
                           double f_max) {
  Matrix6 c = jacobian.transpose();
  c.leftCols<3>() *= m_max;
  c.rightCols<3>() *= f_max;
  return ratio_eta(c, max_torque, &gravity);
}

namespace {
// The sample's 6x6 row-major scene attribute (M_v or M_a), which the evaluator makes reachable
// through q.scene / q.sample; requested by scene_attributes() only for the terms that need it.
// `index` is its position in scene_attributes(): the evaluator resolved it already (no lookup by
// name per sample); other callers (direct use in tests and benchmarks) fall back to the name.
const double* attribute_row(const SampleQuantities& q, int index, const char* name, const char* term) {
  if (const double* row = q.attribute_row(index); row && q.attributes[index]->cols() == 36) return row;
  if (!q.scene || q.sample < 0 || q.sample >= q.scene->size()) {
    throw Error(kName, std::string("the ") + term + " term needs the scene attribute " + name +
                           " of the current sample, but no sample was given (call through the evaluator)");
  }
  const auto it = q.scene->attributes.find(name);
  if (it == q.scene->attributes.end() || it->second.cols() != 36) {
    throw Error(kName, std::string("the ") + term + " term needs the scene attribute " + name +
                           " (36 values per sample); the scene does not provide it");
  }
  return it->second.row(q.sample).data();
}
}  // namespace

HAPSYN_MULTIVERSION
void Coverage::local_sample(const SampleQuantities& q, double* out) const {
  out[0] = 1.0;
  const bool reachable = q.status == SampleStatus::kReachable;
  out[1] = reachable ? 1.0 : 0.0;
  int k = 2;
  if (!reachable) {
    if (velocity_) out[k++] = 0.0;
    if (acceleration_) out[k++] = 0.0;
    if (force_) out[k++] = 0.0;
    return;
  }
  if (!(velocity_ || acceleration_ || force_)) return;
  if (q.jacobian.rows() != 6 || q.jacobian.cols() != 6) {
    throw Error(kName, "the mechanism's Jacobian is " + std::to_string(q.jacobian.rows()) + "x" +
                           std::to_string(q.jacobian.cols()) + ": coverage needs a 6x6 (omega, v) Jacobian of a 6-joint arm");
  }
  const Matrix6 jac = q.jacobian;
  const Vector6 gravity = (acceleration_ || force_) ? Vector6(q.gravity) : Vector6::Zero();
  // One elimination of J serves both the velocity and the acceleration term: [M_v | M_a].
  if (velocity_ || acceleration_) {
    using RowMajor6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;
    Eigen::Matrix<double, 6, 12> rhs;
    if (velocity_) rhs.leftCols<6>() = Eigen::Map<const RowMajor6>(attribute_row(q, 0, "M_v", "velocity"));
    if (acceleration_) rhs.rightCols<6>() = Eigen::Map<const RowMajor6>(attribute_row(q, velocity_ ? 1 : 0, "M_a", "acceleration"));
    if (!velocity_) rhs.leftCols<6>().setZero();
    if (!acceleration_) rhs.rightCols<6>().setZero();
    const bool solved = eliminate(jac, rhs);  // false: J singular, the terms give 0
    if (velocity_) out[k++] = solved ? ratio_eta(rhs.leftCols<6>(), Vector6(q.max_velocity), nullptr) : 0.0;
    if (acceleration_) {
      const Matrix6 b = Matrix6(q.inertia).lazyProduct(rhs.rightCols<6>());
      out[k++] = solved ? ratio_eta(b, Vector6(q.max_torque), &gravity) : 0.0;
    }
  }
  if (force_) out[k++] = eta_force(jac, gravity, Vector6(q.max_torque), options_.m_max, options_.f_max);
}

// After local_sample: clang refuses to multiversion a function already called.
void Coverage::local(const SampleQuantities& q, double* out) const { local_sample(q, out); }

double Coverage::combine(const double* reduced, int) const {
  const double reach_h = reduced[0], reach_m = reduced[1];
  double total = 0.0;
  if (pose_) total += reach_h > 0.0 ? reach_m / reach_h : 0.0;
  int k = 2;
  for (const bool term : {velocity_, acceleration_, force_}) {
    if (!term) continue;
    total += reach_m > 0.0 ? reduced[k] / reach_m : 0.0;
    ++k;
  }
  return total;
}

}  // namespace hapsyn::plugins
