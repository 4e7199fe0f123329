// record_samples (the outputs phase's per-sample records) in one pass: the same records as
// evaluating every sample on its own, each sample solved once, on any thread count.
#include "counting_problem.hpp"

#include <hapsyn/error.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>

using namespace hapsyn::test;

TEST(SampleRecords, WorstCaseStudyMatchesEverySampleAloneAlsoPastTheSamplesThatStopAnEvaluation) {
  Counts counts;
  const int n = 3001;
  const auto problem = counting_problem(counts, n, hapsyn::Reduction::kMin);
  const Eigen::VectorXd full = Eigen::VectorXd::Constant(1, 0.8);
  const hapsyn::SampleRecords reference = records_one_by_one(*problem, full);
  // The pattern has failures of every kind, and the reference records them without locals.
  const int failed = count_failed(n);
  ASSERT_GT(failed, 100);
  for (const char* status : {"unreachable", "singular", "invalid", "reachable"}) {
    EXPECT_NE(std::find(reference.status.begin(), reference.status.end(), status), reference.status.end()) << status;
  }
  for (const int threads : {1, 2, 3}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    counts.solves = 0;
    counts.builds = 0;
    const hapsyn::SampleRecords records = hapsyn::record_samples(*problem, full, threads);
    expect_same_records(records, reference);
    EXPECT_EQ(counts.solves.load(), n);  // every sample solved once, failed ones included
    if (threads == 1) {
      // One piece: one build, and one more after each failed sample that is not the last.
      EXPECT_EQ(counts.builds.load(), 1 + failed - (status_of(n - 1) != SampleStatus::kReachable));
    }
  }
}

TEST(SampleRecords, AveragingStudyKeepsTheLocalsOfFailedSamplesAndSolvesEachOnce) {
  Counts counts;
  const int n = 2000;
  const auto problem = counting_problem(counts, n, hapsyn::Reduction::kSum);
  const Eigen::VectorXd full = Eigen::VectorXd::Constant(1, 0.8);
  const hapsyn::SampleRecords reference = records_one_by_one(*problem, full);
  // No worst-case metric: an unreachable sample has its status and its locals.
  ASSERT_EQ(reference.status[3], "unreachable");
  ASSERT_EQ(reference.has_locals[3], 1);
  for (const int threads : {1, 2}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    counts.solves = 0;
    counts.builds = 0;
    expect_same_records(hapsyn::record_samples(*problem, full, threads), reference);
    EXPECT_EQ(counts.solves.load(), n);
    // One build per piece: far fewer than one per sample.
    EXPECT_LE(counts.builds.load(), 8 * threads);
  }
}

TEST(SampleRecords, ErrorIsTheLowestSamplesWhateverTheThreadCount) {
  Counts counts;
  const int n = 4000;
  // Samples 999 and 2999 return NaN, in different pieces: sample 999's error is the one raised.
  const auto problem = counting_problem(counts, n, hapsyn::Reduction::kSum, 999);
  const Eigen::VectorXd full = Eigen::VectorXd::Constant(1, 0.8);
  for (const int threads : {1, 2}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    try {
      hapsyn::record_samples(*problem, full, threads);
      ADD_FAILURE() << "no error";
    } catch (const hapsyn::Error& e) {
      EXPECT_THAT(e.what(), testing::HasSubstr("metric 'sample_metric' returned nan for local value 0 at sample 999 (reachable)"));
    }
  }
}
