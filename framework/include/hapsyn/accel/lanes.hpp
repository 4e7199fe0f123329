#pragma once
/// \file
/// Lanes: kBlockLanes doubles with element-wise arithmetic, for block kernels
/// (hapsyn/accel/sample_block.hpp) written once for a scalar and for a block of samples.
///
/// A kernel templated on its number type T runs with T = double (one sample) and T = a lanes
/// type (one sample per lane): the same expressions in the same order, so a lane rounds as the
/// scalar code does wherever the compiler contracts the two alike.
///
/// `LanesOf<PartBytes>` holds the eight doubles as 64 / PartBytes compiler vectors (the GCC /
/// clang vector extension) of PartBytes bytes each: one AVX-512 register (`Lanes`, 64), two
/// AVX2 registers (`LanesAvx2`, 32) or four SSE2 registers (`LanesSse2`, 16). Every operation
/// is [[gnu::always_inline]] and acts part by part, so inlined into a function compiled for the
/// matching instruction set each part is one vector instruction. A vector wider than the
/// instruction set's registers is not: GCC 12 lowers the comparisons, selections and splats of
/// a 64-byte vector in AVX2 or SSE2 code lane by lane, through memory (5 to 13 times slower;
/// docs/performance-log.md, "One vector abstraction"). So a kernel is written once as a
/// template on its lanes type and compiled once per instruction set with its own part width by
/// hapsyn::for_each_vector_target (hapsyn/accel/vector_dispatch.hpp), which also picks the
/// version the CPU runs. The three types have the same layout (eight doubles, lane i at byte
/// 8 i), so a kernel's rows are the same memory whichever type reads them.
///
/// Lanes are passed by reference: clang refuses to pass a 64-byte vector by value in code not
/// compiled for AVX-512.
#include <hapsyn/accel/fast_math.hpp>
#include <hapsyn/accel/sample_block.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace hapsyn {

/// Count doubles (kBlockLanes by default: a block), one per lane, as kParts compiler vectors of
/// PartBytes bytes. Lane i is element i % kPerPart of part i / kPerPart; read it with lanes[i],
/// write it with set(i, value). LanesOf<B, B / 8> is one register: a chunk of a block, for
/// kernels that run a block chunk by chunk (VectorChunks, hapsyn/accel/vector_dispatch.hpp).
template <int PartBytes, int Count = kBlockLanes>
struct LanesOf {
  static_assert(PartBytes == 16 || PartBytes == 32 || PartBytes == 64, "parts of 2, 4 or 8 doubles");
  typedef double Part __attribute__((vector_size(PartBytes)));
  /// A part as 64-bit integers: comparison masks (all ones or zero) and bit patterns.
  typedef std::int64_t PartBits __attribute__((vector_size(PartBytes)));
  static constexpr int kPerPart = PartBytes / static_cast<int>(sizeof(double));  ///< lanes per part
  static_assert(Count % (PartBytes / 8) == 0 && Count <= kBlockLanes, "whole parts, at most a block");
  static constexpr int kLanes = Count;                                            ///< lanes
  static constexpr int kParts = Count / kPerPart;                                 ///< parts
  Part part[kParts];

  /// Every lane `value`.
  [[gnu::always_inline]] static LanesOf splat(double value) {
    LanesOf r;
    for (int p = 0; p < kParts; ++p) r.part[p] = Part{} + value;
    return r;
  }
  /// Lanes from kLanes consecutive doubles (e.g. a row of a QuantityBlock matrix).
  [[gnu::always_inline]] static LanesOf load(const double* source) {
    // Part by part: GCC 12 copies a whole array of AVX2 vectors through the stack and scalar
    // registers (memcpy of `part` at once), one part is one unaligned vector load or store.
    LanesOf r;
    for (int p = 0; p < kParts; ++p) std::memcpy(&r.part[p], source + p * kPerPart, sizeof r.part[p]);
    return r;
  }
  [[gnu::always_inline]] void store(double* target) const {
    for (int p = 0; p < kParts; ++p) std::memcpy(target + p * kPerPart, &part[p], sizeof part[p]);
  }
  /// Lane `lane`'s value.
  [[gnu::always_inline]] double operator[](int lane) const { return part[lane / kPerPart][lane % kPerPart]; }
  /// Sets lane `lane` to `value`.
  [[gnu::always_inline]] void set(int lane, double value) { part[lane / kPerPart][lane % kPerPart] = value; }
};

