#pragma once
/// \file
/// Minimal parallel-for used by the framework and solvers.
#include <functional>

namespace hapsyn {

/// Runs body(begin, end, thread_index) over [0, n) split into contiguous chunks on `threads`
/// threads (the calling thread included). Exceptions from any chunk are rethrown (the first).
void parallel_for(long long n, int threads, const std::function<void(long long, long long, int)>& body);

/// Dynamic scheduling: body(index, thread_index) for index in [0, n), handed out in blocks of
/// `block` to `threads` threads. Exceptions are rethrown (the first).
void parallel_for_dynamic(long long n, int threads, long long block,
                          const std::function<void(long long, int)>& body);

/// Hardware concurrency (>= 1).
int hardware_threads();

}  // namespace hapsyn
