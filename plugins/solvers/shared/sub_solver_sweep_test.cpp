// The sweep of sequential and weighted_sum: every subproblem run once, its record, its counts;
// a stopped sub-solver run left for --resume; a resume that skips the finished ones and refuses
// a checkpoint of other subproblems.
#include "shared/sub_solver_sweep.hpp"

#include "analytic_problems.hpp"
#include "test_support.hpp"

#include <boost/filesystem.hpp>

#include <unistd.h>

#include <atomic>
#include <sstream>

namespace {

using hapsyn::Json;
using hapsyn::plugins::SubSolverSweep;
using hapsyn::plugins::SubSolverSweepOutcome;

// A sub-solver whose best design is (0.2 + 0.4 w, 0), w the problem's first objective weight;
// a run on weight `stop_at` stops as on a stop request that came during it (it sets `*flag`,
// the parent's stop flag). It counts its runs.
class WeightSolver : public hapsyn::Solver {
 public:
  WeightSolver() = default;
  WeightSolver(double stop_at, std::atomic<bool>* flag) : stop_at_(stop_at), flag_(flag) {}
  void check(const hapsyn::Problem&) const override {}
  hapsyn::SolverResult solve(const hapsyn::Problem& problem, const hapsyn::SolverContext&) const override {
    ++runs;
    const double w = problem.objectives()[0].weight;
    hapsyn::SolverResult r;
    if (w == stop_at_) {
      *flag_ = true;
      r.status = hapsyn::SolverStatus::kStopped;
      r.design_evaluations = 4;
      r.sample_evaluations = 12;
      return r;
    }
    Eigen::VectorXd design(2);
    design << 0.2 + 0.4 * w, 0.0;
    r.best = hapsyn::SolutionPoint{design, {}, 0.0};
    r.status = hapsyn::SolverStatus::kConverged;
    r.design_evaluations = 10;
    r.sample_evaluations = 30;
    return r;
  }
  mutable std::atomic<int> runs{0};

 private:
  double stop_at_ = -1.0;
  std::atomic<bool>* flag_ = nullptr;
};

const std::vector<std::vector<double>> kWeights = {{1.0, 0.0}, {0.5, 0.5}, {0.0, 1.0}};

// One subproblem per weight vector of kWeights, identified by "weights".
SubSolverSweep weight_sweep(const hapsyn::Problem& problem) {
  SubSolverSweep sweep;
  sweep.solver = "test";
  sweep.fingerprint = "fp";
  sweep.count = kWeights.size();
  sweep.units = "weight vectors";
  sweep.key = "weights";
  sweep.identity = [](std::size_t k) { return Json(kWeights[k]); };
  sweep.named = [](std::size_t k) { return "weight vector " + std::to_string(k); };
  sweep.what = [](std::size_t k) { return "test: weights " + std::to_string(k); };
  sweep.problem = [&problem](std::size_t k) { return hapsyn::plugins::reweighted_problem(problem, kWeights[k]); };
  return sweep;
}

std::string temp_file(const std::string& name) {
  return (boost::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid()) + ".json")).string();
}

}  // namespace

TEST(SubSolverSweep, RunsEverySubproblemOnceAndRecordsItsIdentityDesignAndObjectives) {
  const auto problem = hapsyn::test::two_objective_problem();
  const WeightSolver solver;
  const SubSolverSweepOutcome outcome =
      hapsyn::plugins::run_sub_solver_sweep(solver, *problem, hapsyn::SolverContext{}, weight_sweep(*problem));
  EXPECT_EQ(solver.runs.load(), 3);
  EXPECT_FALSE(outcome.stopped);
  EXPECT_TRUE(outcome.resumed.is_null());
  ASSERT_EQ(outcome.finished.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    ASSERT_TRUE(outcome.finished[k] && outcome.finished[k]->point);
    const Json& record = outcome.finished[k]->record;
    EXPECT_EQ(record["weights"], Json(kWeights[k]));
    EXPECT_EQ(record["status"], "converged");
    EXPECT_EQ(record["design"]["x0"], 0.2 + 0.4 * kWeights[k][0]);
    // The design re-evaluated with all the study's objectives, whatever the subproblem's weights.
    EXPECT_EQ(record["objectives"], Json(outcome.finished[k]->point->objectives));
    EXPECT_EQ(outcome.finished[k]->point->objectives.size(), 2u);
    EXPECT_TRUE(record.contains("seconds"));
    EXPECT_EQ(outcome.finished[k]->sample_evaluations, 30 + 3);  // the re-evaluation: three samples
  }
  EXPECT_EQ(outcome.design_evaluations, 3 * 10);
  EXPECT_EQ(outcome.sample_evaluations, 3 * 33);
}

