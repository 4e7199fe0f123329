#pragma once
// Test support: the vector targets this machine runs (hapsyn/accel/vector_dispatch.hpp), and a
// scope that forces one, so that a test can run a kernel for each instruction set in turn.
#include <hapsyn/accel/vector_dispatch.hpp>

#include <gtest/gtest.h>

#include <vector>

namespace hapsyn::testing {

/// The targets with_vector_lanes() can run here, widest last (SSE2 always).
inline std::vector<VectorTarget> available_vector_targets() {
  std::vector<VectorTarget> out;
  for (const VectorTarget t : {VectorTarget::kSse2, VectorTarget::kAvx2, VectorTarget::kAvx512}) {
    if (vector_target_available(t)) out.push_back(t);
  }
  return out;
}

/// Forces `target` for its lifetime (hapsyn::force_vector_target), then restores the default.
class ForcedVectorTarget {
 public:
  explicit ForcedVectorTarget(VectorTarget target) { force_vector_target(target); }
  ~ForcedVectorTarget() { force_vector_target(std::nullopt); }
  ForcedVectorTarget(const ForcedVectorTarget&) = delete;
  ForcedVectorTarget& operator=(const ForcedVectorTarget&) = delete;
};

/// Runs `check` once per available target, forced, with the target's name in failure messages;
/// stops after a fatal failure.
template <class Check>
void for_each_vector_target(Check&& check) {
  for (const VectorTarget target : available_vector_targets()) {
    const ForcedVectorTarget forced(target);
    SCOPED_TRACE(vector_target_name(target));
    check();
    if (::testing::Test::HasFatalFailure()) return;
  }
}

}  // namespace hapsyn::testing
