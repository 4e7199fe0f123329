#pragma once
/// \file
/// Lanes: kBlockLanes doubles with element-wise arithmetic, for block kernels
/// (hapsyn/accel/sample_block.hpp) written once for a scalar and for a block of samples.
///
/// A kernel templated on its number type T runs with T = double (one sample) and T = Lanes (one
/// sample per lane): the same expressions in the same order, so a lane rounds as the scalar code
/// does wherever the compiler contracts the two alike. The operators act on the
/// lanes' compiler vector (the GCC / clang vector extension): inlined ([[gnu::always_inline]])
/// into a function compiled for a wide instruction set (HAPSYN_MULTIVERSION_WIDE,
/// hapsyn/accel/multiversion.hpp), each is one vector instruction; compiled for baseline CPUs, the
/// compiler splits it into SSE2 halves. The vector sits in a struct passed by reference: clang
/// refuses to pass a 64-byte vector by value in code not compiled for AVX-512.
#include <hapsyn/accel/fast_math.hpp>
#include <hapsyn/accel/sample_block.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>

namespace hapsyn {

/// kBlockLanes doubles, one per lane: a compiler vector (GCC/clang vector extension) in a struct.
/// Element i is v[i].
struct Lanes {
  typedef double Vector __attribute__((vector_size(kBlockLanes * sizeof(double))));
  Vector v;

  /// Every lane `value`.
  [[gnu::always_inline]] static Lanes splat(double value) { return Lanes{Vector{} + value}; }
  /// Lanes from kBlockLanes consecutive doubles (e.g. a row of a QuantityBlock matrix).
  [[gnu::always_inline]] static Lanes load(const double* p) {
    Lanes r;
    std::memcpy(&r.v, p, sizeof r.v);
    return r;
  }
  [[gnu::always_inline]] void store(double* p) const { std::memcpy(p, &v, sizeof v); }
};

/// The lanes as 64-bit integers: comparison masks (all ones or zero) and bit patterns.
typedef std::int64_t LaneBits __attribute__((vector_size(kBlockLanes * sizeof(double))));

#define HAPSYN_LANES_OPERATOR(op)                                                                                \
  [[gnu::always_inline]] inline Lanes operator op(const Lanes& a, const Lanes& b) { return Lanes{a.v op b.v}; } \
  [[gnu::always_inline]] inline Lanes operator op(const Lanes& a, double b) { return Lanes{a.v op b}; }         \
  [[gnu::always_inline]] inline Lanes operator op(double a, const Lanes& b) { return Lanes{a op b.v}; }         \
  [[gnu::always_inline]] inline Lanes& operator op##=(Lanes& a, const Lanes& b) {                               \
    a.v = a.v op b.v;                                                                                             \
    return a;                                                                                                     \
  }                                                                                                               \
  [[gnu::always_inline]] inline Lanes& operator op##=(Lanes& a, double b) {                                      \
    a.v = a.v op b;                                                                                               \
    return a;                                                                                                     \
  }
HAPSYN_LANES_OPERATOR(+)
HAPSYN_LANES_OPERATOR(-)
HAPSYN_LANES_OPERATOR(*)
HAPSYN_LANES_OPERATOR(/)
#undef HAPSYN_LANES_OPERATOR

[[gnu::always_inline]] inline Lanes operator-(const Lanes& a) { return Lanes{-a.v}; }

// Comparisons select rather than return a mask, so that no mask type appears in an interface:
// `x < y ? a : b` lane by lane is one compare and one blend. Truth values that a kernel carries
// along are Lanes holding 0 or 1.
//
// Each selection's result passes an association barrier (GCC 12 and later; no instruction). These
// functions are compiled for the default target and inlined into the AVX-512 clones of
// HAPSYN_MULTIVERSION_WIDE kernels; without the barrier GCC folds two selections into one logic
// operation on their comparison masks, typed for the default target (a vector of 64-bit truth
// values, not an AVX-512 mask register), which the AVX-512 clone then computes lane by lane:
// scalar compares, sets and inserts for every nested or combined selection (docs/design.md
// section 14.2).
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 12
#define HAPSYN_LANES_BARRIER(value) __builtin_assoc_barrier(value)
#else
#define HAPSYN_LANES_BARRIER(value) (value)
#endif
#define HAPSYN_LANES_WHERE(name, op)                                                                          \
  /** Lane-wise `x op y ? a : b`. */                                                                          \
  [[gnu::always_inline]] inline Lanes name(const Lanes& x, const Lanes& y, const Lanes& a, const Lanes& b) { \
    return Lanes{HAPSYN_LANES_BARRIER(x.v op y.v ? a.v : b.v)};                                               \
  }
