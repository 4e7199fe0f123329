#pragma once
/// \file
/// HAPSYN_MULTIVERSION: put before the definition of a hot per-sample function that only its own
/// translation unit calls, after nothing in that unit has called it yet (a file-local function
/// or a private non-virtual member). Public entry points and virtual overrides are plain
/// functions that call it: GCC cannot multiversion virtual functions, clang exports no plain
/// symbol for a multiversioned one and refuses to multiversion a function already called.
/// Block kernels written on a lanes type use hapsyn::with_vector_lanes instead
/// (hapsyn/accel/vector_dispatch.hpp): a lanes type per instruction set, AVX-512 included.
///
/// The function is compiled twice, for x86-64-v3 (AVX2 + FMA) and for baseline
/// x86-64, and the loader picks the version the CPU runs (GCC/Clang target_clones, an ifunc).
///
/// Why not -march=native for the whole build: plugins and the framework pass Eigen objects
/// across library boundaries, and Eigen's alignment (EIGEN_MAX_ALIGN_BYTES) follows the
/// translation unit's instruction set, so mixing flags between libraries is an ODR hazard; and
/// a package built with -march=native does not run on an older CPU. A clone changes only the
/// code generated for that one function (Eigen still sees baseline SSE2 macros), and the
/// scalar kernels gain most from FMA contraction (see benchmarks/haptic6r_benchmark.cpp).
///
/// Results of the two versions may differ in the last bits (fused multiply-add rounding).
/// Define HAPSYN_NO_MULTIVERSION (CMake option HAPSYN_MULTIVERSION=OFF) for one baseline version.
///
/// Sanitizer builds get one version: clang 14 with AddressSanitizer jumps to an unrelocated
/// address when a shared module calls a multiversioned function with external linkage.
#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(undefined_behavior_sanitizer)
#define HAPSYN_SANITIZED_BUILD 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define HAPSYN_SANITIZED_BUILD 1
#endif

#if defined(__x86_64__) && defined(__linux__) && (defined(__GNUC__) || defined(__clang__)) && \
    !defined(HAPSYN_NO_MULTIVERSION) && !defined(HAPSYN_SANITIZED_BUILD)
/// Defined when this build compiles hot functions for several instruction sets (see above).
#define HAPSYN_MULTIVERSION_ENABLED 1
#define HAPSYN_MULTIVERSION __attribute__((target_clones("arch=x86-64-v3", "default")))
/// HAPSYN_MULTIVERSION_WIDE: as HAPSYN_MULTIVERSION, plus an x86-64-v4 (AVX-512) version, for
/// small hot functions that gain from AVX-512 and are called too often for a call through
/// hapsyn::with_vector_lanes (the five-bar's envelope, gii's and gdi's 2 x 2 block loops: through
/// it GDI culling ran 3 to 9 % slower). They use no lanes type: their loops of kBlockLanes
/// doubles are vectorised by the compiler for each version.
#define HAPSYN_MULTIVERSION_WIDE __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define HAPSYN_MULTIVERSION
#define HAPSYN_MULTIVERSION_WIDE
#endif
