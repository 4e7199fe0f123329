// Weighted sums against the closed-form two-objective front: every point lies on the front, but
// none in its convex part (where no weight makes an interior point optimal); bad weights.
#include "weighted_sum.hpp"

#include "shared/replay_cluster.hpp"

#include "analytic_problems.hpp"
#include "test_support.hpp"

#include <hapsyn/checkpoint.hpp>

#include <boost/filesystem.hpp>

#include <unistd.h>

#include <atomic>
#include <fstream>
#include <functional>

using hapsyn::Json;
using hapsyn::test::expect_error;

namespace {
hapsyn::SolverResult solve_weighted(const hapsyn::Problem& problem, Json options) {
  options["sub_solver"] = {{"plugin", "grid"}, {"options", {{"progress_interval", 1e9}}}};
  // The registry creates the sub-solver.
  const auto solver = hapsyn::test::registry().create_solver("weighted_sum", options, "solver");
  solver->check(problem);
  hapsyn::SolverContext context;
  context.threads = 2;
  return solver->solve(problem, context);
}
}  // namespace

TEST(WeightedSum, PointsLieOnTheFrontButMissItsConvexPart) {
  const auto problem = hapsyn::test::two_objective_problem(0.01);
  const auto result = solve_weighted(*problem, {{"count", 21}});
  ASSERT_EQ(result.status, hapsyn::SolverStatus::kConverged) << result.message;
  EXPECT_EQ(result.statistics["runs"].size(), 21u);
  for (const auto& p : result.front) {
    const double f1 = p.objectives[0];
    EXPECT_NEAR(p.objectives[1], hapsyn::test::two_objective_front_f2(f1), 1e-9);
    EXPECT_FALSE(f1 > 0.55 && f1 < 0.95) << "a weighted sum reached the convex part at f1 = " << f1;
  }
  // Clumping: 21 weights, far fewer distinct points.
  EXPECT_LT(result.front.size(), 12u);
}

TEST(WeightedSum, ExplicitWeightsAreUsedInOrder) {
  const auto problem = hapsyn::test::two_objective_problem(0.05);
  const auto result = solve_weighted(*problem, {{"weights", {{1.0, 0.0}, {0.0, 1.0}}}});
  ASSERT_EQ(result.statistics["runs"].size(), 2u);
  EXPECT_NEAR(result.statistics["runs"][0]["objectives"][0].get<double>(), 1.0, 1e-12);
  EXPECT_NEAR(result.statistics["runs"][1]["objectives"][0].get<double>(), 0.0, 1e-12);
}

TEST(WeightedSum, RefusesBadWeightsWithPathValueAndRule) {
  Json doc = hapsyn::test::fivebar_study("weighted_sum");
  doc["objectives"] = Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  doc["solver"]["options"]["weights"] = {{1.0}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); },
               {"weighted_sum: solver.options.weights[0] = [1.0]: must have 2 weights"});
  doc["solver"]["options"]["weights"] = {{1.0, -0.5}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); },
               {"solver.options.weights[0][1] = -0.5: must be finite and >= 0"});
  doc["solver"]["options"]["weights"] = {{0.0, 0.0}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); }, {"the weights must not all be 0"});
  doc["solver"]["options"]["weights"] = Json::array();
  doc["objectives"] = Json::array({{{"metric", "gii"}}});
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); }, {"weighted_sum: objectives: 1 objective(s)"});
}

TEST(WeightedSum, SubSolverErrorsNameTheOption) {
  Json doc = hapsyn::test::fivebar_study("weighted_sum");
  doc["objectives"] = Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  doc["solver"]["options"]["sub_solver"] = {{"plugin", "culling"}, {"options", {{"polsh", false}}}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); },
               {"solver.options.sub_solver.options.polsh: unknown key", "polish"});
}

TEST(WeightedSum, WithoutARegistryFailsWithAStatus) {
  // Options made without a registry: the sub-solver is never created.
  const auto problem = hapsyn::test::two_objective_problem();
  const hapsyn::plugins::WeightedSumSolver solver(hapsyn::default_options<hapsyn::plugins::WeightedSumOptions>());
  const auto result = solver.solve(*problem, hapsyn::SolverContext{});
  EXPECT_EQ(result.status, hapsyn::SolverStatus::kFailed);
  EXPECT_NE(result.message.find("weighted_sum has no sub-solver"), std::string::npos) << result.message;
}

// ---- stop, checkpoint, resume ----

namespace {

// The two-objective problem with its first objective's local calls counted: `stop` is set at
// call `stop_after` (one thread: the same point of the run every time).
struct Counter {
  std::atomic<long long> calls{0};
  long long stop_after = -1;
  std::atomic<bool> stop{false};
};
std::shared_ptr<hapsyn::Problem> counted_problem(Counter& c) {
  return hapsyn::test::analytic_problem(
      {{0.0, 1.0}, {-1.0, 1.0}}, 0.05, {-1.0, 0.0, 1.0},
      {[&c](const double* x, const double*) {
         if (++c.calls == c.stop_after) c.stop = true;
         return x[0] - 0.1 * x[1] * x[1];
       },
       [](const double* x, const double* s) {
         return hapsyn::test::two_objective_h(x[0]) - 0.5 * (x[1] - 0.3 * s[0]) * (x[1] - 0.3 * s[0]);
       }});
}

std::string temp_file(const std::string& name) {
  return (boost::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid()) + ".json")).string();
}

