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
#include <hapsyn/json.hpp>
#include <hapsyn/metric.hpp>

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// The "coverage" metric. Locals (all Sum-reduced): reach_h (1 per sample), reach_m (1 when the
/// manipulator reaches), then eta_v, eta_a, eta_f for the selected terms (0 when unreachable).
/// Thread safety: immutable after construction; local() is const, thread-safe, allocation-free.
class Coverage final : public Metric {
 public:
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  using Vector6 = Eigen::Matrix<double, 6, 1>;

  /// Options: terms (array of "pose", "velocity", "acceleration", "force"; default all),
  /// m_max [N m] (default 10), f_max [N] (default 50). \throws Error for bad options.
  explicit Coverage(const Json& options);

  void local(const SampleQuantities& q, double* out) const override;
  /// pose only: kNeedPose; velocity: Jacobian + ActuatorLimits; acceleration: + Inertia +
  /// Gravity; force: Jacobian + Gravity + ActuatorLimits.
  Needs needs() const override;
  /// "M_v" for velocity, "M_a" for acceleration, nothing else.
  std::vector<std::string> scene_attributes() const override;
  std::vector<LocalValue> locals() const override;
  /// The sum of the selected terms [-] (0 .. number of terms).
  double combine(const double* reduced, int samples) const override;
  Aggregation aggregation() const override { return Aggregation::kAveraging; }

  bool pose() const { return pose_; }
  bool velocity() const { return velocity_; }
  bool acceleration() const { return acceleration_; }
  bool force() const { return force_; }
  double m_max() const { return m_max_; }
  double f_max() const { return f_max_; }

  /// Solves jacobian * x = x (x holds the right-hand side on entry, 6 x 6 or 6 x 12) by Gaussian
  /// elimination with partial pivoting: fixed size, allocation-free, and several times faster at
  /// this size than Eigen's PartialPivLU, which routes multi-column right-hand sides through its
  /// blocked kernels. Compiled for AVX2/FMA and baseline CPUs (hapsyn/multiversion.hpp).
  /// \return false when a pivot is zero (J singular); x is then unspecified.
  static bool solve_jacobian(const Matrix6& jacobian, Eigen::Matrix<double, 6, 6>& x);
  static bool solve_jacobian(const Matrix6& jacobian, Eigen::Matrix<double, 6, 12>& x);

  /// eq. 13 with A = J^-1 M_v (one LU of J). Singular J (non-finite A): 0.
  static double eta_velocity(const Matrix6& jacobian, const Matrix6& m_v, const Vector6& max_velocity);
  /// eq. 16 with B = H J^-1 M_a.
  static double eta_acceleration(const Matrix6& jacobian, const Matrix6& inertia, const Vector6& gravity,
                                 const Matrix6& m_a, const Vector6& max_torque);
  /// eqs. 17-18 with C = J^T M_f and the |tau_grav| term of eq. 16.
  static double eta_force(const Matrix6& jacobian, const Vector6& gravity, const Vector6& max_torque, double m_max,
                          double f_max);

 private:
  // local()'s body, compiled for AVX2/FMA and baseline CPUs (see hapsyn/multiversion.hpp).
  void local_sample(const SampleQuantities& q, double* out) const;

  bool pose_ = true, velocity_ = true, acceleration_ = true, force_ = true;
  double m_max_ = 10.0, f_max_ = 50.0;
};

}  // namespace hapsyn::plugins
