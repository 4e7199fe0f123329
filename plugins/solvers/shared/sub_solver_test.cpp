// The sub-solver helpers of nbi, weighted_sum and sequential: a missing sub-solver is a failed
// status, a refusal is rethrown under the parent's name and option path, and the derived
// problems change only what their names say.
#include "shared/sub_solver.hpp"

#include "analytic_problems.hpp"
#include "test_support.hpp"

#include <hapsyn/error.hpp>

#include <atomic>
#include <iostream>

namespace {

using hapsyn::Json;
using hapsyn::SubSolver;

// A solver that records what it was handed and refuses problems on request.
class RecordingSolver : public hapsyn::Solver {
 public:
  explicit RecordingSolver(std::string refusal = "") : refusal_(std::move(refusal)) {}
  void check(const hapsyn::Problem&) const override {
    if (!refusal_.empty()) throw hapsyn::Error("recording", refusal_);
  }
  hapsyn::SolverResult solve(const hapsyn::Problem& problem, const hapsyn::SolverContext& context) const override {
    seen_context = context;
    seen_objectives = problem.objectives().size();
    hapsyn::SolverResult r;
    r.status = hapsyn::SolverStatus::kConverged;
    r.message = "recorded";
    return r;
  }
  mutable hapsyn::SolverContext seen_context;
  mutable std::size_t seen_objectives = 0;

 private:
  std::string refusal_;
};

SubSolver created(std::shared_ptr<const hapsyn::Solver> solver) {
  SubSolver s;
  s.plugin = "recording";
  s.options = Json{{"depth", 2}};
  s.json_path = "solver.options.shadow_solver";
  s.solver = std::move(solver);
  return s;
}

}  // namespace

TEST(SubSolver, MissingSolverMarksTheResultFailedWithItsMessage) {
  hapsyn::SolverResult result;
  result.status = hapsyn::SolverStatus::kConverged;
  const hapsyn::Solver* solver = hapsyn::plugins::sub_solver_for_solve(SubSolver{}, "nbi", "shadow solver", result);
  EXPECT_EQ(solver, nullptr);
  EXPECT_EQ(result.status, hapsyn::SolverStatus::kFailed);
  EXPECT_EQ(result.message,
            "nbi has no shadow solver (sub-solvers are created when the study is loaded through the registry)");
}

TEST(SubSolver, CreatedSolverIsHandedOutAndTheResultLeftAlone) {
  const auto recording = std::make_shared<RecordingSolver>();
  hapsyn::SolverResult result;
  result.message = "untouched";
  EXPECT_EQ(hapsyn::plugins::sub_solver_for_solve(created(recording), "nbi", "shadow solver", result),
            recording.get());
  EXPECT_EQ(result.message, "untouched");
}

TEST(SubSolver, RefusalIsRethrownWithTheComponentAndWhere) {
  const auto problem = hapsyn::test::two_objective_problem();
  const SubSolver refusing = created(std::make_shared<RecordingSolver>("design.x0 has no step"));
  EXPECT_EQ(hapsyn::test::error_of([&] {
              hapsyn::plugins::check_sub_solver(refusing, *problem, "nbi",
                                                "solver.options.shadow_solver (objective 'f1')");
            }),
            "nbi: solver.options.shadow_solver (objective 'f1'): recording: design.x0 has no step");
  // An accepting solver and an uncreated one pass silently.
  EXPECT_NO_THROW(hapsyn::plugins::check_sub_solver(created(std::make_shared<RecordingSolver>()), *problem, "nbi", "x"));
  EXPECT_NO_THROW(hapsyn::plugins::check_sub_solver(SubSolver{}, *problem, "nbi", "x"));
}

TEST(SubSolver, JsonIsTheOptionAsTheFileGivesIt) {
  EXPECT_EQ(hapsyn::plugins::sub_solver_json(created(nullptr)),
            (Json{{"plugin", "recording"}, {"options", {{"depth", 2}}}}));
}

