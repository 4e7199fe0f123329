#include "fivebar_envelope.hpp"

#include <hapsyn/accel/fast_math.hpp>
#include <hapsyn/accel/multiversion.hpp>

#include <algorithm>
#include <cmath>

namespace hapsyn::plugins {

// The helpers below are always inlined into fivebar_envelope, which is compiled for AVX-512,
// AVX2 and the baseline and picked at load time (HAPSYN_MULTIVERSION_WIDE): out of line they
// would run the baseline code whatever the machine. Paper-resolution culling on one thread
// (user time, same session): GII 4.5 s to 4.05 s, GDI 5.5 s to 5.3 s.
namespace {

constexpr double kPi = 3.14159265358979323846;
// Far above the rounding of the model's angles and of the formulas here (a few 1e-16 rad), far
// below what the bounds need to be useful.
constexpr double kAngleMargin = 1e-9;
constexpr double kRelativeMargin = 1e-9;

struct Interval {
  double lo, hi;
  [[gnu::always_inline]] Interval widened(double by) const { return {lo - by, hi + by}; }
};

[[gnu::always_inline]] inline Interval hull(double a, double b) { return {std::min(a, b), std::max(a, b)}; }

// sin and cos over an angle interval: the ends, and 1 or -1 where an extremum lies inside. The
// inline sin_cos of hapsyn/accel/fast_math.hpp (absolute error below 1e-15, far inside the margins):
// libm's calls were most of an envelope's cost.
[[gnu::always_inline]] inline void sin_cos_of(Interval a, Interval& sine_of, Interval& cosine_of) {
  if (a.hi - a.lo >= 2.0 * kPi) {
    sine_of = cosine_of = {-1.0, 1.0};
    return;
  }
  double s0 = 0.0, c0 = 0.0, s1 = 0.0, c1 = 0.0;
  fast::sin_cos(a.lo, s0, c0);
  fast::sin_cos(a.hi, s1, c1);
  sine_of = hull(s0, s1);
  cosine_of = hull(c0, c1);
  // The extrema lie at the multiples j pi/2 inside the interval (at most four, it is shorter
  // than 2 pi): j mod 4 = 0 is cos = 1, 1 is sin = 1, 2 is cos = -1, 3 is sin = -1. One product
  // and one rounding per end instead of a division per extremum; a multiple within rounding of
  // an end moves the bound by the square of that rounding (the extrema are flat), far inside
  // the margins.
  constexpr double kInvHalfPi = 6.36619772367581382433e-01;
  const double first = fast::ceil_small(a.lo * kInvHalfPi), last = fast::floor_small(a.hi * kInvHalfPi);
  for (double j = first; j <= last; j += 1.0) {
    switch (static_cast<long long>(j) & 3) {
      case 0: cosine_of.hi = 1.0; break;
      case 1: sine_of.hi = 1.0; break;
      case 2: cosine_of.lo = -1.0; break;
      default: sine_of.lo = -1.0; break;
    }
  }
}

// Largest and smallest |sin| over an angle interval.
[[gnu::always_inline]] inline Interval abs_sin_of(Interval a) {
  Interval s{}, c{};
  sin_cos_of(a, s, c);
  const double lo = (s.lo <= 0.0 && 0.0 <= s.hi) ? 0.0 : std::min(std::abs(s.lo), std::abs(s.hi));
  return {lo, std::max(std::abs(s.lo), std::abs(s.hi))};
}


// What one leg contributes: its triangle's angles over the run, for the designs that reach E.
struct LegBounds {
  bool unreachable = false;  // |E - A| outside [|l1 - l2|, l1 + l2] for every design
  Interval sin_gamma{};      // the transmission sine sin(gamma) = |sin(q1 - q2)| (or q3 - q4)
  Interval cos_gamma{};      // cos(gamma) (clamped to [-1, 1])
  double rho2_lo = 0.0, rho2_hi = 0.0;  // |E - A|^2 over the designs that reach E [m^2]
  double rho_lo = 0.0, rho_hi = 0.0;    // |E - A| (set by leg_angles) [m]
  Interval free{};  // the free link's angle theta - beta (q2; for the mirrored right leg pi - q3)
  Interval act{};   // the actuated link's angle theta + alpha (q1; mirrored: pi - q4)
};

// The leg with E - A = (dx, Y), Y in [y_low, y_high] > 0: rho grows with Y; theta = atan2(Y, dx)
// is monotone in Y (increasing for dx > 0, decreasing for dx < 0), so both are hulls of the ends.
[[gnu::always_inline]] inline LegBounds leg_bounds(double dx, const FiveBarRun& run) {
  LegBounds leg;
  const double l1 = run.l1, l2 = run.l2;
  // Squares first: the reach test and the elbow angle need no square root.
  const double rho2_low = (dx * dx + run.y_low * run.y_low) * (1.0 - 1e-12);
  const double rho2_high = (dx * dx + run.y_high * run.y_high) * (1.0 + 1e-12);
  const double reach_min = std::abs(l1 - l2), reach_max = l1 + l2;
  if (rho2_low > reach_max * reach_max * (1.0 + kRelativeMargin) ||
      rho2_high < reach_min * reach_min * (1.0 - kRelativeMargin)) {
    leg.unreachable = true;
    return leg;
  }
  // Only designs that reach E matter for the bounds below.
  const double lo2 = std::max(rho2_low, reach_min * reach_min), hi2 = std::min(rho2_high, reach_max * reach_max);
  leg.rho2_lo = lo2;
  leg.rho2_hi = hi2;
  // Elbow angle: cos(gamma) = (l1^2 + l2^2 - rho^2) / (2 l1 l2), decreasing in rho; sin(gamma)
  // = sqrt(1 - cos^2) is concave in gamma on [0, pi], so its minimum is at an end. (A margin of
  // 1e-9 on the cosine covers one of 1e-9 rad on gamma.)
  const double inv_gamma = 1.0 / (2.0 * l1 * l2);
  const Interval cos_gamma = Interval{(l1 * l1 + l2 * l2 - hi2) * inv_gamma,
                                      (l1 * l1 + l2 * l2 - lo2) * inv_gamma}.widened(kAngleMargin);
  const double c_lo = std::clamp(cos_gamma.lo, -1.0, 1.0), c_hi = std::clamp(cos_gamma.hi, -1.0, 1.0);
  const double sin_a = std::sqrt((1.0 - c_lo) * (1.0 + c_lo)), sin_b = std::sqrt((1.0 - c_hi) * (1.0 + c_hi));
  leg.sin_gamma = {std::min(sin_a, sin_b), (c_lo <= 0.0 && 0.0 <= c_hi) ? 1.0 : std::max(sin_a, sin_b)};
  leg.cos_gamma = {c_lo, c_hi};
  return leg;
}

// The cosine of the angle between the side of length `a` and the side rho of a triangle with
// third side b, over rho in [lo, hi]: (rho + (a^2 - b^2) / rho) / (2 a), smallest at rho =
// sqrt(a^2 - b^2) when a > b, monotone on either side of it (at E: a = l2, b = l1, the angle
// beta; at A: a = l1, b = l2, the angle alpha). Clamped to [-1, 1] and widened by the margin.
[[gnu::always_inline]] inline double triangle_cosine_at(double a, double d, double rho) {
  return (rho + d / rho) / (2.0 * a);
}
[[gnu::always_inline]] inline Interval triangle_cosine(double a, double b, double lo, double hi) {
  const double d = (a - b) * (a + b);
  Interval c = hull(triangle_cosine_at(a, d, lo), triangle_cosine_at(a, d, hi));
  if (d > 0.0) {
    const double turn = std::sqrt(d);
    if (turn > lo && turn < hi) c.lo = std::min(c.lo, triangle_cosine_at(a, d, turn));
  }
  return {std::max(-1.0, c.lo - kAngleMargin), std::min(1.0, c.hi + kAngleMargin)};
}

// (dx, y) turned by acos(c), clockwise (turn = -1) or counter-clockwise (turn = +1): its atan2
// is atan2(y, dx) -+ acos(c) modulo 2 pi, one arc tangent instead of two.
struct Turned {
  double x, y;
  [[gnu::always_inline]] double angle() const { return fast::atan2(y, x); }
  // Within 1e-6 rad of atan2's branch cut at +-pi.
  [[gnu::always_inline]] bool near_cut() const { return x < 0.0 && std::abs(y) <= 1e-6 * -x; }
  // Within 1e-6 rad of 0.
  [[gnu::always_inline]] bool near_zero() const { return x > 0.0 && std::abs(y) <= 1e-6 * x; }
};
[[gnu::always_inline]] inline Turned turned(double dx, double y, double c, double turn) {
  const double s = std::sqrt((1.0 - c) * (1.0 + c)) * turn;
  return {dx * c - y * s, y * c + dx * s};
}

// The leg's angles over the run, for the designs that reach E: theta = atan2(Y, dx) is monotone
// in Y (increasing for dx > 0, decreasing for dx < 0), so its extremes are at the run's ends,
// and the free link's angle theta - beta lies in (-pi, pi): its lower end is the smaller theta
// minus the larger beta, one atan2 of a rotated vector (likewise the upper end).
[[gnu::always_inline]] inline void leg_angles(double dx, const FiveBarRun& run, LegBounds& leg) {
  leg.rho_lo = std::sqrt(leg.rho2_lo);
  leg.rho_hi = std::sqrt(leg.rho2_hi);
  const double y_small = dx >= 0.0 ? run.y_low : run.y_high, y_large = dx >= 0.0 ? run.y_high : run.y_low;
  const Interval beta_cos = triangle_cosine(run.l2, run.l1, leg.rho_lo, leg.rho_hi);
  const Turned lo = turned(dx, y_small, beta_cos.lo, -1.0), hi = turned(dx, y_large, beta_cos.hi, -1.0);
  // Near the cut the atan2 may land on the wrong side: the conservative end (the true angle
  // lies inside (-pi, pi)).
  leg.free = {lo.near_cut() ? -kPi : lo.angle(), hi.near_cut() ? kPi : hi.angle()};
  if (!(leg.free.lo <= leg.free.hi)) leg.free = {-kPi, kPi};
  leg.free = leg.free.widened(2.0 * kAngleMargin);
}

// The actuated link's angle theta + alpha in (0, 2 pi) (the model's q1, or q4 = pi - it for the
// mirrored right leg), alpha the triangle's angle at A, in the same way (after leg_angles).
[[gnu::always_inline]] inline void leg_actuated_angle(double dx, const FiveBarRun& run, LegBounds& leg) {
  const double y_small = dx >= 0.0 ? run.y_low : run.y_high, y_large = dx >= 0.0 ? run.y_high : run.y_low;
  const Interval alpha_cos = triangle_cosine(run.l1, run.l2, leg.rho_lo, leg.rho_hi);
  const Turned lo_turned = turned(dx, y_small, alpha_cos.hi, 1.0), hi_turned = turned(dx, y_large, alpha_cos.lo, 1.0);
  // atan2 gives the angle modulo 2 pi in (-pi, pi], so an angle in (0, 2 pi) is it or it plus
  // 2 pi; near 0 it could be 0+ or 2 pi-: then the whole range.
  double lo = lo_turned.angle(), hi = hi_turned.angle();
  if (lo <= 0.0) lo += 2.0 * kPi;
  if (hi <= 0.0) hi += 2.0 * kPi;
  const bool unsure = lo_turned.near_zero() || hi_turned.near_zero() || !(lo <= hi);
  leg.act = (unsure ? Interval{0.0, 2.0 * kPi} : Interval{lo, hi}).widened(2.0 * kAngleMargin);
}

// The largest 2 s1 s2 / (s1^2 + s2^2) = 2t / (1 + t^2), t = s1 / s2, over two intervals: 1 when
// they overlap (t = 1), else at the closest pair of ends (the function rises to t = 1).
[[gnu::always_inline]] inline double sup_balance(Interval s1, Interval s2) {
  double t = 1.0;
  if (s1.hi < s2.lo) t = s1.hi / s2.lo;
  if (s2.hi < s1.lo) t = s2.hi / s1.lo;
  return 2.0 * t / (1.0 + t * t);
}

// Interval arithmetic for the energy along one direction. Each operation rounds by a few 1e-16
// relative; the result's margin covers that.
[[gnu::always_inline]] inline Interval operator+(Interval a, Interval b) { return {a.lo + b.lo, a.hi + b.hi}; }
[[gnu::always_inline]] inline Interval operator-(Interval a) { return {-a.hi, -a.lo}; }
[[gnu::always_inline]] inline Interval operator*(double k, Interval a) { return k >= 0.0 ? Interval{k * a.lo, k * a.hi} : Interval{k * a.hi, k * a.lo}; }
[[gnu::always_inline]] inline Interval operator*(Interval a, Interval b) {
  const double p[4] = {a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi};
  return {std::min(std::min(p[0], p[1]), std::min(p[2], p[3])), std::max(std::max(p[0], p[1]), std::max(p[2], p[3]))};
}
[[gnu::always_inline]] inline Interval square(Interval a) {
  if (a.lo >= 0.0) return {a.lo * a.lo, a.hi * a.hi};
  if (a.hi <= 0.0) return {a.hi * a.hi, a.lo * a.lo};
  return {0.0, std::max(a.lo * a.lo, a.hi * a.hi)};
}

// The smallest |c| over an interval.
[[gnu::always_inline]] inline double abs_lo(Interval c) {
  return (c.lo <= 0.0 && 0.0 <= c.hi) ? 0.0 : std::min(std::abs(c.lo), std::abs(c.hi));
}

// The smallest l1^2 qdot^2 + 1 - 2 l1 qdot s = (l1 qdot - s)^2 + (1 - s^2) over l1 qdot in `a`
// and s in `s` (|s| <= 1): the squared gap between the two intervals plus 1 - max s^2. Each
// term's minimum is a lower bound, as the interval sum is; this one keeps l1 qdot and s
// together in one square.
[[gnu::always_inline]] inline double squared_centre(Interval a, Interval s) {
  const double gap = std::max(0.0, std::max(a.lo - s.hi, s.lo - a.hi));
  return gap * gap + (1.0 - square(s).hi);
}

// The smallest squared turning rate of a free bar, cos^2(q_act - psi) / (l2 sin(gamma))^2, over
// `c` (the interval of cos(q_act - psi)) and sin(gamma) <= sin_gamma_hi. From q_act - q_free =
// +-(pi - gamma) (the leg triangle's angles add up to pi), (sin(psi - q_free) + l1 qdot
// cos(gamma)) / l2 with qdot = -+cos(q_free - psi) / (l1 sin(gamma)) is +-cos(q_act - psi) /
// (l2 sin(gamma)): one interval instead of three.
[[gnu::always_inline]] inline double turn_squared(Interval c, double sin_gamma_hi, double l2) {
  const double smallest = abs_lo(c);
  const double d = l2 * sin_gamma_hi;
  return smallest * smallest / (d * d);
}

// The kinetic energy 1/2 v^T M v of the unit task velocity v = (cos psi, sin psi), from below,
// over the designs of the run that reach the sample (transmission sines >= the tolerance). The
// angles in the mechanism frame: q1 = theta_1 + alpha_1, q2 = theta_1 - beta_1 (left leg); the
// right leg is solved mirrored, so q4 = pi - (theta_2' + alpha_2), q3 = pi - (theta_2' - beta_2).
// With b_1 = -l1 l2 sin(gamma_1) and b_2 = l1 l2 sin(gamma_2) (elbow out), qdot_1 =
// -cos(q2 - psi) / (l1 sin(gamma_1)), qdot_4 = cos(q3 - psi) / (l1 sin(gamma_2)); the elbow
// moves at v_B = l1 perp(u) qdot, so |v_B + v|^2 = l1^2 qdot^2 + 1 + 2 l1 qdot sin(psi - q_act);
// the free bar turns at (sin(psi - q_free) + l1 qdot cos(gamma)) / l2 (perp(w) . perp(u) = w . u
// = l2 cos(q_free - q_act) = -l2 cos(gamma)).
[[gnu::always_inline]] inline double energy_along(const FiveBarRun& run, const LegBounds& left, const LegBounds& right,
                                                  double psi) {
  const Interval q1{left.act.lo - psi, left.act.hi - psi};
  const Interval q2{left.free.lo - psi, left.free.hi - psi};
  const Interval q4{kPi - right.act.hi - psi, kPi - right.act.lo - psi};
  const Interval q3{kPi - right.free.hi - psi, kPi - right.free.lo - psi};
  Interval s1, c1, s2, c2, s3, c3, s4, c4;  // sin and cos of q_k - psi
  sin_cos_of(q1, s1, c1);
  sin_cos_of(q2, s2, c2);
  sin_cos_of(q3, s3, c3);
  sin_cos_of(q4, s4, c4);
  const double tol = run.singularity_tolerance;  // sines below it are singular samples
  const Interval inv_left{1.0 / (run.l1 * left.sin_gamma.hi), 1.0 / (run.l1 * std::max(left.sin_gamma.lo, tol))};
  const Interval inv_right{1.0 / (run.l1 * right.sin_gamma.hi), 1.0 / (run.l1 * std::max(right.sin_gamma.lo, tol))};
  const Interval qdot1 = -(c2 * inv_left), qdot4 = c3 * inv_right;
  const double l1 = run.l1, inv_l2 = 1.0 / run.l2;
  const Interval one{1.0, 1.0};
  const Interval centre1 = (l1 * l1) * square(qdot1) + one + (-2.0 * l1) * (qdot1 * s1);  // sin(psi - q1) = -s1
  const Interval centre4 = (l1 * l1) * square(qdot4) + one + (-2.0 * l1) * (qdot4 * s4);
  const double centre1_lo = std::max(centre1.lo, squared_centre(l1 * qdot1, s1));
  const double centre4_lo = std::max(centre4.lo, squared_centre(l1 * qdot4, s4));
  const Interval turn1 = inv_l2 * (-s2 + l1 * (qdot1 * left.cos_gamma));
  const Interval turn2 = inv_l2 * (-s3 + l1 * (qdot4 * right.cos_gamma));
  return run.inertia_a * (square(qdot1).lo + square(qdot4).lo) +
         run.mass_f / 4.0 * (std::max(0.0, centre1_lo) + std::max(0.0, centre4_lo)) +
         run.inertia_f * (std::max(square(turn1).lo, turn_squared(c1, left.sin_gamma.hi, run.l2)) +
                          std::max(square(turn2).lo, turn_squared(c4, right.sin_gamma.hi, run.l2)));
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
// m2 / 4 + I_f / l2^2; likewise for leg 1. `sin_mode`: the interval of |sin(q3 - q2)| over the run.
[[gnu::always_inline]] inline double effective_mass_bound(const FiveBarRun& run, const LegBounds& left,
                                                          const LegBounds& right, Interval sin_mode) {
  const double n1 = 1.0 / (run.l1 * left.sin_gamma.hi), n2 = 1.0 / (run.l1 * right.sin_gamma.hi);
  const double sin_hi = sin_mode.hi, sin_lo = sin_mode.lo;
  const double sum = n1 * n1 + n2 * n2;
  const double top = 0.5 * (sum + std::sqrt(std::max(0.0, sum * sum - 4.0 * n1 * n1 * n2 * n2 * sin_hi * sin_hi)));
  const double half = std::sqrt(0.5 * top);  // |qdot_i| at qdot_i^2 = S / 2
  const double cos_lo = std::min(abs_lo(left.cos_gamma), abs_lo(right.cos_gamma));
  const double centre = std::max(0.0, run.l1 * half - 1.0), turn = std::max(0.0, run.l1 * cos_lo * half - 1.0);
  const double along_top = run.inertia_a * top + 2.0 * (run.mass_f / 4.0 * centre * centre +
                                                        run.inertia_f / (run.l2 * run.l2) * turn * turn);
  const double n_max = std::max(n1, n2);
  const double at_rest = run.inertia_a * sin_lo * sin_lo * n_max * n_max + run.mass_f / 4.0 +
                         run.inertia_f / (run.l2 * run.l2);
  // Along the top singular vector of J^-1 at the middle of the angles' intervals (rows e(q2) n_1
  // and e(q3) n_2: the eigenvector of n_1^2 e e^T + n_2^2 e e^T): any direction gives a bound,
  // this one is close to the best for narrow runs.
  const double q2 = 0.5 * (left.free.lo + left.free.hi);
  const double q3 = kPi - 0.5 * (right.free.lo + right.free.hi);
  const double m1 = std::max(0.5 * (left.sin_gamma.lo + left.sin_gamma.hi), run.singularity_tolerance);
  const double m2 = std::max(0.5 * (right.sin_gamma.lo + right.sin_gamma.hi), run.singularity_tolerance);
  const double w1 = 1.0 / (m1 * m1), w2 = 1.0 / (m2 * m2);
  double s2 = 0.0, c2 = 0.0, s3 = 0.0, c3 = 0.0;
  fast::sin_cos(2.0 * q2, s2, c2);
  fast::sin_cos(2.0 * q3, s3, c3);
  const double psi = 0.5 * fast::atan2(w1 * s2 + w2 * s3, w1 * c2 + w2 * c3);
  const double along_psi = energy_along(run, left, right, psi);
  const double bound = std::max(std::max(along_top, at_rest), along_psi);
  return bound * (1.0 - kRelativeMargin) - 1e-12 * run.inertia_a * top;
}

}  // namespace

HAPSYN_MULTIVERSION_WIDE
bool fivebar_envelope(const FiveBarRun& run, double x, bool effective_mass, SampleEnvelope& out) {
  if (!(run.y_low > 0.0) || !(run.y_high >= run.y_low)) return false;
  out = SampleEnvelope{};
  // The model solves the left leg with dx = x + h0 and the right one mirrored, dx = h0 - x.
  const double dx_left = x + run.h0, dx_right = run.h0 - x;
  // The tests without trigonometry first, leg by leg (most runs that fail, fail here): out of
  // reach, or a transmission sine below the singularity tolerance for every design.
  const double tol = run.singularity_tolerance * (1.0 - 1e-6);
  const auto fails = [&] {
    out.all_fail = true;
    return true;
  };
  LegBounds left = leg_bounds(dx_left, run);
  if (left.unreachable || left.sin_gamma.hi < tol) return fails();
  LegBounds right = leg_bounds(dx_right, run);
  if (right.unreachable || right.sin_gamma.hi < tol) return fails();
  const Interval s1 = left.sin_gamma, s2 = right.sin_gamma;
  // q2 = theta_1 - beta_1 and the mirrored free angle theta_2' - beta_2 (q3 = pi - it); a free
  // link pointing down (below -margin) fails the paper's G or is singular (section 13.2).
  leg_angles(dx_left, run, left);
  if (left.free.hi < -1e-6) return fails();
  leg_angles(dx_right, run, right);
  const Interval q2 = left.free, q3_mirrored = right.free;
  const Interval mode{kPi - q3_mirrored.hi - q2.hi, kPi - q3_mirrored.lo - q2.lo};  // q3 - q2
  const Interval sin_mode_of = abs_sin_of(mode);  // |sin(q3 - q2)| over the run, computed once
  const double sin_mode = sin_mode_of.hi;
  if (q3_mirrored.hi < -1e-6 || mode.hi < -1e-6 || sin_mode < tol) return fails();
  // J^-1 rows: norms n_i = 1 / (l1 s_i) at the angle q3 - q2, so with
  // g = 2 sigma_1 sigma_2 / (sigma_1^2 + sigma_2^2) = |sin(q3 - q2)| 2 s1 s2 / (s1^2 + s2^2),
  // sigma_min / sigma_max = g / (1 + sqrt(1 - g^2)), increasing in g.
  const double g = std::min(1.0, sin_mode * sup_balance(s1, s2));
  const double kappa = g / (1.0 + std::sqrt(std::max(0.0, (1.0 - g) * (1.0 + g))));
  out.jacobian_inverse_condition_max = std::min(1.0, kappa * (1.0 + kRelativeMargin) + 1e-12);
  if (effective_mass) {
    leg_actuated_angle(dx_left, run, left);
    leg_actuated_angle(dx_right, run, right);
    out.effective_mass_sigma_max_min = effective_mass_bound(run, left, right, sin_mode_of);
  }
  return true;
}

}  // namespace hapsyn::plugins