TEST(SubSolverSweep, StoppedSubSolverRunIsLeftUnfinishedWithOnlyItsCostKept) {
  const auto problem = hapsyn::test::two_objective_problem();
  std::atomic<bool> stop{false};
  hapsyn::SolverContext context;
  context.stop = &stop;
  const WeightSolver solver(0.5, &stop);
  const SubSolverSweepOutcome outcome = hapsyn::plugins::run_sub_solver_sweep(solver, *problem, context, weight_sweep(*problem));
  EXPECT_TRUE(outcome.stopped);
  EXPECT_TRUE(outcome.finished[0]);
  EXPECT_FALSE(outcome.finished[1]);  // interrupted: run again on --resume
  EXPECT_FALSE(outcome.finished[2]);  // never started
  EXPECT_EQ(solver.runs.load(), 2);
  EXPECT_EQ(outcome.design_evaluations, 10 + 4);
  EXPECT_EQ(outcome.sample_evaluations, 33 + 12);
}

TEST(SubSolverSweep, ResumeSkipsTheFinishedSubproblemsAndSaysSo) {
  const auto problem = hapsyn::test::two_objective_problem();
  const std::string file = temp_file("hapsyn-sweep-resume");
  std::atomic<bool> stop{false};
  hapsyn::SolverContext context;
  context.checkpoint_file = file;
  context.stop = &stop;
  const WeightSolver stopping(0.0, &stop);  // the last weight vector stops
  const SubSolverSweepOutcome first = hapsyn::plugins::run_sub_solver_sweep(stopping, *problem, context, weight_sweep(*problem));
  ASSERT_TRUE(first.stopped);

  stop = false;
  context.resume = true;
  std::ostringstream log;
  context.log = &log;
  const WeightSolver solver;
  const SubSolverSweepOutcome resumed = hapsyn::plugins::run_sub_solver_sweep(solver, *problem, context, weight_sweep(*problem));
  EXPECT_EQ(solver.runs.load(), 1);  // the stopped one only
  EXPECT_FALSE(resumed.stopped);
  EXPECT_EQ(resumed.resumed["finished"], 2);
  EXPECT_EQ(resumed.resumed["checkpoint"], file);
  EXPECT_NE(log.str().find("test: resuming from " + file + ": 2 of 3 weight vectors finished"), std::string::npos) << log.str();
  const SubSolverSweepOutcome uninterrupted =
      hapsyn::plugins::run_sub_solver_sweep(WeightSolver(), *problem, hapsyn::SolverContext{}, weight_sweep(*problem));
  for (std::size_t k = 0; k < 3; ++k) {
    ASSERT_TRUE(resumed.finished[k] && resumed.finished[k]->point);
    EXPECT_EQ(resumed.finished[k]->point->design, uninterrupted.finished[k]->point->design);
    EXPECT_EQ(resumed.finished[k]->point->objectives, uninterrupted.finished[k]->point->objectives);
  }
  boost::filesystem::remove(file);
}

TEST(SubSolverSweep, ResumeRefusesACheckpointOfOtherSubproblems) {
  const auto problem = hapsyn::test::two_objective_problem();
  const std::string file = temp_file("hapsyn-sweep-other");
  hapsyn::SolverContext context;
  context.checkpoint_file = file;
  hapsyn::plugins::run_sub_solver_sweep(WeightSolver(), *problem, context, weight_sweep(*problem));

  context.resume = true;
  SubSolverSweep other = weight_sweep(*problem);
  other.identity = [](std::size_t k) { return Json(std::vector<double>{kWeights[k][1], kWeights[k][0]}); };
  hapsyn::test::expect_error(
      [&] { hapsyn::plugins::run_sub_solver_sweep(WeightSolver(), *problem, context, other); },
      {"checkpoint: " + file + ": finished[0].record.weights = [1.0,0.0]: this study's weight vector 0 is [0.0,1.0]",
       "delete it, or run without --resume"});
  boost::filesystem::remove(file);
}
