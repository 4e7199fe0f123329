#pragma once
/// \file
/// Inline, branch-light sin/cos and atan2 for per-sample kinematics loops.
///
/// Why: libm's sincos and atan2 are out-of-line calls with a correctly-rounded slow path; in
/// the haptic 6R inverse kinematics (12 atan2 per pose) and forward pass (6 sincos) they were
/// about a fifth of the per-sample time. These versions inline, so the independent calls of one
/// sample overlap in the CPU, and they trade the last bit for speed:
/// - `sin_cos(x)`: absolute error <= 2.3e-16 for |x| <= 1e6 (Cody-Waite reduction by pi/2 in
///   two parts and the fdlibm/musl kernel polynomials on [-pi/4, pi/4]); larger or non-finite
///   x fall back to std::sin / std::cos.
/// - `atan2(y, x)`: absolute error <= 4.5e-16 rad for finite arguments, the same quadrant and
///   signed-zero conventions as std::atan2 (it falls back to std::atan2 when both are zero or
///   either is not finite). atan(t), t in [0, 1], is atan(k/8) from a table plus the odd Taylor
///   series of atan(u), u = (t - k/8) / (1 + t k/8), |u| <= 1/16, to u^13 (truncation < 2e-19).
/// Both are checked against libm over random and edge-case arguments in
/// tests/fast_math_test.cpp; benchmarks/fast_math_benchmark.cpp measures them against libm.
///
/// They are always inlined: a caller compiled for a wider instruction set (HAPSYN_MULTIVERSION,
/// hapsyn/accel/multiversion.hpp) would otherwise call the baseline copy through the PLT, as the
/// five-bar's envelope did (docs/design.md section 13.5).
#include <cmath>