/// Eight doubles in one AVX-512 register: the lanes type of AVX-512 code and of interfaces.
using Lanes = LanesOf<64>;
/// Eight doubles in two AVX2 registers.
using LanesAvx2 = LanesOf<32>;
/// Eight doubles in four SSE2 registers (baseline x86-64, and other architectures' 128-bit units).
using LanesSse2 = LanesOf<16>;

#define HAPSYN_LANES_OPERATOR(op)                                                                                    \
  template <int B, int N>                                                                                                   \
  [[gnu::always_inline]] inline LanesOf<B, N> operator op(const LanesOf<B, N>& a, const LanesOf<B, N>& b) {                   \
    LanesOf<B, N> r;                                                                                                    \
    for (int p = 0; p < LanesOf<B, N>::kParts; ++p) r.part[p] = a.part[p] op b.part[p];                                 \
    return r;                                                                                                        \
  }                                                                                                                  \
  template <int B, int N>                                                                                                   \
  [[gnu::always_inline]] inline LanesOf<B, N> operator op(const LanesOf<B, N>& a, double b) {                              \
    LanesOf<B, N> r;                                                                                                    \
    for (int p = 0; p < LanesOf<B, N>::kParts; ++p) r.part[p] = a.part[p] op b;                                         \
    return r;                                                                                                        \
  }                                                                                                                  \
  template <int B, int N>                                                                                                   \
  [[gnu::always_inline]] inline LanesOf<B, N> operator op(double a, const LanesOf<B, N>& b) {                              \
    LanesOf<B, N> r;                                                                                                    \
    for (int p = 0; p < LanesOf<B, N>::kParts; ++p) r.part[p] = a op b.part[p];                                         \
    return r;                                                                                                        \
  }                                                                                                                  \
  template <int B, int N>                                                                                                   \
  [[gnu::always_inline]] inline LanesOf<B, N>& operator op##=(LanesOf<B, N>& a, const LanesOf<B, N>& b) {                     \
    for (int p = 0; p < LanesOf<B, N>::kParts; ++p) a.part[p] = a.part[p] op b.part[p];                                 \
    return a;                                                                                                        \
  }                                                                                                                  \
  template <int B, int N>                                                                                                   \
  [[gnu::always_inline]] inline LanesOf<B, N>& operator op##=(LanesOf<B, N>& a, double b) {                                \
    for (int p = 0; p < LanesOf<B, N>::kParts; ++p) a.part[p] = a.part[p] op b;                                         \
    return a;                                                                                                        \
  }
HAPSYN_LANES_OPERATOR(+)
HAPSYN_LANES_OPERATOR(-)
HAPSYN_LANES_OPERATOR(*)
HAPSYN_LANES_OPERATOR(/)
#undef HAPSYN_LANES_OPERATOR

template <int B, int N>
[[gnu::always_inline]] inline LanesOf<B, N> operator-(const LanesOf<B, N>& a) {
  LanesOf<B, N> r;
  for (int p = 0; p < LanesOf<B, N>::kParts; ++p) r.part[p] = -a.part[p];
  return r;
}

