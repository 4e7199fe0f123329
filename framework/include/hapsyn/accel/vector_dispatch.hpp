#pragma once
/// \file
/// One kernel source for every instruction set: a block kernel is a generic lambda (or any
/// callable) that takes a lanes tag and uses the tag's lanes type (`type` of LanesTag);
/// with_vector_lanes() calls it compiled for the widest instruction set the CPU has, with the
/// lanes type whose parts fill that set's registers (hapsyn/accel/lanes.hpp):
///
/// \code
/// void Model::solve_block(const PoseBlock& poses, QuantityBlock& out) const {
///   hapsyn::with_vector_lanes([&](auto tag) HAPSYN_KERNEL_BODY {
///     using L = typename decltype(tag)::type;  // LanesOf<64>, <32> or <16>
///     const L x = L::load(poses.coordinate[0]);
///     // ...
///   });
/// }
/// \endcode
///
/// The body must be HAPSYN_KERNEL_BODY ([[gnu::always_inline]]) and call only always-inline
/// code on its hot path (the lanes operations, fast_math, the kernel's own templates): inlined
/// into the per-target entry it is compiled for that target; a function it calls out of line is
/// compiled for baseline x86-64 whichever target runs.
///
/// Targets: AVX-512 (x86-64-v4) with `Lanes`, AVX2 + FMA (x86-64-v3) with `LanesAvx2`, and
/// baseline (SSE2 on x86-64, the 128-bit unit elsewhere) with `LanesSse2`. Builds without
/// multiversioning (HAPSYN_NO_MULTIVERSION, sanitizer builds; hapsyn/accel/multiversion.hpp) and
/// other architectures have the baseline only. Results of the targets may differ in the last
/// bits where a kernel source allows multiply-add contraction (hapsyn_kernel_sources CONTRACT);
/// a kernel source without contraction gives the same bits on every target.
#include <hapsyn/accel/lanes.hpp>
#include <hapsyn/accel/multiversion.hpp>

#include <optional>

namespace hapsyn {

/// The instruction sets block kernels are compiled for.
enum class VectorTarget {
  kSse2,   ///< baseline x86-64 (SSE2), or another architecture's 128-bit unit
  kAvx2,   ///< x86-64-v3: AVX2 and FMA
  kAvx512  ///< x86-64-v4: AVX-512 F, BW, CD, DQ, VL
};

/// "sse2", "avx2" or "avx512".
const char* vector_target_name(VectorTarget target);

/// The target with_vector_lanes() runs: the one forced by force_vector_target(), else the widest
/// compiled target the CPU has (detected once).
VectorTarget vector_target();

/// Whether this build has kernels for `target` and the CPU runs them.
bool vector_target_available(VectorTarget target);

/// For tests and benchmarks: makes with_vector_lanes() run `target` (std::nullopt: the CPU's
/// widest again). Not for use while kernels run on other threads. Throws hapsyn::Error
/// ("vector_dispatch") when the target is not available.
void force_vector_target(std::optional<VectorTarget> target);

/// The lanes types of one target, passed to a kernel body as its argument: `type` holds a
/// block (kBlockLanes lanes in one, two or four registers), `chunk` one register of it
/// (kChunks chunks make a block). A kernel whose lanes never meet (no decision over the whole
/// block) runs faster chunk by chunk on the narrower targets: fewer live registers, no spills.
template <int PartBytes>
struct LanesTag {
  using type = LanesOf<PartBytes>;
  using chunk = LanesOf<PartBytes, PartBytes / 8>;
  static constexpr int kChunks = kBlockLanes / (PartBytes / 8);
};

/// Marks a kernel body lambda (after its parameter list) always inline.
#define HAPSYN_KERNEL_BODY __attribute__((always_inline))

namespace vector_dispatch_detail {
#if defined(HAPSYN_MULTIVERSION_ENABLED)
template <class Body>
__attribute__((target("arch=x86-64-v4"), noinline)) void run_avx512(const Body& body) {
  body(LanesTag<64>{});
}
template <class Body>
__attribute__((target("arch=x86-64-v3"), noinline)) void run_avx2(const Body& body) {
  body(LanesTag<32>{});
}
#endif
template <class Body>
__attribute__((noinline)) void run_sse2(const Body& body) {
  body(LanesTag<16>{});
}
}  // namespace vector_dispatch_detail

/// Calls `body(LanesTag<B>{})` compiled for vector_target(), B its part width.
template <class Body>
inline void with_vector_lanes(const Body& body) {
#if defined(HAPSYN_MULTIVERSION_ENABLED)
  switch (vector_target()) {
    case VectorTarget::kAvx512:
      vector_dispatch_detail::run_avx512(body);
      return;
    case VectorTarget::kAvx2:
      vector_dispatch_detail::run_avx2(body);
      return;
    case VectorTarget::kSse2:
      break;
  }
#endif
  vector_dispatch_detail::run_sse2(body);
}

}  // namespace hapsyn
