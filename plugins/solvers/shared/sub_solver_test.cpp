// The sub-solver helpers of nbi, weighted_sum and sequential: a missing sub-solver is a failed
// status, a refusal is rethrown under the parent's name and option path, and the derived
// problems change only what their names say.
#include "shared/sub_solver.hpp"

#include "shared/replay_cluster.hpp"

#include "analytic_problems.hpp"
#include "test_support.hpp"

#include <hapsyn/cluster.hpp>
#include <hapsyn/checkpoint.hpp>
#include <hapsyn/error.hpp>

#include <boost/filesystem.hpp>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>

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

TEST(SubSolver, RunSubSolverPassesThreadsStopAndProgress) {
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
  EXPECT_EQ(recording.seen_context.progress, &std::cerr);
  EXPECT_EQ(recording.seen_objectives, 2u);
}

TEST(SubSolver, RunSubSolverNamesTheSubproblemBeforeAndAfter) {
  const auto problem = hapsyn::test::two_objective_problem();
  const RecordingSolver recording;
  std::ostringstream progress, log;
  hapsyn::SolverContext parent;
  parent.progress = &progress;
  parent.log = &log;
  hapsyn::plugins::run_sub_solver(recording, *problem, parent, "nbi: shadow optimum 1 of 2 (f0)");
  EXPECT_EQ(progress.str().rfind("nbi: shadow optimum 1 of 2 (f0) ...\nnbi: shadow optimum 1 of 2 (f0): ", 0), 0u)
      << progress.str();
  EXPECT_NE(progress.str().find(" s\n"), std::string::npos) << progress.str();
  EXPECT_EQ(log.str(), progress.str());
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

// ---- the checkpoints of solvers that run subproblems ----

namespace {

std::string temp_file(const std::string& name) {
  return (boost::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid()) + ".json")).string();
}

// A finished subproblem with the design (0.4, 0.2) of `problem`, evaluated.
hapsyn::plugins::FinishedSubproblem finished_at(const hapsyn::Problem& problem, double x0, double x1) {
  hapsyn::plugins::FinishedSubproblem f;
  Eigen::VectorXd design(2);
  design << x0, x1;
  std::vector<double> values;
  long long samples = 0;
  EXPECT_TRUE(hapsyn::plugins::evaluate_full_design(problem, design, 1, values, samples));
  f.point = hapsyn::SolutionPoint{design, values, problem.score(values)};
  f.record = {{"k", 1}};
  f.design_evaluations = 7;
  f.sample_evaluations = 9;
  return f;
}

hapsyn::SolverContext checkpoint_context(const std::string& file) {
  hapsyn::SolverContext context;
  context.checkpoint_file = file;
  context.resume = true;
  context.seed = 2;
  return context;
}

// The two-objective problem whose every sample is unreachable for x0 > 0.5.
class HalfReachable : public hapsyn::Mechanism {
 public:
  class Model : public hapsyn::MechanismModel {
   public:
    explicit Model(const double* design) : x0_(design[0]), x1_(design[1]) {}
    void solve(const double*, hapsyn::Needs, hapsyn::MechanismScratch&, hapsyn::SampleQuantities& out) const override {
      out.status = x0_ > 0.5 ? hapsyn::SampleStatus::kUnreachable : hapsyn::SampleStatus::kReachable;
      out.q.resize(2);
      out.q << x0_, x1_;
    }

   private:
    double x0_, x1_;
  };
  std::unique_ptr<const hapsyn::MechanismModel> build(const double* design) const override {
    return std::make_unique<Model>(design);
  }
  hapsyn::MechanismSpecs specs() const override { return {hapsyn::kNeedJacobian, {}}; }
};

std::shared_ptr<hapsyn::Problem> half_reachable_problem() {
  const auto base = hapsyn::test::two_objective_problem();
  auto samples = std::make_shared<hapsyn::SampleSet>(base->samples());
  std::vector<hapsyn::MetricEntry> metrics = base->metrics();
  return std::make_shared<hapsyn::Problem>("half", std::make_shared<HalfReachable>(), samples, metrics,
                                           base->objectives(), base->design_space());
}

}  // namespace