HAPSYN_LANES_WHERE(where_less, <)
HAPSYN_LANES_WHERE(where_greater, >)
HAPSYN_LANES_WHERE(where_equal, ==)
HAPSYN_LANES_WHERE(where_less_equal, <=)
HAPSYN_LANES_WHERE(where_greater_equal, >=)
#undef HAPSYN_LANES_WHERE

/// Lane-wise |a| (as std::fabs: the sign bit cleared).
[[gnu::always_inline]] inline Lanes abs(const Lanes& a) {
  return Lanes{reinterpret_cast<Lanes::Vector>(reinterpret_cast<LaneBits>(a.v) & (LaneBits{} + INT64_MAX))};
}
/// Lane-wise max(a, b) as `a > b ? a : b` (b when either is NaN).
[[gnu::always_inline]] inline Lanes max(const Lanes& a, const Lanes& b) { return where_greater(a, b, a, b); }

/// Lane-wise floor(a) for |a| < 2^51 (round to nearest by the 1.5 * 2^52 trick, then down).
[[gnu::always_inline]] inline Lanes floor_small(const Lanes& a) {
  constexpr double kToInt = 6755399441055744.0;  // 1.5 * 2^52
  const Lanes nearest = (a + kToInt) - kToInt;
  return where_greater(nearest, a, nearest - 1.0, nearest);
}

/// The bitwise OR of the lanes of `bits`: a logarithmic fold (three halvings of eight lanes)
/// instead of reading the lanes one by one. By reference, as every Lanes argument: a 64-byte
/// vector passed by value has a different ABI in the AVX-512 clones (clang's -Wpsabi).
[[gnu::always_inline]] inline std::int64_t or_of_lanes(const LaneBits& bits) {
  static_assert(kBlockLanes == 8, "the fold below halves eight lanes three times");
  LaneBits m = bits;
  m |= __builtin_shufflevector(m, m, 4, 5, 6, 7, 0, 1, 2, 3);
  m |= __builtin_shufflevector(m, m, 2, 3, 0, 1, 6, 7, 4, 5);
  m |= __builtin_shufflevector(m, m, 1, 0, 3, 2, 5, 4, 7, 6);
  return m[0];
}

namespace lanes_detail {
// Two lanes as a vector of the baseline instruction set (SSE2).
typedef double Pair __attribute__((vector_size(2 * sizeof(double))));
typedef std::int64_t PairBits __attribute__((vector_size(2 * sizeof(double))));
// The AND over the lanes of `a op b`, by pairs of lanes: GCC 12 compiles a comparison of the
// whole 64-byte vector lane by lane (a scalar compare and set per lane) in code not compiled for
// AVX-512, such as the evaluator's; by pairs it is one packed compare per pair everywhere.
template <typename Compare>
[[gnu::always_inline]] inline bool all_pairs(const Lanes& a, double b, Compare compare) {
  PairBits all = {-1, -1};
  for (int i = 0; i < kBlockLanes; i += 2) {
    Pair pair;
    std::memcpy(&pair, reinterpret_cast<const double*>(&a.v) + i, sizeof pair);
    all &= compare(pair, b);
  }
  return (all[0] & all[1]) != 0;
}
}  // namespace lanes_detail