hapsyn::SolverResult run_weighted(const hapsyn::Problem& problem, const std::string& checkpoint, bool resume,
                                  const std::atomic<bool>* stop, hapsyn::Cluster* ranks = nullptr, int threads = 1) {
  const Json options = {{"count", 6}, {"sub_solver", {{"plugin", "grid"}, {"options", {{"progress_interval", 1e9}}}}}};
  const auto solver = hapsyn::test::registry().create_solver("weighted_sum", options, "solver");
  solver->check(problem);
  hapsyn::SolverContext context;
  context.threads = threads;
  context.seed = 5;
  context.checkpoint_file = checkpoint;
  context.resume = resume;
  context.stop = stop;
  context.ranks = ranks;
  return solver->solve(problem, context);
}

Json without_seconds(Json records) {
  for (Json& r : records) r.erase("seconds");
  return records;
}

void edit_checkpoint(const std::string& file, const std::function<void(Json& state)>& edit) {
  std::ifstream in(file);
  Json c = Json::parse(in);
  edit(c["state"]);
  c.erase("checksum");
  c["checksum"] = hapsyn::fnv1a_hex(c.dump());
  std::ofstream(file) << c.dump();
}

}  // namespace

TEST(WeightedSum, StopMidRunGivesTheFrontSoFarAndResumeGivesTheUninterruptedResult) {
  Counter full;
  const auto reference = run_weighted(*counted_problem(full), "", false, nullptr);
  ASSERT_EQ(reference.status, hapsyn::SolverStatus::kConverged) << reference.message;
  for (double fraction : {0.05, 0.5, 0.75}) {
    SCOPED_TRACE(fraction);
    const std::string file = temp_file("hapsyn-weighted-stop");
    boost::filesystem::remove(file);
    Counter c;
    c.stop_after = static_cast<long long>(fraction * static_cast<double>(full.calls));
    const auto stopped = run_weighted(*counted_problem(c), file, false, &c.stop);
    ASSERT_EQ(stopped.status, hapsyn::SolverStatus::kStopped) << stopped.message;
    const std::size_t finished = stopped.statistics["runs"].size();
    EXPECT_LT(finished, 6u);
    EXPECT_NE(stopped.message.find("weighted sums stopped on request after " + std::to_string(finished) + " of 6 weight vectors"),
              std::string::npos)
        << stopped.message;
    EXPECT_NE(stopped.message.find("checkpoint " + file + " written"), std::string::npos) << stopped.message;
    EXPECT_EQ(stopped.front.empty(), finished == 0);
    ASSERT_TRUE(boost::filesystem::exists(file));
    Counter again;
    const auto resumed = run_weighted(*counted_problem(again), file, true, nullptr);
    EXPECT_EQ(resumed.status, reference.status);
    EXPECT_EQ(resumed.message, reference.message);
    ASSERT_EQ(resumed.front.size(), reference.front.size());
    for (std::size_t i = 0; i < resumed.front.size(); ++i) {
      EXPECT_EQ(resumed.front[i].design, reference.front[i].design);
      EXPECT_EQ(resumed.front[i].objectives, reference.front[i].objectives);
    }
    EXPECT_EQ(resumed.design_evaluations, reference.design_evaluations);
    EXPECT_EQ(resumed.sample_evaluations, reference.sample_evaluations);
    EXPECT_EQ(without_seconds(resumed.statistics["runs"]), without_seconds(reference.statistics["runs"]));
    EXPECT_EQ(resumed.statistics["resumed"]["finished"].get<std::size_t>(), finished);
    boost::filesystem::remove(file);
  }
}