TEST(SubSolver, RunSubSolverHandsTheSubSolverNoCheckpoint) {
  const auto problem = hapsyn::test::two_objective_problem();
  const RecordingSolver recording;
  hapsyn::SolverContext parent;
  parent.checkpoint_file = "parent-checkpoint.json";
  parent.resume = true;
  hapsyn::plugins::run_sub_solver(recording, *problem, parent);
  EXPECT_EQ(recording.seen_context.checkpoint_file, "");
  EXPECT_FALSE(recording.seen_context.resume);
}

TEST(SubSolver, FinishedSubproblemsRoundTripThroughTheCheckpointWithTheirPointsRechecked) {
  const auto problem = hapsyn::test::two_objective_problem();
  const std::string file = temp_file("hapsyn-subproblem-roundtrip");
  // Tasks 1 and 3 of 4 finished (out of order, as on several ranks); task 3 infeasible.
  hapsyn::plugins::SubproblemSlots finished(4);
  finished[1] = finished_at(*problem, 0.4, 0.2);
  finished[3] = hapsyn::plugins::FinishedSubproblem{};
  finished[3]->record = {{"k", 2}};  // an infeasible one: no point
  finished[3]->design_evaluations = 3;
  const hapsyn::SolverContext context = checkpoint_context(file);
  hapsyn::plugins::write_subproblem_checkpoint(context, "test", "fp", {{"finished", &finished}}, 12.5);
  {
    std::ifstream in(file);
    const Json entries = Json::parse(in)["state"]["finished"];
    ASSERT_EQ(entries.size(), 2u);
    EXPECT_EQ(entries[0]["task"], 1);
    EXPECT_EQ(entries[1]["task"], 3);
  }
  const auto read = hapsyn::plugins::read_subproblem_checkpoint(*problem, context, "test", "fp", {{"finished", 4}});
  ASSERT_TRUE(read);
  EXPECT_EQ(read->seconds, 12.5);
  EXPECT_EQ(read->recheck_samples, 3);  // one design over three samples
  const auto& list = read->lists.at("finished");
  ASSERT_EQ(list.size(), 4u);
  EXPECT_FALSE(list[0]);
  EXPECT_FALSE(list[2]);
  EXPECT_EQ(hapsyn::plugins::finished_count(list), 2u);
  ASSERT_TRUE(list[1] && list[3]);
  EXPECT_EQ(list[1]->record, finished[1]->record);
  ASSERT_TRUE(list[1]->point);
  EXPECT_EQ(list[1]->point->design, finished[1]->point->design);
  EXPECT_EQ(list[1]->point->objectives, finished[1]->point->objectives);
  EXPECT_EQ(list[1]->design_evaluations, 7);
  EXPECT_EQ(list[1]->sample_evaluations, 9);
  EXPECT_FALSE(list[3]->point);
  EXPECT_EQ(list[3]->design_evaluations, 3);
  // Messages name the entry in the file, not the task.
  EXPECT_EQ(read->where("finished", 3), "finished[1]");
  boost::filesystem::remove(file);
}

TEST(SubSolver, CheckpointEntriesWithoutATaskAreTheFinishedPrefix) {
  // Checkpoints written before tasks could finish out of order.
  const auto problem = hapsyn::test::two_objective_problem();
  const std::string file = temp_file("hapsyn-subproblem-prefix");
  hapsyn::plugins::SubproblemSlots finished = {finished_at(*problem, 0.4, 0.2), finished_at(*problem, 0.3, 0.1), std::nullopt};
  const hapsyn::SolverContext context = checkpoint_context(file);
  hapsyn::plugins::write_subproblem_checkpoint(context, "test", "fp", {{"finished", &finished}}, 1.0);
  {
    std::ifstream in(file);
    Json c = Json::parse(in);
    for (Json& entry : c["state"]["finished"]) entry.erase("task");
    c.erase("checksum");
    c["checksum"] = hapsyn::fnv1a_hex(c.dump());
    std::ofstream(file) << c.dump();
  }
  const auto read = hapsyn::plugins::read_subproblem_checkpoint(*problem, context, "test", "fp", {{"finished", 3}});
  ASSERT_TRUE(read);
  const auto& list = read->lists.at("finished");
  ASSERT_TRUE(list[0] && list[1]);
  EXPECT_FALSE(list[2]);
  EXPECT_EQ(list[1]->point->design, finished[1]->point->design);
  boost::filesystem::remove(file);
}

