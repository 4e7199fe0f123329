#pragma once
/// \file
/// Bounds of one sample's quantities over a block of designs: the designs that equal a given
/// design except in one component, which runs over an interval (a run of a grid line). A
/// mechanism fills what it can prove (MechanismAcceleration::sample_envelope), a worst-case metric turns it
/// into an upper bound of its value (MetricAcceleration::envelope_bound), and a grid solver then rules out
/// the whole block at once when that bound cannot beat its reference (docs/design.md
/// section 13.5). Every field is a rigorous bound, rounding included: a field the mechanism
/// cannot prove keeps its default, which says nothing.
#include <limits>

namespace hapsyn {

struct SampleEnvelope {
  /// True when the sample fails (is not kReachable) for every design of the block: each of them
  /// is infeasible in a worst-case study, whatever the metrics.
  bool all_fail = false;
  /// Upper bound of sigma_min(J) / sigma_max(J) (J as the mechanism returns it) over the
  /// designs of the block that reach the sample [-]. Default: +inf (no bound).
  double jacobian_inverse_condition_max = std::numeric_limits<double>::infinity();
  /// Lower bound of sigma_max(M), M the effective mass at the end effector, over the designs of
  /// the block that reach the sample [kg]. Default: 0 (no bound).
  double effective_mass_sigma_max_min = 0.0;
};

}  // namespace hapsyn
