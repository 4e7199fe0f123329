#include <hapsyn/parallel.hpp>

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace hapsyn {

int hardware_threads() { return std::max(1u, std::thread::hardware_concurrency()); }

namespace {
// Runs fn(t) for t in [0, threads) on threads-1 new threads plus the caller; keeps the first
// exception and rethrows it after every thread joined (no thread is left running).
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
  for (int t = 1; t < threads; ++t) pool.emplace_back(guarded, t);
  guarded(0);
  for (std::thread& th : pool) th.join();
  if (first) std::rethrow_exception(first);
}
}  // namespace

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
