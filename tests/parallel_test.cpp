// parallel_for_dynamic when threads cannot be started (issue 20): it runs on those that did,
// warns once, and never terminates the process.
#include <hapsyn/parallel.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <thread>
#include <mutex>
#include <vector>

namespace {

// Resets the seam when a test ends, whatever happens in it.
struct StartLimit {
  explicit StartLimit(int limit) { hapsyn::set_thread_start_limit_for_testing(limit); }
  ~StartLimit() { hapsyn::set_thread_start_limit_for_testing(-1); }
};

// Threads of this process now (Linux: one entry per thread in /proc/self/task).
std::size_t process_threads() {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator("/proc/self/task")) ++n;
  return n;
}

}  // namespace

TEST(Parallel, ThreadsThatCannotStartLeaveTheWorkToTheOthersWithOneWarning) {
  const StartLimit limit(11);  // 11 new threads + the caller = 12 of 64
  std::vector<std::atomic<int>> done(1000);
  std::mutex mutex;
  std::set<int> used;
  testing::internal::CaptureStderr();
  hapsyn::parallel_for_dynamic(1000, 64, 1, [&](long long i, int t) {
    done[static_cast<std::size_t>(i)]++;
    std::lock_guard<std::mutex> lock(mutex);
    used.insert(t);
  });
  hapsyn::parallel_for_dynamic(1000, 64, 1, [&](long long i, int) { done[static_cast<std::size_t>(i)]++; });
  const std::string err = testing::internal::GetCapturedStderr();
  for (const auto& d : done) EXPECT_EQ(d.load(), 2);
  EXPECT_LT(*used.rbegin(), 12);
  EXPECT_EQ(err, "hapsyn: warning: could only start 12 of 64 threads (Resource temporarily unavailable); running on 12\n");
}

TEST(Parallel, WhenNoThreadStartsTheCallerDoesAllTheWork) {
  const StartLimit limit(0);
  std::atomic<long long> sum{0};
  std::set<int> used;
  testing::internal::CaptureStderr();
  hapsyn::parallel_for_dynamic(100, 8, 3, [&](long long i, int t) {
    sum += i;
    used.insert(t);  // one thread only: no lock needed
  });
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(sum.load(), 4950);
  EXPECT_EQ(used, std::set<int>{0});
  EXPECT_NE(err.find("could only start 1 of 8 threads"), std::string::npos) << err;
  EXPECT_NE(err.find("running on 1"), std::string::npos) << err;
}

TEST(Parallel, ExceptionsStillReachTheCallerWithFewerThreads) {
  const StartLimit limit(1);
  testing::internal::CaptureStderr();
  EXPECT_THROW(hapsyn::parallel_for_dynamic(100, 8, 1,
                                            [](long long i, int) {
                                              if (i == 50) throw std::runtime_error("deliberate");
                                            }),
               std::runtime_error);
  testing::internal::GetCapturedStderr();
}

TEST(Parallel, WithoutALimitEveryThreadRunsAndNothingIsPrinted) {
  std::atomic<long long> sum{0};
  testing::internal::CaptureStderr();
  hapsyn::parallel_for_dynamic(1000, 4, 1, [&](long long i, int) { sum += i; });
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  EXPECT_EQ(sum.load(), 499500);
}

