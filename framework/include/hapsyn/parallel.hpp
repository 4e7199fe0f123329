#pragma once
/// \file
/// Minimal dynamic parallel-for used by the framework and plugins, and the hardware thread count.
#include <functional>

namespace hapsyn {

/// Dynamic scheduling: body(index, thread_index) for index in [0, n), handed out in blocks of
/// `block` to `threads` threads. Exceptions are rethrown (the first).
///
/// A thread that cannot be started (std::thread throws std::system_error, e.g. EAGAIN under a
/// container's process limit) does not end the process: the loop runs on the threads that did
/// start (at least the calling thread, so thread_index stays below the count that started) and
/// prints once per process to stderr "hapsyn: warning: could only start 12 of 64 threads
/// (Resource temporarily unavailable); running on 12". The result is the same; only slower.
void parallel_for_dynamic(long long n, int threads, long long block,
                          const std::function<void(long long, int)>& body);

/// Starts the worker threads that parallel_for_dynamic's loops of up to `threads` threads use
/// (they stay alive between loops), unless they run already, and returns without waiting for
/// them. Optional: the first such loop starts them otherwise. Call it early, when the thread
/// count is known and before a timed or short first loop: on Linux a thread started by a busy
/// thread may wait for the scheduler's next balancing tick before it runs anywhere, measured at 1
/// to 4 ms on a 2-core VM, during which that first loop ran on the caller alone (hapsyn run calls
/// it before loading the study). A thread that cannot start gives the warning described above,
/// once; the loops then run as described there. Does nothing for threads <= 1, nor under the
/// test seam's limit below (whose loops start their own threads).
void start_worker_threads(int threads);

/// Hardware concurrency (>= 1).
int hardware_threads();

/// Test seam: at most `limit` threads beyond the caller start afterwards; the next one fails as
/// std::thread fails under a process limit (std::system_error, EAGAIN). A negative limit removes
/// it. Also re-arms the once-per-process warning. Not for production use.
void set_thread_start_limit_for_testing(int limit);

}  // namespace hapsyn
