#include "fivebar_envelope.hpp"

#include <hapsyn/fast_math.hpp>

#include <algorithm>
#include <cmath>

namespace hapsyn::plugins {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Far above the rounding of the model's angles and of the formulas here (a few 1e-16 rad), far
// below what the bounds need to be useful.
constexpr double kAngleMargin = 1e-9;
constexpr double kRelativeMargin = 1e-9;

struct Interval {
  double lo, hi;
  Interval widened(double by) const { return {lo - by, hi + by}; }
};

Interval hull(double a, double b) { return {std::min(a, b), std::max(a, b)}; }

// The inline sine, arc tangent and arc cosine of hapsyn/fast_math.hpp (absolute errors below
// 1e-15 rad, far inside the margins): libm's calls were most of an envelope's cost.
double sine(double a) {
  double s = 0.0, c = 0.0;
  fast::sin_cos(a, s, c);
  return s;
}
double arc_cos(double c) { return fast::atan2(std::sqrt((1.0 - c) * (1.0 + c)), c); }

// Largest and smallest |sin| over an angle interval.
double sup_abs_sin(Interval a) {
  if (a.hi - a.lo >= kPi) return 1.0;
  const double k = std::ceil((a.lo - 0.5 * kPi) / kPi);  // the first pi/2 + k pi at or above lo
  if (0.5 * kPi + k * kPi <= a.hi) return 1.0;
  return std::max(std::abs(sine(a.lo)), std::abs(sine(a.hi)));
}
double inf_abs_sin(Interval a) {
  if (a.hi - a.lo >= kPi) return 0.0;
  if (std::ceil(a.lo / kPi) * kPi <= a.hi) return 0.0;
  return std::min(std::abs(sine(a.lo)), std::abs(sine(a.hi)));
}

// acos over an interval of cosines (clamped to [-1, 1]): decreasing.
Interval acos_of(Interval c) {
  return {arc_cos(std::clamp(c.hi, -1.0, 1.0)), arc_cos(std::clamp(c.lo, -1.0, 1.0))};
}

// What one leg contributes: its triangle's angles over the run, for the designs that reach E.
struct LegBounds {
  bool unreachable = false;  // |E - A| outside [|l1 - l2|, l1 + l2] for every design
  Interval sin_gamma{};      // the transmission sine sin(gamma) = |sin(q1 - q2)| (or q3 - q4)
  double abs_cos_gamma_lo = 0.0;  // the smallest |cos(gamma)|
  double rho_lo = 0.0, rho_hi = 0.0;  // |E - A| over the designs that reach E [m]
  Interval theta{}, beta{};
};

// The leg with E - A = (dx, Y), Y in [y_low, y_high] > 0: rho grows with Y; theta = atan2(Y, dx)
// is monotone in Y (increasing for dx > 0, decreasing for dx < 0), so both are hulls of the ends.
LegBounds leg_bounds(double dx, const FiveBarRun& run) {
  LegBounds leg;
  const double l1 = run.l1, l2 = run.l2;
  const double rho_low = std::sqrt(dx * dx + run.y_low * run.y_low) * (1.0 - 1e-12);
  const double rho_high = std::sqrt(dx * dx + run.y_high * run.y_high) * (1.0 + 1e-12);
  const double reach_min = std::abs(l1 - l2), reach_max = l1 + l2;
  if (rho_low > reach_max * (1.0 + kRelativeMargin) || rho_high < reach_min * (1.0 - kRelativeMargin)) {
    leg.unreachable = true;
    return leg;
  }
  // Only designs that reach E matter for the bounds below.
  const double lo = std::max(rho_low, reach_min), hi = std::min(rho_high, reach_max);
  leg.rho_lo = lo;
  leg.rho_hi = hi;
  // Elbow angle: cos(gamma) = (l1^2 + l2^2 - rho^2) / (2 l1 l2), decreasing in rho; sin(gamma)
  // = sqrt(1 - cos^2) is concave in gamma on [0, pi], so its minimum is at an end. (A margin of
  // 1e-9 on the cosine covers one of 1e-9 rad on gamma.)
  const double inv_gamma = 1.0 / (2.0 * l1 * l2);
  const Interval cos_gamma = Interval{(l1 * l1 + l2 * l2 - hi * hi) * inv_gamma,
                                      (l1 * l1 + l2 * l2 - lo * lo) * inv_gamma}.widened(kAngleMargin);
  const double c_lo = std::clamp(cos_gamma.lo, -1.0, 1.0), c_hi = std::clamp(cos_gamma.hi, -1.0, 1.0);
  const double sin_a = std::sqrt((1.0 - c_lo) * (1.0 + c_lo)), sin_b = std::sqrt((1.0 - c_hi) * (1.0 + c_hi));
  leg.sin_gamma = {std::min(sin_a, sin_b), (c_lo <= 0.0 && 0.0 <= c_hi) ? 1.0 : std::max(sin_a, sin_b)};
  leg.abs_cos_gamma_lo = (c_lo <= 0.0 && 0.0 <= c_hi) ? 0.0 : std::min(std::abs(c_lo), std::abs(c_hi));
  return leg;
}

// The leg's angles theta = atan2(Y, dx) (monotone in Y: increasing for dx > 0, decreasing for
// dx < 0, so a hull of the ends) and beta (see below), for the designs that reach E.
void leg_angles(double dx, const FiveBarRun& run, LegBounds& leg) {
  const double l1 = run.l1, l2 = run.l2, lo = leg.rho_lo, hi = leg.rho_hi;
  leg.theta = hull(fast::atan2(run.y_low, dx), fast::atan2(run.y_high, dx)).widened(kAngleMargin);
  // Angle at E: cos(beta) = (rho + (l2^2 - l1^2) / rho) / (2 l2), smallest at
  // rho = sqrt(l2^2 - l1^2) when l2 > l1, monotone on either side of it.
  const double d = (l2 - l1) * (l2 + l1);
  const auto cos_beta = [&](double rho) { return (rho + d / rho) / (2.0 * l2); };
  Interval c = hull(cos_beta(lo), cos_beta(hi));
  if (d > 0.0) {
    const double turn = std::sqrt(d);
    if (turn > lo && turn < hi) c.lo = std::min(c.lo, cos_beta(turn));
  }
  leg.beta = acos_of(c).widened(kAngleMargin);
}

// The largest 2 s1 s2 / (s1^2 + s2^2) = 2t / (1 + t^2), t = s1 / s2, over two intervals: 1 when
// they overlap (t = 1), else at the closest pair of ends (the function rises to t = 1).
double sup_balance(Interval s1, Interval s2) {
  double t = 1.0;
  if (s1.hi < s2.lo) t = s1.hi / s2.lo;
  if (s2.hi < s1.lo) t = s2.hi / s1.lo;
  return 2.0 * t / (1.0 + t * t);
}

// sigma_max(M) from below: the kinetic energy 1/2 v^T M v of a unit task velocity v, over the
// designs of the run. With qdot = J^-1 v, each leg's actuated bar gives I_a qdot_i^2, its free
// bar's centre moves at (v_B + v) / 2 with |v_B| = l1 |qdot_i|, so m2 |.|^2 >= m2 / 4
// (l1 |qdot_i| - 1)_+^2, and the free bar turns at omega_i = perp(w_i) . (v - v_B) / l2^2 with
// |perp(w_i) . v_B| = l1 l2 |cos(gamma_i)| |qdot_i|, so I_f omega_i^2 >= I_f / l2^2
// (l1 |cos(gamma_i)| |qdot_i| - 1)_+^2. Both are convex in qdot_i^2; for v the top singular
// vector of J^-1 the qdot_i^2 add up to S = sigma_max(J^-1)^2, so (Jensen) the sum over the legs is
// at least twice its value at qdot_i^2 = S / 2. S is increasing in the row norms n_i = 1 / (l1
// sin(gamma_i)) and decreasing in |sin(q3 - q2)|. Also, along v perpendicular to w_2 (actuator 2
// at rest, free bar 2 turning about B2 at 1 / l2) the energy is at least I_a sin^2(q3 - q2) n_1^2 +
// m2 / 4 + I_f / l2^2; likewise for leg 1.
double effective_mass_bound(const FiveBarRun& run, const LegBounds& left, const LegBounds& right, Interval mode) {
  const double n1 = 1.0 / (run.l1 * left.sin_gamma.hi), n2 = 1.0 / (run.l1 * right.sin_gamma.hi);
  const double sin_hi = sup_abs_sin(mode), sin_lo = inf_abs_sin(mode);
  const double sum = n1 * n1 + n2 * n2;
  const double top = 0.5 * (sum + std::sqrt(std::max(0.0, sum * sum - 4.0 * n1 * n1 * n2 * n2 * sin_hi * sin_hi)));
  const double half = std::sqrt(0.5 * top);  // |qdot_i| at qdot_i^2 = S / 2
  const double cos_lo = std::min(left.abs_cos_gamma_lo, right.abs_cos_gamma_lo);
  const double centre = std::max(0.0, run.l1 * half - 1.0), turn = std::max(0.0, run.l1 * cos_lo * half - 1.0);
  const double along_top = run.inertia_a * top + 2.0 * (run.mass_f / 4.0 * centre * centre +
                                                        run.inertia_f / (run.l2 * run.l2) * turn * turn);
  const double n_max = std::max(n1, n2);
  const double at_rest = run.inertia_a * sin_lo * sin_lo * n_max * n_max + run.mass_f / 4.0 +
                         run.inertia_f / (run.l2 * run.l2);
  return std::max(along_top, at_rest) * (1.0 - kRelativeMargin);
}

}  // namespace

