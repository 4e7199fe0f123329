#pragma once
/// \file
/// Minimal dynamic parallel-for used by the framework and plugins, and the hardware thread count.
#include <functional>

namespace hapsyn {

/// Dynamic scheduling: body(index, thread_index) for index in [0, n), handed out in blocks of
/// `block` to `threads` threads. Exceptions are rethrown (the first).
void parallel_for_dynamic(long long n, int threads, long long block,
                          const std::function<void(long long, int)>& body);

/// Hardware concurrency (>= 1).
int hardware_threads();

}  // namespace hapsyn
