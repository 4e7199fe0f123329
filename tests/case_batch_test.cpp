// Tests of a batch of cases (hapsyn/internal/case_batch.hpp) on its own, with cases that only
// record what happened to them: reuse, force, stop, shards, continuing a folder, and the errors
// rank 0 decides. (Sweeps and comparisons over real studies: sweep_test, compare_test.)
#include "test_support.hpp"

#include <hapsyn/cluster.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/internal/case_batch.hpp>

#include <boost/filesystem.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <stdexcept>
#include <unistd.h>

using hapsyn::CaseBatch;
using hapsyn::CaseBatchOutcome;
using hapsyn::Cluster;
using hapsyn::Json;
using hapsyn::test::expect_error;
namespace fs = boost::filesystem;

namespace {

fs::path fresh(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("hapsyn-case-batch-test-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}

// Cases c0..c{count-1}: those in `finished` are reused, the others run and record {"ran": c}.
CaseBatch batch_of(long long count, const fs::path& out, const std::vector<long long>& finished, std::vector<long long>& ran) {
  CaseBatch b;
  b.count = count;
  b.output_directory = out.string();
  b.component = "batch";
  b.reuse = [finished](long long c) -> std::optional<Json> {
    if (std::find(finished.begin(), finished.end(), c) == finished.end()) return std::nullopt;
    return Json{{"reused", c}};
  };
  b.run = [&ran](long long c) -> std::optional<Json> {
    ran.push_back(c);
    return Json{{"ran", c}};
  };
  return b;
}

const std::vector<std::string> kNames = {"c0", "c1", "c2", "c3"};

}  // namespace

TEST(CaseBatch, RunsEveryCaseThatIsNotReusedAndGathersTheRecords) {
  const fs::path out = fresh("reuse");
  std::vector<long long> ran;
  const CaseBatchOutcome o = hapsyn::run_case_batch(batch_of(4, out, {1, 3}, ran), Cluster::local());
  EXPECT_TRUE(fs::is_directory(out)) << "rank 0 creates the output directory";
  EXPECT_EQ(o.first, 0);
  EXPECT_EQ(o.last, 4);
  EXPECT_EQ(ran, (std::vector<long long>{0, 2}));
  EXPECT_EQ(o.reused, (std::vector<char>{0, 1, 0, 1}));
  EXPECT_EQ(o.started, (std::vector<char>{1, 0, 1, 0}));
  ASSERT_EQ(o.records.size(), 4u);
  EXPECT_EQ(*o.records[0], (Json{{"ran", 0}}));
  EXPECT_EQ(*o.records[1], (Json{{"reused", 1}}));
  EXPECT_EQ(hapsyn::first_unfinished(o, kNames, Cluster::local()), "");
  fs::remove_all(out);
}

TEST(CaseBatch, ForceRunsEveryCaseWithoutAskingForReuse) {
  const fs::path out = fresh("force");
  std::vector<long long> ran;
  CaseBatch b = batch_of(3, out, {}, ran);
  b.force = true;
  b.reuse = [](long long) -> std::optional<Json> {
    ADD_FAILURE() << "reuse asked under force";
    return std::nullopt;
  };
  const CaseBatchOutcome o = hapsyn::run_case_batch(b, Cluster::local());
  EXPECT_EQ(ran, (std::vector<long long>{0, 1, 2}));
  EXPECT_EQ(o.reused, (std::vector<char>{0, 0, 0}));
  fs::remove_all(out);
}

TEST(CaseBatch, StopLeavesTheRestUnstartedAndTheFirstUnfinishedIsNamed) {
  const fs::path out = fresh("stop");
  std::vector<long long> ran;
  std::atomic<bool> stop{false};
  CaseBatch b = batch_of(4, out, {0}, ran);
  b.stop = &stop;
  b.run = [&](long long c) -> std::optional<Json> {
    ran.push_back(c);
    stop = true;  // the case in progress stops; no further one starts
    return std::nullopt;
  };
  CaseBatchOutcome o = hapsyn::run_case_batch(b, Cluster::local());
  EXPECT_EQ(ran, (std::vector<long long>{1}));
  EXPECT_EQ(o.started, (std::vector<char>{0, 1, 0, 0}));
  EXPECT_FALSE(o.records[1]);
  EXPECT_EQ(hapsyn::first_unfinished(o, kNames, Cluster::local()), "c1");
  o.records[1] = Json{{"ran", 1}};
  EXPECT_EQ(hapsyn::first_unfinished(o, kNames, Cluster::local()), "c2 (not started)");
  fs::remove_all(out);
}

TEST(CaseBatch, ReuseErrorsAreThrownWithTheirComponent) {
  const fs::path out = fresh("errors");
  std::vector<long long> ran;
  CaseBatch b = batch_of(2, out, {}, ran);
  b.reuse = [](long long) -> std::optional<Json> { throw hapsyn::Error("merge", "run-0: nothing to reuse"); };
  expect_error([&] { hapsyn::run_case_batch(b, Cluster::local()); }, {"merge: run-0: nothing to reuse"});
  b.reuse = [](long long) -> std::optional<Json> { throw std::runtime_error("disk full"); };
  expect_error([&] { hapsyn::run_case_batch(b, Cluster::local()); }, {"batch: disk full"});
  EXPECT_TRUE(ran.empty()) << "no case runs after a refused reuse";
  fs::remove_all(out);
}

TEST(CaseBatch, ShardRunsItsShareAndSummaryNamesIt) {
  const fs::path out = fresh("shard");
  std::vector<long long> ran;
  hapsyn::ShardCluster share(1, 2);
  const CaseBatchOutcome o = hapsyn::run_case_batch(batch_of(4, out, {3}, ran), share);
  EXPECT_EQ(o.first, 2);
  EXPECT_EQ(o.last, 4);
  EXPECT_EQ(ran, (std::vector<long long>{2}));
  EXPECT_EQ(o.reused, (std::vector<char>{0, 0, 0, 1}));
  Json summary = Json::object();
  hapsyn::add_shard_entry(summary, o, kNames, share, "");
  EXPECT_EQ(summary["shard"], (Json{{"index", 2}, {"count", 2}, {"cases", {"c2", "c3"}}}));
  EXPECT_EQ(summary["message"], share.shard_message());
  Json stopped = {{"message", "stopped on request"}};
  hapsyn::add_shard_entry(stopped, o, kNames, share, "c2");
  EXPECT_EQ(stopped["message"], "stopped on request") << "a stopped share keeps its message";
  Json whole = Json::object();
  hapsyn::add_shard_entry(whole, o, kNames, Cluster::local(), "");
  EXPECT_EQ(whole, Json::object()) << "no shard entry without --shard";
  fs::remove_all(out);
}

TEST(CaseBatch, ContinuingAFolderResumesItsCheckpointOrForceOverwrites) {
  const fs::path dir = fresh("folder");
  fs::create_directories(dir);
  std::ofstream((dir / "result.json").string()) << "{}";
  std::ofstream((dir / "checkpoint.json").string()) << "{}";
  hapsyn::RunOptions forced;
  forced.output_directory = dir.string();
  hapsyn::continue_in_folder(forced, true);
  EXPECT_TRUE(forced.force);
  EXPECT_FALSE(forced.resume);
  EXPECT_TRUE(fs::exists(dir / "result.json")) << "force leaves the folder to the run";
  hapsyn::RunOptions resumed;
  resumed.output_directory = dir.string();
  hapsyn::continue_in_folder(resumed, false);
  EXPECT_FALSE(resumed.force);
  EXPECT_TRUE(resumed.resume);
  EXPECT_FALSE(fs::exists(dir / "result.json")) << "a stopped run's result gives way to the continued run's";
  fs::remove(dir / "checkpoint.json");
  hapsyn::RunOptions fresh_run;
  fresh_run.output_directory = dir.string();
  hapsyn::continue_in_folder(fresh_run, false);
  EXPECT_FALSE(fresh_run.resume) << "nothing to resume without a checkpoint";
  fs::remove_all(dir);
}

TEST(CaseBatch, SummaryIsRankZerosOrItsErrorOnEveryRank) {
  EXPECT_EQ(hapsyn::summary_on_every_rank(Cluster::local(), [] { return Json{{"status", "finished"}}; }, "batch"),
            (Json{{"status", "finished"}}));
  expect_error([] { hapsyn::summary_on_every_rank(Cluster::local(), []() -> Json { throw std::runtime_error("no space"); }, "batch"); },
               {"batch: no space"});
  expect_error([] { hapsyn::summary_on_every_rank(Cluster::local(), []() -> Json { throw hapsyn::Error("plot", "gnuplot"); }, "batch"); },
               {"plot: gnuplot"});
}
