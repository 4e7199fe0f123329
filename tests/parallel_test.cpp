// parallel_for_dynamic when threads cannot be started (issue 20): it runs on those that did,
// warns once, and never terminates the process.
#include <hapsyn/parallel.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <set>
#include <mutex>
#include <vector>

namespace {

// Resets the seam when a test ends, whatever happens in it.
struct StartLimit {
  explicit StartLimit(int limit) { hapsyn::set_thread_start_limit_for_testing(limit); }
  ~StartLimit() { hapsyn::set_thread_start_limit_for_testing(-1); }
};

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
