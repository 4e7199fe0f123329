#include <hapsyn/parallel.hpp>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <exception>
#include <iostream>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

namespace hapsyn {

int hardware_threads() { return std::max(1u, std::thread::hardware_concurrency()); }

namespace {

std::atomic<int> start_limit{-1};   // the test seam; < 0: no limit
std::atomic<bool> warned{false};    // the shortfall warning is printed once per process

// std::thread, or the failure the test seam injects in its place.
std::thread start_thread(int already_started, std::function<void()> fn) {
  const int limit = start_limit.load();
  if (limit >= 0 && already_started >= limit) {
    throw std::system_error(std::make_error_code(std::errc::resource_unavailable_try_again), "thread start limit");
  }
  return std::thread(std::move(fn));
}

void warn_shortfall(int started, int wanted, const std::system_error& e) {
  if (warned.exchange(true)) return;
  // The code's message, not e.what(): libstdc++ prefixes it with its own function names.
  std::cerr << "hapsyn: warning: could only start " << started << " of " << wanted << " threads ("
            << e.code().message() << "); running on " << started << "\n";
}

// Runs fn(t) for t in [0, started) on up to threads-1 new threads plus the caller, `started`
// being the threads that could be started; keeps the first exception and rethrows it after every
// thread joined (no thread is left running). The work must not depend on every t running: a
// thread that fails to start leaves its share to the others (parallel_for_dynamic's queue).
void run_threads(int threads, const std::function<void(int)>& fn) {
  std::exception_ptr first;
  std::mutex mutex;
  auto guarded = [&](int t) {
    try {
      fn(t);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex);
      if (!first) first = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(threads > 1 ? threads - 1 : 0));
  for (int t = 1; t < threads; ++t) {
    try {
      pool.push_back(start_thread(t - 1, [&guarded, t] { guarded(t); }));
    } catch (const std::system_error& e) {
      warn_shortfall(t, threads, e);
      break;
    }
  }
  guarded(0);
  for (std::thread& th : pool) th.join();
  if (first) std::rethrow_exception(first);
}
}  // namespace

void set_thread_start_limit_for_testing(int limit) {
  start_limit = limit;
  warned = false;
}

void parallel_for_dynamic(long long n, int threads, long long block,
                          const std::function<void(long long, int)>& body) {
  if (n <= 0) return;
  block = std::max(1LL, block);
  threads = static_cast<int>(std::max(1LL, std::min<long long>(threads, (n + block - 1) / block)));
  std::atomic<long long> next{0};
  std::atomic<bool> failed{false};
  run_threads(threads, [&](int t) {
    try {
      for (;;) {
        if (failed.load(std::memory_order_relaxed)) return;
        const long long begin = next.fetch_add(block);
        if (begin >= n) return;
        const long long end = std::min(n, begin + block);
        for (long long i = begin; i < end; ++i) body(i, t);
      }
    } catch (...) {
      failed = true;
      throw;
    }
  });
}

}  // namespace hapsyn
