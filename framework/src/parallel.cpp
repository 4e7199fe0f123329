#include <hapsyn/parallel.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cerrno>
#include <exception>
#include <iostream>
#include <mutex>
#include <pthread.h>
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

// Threads that stay alive between parallel loops and wait for the next one: starting a thread
// per loop cost about 60 us on the 2-core VMs we measure on (a fifth of what a haptic 6R design
// evaluation on 2 threads loses to its threads). One loop at a time uses the workers; a loop that
// starts while they are busy (another thread's, or a loop inside a loop) starts its own threads
// as before. The pool is never destroyed: its workers are detached and end with the process.
class WorkerPool {
 public:
  /// Starts workers until `helpers` run (fewer, with the shortfall warning, when no more can
  /// start); does nothing when the workers are busy.
  void start(int helpers, int threads) {
    if (busy_.exchange(true, std::memory_order_acquire)) return;
    start_workers(helpers, threads);
    busy_.store(false, std::memory_order_release);
  }

  /// Runs job(t) for t in [1, helpers] on the workers (started as needed; `helpers` drops to the
  /// ones that could be started, with the shortfall warning) and job(0) on the caller; returns
  /// after every call returned. False, running nothing, when the workers are busy. job must not throw.
  bool run(int helpers, int threads, const std::function<void(int)>& job) {
    if (busy_.exchange(true, std::memory_order_acquire)) return false;
    helpers = start_workers(helpers, threads);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      job_ = &job;
      helpers_ = helpers;
      pending_.store(helpers, std::memory_order_relaxed);
      generation_.store(generation_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
    }
    if (helpers > 0) work_ready_.notify_all();
    job(0);
    spin_until([&] { return pending_.load(std::memory_order_acquire) == 0; });
    {
      std::unique_lock<std::mutex> lock(mutex_);
      done_.wait(lock, [&] { return pending_.load(std::memory_order_acquire) == 0; });
      job_ = nullptr;
    }
    busy_.store(false, std::memory_order_release);
    return true;
  }

 private:
  // Starts workers until `helpers` run; returns how many run (caller holds busy_).
  int start_workers(int helpers, int threads) {
    while (static_cast<int>(started_) < helpers) {
      try {
        std::thread(&WorkerPool::work, this, static_cast<int>(started_) + 1).detach();
        ++started_;
      } catch (const std::system_error& e) {
        warn_shortfall(static_cast<int>(started_) + 1, threads, e);
        return static_cast<int>(started_);
      }
    }
    return helpers;
  }

  void work(int index) {
    std::uint64_t seen = 0;
    for (;;) {
      // Loops often follow each other closely (one per design evaluation): a worker watches for
      // the next one a short while before it sleeps, since waking a sleeping one costs tens of us.
      spin_until([&] { return generation_.load(std::memory_order_acquire) != seen; });
      std::unique_lock<std::mutex> lock(mutex_);
      work_ready_.wait(lock, [&] { return generation_.load(std::memory_order_relaxed) != seen; });
      seen = generation_.load(std::memory_order_relaxed);
      if (index > helpers_) continue;  // not needed for this loop
      const std::function<void(int)>* job = job_;
      lock.unlock();
      (*job)(index);
      lock.lock();  // the caller may be about to wait on done_: decrement and notify under mutex_
      if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) done_.notify_one();
    }
  }

  // Polls `ready` for at most kSpin before the caller blocks on a condition variable.
  template <typename Ready>
  static void spin_until(const Ready& ready) {
    constexpr auto kSpin = std::chrono::microseconds(200);
    const auto until = std::chrono::steady_clock::now() + kSpin;
    for (int i = 0;; ++i) {
      if (ready()) return;
#if defined(__x86_64__) || defined(__i386__)
      __builtin_ia32_pause();
#endif
      if ((i & 63) == 63 && std::chrono::steady_clock::now() > until) return;
    }
  }

  std::atomic<bool> busy_{false};
  std::size_t started_ = 0;  // read and written by the thread that holds busy_
  std::mutex mutex_;
  std::condition_variable work_ready_, done_;
  std::atomic<std::uint64_t> generation_{0};  // written under mutex_, read without it while spinning
  std::atomic<int> pending_{0};  // helpers still running the loop; written under mutex_, read while spinning
  const std::function<void(int)>* job_ = nullptr;
  int helpers_ = 0;
};

std::atomic<WorkerPool*> worker_pool{nullptr};
std::once_flag fork_handler_installed;

// A forked child has none of the parent's threads: it starts a pool of its own (the parent's
// object is left as it is; its mutex may be held by a thread the child does not have).
void reset_pool_in_child() { worker_pool.store(nullptr); }

WorkerPool& pool() {
  std::call_once(fork_handler_installed, [] { pthread_atfork(nullptr, nullptr, reset_pool_in_child); });
  WorkerPool* p = worker_pool.load(std::memory_order_acquire);
  if (!p) {
    auto* fresh = new WorkerPool;  // never deleted (see WorkerPool)
    if (worker_pool.compare_exchange_strong(p, fresh, std::memory_order_acq_rel)) {
      p = fresh;
    } else {
      delete fresh;
    }
  }
  return *p;
}

// Runs fn(t) for t in [0, started) on up to threads-1 other threads plus the caller, `started`
// being the threads that could be started; keeps the first exception and rethrows it after every
// call returned (no thread is left working). The work must not depend on every t running: a
// thread that fails to start leaves its share to the others (parallel_for_dynamic's queue).
void run_threads(int threads, const std::function<void(int)>& fn) {
  std::exception_ptr first;
  std::mutex mutex;
  const std::function<void(int)> guarded = [&](int t) {
    try {
      fn(t);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex);
      if (!first) first = std::current_exception();
    }
  };
  // The test seam's limit applies to threads started per loop, so it bypasses the pool.
  if (threads > 1 && start_limit.load() < 0 && pool().run(threads - 1, threads, guarded)) {
    if (first) std::rethrow_exception(first);
    return;
  }
  std::vector<std::thread> threads_started;
  threads_started.reserve(static_cast<std::size_t>(threads > 1 ? threads - 1 : 0));
  for (int t = 1; t < threads; ++t) {
    try {
      threads_started.push_back(start_thread(t - 1, [&guarded, t] { guarded(t); }));
    } catch (const std::system_error& e) {
      warn_shortfall(t, threads, e);
      break;
    }
  }
  guarded(0);
  for (std::thread& th : threads_started) th.join();
  if (first) std::rethrow_exception(first);
}
}  // namespace

void start_worker_threads(int threads) {
  // The test seam's loops bypass the pool (run_threads), so the seam bypasses this as well.
  if (threads > 1 && start_limit.load() < 0) pool().start(threads - 1, threads);
}

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
