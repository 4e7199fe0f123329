// The single-process and shard clusters (hapsyn/cluster.hpp) and --shard parsing. The MPI
// cluster is tested end to end under mpirun (tests/mpi/mpi_test.py).
#include "test_support.hpp"

#include <hapsyn/cluster.hpp>
#include <hapsyn/error.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <map>
#include <set>
#include <string>

namespace {

using hapsyn::test::expect_error;

// A farm whose tasks return their index as text and whose collect records them.
struct RecordingFarm {
  std::map<long long, std::string> collected;
  std::atomic<int> runs{0};
  hapsyn::TaskFarm farm;

  RecordingFarm(long long count, bool shardable) {
    farm.count = count;
    farm.shardable = shardable;
    farm.run = [this](long long index, int) -> std::optional<std::string> {
      ++runs;
      return std::to_string(index * index);
    };
    farm.collect = [this](long long index, std::string&& result) {
      EXPECT_EQ(collected.count(index), 0u) << "task " << index << " collected twice";
      collected[index] = std::move(result);
    };
  }
};

}  // namespace

TEST(Ranks, LocalRunsEveryTaskOnceAndCollectsItsResult) {
  for (int threads : {1, 3}) {
    RecordingFarm f(100, false);
    const hapsyn::FarmOutcome outcome = hapsyn::Cluster::local().run_tasks(f.farm, threads);
    EXPECT_FALSE(outcome.stopped);
    EXPECT_FALSE(outcome.partial);
    ASSERT_EQ(f.collected.size(), 100u);
    for (const auto& [index, result] : f.collected) EXPECT_EQ(result, std::to_string(index * index));
  }
}

TEST(Ranks, LocalSkipsTasksDoneBefore) {
  RecordingFarm f(20, false);
  f.farm.done = [](long long index) { return index % 2 == 0; };
  hapsyn::Cluster::local().run_tasks(f.farm, 2);
  EXPECT_EQ(f.runs.load(), 10);
  for (const auto& [index, result] : f.collected) EXPECT_EQ(index % 2, 1);
}

TEST(Ranks, ATaskThatStopsMakesTheFarmStoppedAndIsNotCollected) {
  RecordingFarm f(50, false);
  f.farm.run = [](long long index, int) -> std::optional<std::string> {
    if (index == 7) return std::nullopt;
    return std::string("x");
  };
  const hapsyn::FarmOutcome outcome = hapsyn::Cluster::local().run_tasks(f.farm, 1);
  EXPECT_TRUE(outcome.stopped);
  EXPECT_EQ(f.collected.count(7), 0u);
  EXPECT_LT(f.collected.size(), 50u);  // one thread: nothing after task 7 starts
}

TEST(Ranks, LocalPropagatesATaskException) {
  RecordingFarm f(10, false);
  f.farm.run = [](long long index, int) -> std::optional<std::string> {
    if (index == 3) throw hapsyn::Error("metric", "boom");
    return std::string();
  };
  expect_error([&] { hapsyn::Cluster::local().run_tasks(f.farm, 2); }, {"metric: boom"});
}

TEST(Ranks, ShardsPartitionAShardableFarmIntoContiguousShares) {
  for (long long count : {0LL, 1LL, 10LL, 101LL}) {
    std::set<long long> seen;
    long long previous_last = -1;
    for (int i = 0; i < 3; ++i) {
      hapsyn::ShardCluster shard(i, 3);
      RecordingFarm f(count, true);
      const hapsyn::FarmOutcome outcome = shard.run_tasks(f.farm, 2);
      EXPECT_TRUE(outcome.partial);
      EXPECT_FALSE(outcome.stopped);
      for (const auto& [index, result] : f.collected) {
        EXPECT_TRUE(seen.insert(index).second) << "task " << index << " in two shares";
        EXPECT_GT(index, previous_last) << "shares are contiguous and in order";
      }
      if (!f.collected.empty()) previous_last = f.collected.rbegin()->first;
    }
    EXPECT_EQ(static_cast<long long>(seen.size()), count) << "every task in some share";
  }
}

TEST(Ranks, ShardsRunFarmsThatAreNotShardableInFull) {
  hapsyn::ShardCluster shard(1, 3);
  RecordingFarm f(30, false);
  const hapsyn::FarmOutcome outcome = shard.run_tasks(f.farm, 2);
  EXPECT_FALSE(outcome.partial);
  EXPECT_EQ(f.collected.size(), 30u);
  EXPECT_EQ(shard.shard(), std::make_pair(1, 3));
  EXPECT_NE(shard.shard_message().find("shard 2/3 done"), std::string::npos);
}

TEST(Ranks, ParseShardAcceptsOneBasedShares) {
  EXPECT_EQ(hapsyn::parse_shard("1/1"), std::make_pair(0, 1));
  EXPECT_EQ(hapsyn::parse_shard("2/3"), std::make_pair(1, 3));
  EXPECT_EQ(hapsyn::parse_shard("64/64"), std::make_pair(63, 64));
}

TEST(Ranks, ParseShardRefusesBadSharesNamingTheRule) {
  expect_error([] { hapsyn::parse_shard("3/2"); }, {"shard: --shard 3/2", "must lie in 1..N (N = 2)"});
  expect_error([] { hapsyn::parse_shard("0/0"); }, {"--shard 0/0", "N must be >= 1"});
  expect_error([] { hapsyn::parse_shard("0/4"); }, {"--shard 0/4", "must lie in 1..N"});
  expect_error([] { hapsyn::parse_shard("a/b"); }, {"--shard a/b", "whole numbers"});
  expect_error([] { hapsyn::parse_shard("1/"); }, {"--shard 1/", "whole numbers"});
  expect_error([] { hapsyn::parse_shard("-1/2"); }, {"--shard -1/2", "whole numbers"});
  expect_error([] { hapsyn::parse_shard("2"); }, {"--shard 2", "expected i/N"});
  expect_error([] { hapsyn::ShardCluster(3, 3); }, {"shard: share 4/3"});
}

TEST(Ranks, LocalClusterIsOneRankThatIsRoot) {
  hapsyn::Cluster& c = hapsyn::Cluster::local();
  EXPECT_EQ(c.rank(), 0);
  EXPECT_EQ(c.size(), 1);
  EXPECT_TRUE(c.root());
  std::string bytes = "same";
  c.broadcast(bytes);
  EXPECT_EQ(bytes, "same");
  EXPECT_EQ(c.all_gather("x"), std::vector<std::string>{"x"});
  EXPECT_TRUE(hapsyn::first_on_node(c));
}