// Comparisons select rather than return a mask, so that no mask type appears in an interface:
// `x < y ? a : b` lane by lane is one compare and one blend per part. Truth values that a
// kernel carries along are lanes holding 0 or 1.
//
// Each selection's result passes an association barrier (GCC 12 and later; no instruction). These
// functions are compiled for the default target and inlined into AVX-512 code; without the
// barrier GCC folds two selections into one logic operation on their comparison masks, typed
// for the default target (a vector of 64-bit truth values, not an AVX-512 mask register), which
// the AVX-512 code then computes lane by lane: scalar compares, sets and inserts for every
// nested or combined selection (KERNELS.md of the haptic 6R, "Lane selections").
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 12
#define HAPSYN_LANES_BARRIER(value) __builtin_assoc_barrier(value)
#else
#define HAPSYN_LANES_BARRIER(value) (value)
#endif
#define HAPSYN_LANES_WHERE(name, op)                                                                           \
  /** Lane-wise `x op y ? a : b`. */                                                                           \
  template <int B, int N>                                                                                             \
  [[gnu::always_inline]] inline LanesOf<B, N> name(const LanesOf<B, N>& x, const LanesOf<B, N>& y, const LanesOf<B, N>& a, \
                                                const LanesOf<B, N>& b) {                                         \
    LanesOf<B, N> r;                                                                                              \
    for (int p = 0; p < LanesOf<B, N>::kParts; ++p) {                                                             \
      r.part[p] = HAPSYN_LANES_BARRIER(x.part[p] op y.part[p] ? a.part[p] : b.part[p]);                        \
    }                                                                                                          \
    return r;                                                                                                  \
  }
HAPSYN_LANES_WHERE(where_less, <)
HAPSYN_LANES_WHERE(where_greater, >)
HAPSYN_LANES_WHERE(where_equal, ==)
HAPSYN_LANES_WHERE(where_less_equal, <=)
HAPSYN_LANES_WHERE(where_greater_equal, >=)
#undef HAPSYN_LANES_WHERE

/// Lane-wise `x has its sign bit set ? a : b` (as std::signbit: true for -0 and negative NaNs).
template <int B, int N>
[[gnu::always_inline]] inline LanesOf<B, N> where_sign_bit(const LanesOf<B, N>& x, const LanesOf<B, N>& a, const LanesOf<B, N>& b) {
  typedef typename LanesOf<B, N>::PartBits Bits;
  LanesOf<B, N> r;
  for (int p = 0; p < LanesOf<B, N>::kParts; ++p) {
    r.part[p] = HAPSYN_LANES_BARRIER(reinterpret_cast<Bits>(x.part[p]) < 0 ? a.part[p] : b.part[p]);
  }
  return r;
}

/// Lane-wise |a| (as std::fabs: the sign bit cleared).
template <int B, int N>
[[gnu::always_inline]] inline LanesOf<B, N> abs(const LanesOf<B, N>& a) {
  typedef typename LanesOf<B, N>::Part Part;
  typedef typename LanesOf<B, N>::PartBits Bits;
  LanesOf<B, N> r;
  for (int p = 0; p < LanesOf<B, N>::kParts; ++p) {
    r.part[p] = reinterpret_cast<Part>(reinterpret_cast<Bits>(a.part[p]) & (Bits{} + INT64_MAX));
  }
  return r;
}
/// Lane-wise max(a, b) as `a > b ? a : b` (b when either is NaN).
template <int B, int N>
[[gnu::always_inline]] inline LanesOf<B, N> max(const LanesOf<B, N>& a, const LanesOf<B, N>& b) {
  return where_greater(a, b, a, b);
}

/// Lane-wise floor(a) for |a| < 2^51 (round to nearest by the 1.5 * 2^52 trick, then down).
template <int B, int N>
[[gnu::always_inline]] inline LanesOf<B, N> floor_small(const LanesOf<B, N>& a) {
  constexpr double kToInt = 6755399441055744.0;  // 1.5 * 2^52
  const LanesOf<B, N> nearest = (a + kToInt) - kToInt;
  return where_greater(nearest, a, nearest - 1.0, nearest);
}

/// Lane-wise std::sqrt. One vector instruction per part where the translation unit is compiled
/// with -fno-math-errno (otherwise the compiler keeps libm's errno path, lane by lane).
template <int B, int N>
[[gnu::always_inline]] inline LanesOf<B, N> sqrt(const LanesOf<B, N>& a) {
  LanesOf<B, N> r;
  for (int p = 0; p < LanesOf<B, N>::kParts; ++p) {
    for (int i = 0; i < LanesOf<B, N>::kPerPart; ++i) r.part[p][i] = std::sqrt(a.part[p][i]);
  }
  return r;
}

