#pragma once
/// \file
/// The validation of a design on recorded motion (Fennel, Zea, Hanebeck, IEEE ToH 2022, section
/// VII-B), an averaging metric: the share of the scene's samples that the manipulator reaches,
/// whose demanded velocity it achieves, and whose demanded acceleration it achieves within its
/// torque limits, by the full kinematic and dynamic model.
///
/// Per sample, with the demanded twist t and twist rate t' of the scene (SampleQuantities::twist,
/// twist_rate; the `motion` scene provides them) and the mechanism's quantities at the chosen
/// configuration q:
///   reachable             = the IK classifies the sample reachable (singular, invalid and
///                           unreachable samples fail every share);
///   velocity_feasible     = reachable and |qdot_i| <= qdot_max_i for every joint, J qdot = t;
///   acceleration_feasible = reachable and |tau_i| <= tau_max_i for every joint, with the full
///                           inverse dynamics tau = H(q) qddot + C(q, qdot) qdot + g(q) and
///                           J qddot = t' - Jdot qdot;
///   feasible              = all three.
/// The value is the chosen share's mean over the samples (the weighted mean with scene weights).
/// A sample exactly at a limit is feasible.
#include <hapsyn/metric.hpp>
#include <hapsyn/options.hpp>

#include <string>
#include <vector>

namespace hapsyn::plugins {

/// Options of the motion_feasibility metric, declared once (the schema follows from them).
struct MotionFeasibilityOptions {
  std::string share{};  ///< "reachable", "velocity", "acceleration" or "all"

  static void declare(OptionDeclarations<MotionFeasibilityOptions>& d) {
    d.describe(
        "Share of the samples of recorded motion that a design serves (Fennel 2022, section VII-B): reachable (IK), "
        "velocity feasible (joint rates J^-1 v within the actuator limits) or acceleration feasible (the full inverse "
        "dynamics H qddot + C qdot + g within the torque limits); unreachable samples fail every share. Needs a scene "
        "with the demanded twist per sample (the motion scene). Only what the chosen share needs is computed.");
    d.add(&MotionFeasibilityOptions::share, "share", "all",
          "Which share is the value: \"reachable\", \"velocity\" (reachable and velocity feasible), "
          "\"acceleration\" (reachable and torque feasible) or \"all\" (all three at once). The per-sample columns "
          "of every share computed are in samples.csv.")
        .one_of({"reachable", "velocity", "acceleration", "all"});
  }
};

/// The "motion_feasibility" metric. Locals (all sum-reduced, 0 or 1 per sample): `reachable`,
/// then `velocity_feasible` (shares velocity, all), `acceleration_feasible` (acceleration, all),
/// `feasible` (all). Thread safety: immutable after construction; local() is const,
/// thread-safe and allocation-free.
class MotionFeasibility final : public Metric {
 public:
  using Options = MotionFeasibilityOptions;
  /// \param options validated options (MotionFeasibilityOptions::declare).
  explicit MotionFeasibility(const MotionFeasibilityOptions& options);

  void local(const SampleQuantities& q, double* out) const override;
  /// reachable: pose only; velocity: joint velocity and actuator limits; acceleration: joint
  /// acceleration, velocity torque, inertia, gravity and actuator limits; all: the union.
  Needs needs() const;
  MetricSpecs specs() const override { return {needs(), {}}; }
  std::vector<LocalValue> locals() const override;
  /// The chosen share [-] in [0, 1]: its sum over the samples / the sample count.
  double combine(const double* reduced, int samples) const override;
  Aggregation aggregation() const override { return Aggregation::kAveraging; }

  /// Whether q's joint rates are within the actuator velocity limits (q reachable).
  static bool velocity_within_limits(const SampleQuantities& q);
  /// Whether the full inverse-dynamics torque H qddot + c + g is within the torque limits.
  static bool torque_within_limits(const SampleQuantities& q);

 private:
  bool velocity_ = false;      // velocity_feasible is computed
  bool acceleration_ = false;  // acceleration_feasible is computed
  bool all_ = false;           // feasible is computed
  int value_local_ = 0;        // the local whose mean is the value
};

}  // namespace hapsyn::plugins