TEST(SubSolver, WithoutACheckpointTheSolverStartsOverAndSaysSo) {
  const auto problem = hapsyn::test::two_objective_problem();
  const std::string file = temp_file("hapsyn-subproblem-absent");
  boost::filesystem::remove(file);
  hapsyn::SolverContext context = checkpoint_context(file);
  std::ostringstream log;
  context.log = &log;
  EXPECT_FALSE(hapsyn::plugins::read_subproblem_checkpoint(*problem, context, "test", "fp", {{"finished", 2}}));
  EXPECT_EQ(log.str(), "test: no checkpoint to resume from; starting from the beginning\n");
  EXPECT_EQ(hapsyn::plugins::checkpoint_note(context),
            "; checkpoint " + file + " written: `hapsyn run --resume` continues from there");
  EXPECT_EQ(hapsyn::plugins::checkpoint_note(hapsyn::SolverContext{}), "; no checkpoint (no checkpoint file in this context)");
}

TEST(SubSolver, CheckpointEntriesOfTheWrongShapeOrWithEditedValuesAreRefused) {
  const auto problem = hapsyn::test::two_objective_problem();
  const std::string file = temp_file("hapsyn-subproblem-refused");
  const hapsyn::SolverContext context = checkpoint_context(file);
  const hapsyn::plugins::SubproblemSlots finished = {finished_at(*problem, 0.4, 0.2)};
  const auto refused = [&](const hapsyn::Problem& p, const std::function<void(Json&)>& edit,
                           std::initializer_list<std::string> fragments) {
    hapsyn::plugins::write_subproblem_checkpoint(context, "test", "fp", {{"finished", &finished}}, 1.0);
    std::ifstream in(file);
    Json c = Json::parse(in);
    edit(c["state"]);
    c.erase("checksum");
    c["checksum"] = hapsyn::fnv1a_hex(c.dump());
    std::ofstream(file) << c.dump();
    hapsyn::test::expect_error([&] { hapsyn::plugins::read_subproblem_checkpoint(p, context, "test", "fp", {{"finished", 1}}); },
                               fragments);
  };
  const std::string prefix = "checkpoint: " + file + ": ";
  refused(*problem, [](Json& s) { s.erase("seconds"); }, {prefix + "seconds: missing or not a number >= 0; delete it"});
  refused(*problem, [](Json& s) { s["other"] = s["finished"]; s.erase("finished"); }, {prefix + "no \"finished\" array"});
  refused(*problem, [](Json& s) { s["finished"].push_back(s["finished"][0]); },
          {prefix + "finished: 2 finished subproblems, this study has 1"});
  refused(*problem, [](Json& s) { s["finished"][0] = 3; }, {prefix + "finished[0]: not an object"});
  refused(*problem, [](Json& s) { s["finished"][0]["task"] = 1; },
          {prefix + "finished[0].task = 1: must be an integer in 0..0 (a subproblem of this study)"});
  refused(*problem, [](Json& s) { s["finished"][0]["task"] = -1; },
          {prefix + "finished[0].task = -1: must be an integer in 0..0"});
  refused(*problem, [](Json& s) { s["finished"][0].erase("record"); }, {prefix + "finished[0].record: missing or not an object"});
  refused(*problem, [](Json& s) { s["finished"][0]["sample_evaluations"] = 1.5; },
          {prefix + "finished[0].sample_evaluations: missing or not a count (an integer >= 0)"});
  refused(*problem, [](Json& s) { s["finished"][0]["design"] = {0.4}; },
          {prefix + "finished[0].design = [0.4]: must be 2 numbers (the full design)"});
  refused(*problem, [](Json& s) { s["finished"][0]["objectives"] = {0.4, "x"}; },
          {prefix + "finished[0].objectives = [0.4,\"x\"]: must be 2 numbers (one per objective)"});
  refused(*problem, [](Json& s) { s["finished"][0]["design"][0] = 2.0; },
          {prefix + "finished[0].design = [2.0,0.2]: cannot be evaluated (", "x0"});
  refused(*problem, [](Json& s) { s["finished"][0]["objectives"][0] = 0.5; },
          {prefix + "finished[0]: the design re-evaluates to objectives [0.39", "the checkpoint claims [0.5,"});
  // A fixed component that differs from the study's value.
  const auto fixed = hapsyn::plugins::fixed_component_problem(*problem, 1, 0.25);
  refused(*fixed, [](Json&) {}, {prefix + "finished[0].design[1] = 0.2: x1 is fixed at 0.25 in this study"});
  // A design that is not feasible in this study.
  const auto half = half_reachable_problem();
  refused(*half, [](Json& s) { s["finished"][0]["design"][0] = 0.75; },
          {prefix + "finished[0]: the design is not feasible, the checkpoint claims objectives ["});
  boost::filesystem::remove(file);
}