bool fivebar_envelope(const FiveBarRun& run, double x, SampleEnvelope& out) {
  if (!(run.y_low > 0.0) || !(run.y_high >= run.y_low)) return false;
  out = SampleEnvelope{};
  // The model solves the left leg with dx = x + h0 and the right one mirrored, dx = h0 - x.
  const double dx_left = x + run.h0, dx_right = run.h0 - x;
  LegBounds left = leg_bounds(dx_left, run), right = leg_bounds(dx_right, run);
  // The tests without trigonometry first: out of reach, or a transmission sine below the
  // singularity tolerance for every design.
  const double tol = run.singularity_tolerance * (1.0 - 1e-6);
  const Interval s1 = left.sin_gamma, s2 = right.sin_gamma;
  if (left.unreachable || right.unreachable || s1.hi < tol || s2.hi < tol) {
    out.all_fail = true;
    return true;
  }
  leg_angles(dx_left, run, left);
  leg_angles(dx_right, run, right);
  // q2 = theta_1 - beta_1 and the mirrored free angle theta_2' - beta_2 (q3 = pi - it); a free
  // link pointing down (below -margin) fails the paper's G or is singular (section 13.2).
  const Interval q2{left.theta.lo - left.beta.hi, left.theta.hi - left.beta.lo};
  const Interval q3_mirrored{right.theta.lo - right.beta.hi, right.theta.hi - right.beta.lo};
  const Interval mode{kPi - q3_mirrored.hi - q2.hi, kPi - q3_mirrored.lo - q2.lo};  // q3 - q2
  if (q2.hi < -1e-6 || q3_mirrored.hi < -1e-6 || mode.hi < -1e-6 || sup_abs_sin(mode) < tol) {
    out.all_fail = true;
    return true;
  }
  // J^-1 rows: norms n_i = 1 / (l1 s_i) at the angle q3 - q2, so with
  // g = 2 sigma_1 sigma_2 / (sigma_1^2 + sigma_2^2) = |sin(q3 - q2)| 2 s1 s2 / (s1^2 + s2^2),
  // sigma_min / sigma_max = g / (1 + sqrt(1 - g^2)), increasing in g.
  const double g = std::min(1.0, sup_abs_sin(mode) * sup_balance(s1, s2));
  const double kappa = g / (1.0 + std::sqrt(std::max(0.0, (1.0 - g) * (1.0 + g))));
  out.jacobian_inverse_condition_max = std::min(1.0, kappa * (1.0 + kRelativeMargin) + 1e-12);
  out.effective_mass_sigma_max_min = effective_mass_bound(run, left, right, mode);
  return true;
}

}  // namespace hapsyn::plugins