TEST(SubSolver, SingleObjectiveProblemKeepsOneObjectiveAtWeightOne) {
  auto objectives = hapsyn::test::two_objective_problem()->objectives();
  objectives[1].weight = 0.3;
  objectives[1].sense = hapsyn::Sense::kMinimize;
  const auto problem = hapsyn::test::two_objective_problem()->with_objectives(objectives);
  const auto single = hapsyn::plugins::single_objective_problem(*problem, 1);
  ASSERT_EQ(single->objectives().size(), 1u);
  EXPECT_EQ(single->objectives()[0].name, "f2");
  EXPECT_EQ(single->objectives()[0].weight, 1.0);
  EXPECT_EQ(single->objectives()[0].sense, hapsyn::Sense::kMinimize);
  EXPECT_EQ(single->objectives()[0].metric, objectives[1].metric);
  EXPECT_EQ(single->design_space().free_size(), problem->design_space().free_size());
}

TEST(SubSolver, ReweightedProblemChangesTheWeightsOnly) {
  const auto problem = hapsyn::test::two_objective_problem();
  const auto reweighted = hapsyn::plugins::reweighted_problem(*problem, {0.25, 0.75});
  ASSERT_EQ(reweighted->objectives().size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(reweighted->objectives()[i].name, problem->objectives()[i].name);
    EXPECT_EQ(reweighted->objectives()[i].sense, problem->objectives()[i].sense);
  }
  EXPECT_EQ(reweighted->objectives()[0].weight, 0.25);
  EXPECT_EQ(reweighted->objectives()[1].weight, 0.75);
  // The score is the new weighted sum of the same objective values.
  const double x[2] = {0.4, 0.2};
  auto ws = reweighted->make_eval_scratch();
  const hapsyn::Evaluation e = reweighted->evaluate(x, *ws);
  EXPECT_EQ(e.score, 0.25 * e.objectives[0] + 0.75 * e.objectives[1]);
}

TEST(SubSolver, FixedComponentProblemFixesOneFreeVariableAtTheValue) {
  const auto problem = hapsyn::test::two_objective_problem();
  const auto fixed = hapsyn::plugins::fixed_component_problem(*problem, 1, 0.25);
  ASSERT_EQ(fixed->design_space().free_size(), 1u);
  const hapsyn::DesignComponent& c = fixed->design_space().components()[1];
  EXPECT_TRUE(c.fixed);
  EXPECT_EQ(c.lower, 0.25);
  EXPECT_EQ(c.upper, 0.25);
  EXPECT_EQ(c.step, 0.0);
  EXPECT_EQ(fixed->design_space().components()[0].lower, problem->design_space().components()[0].lower);
  const double free_x0 = 0.6;
  const Eigen::VectorXd full = fixed->full_design(&free_x0);
  EXPECT_EQ(full[0], 0.6);
  EXPECT_EQ(full[1], 0.25);
}

TEST(SubSolver, RunSubSolverPassesThreadsAndStopButNoProgress) {
  const auto problem = hapsyn::test::two_objective_problem();
  const RecordingSolver recording;
  const std::atomic<bool> stop{false};
  hapsyn::SolverContext parent;
  parent.threads = 3;
  parent.seed = 11;
  parent.stop = &stop;
  parent.progress = &std::cerr;
  const hapsyn::SolverResult r = hapsyn::plugins::run_sub_solver(recording, *problem, parent);
  EXPECT_EQ(r.message, "recorded");
  EXPECT_EQ(recording.seen_context.threads, 3);
  EXPECT_EQ(recording.seen_context.seed, 11u);
  EXPECT_EQ(recording.seen_context.stop, &stop);
  EXPECT_EQ(recording.seen_context.progress, nullptr);
  EXPECT_EQ(recording.seen_objectives, 2u);
}

TEST(SubSolver, EvaluateFullDesignGivesEveryObjectiveOverEverySample) {
  const auto problem = hapsyn::test::two_objective_problem();
  Eigen::VectorXd full(2);
  full << 0.4, 0.2;
  std::vector<double> objectives;
  long long samples = 5;
  ASSERT_TRUE(hapsyn::plugins::evaluate_full_design(*problem, full, 2, objectives, samples));
  ASSERT_EQ(objectives.size(), 2u);
  EXPECT_DOUBLE_EQ(objectives[0], 0.4 - 0.1 * 0.2 * 0.2);
  // f2 = h(x0) - 0.5 (|x1| + 0.3)^2: the worst sample is s = -1.
  EXPECT_DOUBLE_EQ(objectives[1], hapsyn::test::two_objective_h(0.4) - 0.5 * 0.5 * 0.5);
  EXPECT_EQ(samples, 5 + 3);  // added to the count: three samples
}