TEST(SubSolver, CheckpointTasksOutOfOrderOrRepeatedAreRefused) {
  const auto problem = hapsyn::test::two_objective_problem();
  const std::string file = temp_file("hapsyn-subproblem-order");
  const hapsyn::SolverContext context = checkpoint_context(file);
  hapsyn::plugins::SubproblemSlots finished = {finished_at(*problem, 0.4, 0.2), finished_at(*problem, 0.3, 0.1)};
  for (const int second : {0, -1}) {
    hapsyn::plugins::write_subproblem_checkpoint(context, "test", "fp", {{"finished", &finished}}, 1.0);
    std::ifstream in(file);
    Json c = Json::parse(in);
    in.close();
    if (second >= 0) {
      c["state"]["finished"][1]["task"] = second;  // task 0 twice
    } else {
      std::swap(c["state"]["finished"][0], c["state"]["finished"][1]);  // 1, then 0
    }
    c.erase("checksum");
    c["checksum"] = hapsyn::fnv1a_hex(c.dump());
    std::ofstream(file) << c.dump();
    hapsyn::test::expect_error(
        [&] { hapsyn::plugins::read_subproblem_checkpoint(*problem, context, "test", "fp", {{"finished", 2}}); },
        {"checkpoint: " + file + ": finished[1].task = 0: the entries must be in increasing task order, each task once "
                                 "(the entry before is task " + std::string(second >= 0 ? "0" : "1") + ")"});
  }
  boost::filesystem::remove(file);
}

// ---- subproblems as a task farm ----

namespace {

// A farm whose task i finds the design (0.1 i, 0.05) of the two-objective problem; task `stop_at`
// returns nullopt (a stop), and every task notes which thread ran it.
hapsyn::plugins::SubproblemFarm design_farm(const hapsyn::Problem& problem, long long stop_at = -1) {
  hapsyn::plugins::SubproblemFarm farm;
  farm.run = [&problem, stop_at](std::size_t i) -> std::optional<hapsyn::plugins::FinishedSubproblem> {
    if (static_cast<long long>(i) == stop_at) return std::nullopt;
    hapsyn::plugins::FinishedSubproblem f = finished_at(problem, 0.1 * static_cast<double>(i), 0.05);
    f.record = {{"task", i}, {"status", "converged"}, {"seconds", 0.25}};
    return f;
  };
  farm.what = [](std::size_t i) { return "test: task " + std::to_string(i); };
  return farm;
}

}  // namespace

