#pragma once
/// \file
/// The five-bar's block bound of one sample over a run of r (KERNELS.md section 13.5).
///
/// The designs (l0, l1, l2, r) with r in [r_lo, r_hi] put the sample (x, y) at E = (x, Y),
/// Y = y + r in [y + r_lo, y + r_hi]. Everything the metrics use is a function of three angles
/// of the two leg triangles (A_i, B_i, E), each monotone in Y or in the leg's reach rho_i:
/// - the transmission sines |sin(q1 - q2)| = sin(gamma_1), |sin(q3 - q4)| = sin(gamma_2), gamma_i
///   the elbow angle, cos(gamma_i) = (l1^2 + l2^2 - rho_i^2) / (2 l1 l2), rho_i increasing in Y;
/// - the free links' angles q2 = theta_1 - beta_1 and q3 = pi - (theta_2' - beta_2), theta the
///   angle of E - A (theta_2' in the frame mirrored about x = 0, as the model solves the right
///   leg) and beta_i the triangle's angle at E, cos(beta_i) = (rho_i^2 + l2^2 - l1^2) /
///   (2 l2 rho_i);
/// - J^-1 has the rows w_i / b_i of norms 1 / (l1 sin(gamma_i)) at the angle q3 - q2.
/// Interval bounds of these angles (from the run's two ends and the one interior extremum of
/// cos(beta)) bound sigma_min(J) / sigma_max(J) from above and sigma_max(M) from below, and
/// prove failure (unreachable, singular or outside the paper's G) for every design of the run.
/// Each angle interval is widened by 1e-9 rad and each final bound by 1e-9 relative, far above
/// the rounding of the model and of these formulas.
#include <hapsyn/accel/sample_envelope.hpp>

namespace hapsyn::plugins {

/// One run of designs differing in r only.
struct FiveBarRun {
  double h0 = 0.0;      ///< l0 / 2 [m], as the model computes it
  double l1 = 0.0;      ///< actuated link length [m]
  double l2 = 0.0;      ///< free link length [m]
  double y_low = 0.0;   ///< y + r at the run's smallest r [m] (the model's rounded sum)
  double y_high = 0.0;  ///< y + r at the run's largest r [m]
  double singularity_tolerance = 0.0;  ///< the model's option [-]
  double inertia_a = 0.0;  ///< actuated bar about its joint [kg m^2]
  double mass_f = 0.0;     ///< free bar mass [kg]
  double inertia_f = 0.0;  ///< free bar about its centre [kg m^2]
};

/// Fills `out` for the sample (x, y_low .. y_high) of the run (the bound of sigma_max(M) only
/// when `effective_mass` is set). Returns false when it proves
/// nothing (part of the run at or below the actuated joints' axis, Y <= 0). No allocation.
bool fivebar_envelope(const FiveBarRun& run, double x, bool effective_mass, SampleEnvelope& out);

}  // namespace hapsyn::plugins