namespace hapsyn::fast {

/// The body of sin_cos() for |x| <= 1e6 on any number type with + - * by doubles (double, or
/// hapsyn::Lanes for one value per SIMD lane, hapsyn/accel/lanes.hpp): n = round(x / (pi/2)) (an
/// integer-valued number) and s, c = sin, cos of the reduced argument x - n pi/2. The caller
/// maps (s, c) to the quadrant n mod 4.
template <typename T>
[[gnu::always_inline]] inline void sin_cos_reduced(const T& x, T& n, T& s, T& c) {
  // n = round(x / (pi/2)) by the 1.5 * 2^52 trick (no SSE4.1 round instruction at baseline x86-64).
  constexpr double kInvHalfPi = 6.36619772367581382433e-01;
  constexpr double kToInt = 6755399441055744.0;  // 1.5 * 2^52
  constexpr double kHalfPi1 = 1.57079632673412561417e+00;   // first 33 bits of pi/2: n * kHalfPi1 is exact
  constexpr double kHalfPi1Tail = 6.07710050650619224932e-11;  // pi/2 - kHalfPi1
  n = (x * kInvHalfPi + kToInt) - kToInt;
  const T r = (x - n * kHalfPi1) - n * kHalfPi1Tail;  // in [-pi/4, pi/4] up to rounding
  const T z = r * r, w = z * z;
  // fdlibm / musl __sin and __cos kernels (|r| <= pi/4, error < 2^-58 relative to the result).
  constexpr double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                   S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                   S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
  constexpr double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                   C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                   C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
  const T sin_poly = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
  s = r + z * r * (S1 + z * sin_poly);
  const T cos_poly = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
  const T half_z = 0.5 * z, one_minus = 1.0 - half_z;
  c = one_minus + (((1.0 - one_minus) - half_z) + z * cos_poly);
}

/// sin(x) and cos(x) together [x in rad]. See the file comment for the accuracy.
[[gnu::always_inline]] inline void sin_cos(double x, double& sine, double& cosine) {
  if (!(std::abs(x) <= 1e6)) {  // also NaN and infinities
    sine = std::sin(x);
    cosine = std::cos(x);
    return;
  }
  double n = 0.0, s = 0.0, c = 0.0;
  sin_cos_reduced(x, n, s, c);
  // Quadrant n mod 4: (sin, cos) = (s, c), (c, -s), (-s, -c), (-c, s).
  const long quadrant = static_cast<long>(n) & 3;
  const double swapped_sine = (quadrant & 1) ? c : s;
  const double swapped_cosine = (quadrant & 1) ? s : c;
  sine = (quadrant & 2) ? -swapped_sine : swapped_sine;
  cosine = ((quadrant + 1) & 2) ? -swapped_cosine : swapped_cosine;
}

/// floor(x) and ceil(x) without a library call: GCC does not expand std::floor / std::ceil
/// inline on the baseline instruction set, nor in a multiversioned function
/// (hapsyn/accel/multiversion.hpp), and the call spills every live vector register. Exact for
/// |x| < 2^52 (the conversion truncates toward zero); larger, infinite or NaN x go to
/// std::floor / std::ceil. (hapsyn::floor_small in hapsyn/accel/lanes.hpp is the lane version.)
[[gnu::always_inline]] inline double floor_small(double x) {
  if (!(std::abs(x) < 4.5e15)) return std::floor(x);
  const double t = static_cast<double>(static_cast<long long>(x));
  return t > x ? t - 1.0 : t;
}
[[gnu::always_inline]] inline double ceil_small(double x) {
  if (!(std::abs(x) < 4.5e15)) return std::ceil(x);
  const double t = static_cast<double>(static_cast<long long>(x));
  return t < x ? t + 1.0 : t;
}

/// atan(k / 8), k = 0..8, correctly rounded: the table of atan2().
inline constexpr double kAtanTable[9] = {0.0,
                                         0.12435499454676144,
                                         0.24497866312686414,
                                         0.35877067027057225,
                                         0.4636476090008061,
                                         0.5585993153435624,
                                         0.6435011087932844,
                                         0.7188299996216245,
                                         0.7853981633974483};

/// The body of atan2() on any number type with + - * / by doubles (double, or hapsyn::Lanes,
/// hapsyn/accel/lanes.hpp): atan(t) for t = smallest / largest in [0, 1], given ck = k / 8 (k the
/// nearest integer to 8 t) and table_k = kAtanTable[k]. The caller maps it to the octant.
template <typename T>
[[gnu::always_inline]] inline T atan_reduced(const T& t, const T& ck, const T& table_k) {
  const T u = (t - ck) / (1.0 + t * ck);  // |u| <= 1/16
  const T z = u * u;
  const T series =
      u + u * z *
              (-1.0 / 3.0 +
               z * (1.0 / 5.0 + z * (-1.0 / 7.0 + z * (1.0 / 9.0 + z * (-1.0 / 11.0 + z * (1.0 / 13.0))))));
  return table_k + series;  // atan(smallest / largest) in [0, pi/4]
}

/// atan2(y, x) [rad] in [-pi, pi]. See the file comment for the accuracy.
[[gnu::always_inline]] inline double atan2(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double largest = ax > ay ? ax : ay, smallest = ax > ay ? ay : ax;
  if (!(largest > 0.0) || !(largest <= 1.7976931348623157e308) || !(smallest >= 0.0)) return std::atan2(y, x);
  const double t = smallest / largest;  // in [0, 1]
  const int k = static_cast<int>(t * 8.0 + 0.5);
  double angle = atan_reduced(t, 0.125 * k, kAtanTable[k]);
  constexpr double kHalfPi = 1.5707963267948966, kPi = 3.141592653589793;
  if (ay > ax) angle = kHalfPi - angle;
  // The builtin, not std::signbit: libstdc++'s is an out-of-line call from a multiversioned
  // caller (hapsyn/accel/multiversion.hpp).
  if (__builtin_signbit(x)) angle = kPi - angle;
  return __builtin_signbit(y) ? -angle : angle;
}

}  // namespace hapsyn::fast