// The workers persist between loops: many short loops in a row, each with every index once and
// thread numbers below the count; an exception from a worker's share reaches the caller and the
// next loop runs normally.
TEST(Parallel, PersistentWorkersRunLoopAfterLoopAndPassExceptionsOn) {
  for (int loop = 0; loop < 500; ++loop) {
    std::vector<std::atomic<int>> done(64);
    std::atomic<int> highest{0};
    hapsyn::parallel_for_dynamic(64, 3, 1, [&](long long i, int t) {
      done[static_cast<std::size_t>(i)]++;
      int seen = highest.load();
      while (t > seen && !highest.compare_exchange_weak(seen, t)) {
      }
    });
    for (const auto& d : done) ASSERT_EQ(d.load(), 1) << "loop " << loop;
    ASSERT_LT(highest.load(), 3);
  }
  std::atomic<int> thrown_on{-1};
  EXPECT_THROW(hapsyn::parallel_for_dynamic(1000, 2, 1,
                                            [&](long long i, int t) {
                                              if (i == 999) {
                                                thrown_on = t;
                                                throw std::runtime_error("deliberate");
                                              }
                                            }),
               std::runtime_error);
  std::atomic<long long> sum{0};
  hapsyn::parallel_for_dynamic(100, 2, 1, [&](long long i, int) { sum += i; });
  EXPECT_EQ(sum.load(), 4950);
}

// A loop inside a loop, and loops started by two threads at once: the workers serve one loop at
// a time, the others start threads of their own; every index runs once.
TEST(Parallel, NestedAndConcurrentLoopsEachRunEveryIndexOnce) {
  std::vector<std::atomic<int>> inner(8 * 50);
  hapsyn::parallel_for_dynamic(8, 2, 1, [&](long long outer, int) {
    hapsyn::parallel_for_dynamic(50, 2, 1, [&](long long i, int) { inner[static_cast<std::size_t>(outer * 50 + i)]++; });
  });
  for (const auto& d : inner) EXPECT_EQ(d.load(), 1);
  std::vector<std::atomic<int>> a(2000), b(2000);
  std::thread other([&] {
    for (int r = 0; r < 20; ++r) hapsyn::parallel_for_dynamic(100, 2, 1, [&](long long i, int) { a[static_cast<std::size_t>(r * 100 + i)]++; });
  });
  for (int r = 0; r < 20; ++r) hapsyn::parallel_for_dynamic(100, 2, 1, [&](long long i, int) { b[static_cast<std::size_t>(r * 100 + i)]++; });
  other.join();
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].load(), 1) << i;
    EXPECT_EQ(b[i].load(), 1) << i;
  }
}

// start_worker_threads starts the pool's workers ahead of the first loop: a loop of that many
// threads afterwards starts none of its own and still runs on every thread index.
TEST(Parallel, StartedWorkersServeTheNextLoopWithoutStartingThreads) {
  constexpr int kThreads = 7;  // more than any other test of this file uses
  const std::size_t before = process_threads();
  hapsyn::start_worker_threads(kThreads);
  const std::size_t started = process_threads();
  EXPECT_GT(started, before);
  hapsyn::start_worker_threads(kThreads);  // already running: nothing new
  EXPECT_EQ(process_threads(), started);
  std::vector<std::atomic<int>> ran_on(kThreads);
  std::atomic<int> waiting{kThreads};
  std::atomic<std::size_t> during{0};
  hapsyn::parallel_for_dynamic(kThreads, kThreads, 1, [&](long long, int t) {
    ran_on[static_cast<std::size_t>(t)]++;
    // Hold each index until all have started (at most 10 s), so that every thread takes one.
    waiting--;
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (waiting.load() > 0 && std::chrono::steady_clock::now() < until) std::this_thread::yield();
    if (t == 0) during = process_threads();
  });
  for (int t = 0; t < kThreads; ++t) EXPECT_EQ(ran_on[static_cast<std::size_t>(t)].load(), 1) << "thread " << t;
  EXPECT_EQ(during.load(), started);  // the loop ran on the started workers, no thread of its own
}

// Under the test seam's limit (which loops bypass the pool for) and for one thread it does nothing.
TEST(Parallel, StartingWorkersUnderTheSeamOrForOneThreadStartsNone) {
  const std::size_t before = process_threads();
  hapsyn::start_worker_threads(1);
  EXPECT_EQ(process_threads(), before);
  {
    StartLimit limit(0);
    hapsyn::start_worker_threads(64);
    EXPECT_EQ(process_threads(), before);
  }
}