namespace lanes_detail {
// The OR (or AND) of the elements of one part of masks or bits: a logarithmic fold of halvings
// instead of reading the elements one by one.
template <typename Bits, int N>
[[gnu::always_inline]] inline std::int64_t fold_or(const Bits& bits) {
  Bits m = bits;
  if constexpr (N == 8) {
    m |= __builtin_shufflevector(m, m, 4, 5, 6, 7, 0, 1, 2, 3);
    m |= __builtin_shufflevector(m, m, 2, 3, 0, 1, 6, 7, 4, 5);
    m |= __builtin_shufflevector(m, m, 1, 0, 3, 2, 5, 4, 7, 6);
  } else if constexpr (N == 4) {
    m |= __builtin_shufflevector(m, m, 2, 3, 0, 1);
    m |= __builtin_shufflevector(m, m, 1, 0, 3, 2);
  } else {
    static_assert(N == 2, "parts of 2, 4 or 8 lanes");
    m |= __builtin_shufflevector(m, m, 1, 0);
  }
  return m[0];
}
}  // namespace lanes_detail

/// Whether every lane of `a` is strictly greater than `b` (false when a lane is NaN), without a
/// branch per lane.
template <int B, int N>
[[gnu::always_inline]] inline bool all_greater(const LanesOf<B, N>& a, double b) {
  typedef typename LanesOf<B, N>::PartBits Bits;
  Bits none = {};
  for (int i = 0; i < LanesOf<B, N>::kParts; ++i) none |= ~(a.part[i] > b);
  return lanes_detail::fold_or<Bits, LanesOf<B, N>::kPerPart>(none) == 0;
}
/// Whether every lane of `a` is strictly less than `b` (false when a lane is NaN).
template <int B, int N>
[[gnu::always_inline]] inline bool all_less(const LanesOf<B, N>& a, double b) {
  typedef typename LanesOf<B, N>::PartBits Bits;
  Bits none = {};
  for (int i = 0; i < LanesOf<B, N>::kParts; ++i) none |= ~(a.part[i] < b);
  return lanes_detail::fold_or<Bits, LanesOf<B, N>::kPerPart>(none) == 0;
}
/// Whether any lane of `a` is non-zero (NaN counts as non-zero), without a branch per lane.
template <int B, int N>
[[gnu::always_inline]] inline bool any_nonzero(const LanesOf<B, N>& a) {
  typedef typename LanesOf<B, N>::PartBits Bits;
  Bits some = {};
  for (int i = 0; i < LanesOf<B, N>::kParts; ++i) some |= a.part[i] != 0.0;
  return lanes_detail::fold_or<Bits, LanesOf<B, N>::kPerPart>(some) != 0;
}
/// Whether any lane of `a` is zero.
template <int B, int N>
[[gnu::always_inline]] inline bool any_zero(const LanesOf<B, N>& a) {
  typedef typename LanesOf<B, N>::PartBits Bits;
  Bits some = {};
  for (int i = 0; i < LanesOf<B, N>::kParts; ++i) some |= a.part[i] == 0.0;
  return lanes_detail::fold_or<Bits, LanesOf<B, N>::kPerPart>(some) != 0;
}

/// The set of the lanes' values as bits, for lanes holding whole numbers 0..63: bit r is set
/// when some lane holds r. One conversion, one shift per part and a fold, where reading the lanes
/// one by one cost a conversion and a shift per lane.
template <int B, int N>
[[gnu::always_inline]] inline std::uint64_t bits_of_small_integers(const LanesOf<B, N>& a) {
  typedef typename LanesOf<B, N>::PartBits Bits;
  Bits m = (Bits{} + 1) << __builtin_convertvector(a.part[0], Bits);
  for (int p = 1; p < LanesOf<B, N>::kParts; ++p) m |= (Bits{} + 1) << __builtin_convertvector(a.part[p], Bits);
  return static_cast<std::uint64_t>(lanes_detail::fold_or<Bits, LanesOf<B, N>::kPerPart>(m));
}