/// Whether every lane of `a` is strictly greater than `b` (false when a lane is NaN), without a
/// branch per lane: one packed compare per pair of lanes, also in baseline code.
[[gnu::always_inline]] inline bool all_greater(const Lanes& a, double b) {
  return lanes_detail::all_pairs(a, b, [](const lanes_detail::Pair& p, double c) { return p > c; });
}
/// Whether every lane of `a` is strictly less than `b` (false when a lane is NaN).
[[gnu::always_inline]] inline bool all_less(const Lanes& a, double b) {
  return lanes_detail::all_pairs(a, b, [](const lanes_detail::Pair& p, double c) { return p < c; });
}

/// Whether any lane of `a` is non-zero (NaN counts as non-zero): one compare and or_of_lanes(),
/// instead of a branch per lane.
[[gnu::always_inline]] inline bool any_nonzero(const Lanes& a) { return or_of_lanes(a.v != 0.0) != 0; }
/// Whether any lane of `a` is zero.
[[gnu::always_inline]] inline bool any_zero(const Lanes& a) { return or_of_lanes(a.v == 0.0) != 0; }

/// Lane-wise `x has its sign bit set ? a : b` (as std::signbit: true for -0 and negative NaNs).
[[gnu::always_inline]] inline Lanes where_sign_bit(const Lanes& x, const Lanes& a, const Lanes& b) {
  return Lanes{HAPSYN_LANES_BARRIER(reinterpret_cast<LaneBits>(x.v) < 0 ? a.v : b.v)};
}

/// Lane-wise std::sqrt. One vector instruction where the translation unit is compiled with
/// -fno-math-errno (otherwise the compiler keeps libm's errno path, lane by lane).
[[gnu::always_inline]] inline Lanes sqrt(const Lanes& a) {
  Lanes r;
  for (int i = 0; i < kBlockLanes; ++i) r.v[i] = std::sqrt(a.v[i]);
  return r;
}