TEST(SubSolver, FarmFillsTheUnfinishedSlotsAndSkipsTheFinishedOnes) {
  const auto problem = hapsyn::test::two_objective_problem();
  for (int threads : {1, 3}) {
    hapsyn::plugins::SubproblemSlots slots(5);
    slots[2] = hapsyn::plugins::FinishedSubproblem{};
    slots[2]->record = {{"from", "checkpoint"}};
    hapsyn::plugins::SubproblemFarm farm = design_farm(*problem);
    farm.threads = threads;
    std::vector<std::size_t> collected;
    farm.collected = [&](std::size_t i) { collected.push_back(i); };
    std::ostringstream progress;
    hapsyn::SolverContext context;
    context.progress = &progress;
    const hapsyn::FarmOutcome outcome = hapsyn::plugins::run_subproblem_farm(*problem, context, slots, farm);
    EXPECT_FALSE(outcome.stopped);
    std::sort(collected.begin(), collected.end());
    EXPECT_EQ(collected, (std::vector<std::size_t>{0, 1, 3, 4}));
    EXPECT_EQ(slots[2]->record, (Json{{"from", "checkpoint"}}));
    ASSERT_TRUE(slots[4] && slots[4]->point);
    EXPECT_EQ(slots[4]->point->design[0], 0.4);
    EXPECT_EQ(slots[4]->point->score, problem->score(slots[4]->point->objectives));
    // One process: the sub-solvers name themselves; the farm adds no line.
    EXPECT_EQ(progress.str(), "");
  }
}

TEST(SubSolver, FarmOnRanksGivesEveryRankRankZerosSlots) {
  const auto problem = hapsyn::test::two_objective_problem();
  const auto tape = std::make_shared<hapsyn::plugins::test::ReplayTape>();
  hapsyn::plugins::SubproblemSlots rank0(6), rank1(6);
  rank0[1] = rank1[1] = finished_at(*problem, 0.9, 0.0);  // from a checkpoint, on both
  std::ostringstream progress0;
  std::vector<std::size_t> collected0, collected1;
  {
    hapsyn::plugins::test::ReplayCluster cluster(0, tape);
    hapsyn::SolverContext context;
    context.ranks = &cluster;
    context.progress = &progress0;
    hapsyn::plugins::SubproblemFarm farm = design_farm(*problem);
    farm.collected = [&](std::size_t i) { collected0.push_back(i); };
    EXPECT_FALSE(hapsyn::plugins::run_subproblem_farm(*problem, context, rank0, farm).stopped);
  }
  {
    hapsyn::plugins::test::ReplayCluster cluster(1, tape);
    hapsyn::SolverContext context;
    context.ranks = &cluster;
    hapsyn::plugins::SubproblemFarm farm = design_farm(*problem);
    farm.collected = [&](std::size_t i) { collected1.push_back(i); };
    EXPECT_FALSE(hapsyn::plugins::run_subproblem_farm(*problem, context, rank1, farm).stopped);
  }
  EXPECT_TRUE(tape->events.empty());
  EXPECT_EQ(collected0.size(), 5u);
  EXPECT_TRUE(collected1.empty());  // rank 1 collects nothing ...
  for (std::size_t i = 0; i < 6; ++i) {  // ... and has rank 0's slots, bit for bit
    ASSERT_TRUE(rank0[i] && rank1[i]) << i;
    EXPECT_EQ(rank1[i]->record, rank0[i]->record);
    EXPECT_EQ(rank1[i]->point->design, rank0[i]->point->design);
    EXPECT_EQ(rank1[i]->point->objectives, rank0[i]->point->objectives);
    EXPECT_EQ(rank1[i]->point->score, rank0[i]->point->score);
    EXPECT_EQ(rank1[i]->sample_evaluations, rank0[i]->sample_evaluations);
  }
  // Under MPI rank 0 names what it collects (the sub-solvers ran without progress).
  EXPECT_NE(progress0.str().find("test: task 3: converged in 0.25 s\n"), std::string::npos) << progress0.str();
}

