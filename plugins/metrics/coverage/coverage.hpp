#pragma once
/// \file
/// The coverage metrics of Fennel, Zea, Hanebeck (IEEE ToH 2022, eqs. 9-18), an averaging metric:
///   J_x = n_reach^m / n_reach^h                        (pose, eqs. 10-11)
///   J_v = sum eta_v / n_reach^m, eta_v = min(1, min_ij qdot_max_i / |A_ij|),  A = J^-1 M_v  (12-14)
///   J_a = sum eta_a / n_reach^m, eta_a = min(1, min_ij tau_max_i / (|B_ij| + |tau_grav_i|)),
///         B = H J^-1 M_a                                (15-16)
///   J_f = sum eta_f / n_reach^m, eta_f like eta_a with C = J^T M_f, M_f = diag(m_max I, f_max I) (17-18)
///   J = the sum of the selected terms (eq. 9), each in [0, 1].
/// J, M_v, M_a are in the manipulator base B with rows (omega, v); the human_arm scene already
/// applies blockdiag(C_S^B, C_S^B) to M_v, M_a. Every scene sample is a human-reachable pose, so
/// n_reach^h is the sample count. A manipulator-unreachable (or singular / invalid) sample adds
/// 0 to n_reach^m and to every eta sum. With n_reach^m = 0, J_v = J_a = J_f = 0.
#include <hapsyn/accel/metric_acceleration.hpp>
#include <hapsyn/metric.hpp>
#include <hapsyn/accel/lanes.hpp>
#include <hapsyn/accel/sample_block.hpp>
#include <hapsyn/options.hpp>

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// Options of the coverage metric, declared once (the plugin's schema is derived from them).
struct CoverageOptions {
  std::vector<std::string> terms{};  ///< selected terms, each listed once (checked by Coverage)
  double m_max{};                    ///< [N m]
  double f_max{};                    ///< [N]

  static void declare(OptionDeclarations<CoverageOptions>& d) {
    d.describe(
        "Coverage of the human arm's capabilities by a 6-joint manipulator (Fennel, Zea, Hanebeck 2022, eqs. 9-18): "
        "the sum of the selected terms, each in [0, 1]. pose J_x = n_reach^m / n_reach^h; velocity J_v, acceleration "
        "J_a, force J_f = mean of eta over the manipulator-reachable samples. Needs the human_arm scene (M_v, M_a "
        "requested only for velocity / acceleration).");
    d.add(&CoverageOptions::terms, "terms", {"pose", "velocity", "acceleration", "force"},
          "Terms summed into the value: \"pose\" (J_x), \"velocity\" (J_v), \"acceleration\" (J_a), \"force\" "
          "(J_f). Only what the selected terms need is computed.")
        .one_of({"pose", "velocity", "acceleration", "force"})
        .min_size(1);
    d.add(&CoverageOptions::m_max, "m_max", 10.0, "Worst-case torque magnitude of the force/torque term (eq. 17).")
        .greater_than(0)
        .unit("N m");
    d.add(&CoverageOptions::f_max, "f_max", 50.0, "Worst-case force magnitude of the force/torque term (eq. 17).")
        .greater_than(0)
        .unit("N");
    d.rule({"terms"}, "no term listed twice", [](const CoverageOptions& o) -> std::string {
      for (std::size_t i = 0; i < o.terms.size(); ++i) {
        for (std::size_t k = 0; k < i; ++k) {
          if (o.terms[k] == o.terms[i]) return "[" + std::to_string(i) + "] = " + Json(o.terms[i]).dump() + ": listed twice";
        }
      }
      return "";
    });
  }
};

/// The "coverage" metric. Locals (all Sum-reduced): reach_h (1 per sample), reach_m (1 when the
/// manipulator reaches), then eta_v, eta_a, eta_f for the selected terms (0 when unreachable).
/// Thread safety: immutable after construction; local() is const, thread-safe, allocation-free.
class Coverage final : public Metric, public MetricAcceleration {
 public:
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  using Vector6 = Eigen::Matrix<double, 6, 1>;

  using Options = CoverageOptions;
  /// \param options validated options (CoverageOptions::declare).
  explicit Coverage(const CoverageOptions& options);

