// SolveRecording: the solve's evaluation of a fixed design keeps its per-sample records, so the
// outputs phase does not evaluate the design again; the evaluation itself is unchanged.
#include "counting_problem.hpp"
#include "test_support.hpp"

#include <hapsyn/internal/solve_recording.hpp>
#include <hapsyn/internal/study.hpp>
#include <hapsyn/internal/study_runner.hpp>

#include <boost/filesystem.hpp>

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

using namespace hapsyn::test;
using hapsyn::Json;

namespace {

const Eigen::VectorXd kDesign = Eigen::VectorXd::Constant(1, 0.8);

void expect_same_evaluation(const hapsyn::Evaluation& a, const hapsyn::Evaluation& b) {
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.objectives, b.objectives);  // bit for bit
  EXPECT_EQ(a.reduced, b.reduced);
  EXPECT_EQ(a.critical_samples, b.critical_samples);
  EXPECT_EQ(a.samples_evaluated, b.samples_evaluated);
}

}  // namespace

TEST(SolveRecording, KeepsTheRecordsOfTheSolvesEvaluationOfItsDesignSolvingEachSampleOnce) {
  Counts counts;
  const int n = 2000;
  const auto problem = counting_problem(counts, n, hapsyn::Reduction::kSum);
  const hapsyn::SampleRecords reference = records_one_by_one(*problem, kDesign);
  const hapsyn::Evaluation plain = problem->evaluate_parallel(kDesign.data(), 2);
  counts.solves = 0;
  hapsyn::SolveRecording recording(*problem, kDesign);
  EXPECT_FALSE(recording.complete());
  const hapsyn::Evaluation recorded = problem->evaluate_parallel(kDesign.data(), 2);
  EXPECT_EQ(counts.solves.load(), n);  // the evaluation is the only pass
  ASSERT_TRUE(recording.complete());
  expect_same_records(recording.records(), reference);
  expect_same_evaluation(recorded, plain);
}

TEST(SolveRecording, IgnoresOtherDesignsSubsetsAndOtherProblems) {
  Counts counts;
  const auto problem = counting_problem(counts, 500, hapsyn::Reduction::kSum);
  const auto other = counting_problem(counts, 500, hapsyn::Reduction::kSum);  // the same study, other objects
  hapsyn::SolveRecording recording(*problem, kDesign);
  const Eigen::VectorXd moved = Eigen::VectorXd::Constant(1, 0.7);
  problem->evaluate_parallel(moved.data(), 2);
  EXPECT_FALSE(recording.complete());
  const std::vector<int> subset = {1, 2, 3};
  hapsyn::Problem::ParallelOptions options;
  options.subset = &subset;
  problem->evaluate_parallel(kDesign.data(), 2, options);
  EXPECT_FALSE(recording.complete());
  other->evaluate_parallel(kDesign.data(), 2);
  EXPECT_FALSE(recording.complete());
  // A problem with other objectives shares the mechanism, scene and metrics: its records are the same.
  const auto reweighted = problem->with_objectives({hapsyn::Objective{"m2", 0, hapsyn::Sense::kMinimize, 2.0}});
  reweighted->evaluate_parallel(kDesign.data(), 2);
  ASSERT_TRUE(recording.complete());
  expect_same_records(recording.records(), records_one_by_one(*problem, kDesign));
}

TEST(SolveRecording, EvaluationStoppedAtAFailedSampleLeavesTheRecordingIncomplete) {
  Counts counts;
  const auto problem = counting_problem(counts, 500, hapsyn::Reduction::kMin);  // sample 3 is unreachable
  hapsyn::SolveRecording recording(*problem, kDesign);
  const hapsyn::Evaluation e = problem->evaluate_parallel(kDesign.data(), 2);
  ASSERT_EQ(e.status, hapsyn::EvalStatus::kSampleFailed);
  EXPECT_FALSE(recording.complete());
}

TEST(SolveRecording, BlockPathStudyIsNotRecordedAndItsEvaluationIsUnchanged) {
  // The five-bar's GII study is on the block path: a callback would take it off.
  Json doc = fivebar_study("evaluate");
  doc["design"] = {{"l0", {{"value", 0.0004}}}, {"l1", {{"value", 0.2997}}}, {"l2", {{"value", 0.3}}}, {"r", {{"value", 0.4196}}}};
  const hapsyn::Study study = hapsyn::load_study(doc, registry());
  ASSERT_TRUE(study.problem->block_path());
  const hapsyn::Evaluation plain = study.problem->evaluate_parallel(nullptr, 2);
  hapsyn::SolveRecording recording(*study.problem, study.problem->full_design(nullptr));
  expect_same_evaluation(study.problem->evaluate_parallel(nullptr, 2), plain);
  EXPECT_FALSE(recording.complete());
}

namespace {

// A worst-case metric counting its local() calls: the smallest first joint angle.
class CountingMetric : public hapsyn::Metric {
 public:
  explicit CountingMetric(std::atomic<long long>& calls) : calls_(calls) {}
  void local(const hapsyn::SampleQuantities& q, double* out) const override {
    ++calls_;
    out[0] = q.q[0];
  }
  hapsyn::MetricSpecs specs() const override { return {hapsyn::kNeedJacobian, {}}; }

 private:
  std::atomic<long long>& calls_;
};

}  // namespace

TEST(SolveRecording, RunOfAFixedDesignEvaluatesEachSampleOnceForTheSolveAndTheOutputs) {
  namespace fs = boost::filesystem;
  std::atomic<long long> calls{0};
  hapsyn::InProcessMetric metric;
  metric.name = "counting";
  metric.thread_safety = hapsyn::ThreadSafety::kConcurrent;
  metric.create = [&calls](const Json&, const std::string&) { return std::make_shared<CountingMetric>(calls); };
  Json doc = fivebar_study("evaluate");
  doc["scene"]["options"]["step"] = 0.005;
  doc["design"] = {{"l0", {{"value", 0.0004}}}, {"l1", {{"value", 0.2997}}}, {"l2", {{"value", 0.3}}}, {"r", {{"value", 0.4196}}}};
  doc["objectives"] = Json::array({{{"metric", "counting"}}});
  doc["threads"] = 2;
  hapsyn::Study study = hapsyn::load_study(doc, registry(), {metric});
  ASSERT_FALSE(study.problem->block_path());
  const int n = study.problem->samples().size();
  ASSERT_GT(n, 400);
  const fs::path dir = fs::temp_directory_path() / fs::unique_path("hapsyn-recording-%%%%%%");
  hapsyn::RunOptions options;
  options.output_directory = dir.string();
  options.quiet = true;
  const Json result = hapsyn::run_study(study, options);
  ASSERT_EQ(result["status"], "converged") << result.dump();
  EXPECT_EQ(calls.load(), n);  // the solve's pass only: the outputs took its records
  // samples.csv is what a separate pass over the design gives, byte for byte.
  const std::string expected =
      hapsyn::samples_csv(*study.problem, hapsyn::record_samples(*study.problem, study.problem->full_design(nullptr), 2));
  EXPECT_EQ(calls.load(), 2 * n);
  std::ifstream written((dir / "samples.csv").string());
  std::stringstream text;
  text << written.rdbuf();
  EXPECT_EQ(text.str(), expected);
  fs::remove_all(dir);
}