namespace lanes_detail {
// atan2's work that depends on |x| and |y| only: the angle of (|x|, |y|) in [0, pi/2] and the
// lanes inside fast::atan2's range (1 or 0).
struct AtanCore {
  Lanes angle, in_range;
};
[[gnu::always_inline]] inline AtanCore atan_core(const Lanes& y, const Lanes& x) {
  const Lanes ax = abs(x), ay = abs(y), zero = Lanes::splat(0.0);
  const Lanes largest = where_greater(ax, ay, ax, ay), smallest = where_greater(ax, ay, ay, ax);
  // Lanes outside fast::atan2's range compute atan(0) here (no NaN reaches the table index).
  // The scalar's !(largest > 0) || !(largest <= DBL_MAX) || !(smallest >= 0): zero, infinite
  // or NaN arguments (smallest == smallest is false for a NaN |x| next to a finite |y|).
  const Lanes one = Lanes::splat(1.0);
  AtanCore core;
  core.in_range = where_greater(
      largest, zero, where_greater(largest, Lanes::splat(1.7976931348623157e308), zero, where_equal(smallest, smallest, one, zero)),
      zero);
  const Lanes t = where_equal(core.in_range, zero, zero, smallest / where_equal(core.in_range, zero, one, largest));
  const Lanes k = floor_small(t * 8.0 + 0.5);  // t * 8 + 0.5 >= 0.5: floor is the scalar's truncation
  Lanes table_k;
#if defined(__clang__)
  for (int i = 0; i < kBlockLanes; ++i) table_k.v[i] = fast::kAtanTable[static_cast<int>(k.v[i])];
#else
  // The table as two vectors and one two-source permutation (one instruction with AVX-512).
  static_assert(kBlockLanes == 8, "the permuted table holds 16 entries");
  const Lanes::Vector low = {fast::kAtanTable[0], fast::kAtanTable[1], fast::kAtanTable[2], fast::kAtanTable[3],
                             fast::kAtanTable[4], fast::kAtanTable[5], fast::kAtanTable[6], fast::kAtanTable[7]};
  const Lanes::Vector high = {fast::kAtanTable[8], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  table_k.v = __builtin_shuffle(low, high, __builtin_convertvector(k.v, LaneBits));
#endif
  const Lanes angle = fast::atan_reduced(t, 0.125 * k, table_k);
  constexpr double kHalfPi = 1.5707963267948966;
  core.angle = where_greater(ay, ax, kHalfPi - angle, angle);
  return core;
}
// The core's angle in the quadrant of (x, y), and libm's atan2 for the lanes outside the range.
[[gnu::always_inline]] inline Lanes atan_quadrant(const AtanCore& core, const Lanes& y, const Lanes& x) {
  constexpr double kPi = 3.141592653589793;
  Lanes angle = where_sign_bit(x, kPi - core.angle, core.angle);
  angle = where_sign_bit(y, -angle, angle);
  if (any_zero(core.in_range)) {
    // Through memory: reading the lanes of in_range and angle in place makes GCC 12 compute
    // them lane by lane (scalar compares) from the start of the function.
    double flag[kBlockLanes], value[kBlockLanes], ys[kBlockLanes], xs[kBlockLanes];
    core.in_range.store(flag);
    angle.store(value);
    y.store(ys);
    x.store(xs);
    for (int i = 0; i < kBlockLanes; ++i) {
      if (flag[i] == 0.0) value[i] = std::atan2(ys[i], xs[i]);
    }
    angle = Lanes::load(value);
  }
  return angle;
}
}  // namespace lanes_detail

/// fast::atan2 (hapsyn/accel/fast_math.hpp) of every lane: the same table and series (one template,
/// fast::atan_reduced), so a lane gets what the scalar call gives (up to the compiler's
/// multiply-add fusion); lanes with a zero or non-finite argument take libm, as the scalar does.
[[gnu::always_inline]] inline Lanes atan2(const Lanes& y, const Lanes& x) {
  return lanes_detail::atan_quadrant(lanes_detail::atan_core(y, x), y, x);
}

/// atan2(y, x) and atan2(y, -x) of every lane, bit for bit the two calls: everything but the
/// quadrant depends on |x| and |y| only, so it is computed once.
[[gnu::always_inline]] inline void atan2_and_mirrored(const Lanes& y, const Lanes& x, Lanes& angle, Lanes& mirrored) {
  const lanes_detail::AtanCore core = lanes_detail::atan_core(y, x);
  angle = lanes_detail::atan_quadrant(core, y, x);
  mirrored = lanes_detail::atan_quadrant(core, y, -x);
}

/// fast::sin_cos (hapsyn/accel/fast_math.hpp) of every lane: the same reduction and polynomials, so a
/// lane gets what the scalar call gives (up to the compiler's multiply-add fusion).
[[gnu::always_inline]] inline void sin_cos(const Lanes& x, Lanes& sine, Lanes& cosine) {
  const Lanes limit = Lanes::splat(1e6);
  // Out-of-range lanes (|x| > 1e6, NaN, infinities) reduce a 0 here and take libm below.
  const Lanes inside = where_greater(abs(x), limit, Lanes::splat(0.0), x);
  Lanes n, s, c;
  fast::sin_cos_reduced(inside, n, s, c);
  // Quadrant n mod 4 (n is integer-valued): (sin, cos) = (s, c), (c, -s), (-s, -c), (-c, s).
  const Lanes quadrant = n - 4.0 * floor_small(n * 0.25);
  const Lanes one = Lanes::splat(1.0), two = Lanes::splat(2.0), three = Lanes::splat(3.0);
  const Lanes odd = where_equal(quadrant, one, one, where_equal(quadrant, three, one, Lanes::splat(0.0)));
  const Lanes swapped_sine = where_equal(odd, one, c, s), swapped_cosine = where_equal(odd, one, s, c);
  sine = where_less(quadrant, two, swapped_sine, -swapped_sine);
  cosine = where_equal(quadrant, one, -swapped_cosine, where_equal(quadrant, two, -swapped_cosine, swapped_cosine));
  for (int i = 0; i < kBlockLanes; ++i) {
    if (!(std::fabs(x.v[i]) <= 1e6)) {
      sine.v[i] = std::sin(x.v[i]);
      cosine.v[i] = std::cos(x.v[i]);
    }
  }
}

}  // namespace hapsyn