TEST(SubSolver, StoppedFarmLeavesTheUnfinishedSlotsEmptyOnEveryRank) {
  const auto problem = hapsyn::test::two_objective_problem();
  const auto tape = std::make_shared<hapsyn::plugins::test::ReplayTape>();
  hapsyn::plugins::SubproblemSlots rank0(4), rank1(4);
  std::atomic<bool> visible{false};
  {
    hapsyn::plugins::test::ReplayCluster cluster(0, tape);
    hapsyn::SolverContext context;
    context.ranks = &cluster;
    EXPECT_TRUE(hapsyn::plugins::run_subproblem_farm(*problem, context, rank0, design_farm(*problem, 2)).stopped);
  }
  {
    hapsyn::plugins::test::ReplayCluster cluster(1, tape, &visible);
    hapsyn::SolverContext context;
    context.ranks = &cluster;
    EXPECT_TRUE(hapsyn::plugins::run_subproblem_farm(*problem, context, rank1, design_farm(*problem)).stopped);
  }
  EXPECT_TRUE(visible.load());  // the agreed stop reaches rank 1's flag
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(rank1[i].has_value(), rank0[i].has_value()) << i;
  EXPECT_TRUE(rank0[0] && rank0[1]);
  EXPECT_FALSE(rank0[2]);
}

TEST(SubSolver, TaskContextKeepsProgressInOneProcessOnly) {
  std::ostringstream progress, log;
  std::atomic<bool> stop{false};
  hapsyn::SolverContext context;
  context.threads = 3;
  context.progress = &progress;
  context.log = &log;
  context.stop = &stop;
  context.checkpoint_file = "parent.json";
  context.resume = true;
  hapsyn::SolverContext one = hapsyn::plugins::task_context(context);
  EXPECT_EQ(one.progress, &progress);
  EXPECT_EQ(one.log, &log);
  EXPECT_EQ(one.threads, 3);
  EXPECT_EQ(one.stop, &stop);
  EXPECT_EQ(one.checkpoint_file, "");
  EXPECT_FALSE(one.resume);
  const auto tape = std::make_shared<hapsyn::plugins::test::ReplayTape>();
  hapsyn::plugins::test::ReplayCluster cluster(0, tape);
  context.ranks = &cluster;
  hapsyn::SolverContext ranked = hapsyn::plugins::task_context(context);
  EXPECT_EQ(ranked.progress, nullptr);
  EXPECT_EQ(ranked.log, nullptr);
  EXPECT_EQ(ranked.ranks, nullptr);  // the sub-solver runs on this process alone
  EXPECT_EQ(&ranked.cluster(), &hapsyn::Cluster::local());
  EXPECT_EQ(ranked.threads, 3);
}

TEST(SubSolver, CheckpointIsWrittenByRankZeroOnly) {
  const auto problem = hapsyn::test::two_objective_problem();
  const std::string file = temp_file("hapsyn-subproblem-rank1");
  boost::filesystem::remove(file);
  const auto tape = std::make_shared<hapsyn::plugins::test::ReplayTape>();
  hapsyn::plugins::test::ReplayCluster cluster(1, tape);
  hapsyn::SolverContext context = checkpoint_context(file);
  context.ranks = &cluster;
  const hapsyn::plugins::SubproblemSlots finished = {finished_at(*problem, 0.4, 0.2)};
  hapsyn::plugins::write_subproblem_checkpoint(context, "test", "fp", {{"finished", &finished}}, 1.0);
  EXPECT_FALSE(boost::filesystem::exists(file));
  context.ranks = nullptr;
  hapsyn::plugins::write_subproblem_checkpoint(context, "test", "fp", {{"finished", &finished}}, 1.0);
  EXPECT_TRUE(boost::filesystem::exists(file));
  boost::filesystem::remove(file);
}