TEST(WeightedSum, EditedCheckpointIsRefused) {
  const std::string file = temp_file("hapsyn-weighted-edit");
  boost::filesystem::remove(file);
  Counter c;
  ASSERT_EQ(run_weighted(*counted_problem(c), file, false, nullptr).status, hapsyn::SolverStatus::kConverged);
  std::string original;
  {
    std::ifstream in(file);
    original.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto refused = [&](const std::function<void(Json&)>& edit, std::initializer_list<std::string> fragments) {
    std::ofstream(file) << original;
    edit_checkpoint(file, edit);
    Counter again;
    expect_error([&] { run_weighted(*counted_problem(again), file, true, nullptr); }, fragments);
  };
  refused([](Json& s) { s["finished"][3]["objectives"][1] = s["finished"][3]["objectives"][1].get<double>() * 1.001; },
          {"checkpoint: " + file + ": finished[3]: the design re-evaluates to objectives [", "the checkpoint claims [",
           "; delete it, or run without --resume"});
  refused([](Json& s) { s["finished"][1]["record"]["weights"] = {0.5, 0.5}; },
          {"finished[1].record.weights = [0.5,0.5]: this study's weight vector 1 is [0.8,0.2]"});
  refused([](Json& s) { s["finished"].push_back(s["finished"][0]); },
          {"finished: 7 finished subproblems, this study has 6"});
  // Damage without a recomputed checksum: the framework's check.
  std::ofstream(file) << original.substr(0, original.size() / 2);
  Counter again;
  expect_error([&] { run_weighted(*counted_problem(again), file, true, nullptr); },
               {"checkpoint: " + file + ": not valid JSON (truncated or damaged)"});
  boost::filesystem::remove(file);
}

// ---- on several threads and ranks ----

namespace {
// The same front, counts and records (times aside).
void expect_same_front(const hapsyn::SolverResult& got, const hapsyn::SolverResult& expected) {
  EXPECT_EQ(got.status, expected.status);
  EXPECT_EQ(got.message, expected.message);
  ASSERT_EQ(got.front.size(), expected.front.size());
  for (std::size_t i = 0; i < got.front.size(); ++i) {
    EXPECT_EQ(got.front[i].design, expected.front[i].design) << i;
    EXPECT_EQ(got.front[i].objectives, expected.front[i].objectives) << i;
  }
  EXPECT_EQ(got.design_evaluations, expected.design_evaluations);
  EXPECT_EQ(without_seconds(got.statistics["runs"]), without_seconds(expected.statistics["runs"]));
}
}  // namespace

TEST(WeightedSum, ThreadCountDoesNotChangeTheResult) {
  Counter a, b;
  const auto one = run_weighted(*counted_problem(a), "", false, nullptr, nullptr, 1);
  const auto three = run_weighted(*counted_problem(b), "", false, nullptr, nullptr, 3);
  ASSERT_EQ(one.status, hapsyn::SolverStatus::kConverged) << one.message;
  expect_same_front(three, one);
}

TEST(WeightedSum, EveryRankEndsWithTheSingleProcessResult) {
  Counter reference_calls;
  const auto reference = run_weighted(*counted_problem(reference_calls), "", false, nullptr);
  const auto tape = std::make_shared<hapsyn::plugins::test::ReplayTape>();
  hapsyn::plugins::test::ReplayCluster rank0(0, tape), rank1(1, tape);
  Counter c0, c1;
  const auto r0 = run_weighted(*counted_problem(c0), "", false, nullptr, &rank0);
  const auto r1 = run_weighted(*counted_problem(c1), "", false, nullptr, &rank1);
  EXPECT_EQ(rank0.farms(), 1);  // one farm of six weight vectors
  EXPECT_TRUE(tape->events.empty());  // rank 1 called the same collectives
  expect_same_front(r0, reference);
  expect_same_front(r1, reference);
  // Rank 1 ran only its share of the weight vectors (the odd ones) and still has every record.
  EXPECT_LT(c1.calls.load(), c0.calls.load());
  EXPECT_EQ(r1.statistics["runs"].size(), 6u);
}

TEST(WeightedSum, ResumeFromWeightVectorsFinishedOutOfOrderGivesTheUninterruptedResult) {
  const std::string file = temp_file("hapsyn-weighted-holes");
  boost::filesystem::remove(file);
  Counter c;
  const auto reference = run_weighted(*counted_problem(c), file, false, nullptr);
  ASSERT_EQ(reference.status, hapsyn::SolverStatus::kConverged) << reference.message;
  // Weight vectors 1 and 4 finished, as ranks finish them.
  edit_checkpoint(file, [](Json& s) {
    const Json finished = s["finished"];
    s["finished"] = Json::array({finished[1], finished[4]});
  });
  Counter again;
  const auto resumed = run_weighted(*counted_problem(again), file, true, nullptr);
  expect_same_front(resumed, reference);
  EXPECT_EQ(resumed.statistics["resumed"]["finished"], 2);
  EXPECT_LT(again.calls.load(), c.calls.load());
  boost::filesystem::remove(file);
}

TEST(WeightedSum, StopOnRanksIsTheSameOnEveryRankAndResumeFinishesIt) {
  Counter full;
  const auto reference = run_weighted(*counted_problem(full), "", false, nullptr);
  const std::string file = temp_file("hapsyn-weighted-ranks-stop");
  boost::filesystem::remove(file);
  const auto tape = std::make_shared<hapsyn::plugins::test::ReplayTape>();
  std::atomic<bool> visible{false};
  Counter c0, c1;
  hapsyn::plugins::test::ReplayCluster rank0(0, tape, &c0.stop), rank1(1, tape, &visible);
  c0.stop_after = full.calls / 2;
  const auto r0 = run_weighted(*counted_problem(c0), file, false, &c0.stop, &rank0);
  const auto r1 = run_weighted(*counted_problem(c1), file, false, &visible, &rank1);
  ASSERT_EQ(r0.status, hapsyn::SolverStatus::kStopped) << r0.message;
  EXPECT_EQ(r1.status, hapsyn::SolverStatus::kStopped) << r1.message;
  EXPECT_EQ(r1.statistics["runs"], r0.statistics["runs"]);
  EXPECT_TRUE(tape->events.empty());
  Counter again;
  expect_same_front(run_weighted(*counted_problem(again), file, true, nullptr), reference);
  boost::filesystem::remove(file);
}
