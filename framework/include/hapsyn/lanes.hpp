#pragma once
/// \file
/// Lanes: kBlockLanes doubles with element-wise arithmetic, for block kernels
/// (hapsyn/sample_block.hpp) written once for a scalar and for a block of samples.
///
/// A kernel templated on its number type T runs with T = double (one sample) and T = Lanes (one
/// sample per lane): the same expressions in the same order, so a lane rounds as the scalar code
/// does wherever the compiler contracts the two alike. The operators act on the
/// lanes' compiler vector (the GCC / clang vector extension): inlined ([[gnu::always_inline]])
/// into a function compiled for a wide instruction set (HAPSYN_MULTIVERSION_WIDE,
/// hapsyn/multiversion.hpp), each is one vector instruction; compiled for baseline CPUs, the
/// compiler splits it into SSE2 halves. The vector sits in a struct passed by reference: clang
/// refuses to pass a 64-byte vector by value in code not compiled for AVX-512.
#include <hapsyn/sample_block.hpp>

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
#define HAPSYN_LANES_WHERE(name, op)                                                                          \
  /** Lane-wise `x op y ? a : b`. */                                                                          \
  [[gnu::always_inline]] inline Lanes name(const Lanes& x, const Lanes& y, const Lanes& a, const Lanes& b) { \
    return Lanes{x.v op y.v ? a.v : b.v};                                                                     \
  }
HAPSYN_LANES_WHERE(where_less, <)
HAPSYN_LANES_WHERE(where_greater, >)
HAPSYN_LANES_WHERE(where_equal, ==)
#undef HAPSYN_LANES_WHERE

/// Lane-wise |a| (as std::fabs: the sign bit cleared).
[[gnu::always_inline]] inline Lanes abs(const Lanes& a) {
  typedef std::int64_t Bits __attribute__((vector_size(kBlockLanes * sizeof(double))));
  return Lanes{reinterpret_cast<Lanes::Vector>(reinterpret_cast<Bits>(a.v) & (Bits{} + INT64_MAX))};
}
/// Lane-wise max(a, b) as `a > b ? a : b` (b when either is NaN).
[[gnu::always_inline]] inline Lanes max(const Lanes& a, const Lanes& b) { return where_greater(a, b, a, b); }

}  // namespace hapsyn