  void local(const SampleQuantities& q, double* out) const override;
  /// The block path (coverage_block.cpp, docs/design.md section 14): local() for every lane, one
  /// sample per SIMD lane (agreement to 1e-12 relative).
  bool has_local_block() const override { return true; }
  void local_block(const QuantityBlock& q, double* out) const override;
  /// pose only: kNeedPose; velocity: Jacobian + ActuatorLimits; acceleration: + Inertia +
  /// Gravity; force: Jacobian + Gravity + ActuatorLimits.
  Needs needs() const;
  MetricSpecs specs() const override { return {needs(), scene_attributes()}; }
  const MetricAcceleration* acceleration() const override { return this; }

  /// "M_v" for velocity, "M_a" for acceleration, nothing else.
  std::vector<std::string> scene_attributes() const;
  std::vector<LocalValue> locals() const override;
  /// The sum of the selected terms [-] (0 .. number of terms).
  double combine(const double* reduced, int samples) const override;
  Aggregation aggregation() const override { return Aggregation::kAveraging; }

  /// Which terms the options select.
  bool pose_term() const { return pose_; }
  bool velocity_term() const { return velocity_; }
  bool acceleration_term() const { return acceleration_; }
  bool force_term() const { return force_; }
  double m_max() const { return options_.m_max; }  ///< [N m]
  double f_max() const { return options_.f_max; }  ///< [N]

  /// Solves jacobian * x = x (x holds the right-hand side on entry, 6 x 6 or 6 x 12) by Gaussian
  /// elimination with partial pivoting: fixed size, allocation-free, and several times faster at
  /// this size than Eigen's PartialPivLU, which routes multi-column right-hand sides through its
  /// blocked kernels. Compiled for AVX2/FMA and baseline CPUs (hapsyn/accel/multiversion.hpp).
  /// \return false when a pivot is zero (J singular); x is then unspecified.
  static bool solve_jacobian(const Matrix6& jacobian, Eigen::Matrix<double, 6, 6>& x);
  static bool solve_jacobian(const Matrix6& jacobian, Eigen::Matrix<double, 6, 12>& x);

  /// solve_jacobian() for every lane of a block, one per SIMD lane: J is q's Jacobian (6 x 6
  /// per lane); x holds the right-hand sides on entry and the solutions on exit, entry (r, c) of
  /// lane i at x[r * 6 + c][i]. regular[i] is 1 when lane i's elimination met no zero pivot (x
  /// is then its solution, to 1e-12 relative of solve_jacobian()), else 0 (x finite, unspecified).
  static void solve_jacobian_block(const QuantityBlock& q, double (*x)[kBlockLanes], double* regular);
  /// As solve_jacobian_block, then times the block's inertia: x = H J^-1 x per lane (eq. 16's B
  /// for x = M_a), the products summed in column order as local() sums them.
  static void acceleration_torque_block(const QuantityBlock& q, double (*x)[kBlockLanes], double* regular);

  /// eq. 13 with A = J^-1 M_v (one LU of J). Singular J (non-finite A): 0.
  static double eta_velocity(const Matrix6& jacobian, const Matrix6& m_v, const Vector6& max_velocity);
  /// eq. 16 with B = H J^-1 M_a.
  static double eta_acceleration(const Matrix6& jacobian, const Matrix6& inertia, const Vector6& gravity,
                                 const Matrix6& m_a, const Vector6& max_torque);
  /// eqs. 17-18 with C = J^T M_f and the |tau_grav| term of eq. 16.
  static double eta_force(const Matrix6& jacobian, const Vector6& gravity, const Vector6& max_torque, double m_max,
                          double f_max);

 private:
  // local()'s body, compiled for AVX2/FMA and baseline CPUs (see hapsyn/accel/multiversion.hpp).
  void local_sample(const SampleQuantities& q, double* out) const;
  // local_block()'s body on lanes type L, inlined into each instruction set's entry
  // (hapsyn/accel/vector_dispatch.hpp; coverage_block.cpp).
  template <class L>
  void local_block_lanes(const QuantityBlock& q, double* out) const;
  template <int Cols, class L>  // inlined into local_block_lanes
  void velocity_acceleration(const QuantityBlock& q, const L (&jacobian)[6][6], const L* gravity, const L& reachable,
                             double* out, int& k) const;

  CoverageOptions options_;
  // The selected terms (options_.terms as flags: local() runs per sample).
  bool pose_{}, velocity_{}, acceleration_{}, force_{};
};

}  // namespace hapsyn::plugins
