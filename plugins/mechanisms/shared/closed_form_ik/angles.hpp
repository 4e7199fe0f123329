#pragma once
/// \file
/// remainder_two_pi(x): std::remainder(x, 2 pi), bit for bit, without glibc's rounding-mode
/// switch (the per-sample IK wraps every candidate angle, where std::remainder cost 7 % of a
/// coverage evaluation).
#include <cmath>

namespace hapsyn::plugins::closed_form_ik {

/// std::remainder(x, 2 pi) with 2 pi the double 2 * M_PI, bit for bit (ties, +-0, +-inf and NaN
/// included): x itself when |x| <= pi, x -+ 2 pi when that lands strictly inside (-pi, pi), which
/// is exact (Sterbenz: pi <= |x| < 3 pi), else std::remainder.
inline double remainder_two_pi(double x) {
  constexpr double kPi = M_PI;
  constexpr double kTwoPi = 2.0 * M_PI;
  if (std::abs(x) <= kPi) return x;
  const double shifted = x > 0.0 ? x - kTwoPi : x + kTwoPi;
  if (std::abs(shifted) < kPi) return shifted == 0.0 ? std::copysign(0.0, x) : shifted;  // a zero has x's sign
  return std::remainder(x, kTwoPi);
}

}  // namespace hapsyn::plugins::closed_form_ik
