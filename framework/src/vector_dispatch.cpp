// The CPU's widest kernel target, detected once, and the test override.
#include <hapsyn/accel/vector_dispatch.hpp>
#include <hapsyn/error.hpp>

#include <atomic>

namespace hapsyn {

namespace {

bool cpu_has(VectorTarget target) {
#if defined(HAPSYN_MULTIVERSION_ENABLED)
  __builtin_cpu_init();
  switch (target) {
    case VectorTarget::kAvx512:
      // x86-64-v4: the AVX-512 subsets its code generation assumes, and everything of v3.
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
             __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512dq") &&
             __builtin_cpu_supports("avx512vl") && cpu_has(VectorTarget::kAvx2);
    case VectorTarget::kAvx2:
      // x86-64-v3 (clang 14 knows no level names in __builtin_cpu_supports): AVX2, FMA, BMI1/2,
      // F16C and the v2 instructions these CPUs all have.
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi") &&
             __builtin_cpu_supports("bmi2") && __builtin_cpu_supports("f16c") && __builtin_cpu_supports("popcnt") &&
             __builtin_cpu_supports("sse4.2");
    case VectorTarget::kSse2:
      return true;
  }
  return false;
#else
  return target == VectorTarget::kSse2;
#endif
}

VectorTarget widest() {
  if (cpu_has(VectorTarget::kAvx512)) return VectorTarget::kAvx512;
  if (cpu_has(VectorTarget::kAvx2)) return VectorTarget::kAvx2;
  return VectorTarget::kSse2;
}

// -1: no override. Relaxed: kernels read it on every block; force_vector_target() is documented
// as not concurrent with running kernels.
std::atomic<int> forced{-1};

}  // namespace

const char* vector_target_name(VectorTarget target) {
  switch (target) {
    case VectorTarget::kAvx512:
      return "avx512";
    case VectorTarget::kAvx2:
      return "avx2";
    case VectorTarget::kSse2:
      return "sse2";
  }
  return "?";
}

bool vector_target_available(VectorTarget target) { return cpu_has(target); }

VectorTarget vector_target() {
  static const VectorTarget best = widest();
  const int f = forced.load(std::memory_order_relaxed);
  return f < 0 ? best : static_cast<VectorTarget>(f);
}

void force_vector_target(std::optional<VectorTarget> target) {
  if (target && !vector_target_available(*target)) {
    throw Error("vector_dispatch", std::string("cannot run kernels for ") + vector_target_name(*target) +
                                       ": this CPU or build lacks it (widest available: " +
                                       vector_target_name(widest()) + ")");
  }
  forced.store(target ? static_cast<int>(*target) : -1, std::memory_order_relaxed);
}

}  // namespace hapsyn