/// Each lane converted to a 32-bit integer (truncated toward zero, as a C++ conversion; lanes
/// must hold values an int32 represents) into out[0..N).
template <int B, int N>
[[gnu::always_inline]] inline void to_int32(const LanesOf<B, N>& a, std::int32_t* out) {
  typedef std::int32_t Ints __attribute__((vector_size(LanesOf<B, N>::kPerPart * sizeof(std::int32_t))));
  for (int p = 0; p < LanesOf<B, N>::kParts; ++p) {
    const Ints ints = __builtin_convertvector(a.part[p], Ints);
    std::memcpy(out + p * LanesOf<B, N>::kPerPart, &ints, sizeof ints);
  }
}

namespace lanes_detail {
// atan2's work that depends on |x| and |y| only: the angle of (|x|, |y|) in [0, pi/2] and the
// lanes inside fast::atan2's range (1 or 0).
template <int B, int N>
struct AtanCore {
  LanesOf<B, N> angle, in_range;
};
// fast::kAtanTable[k] for every lane (k a whole number 0..8 per lane).
template <int B, int N>
[[gnu::always_inline]] inline LanesOf<B, N> atan_table(const LanesOf<B, N>& k) {
  LanesOf<B, N> table_k;
#if !defined(__clang__)
  if constexpr (B == 64 && N == 8) {
    // The table as two vectors and one two-source permutation (one instruction with AVX-512).
    typedef typename LanesOf<B, N>::Part Part;
    typedef typename LanesOf<B, N>::PartBits Bits;
    static_assert(kBlockLanes == 8, "the permuted table holds 16 entries");
    const Part low = {fast::kAtanTable[0], fast::kAtanTable[1], fast::kAtanTable[2], fast::kAtanTable[3],
                      fast::kAtanTable[4], fast::kAtanTable[5], fast::kAtanTable[6], fast::kAtanTable[7]};
    const Part high = {fast::kAtanTable[8], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    table_k.part[0] = __builtin_shuffle(low, high, __builtin_convertvector(k.part[0], Bits));
    return table_k;
  }
#endif
  // Narrower parts have no two-source permutation of nine entries: a load per lane.
  for (int i = 0; i < N; ++i) table_k.set(i, fast::kAtanTable[static_cast<int>(k[i])]);
  return table_k;
}
template <int B, int N>
[[gnu::always_inline]] inline AtanCore<B, N> atan_core(const LanesOf<B, N>& y, const LanesOf<B, N>& x) {
  typedef LanesOf<B, N> L;
  const L ax = abs(x), ay = abs(y), zero = L::splat(0.0);
  const L largest = where_greater(ax, ay, ax, ay), smallest = where_greater(ax, ay, ay, ax);
  // Lanes outside fast::atan2's range compute atan(0) here (no NaN reaches the table index).
  // The scalar's !(largest > 0) || !(largest <= DBL_MAX) || !(smallest >= 0): zero, infinite
  // or NaN arguments (smallest == smallest is false for a NaN |x| next to a finite |y|).
  const L one = L::splat(1.0);
  AtanCore<B, N> core;
  core.in_range = where_greater(
      largest, zero, where_greater(largest, L::splat(1.7976931348623157e308), zero, where_equal(smallest, smallest, one, zero)),
      zero);
  const L t = where_equal(core.in_range, zero, zero, smallest / where_equal(core.in_range, zero, one, largest));
  const L k = floor_small(t * 8.0 + 0.5);  // t * 8 + 0.5 >= 0.5: floor is the scalar's truncation
  const L angle = fast::atan_reduced(t, 0.125 * k, atan_table(k));
  constexpr double kHalfPi = 1.5707963267948966;
  core.angle = where_greater(ay, ax, kHalfPi - angle, angle);
  return core;
}
// The core's angle in the quadrant of (x, y), and libm's atan2 for the lanes outside the range.
template <int B, int N>
[[gnu::always_inline]] inline LanesOf<B, N> atan_quadrant(const AtanCore<B, N>& core, const LanesOf<B, N>& y,
                                                       const LanesOf<B, N>& x) {
  constexpr double kPi = 3.141592653589793;
  LanesOf<B, N> angle = where_sign_bit(x, kPi - core.angle, core.angle);
  angle = where_sign_bit(y, -angle, angle);
  if (any_zero(core.in_range)) {
    // Through memory: reading the lanes of in_range and angle in place makes GCC 12 compute
    // them lane by lane (scalar compares) from the start of the function.
    double flag[N], value[N], ys[N], xs[N];
    core.in_range.store(flag);
    angle.store(value);
    y.store(ys);
    x.store(xs);
    for (int i = 0; i < N; ++i) {
      if (flag[i] == 0.0) value[i] = std::atan2(ys[i], xs[i]);
    }
    angle = LanesOf<B, N>::load(value);
  }
  return angle;
}
}  // namespace lanes_detail

/// fast::atan2 (hapsyn/accel/fast_math.hpp) of every lane: the same table and series (one template,
/// fast::atan_reduced), so a lane gets what the scalar call gives (up to the compiler's
/// multiply-add fusion); lanes with a zero or non-finite argument take libm, as the scalar does.
template <int B, int N>
[[gnu::always_inline]] inline LanesOf<B, N> atan2(const LanesOf<B, N>& y, const LanesOf<B, N>& x) {
  return lanes_detail::atan_quadrant(lanes_detail::atan_core(y, x), y, x);
}

/// atan2(y, x) and atan2(y, -x) of every lane, bit for bit the two calls: everything but the
/// quadrant depends on |x| and |y| only, so it is computed once.
template <int B, int N>
[[gnu::always_inline]] inline void atan2_and_mirrored(const LanesOf<B, N>& y, const LanesOf<B, N>& x, LanesOf<B, N>& angle,
                                                      LanesOf<B, N>& mirrored) {
  const lanes_detail::AtanCore<B, N> core = lanes_detail::atan_core(y, x);
  angle = lanes_detail::atan_quadrant(core, y, x);
  mirrored = lanes_detail::atan_quadrant(core, y, -x);
}

/// fast::sin_cos (hapsyn/accel/fast_math.hpp) of every lane: the same reduction and polynomials, so a
/// lane gets what the scalar call gives (up to the compiler's multiply-add fusion).
template <int B, int N>
[[gnu::always_inline]] inline void sin_cos(const LanesOf<B, N>& x, LanesOf<B, N>& sine, LanesOf<B, N>& cosine) {
  typedef LanesOf<B, N> L;
  const L limit = L::splat(1e6);
  // Out-of-range lanes (|x| > 1e6, NaN, infinities) reduce a 0 here and take libm below.
  const L inside = where_greater(abs(x), limit, L::splat(0.0), x);
  L n, s, c;
  fast::sin_cos_reduced(inside, n, s, c);
  // Quadrant n mod 4 (n is integer-valued): (sin, cos) = (s, c), (c, -s), (-s, -c), (-c, s).
  const L quadrant = n - 4.0 * floor_small(n * 0.25);
  const L one = L::splat(1.0), two = L::splat(2.0), three = L::splat(3.0);
  const L odd = where_equal(quadrant, one, one, where_equal(quadrant, three, one, L::splat(0.0)));
  const L swapped_sine = where_equal(odd, one, c, s), swapped_cosine = where_equal(odd, one, s, c);
  sine = where_less(quadrant, two, swapped_sine, -swapped_sine);
  cosine = where_equal(quadrant, one, -swapped_cosine, where_equal(quadrant, two, -swapped_cosine, swapped_cosine));
  for (int i = 0; i < N; ++i) {
    if (!(std::fabs(x[i]) <= 1e6)) {
      sine.set(i, std::sin(x[i]));
      cosine.set(i, std::cos(x[i]));
    }
  }
}

}  // namespace hapsyn
