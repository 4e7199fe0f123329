// Sequential optimization against its definition on a small five-bar grid (brute force per
// value), and its error paths.
#include "sequential.hpp"

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
Json sequential_doc() {
  Json doc = hapsyn::test::fivebar_study("sequential");
  doc["objectives"] = Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  doc["solver"]["options"] = {{"sub_solver", {{"plugin", "grid"}}}};
  return doc;
}
}  // namespace

TEST(Sequential, PicksTheBestSecondObjectiveAmongTheFirstObjectiveOptimaPerValue) {
  const hapsyn::Study study = hapsyn::load_study(sequential_doc(), hapsyn::test::registry());
  hapsyn::SolverContext context;
  context.threads = 2;
  const auto result = study.solver->solve(*study.problem, context);
  ASSERT_EQ(result.status, hapsyn::SolverStatus::kConverged) << result.message;
  ASSERT_TRUE(result.best);
  // Brute force: per r, the best GII design (first in grid order), then the best GDI among them.
  const auto& problem = *study.problem;
  const auto counts = problem.design_space().grid_counts();  // l0, l1, l2, r (r fastest)
  long long total = 1;
  for (long long c : counts) total *= c;
  std::vector<double> best_gii(static_cast<std::size_t>(counts[3]), -1.0), gdi_of(static_cast<std::size_t>(counts[3]), -1.0);
  auto ws = problem.make_eval_scratch();
  std::vector<double> x(4);
  for (long long i = 0; i < total; ++i) {
    problem.design_space().grid_point(i, counts, x.data());
    const auto& e = problem.evaluate(x.data(), *ws);
    if (e.status != hapsyn::EvalStatus::kFeasible) continue;
    const std::size_t ri = static_cast<std::size_t>(i % counts[3]);
    if (e.objectives[0] > best_gii[ri]) {
      best_gii[ri] = e.objectives[0];
      gdi_of[ri] = e.objectives[1];
    }
  }
  double expected_gdi = -1.0;
  for (double g : gdi_of) expected_gdi = std::max(expected_gdi, g);
  EXPECT_DOUBLE_EQ(result.best->objectives[1], expected_gdi);
  EXPECT_EQ(result.statistics["per_value"].size(), static_cast<std::size_t>(counts[3]));
}

TEST(Sequential, RefusesWrongObjectivesAndVariables) {
  Json doc = sequential_doc();
  doc["objectives"] = Json::array({{{"metric", "gii"}}});
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); },
               {"sequential: objectives: 1 objective(s); sequential optimization takes exactly 2"});
  doc = sequential_doc();
  doc["solver"]["options"]["variable"] = "q";
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); },
               {"solver.options.variable = \"q\": not a free design variable (free: l0, l1, l2, r)"});
  doc = sequential_doc();
  doc["design"]["r"].erase("step");
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); }, {"sequential: design.r has no step"});
}

TEST(Sequential, WithoutARegistryFailsWithAStatus) {
  // Options made without a registry: the sub-solver is never created.
  const auto problem = hapsyn::test::two_objective_problem();
  const hapsyn::plugins::SequentialSolver solver(
      hapsyn::make_options<hapsyn::plugins::SequentialOptions>(Json{{"variable", "x1"}}));
  const auto result = solver.solve(*problem, hapsyn::SolverContext{});
  EXPECT_EQ(result.status, hapsyn::SolverStatus::kFailed);
  EXPECT_NE(result.message.find("sequential has no sub-solver"), std::string::npos) << result.message;
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

hapsyn::SolverResult run_sequential(const hapsyn::Problem& problem, const std::string& checkpoint, bool resume,
                                    const std::atomic<bool>* stop, hapsyn::Cluster* ranks = nullptr, int threads = 1) {
  const Json options = {{"variable", "x0"}, {"sub_solver", {{"plugin", "grid"}, {"options", {{"progress_interval", 1e9}}}}}};
  const auto solver = hapsyn::test::registry().create_solver("sequential", options, "solver");
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

TEST(Sequential, StopMidRunGivesTheBestSoFarAndResumeGivesTheUninterruptedResult) {
  Counter full;
  const auto reference = run_sequential(*counted_problem(full), "", false, nullptr);
  ASSERT_EQ(reference.status, hapsyn::SolverStatus::kConverged) << reference.message;
  ASSERT_TRUE(reference.best);
  for (double fraction : {0.01, 0.3, 0.9}) {
    SCOPED_TRACE(fraction);
    const std::string file = temp_file("hapsyn-sequential-stop");
    boost::filesystem::remove(file);
    Counter c;
    c.stop_after = static_cast<long long>(fraction * static_cast<double>(full.calls));
    const auto stopped = run_sequential(*counted_problem(c), file, false, &c.stop);
    ASSERT_EQ(stopped.status, hapsyn::SolverStatus::kStopped) << stopped.message;
    const std::size_t finished = stopped.statistics["per_value"].size();
    EXPECT_LT(finished, 21u);
    EXPECT_NE(stopped.message.find("sequential stopped on request after " + std::to_string(finished) + " of 21 values of x0"),
              std::string::npos)
        << stopped.message;
    EXPECT_NE(stopped.message.find("checkpoint " + file + " written"), std::string::npos) << stopped.message;
    EXPECT_EQ(stopped.best.has_value(), finished > 0);
    ASSERT_TRUE(boost::filesystem::exists(file));
    Counter again;
    const auto resumed = run_sequential(*counted_problem(again), file, true, nullptr);
    EXPECT_EQ(resumed.status, reference.status);
    EXPECT_EQ(resumed.message, reference.message);
    ASSERT_TRUE(resumed.best);
    EXPECT_EQ(resumed.best->design, reference.best->design);
    EXPECT_EQ(resumed.best->objectives, reference.best->objectives);
    EXPECT_EQ(resumed.design_evaluations, reference.design_evaluations);
    EXPECT_EQ(resumed.sample_evaluations, reference.sample_evaluations);
    EXPECT_EQ(without_seconds(resumed.statistics["per_value"]), without_seconds(reference.statistics["per_value"]));
    EXPECT_EQ(resumed.statistics["resumed"]["finished"].get<std::size_t>(), finished);
    boost::filesystem::remove(file);
  }
}

TEST(Sequential, EditedCheckpointIsRefused) {
  const std::string file = temp_file("hapsyn-sequential-edit");
  boost::filesystem::remove(file);
  Counter c;
  ASSERT_EQ(run_sequential(*counted_problem(c), file, false, nullptr).status, hapsyn::SolverStatus::kConverged);
  std::string original;
  {
    std::ifstream in(file);
    original.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto refused = [&](const std::function<void(Json&)>& edit, std::initializer_list<std::string> fragments) {
    std::ofstream(file) << original;
    edit_checkpoint(file, edit);
    Counter again;
    expect_error([&] { run_sequential(*counted_problem(again), file, true, nullptr); }, fragments);
  };
  // A better second objective claimed for one value would change the choice: refused.
  refused([](Json& s) { s["finished"][4]["objectives"][1] = 10.0; },
          {"checkpoint: " + file + ": finished[4]: the design re-evaluates to objectives [",
           "the checkpoint claims [", "; delete it, or run without --resume"});
  refused([](Json& s) { s["finished"][2]["record"]["value"] = 0.25; },
          {"finished[2].record.value = 0.25: this study's value 2 of x0 is 0.1"});
  refused([](Json& s) { s["finished"][0]["design_evaluations"] = -1; },
          {"finished[0].design_evaluations: missing or not a count (an integer >= 0)"});
  boost::filesystem::remove(file);
}

// ---- on several threads and ranks ----

namespace {
// The same design, counts and per-value records (times aside).
void expect_same_choice(const hapsyn::SolverResult& got, const hapsyn::SolverResult& expected) {
  EXPECT_EQ(got.status, expected.status);
  EXPECT_EQ(got.message, expected.message);
  ASSERT_EQ(got.best.has_value(), expected.best.has_value());
  if (got.best) {
    EXPECT_EQ(got.best->design, expected.best->design);
    EXPECT_EQ(got.best->objectives, expected.best->objectives);
  }
  EXPECT_EQ(got.design_evaluations, expected.design_evaluations);
  EXPECT_EQ(without_seconds(got.statistics["per_value"]), without_seconds(expected.statistics["per_value"]));
}
}  // namespace

TEST(Sequential, ThreadCountDoesNotChangeTheResult) {
  Counter a, b;
  const auto one = run_sequential(*counted_problem(a), "", false, nullptr, nullptr, 1);
  const auto three = run_sequential(*counted_problem(b), "", false, nullptr, nullptr, 3);
  ASSERT_EQ(one.status, hapsyn::SolverStatus::kConverged) << one.message;
  expect_same_choice(three, one);
}

TEST(Sequential, EveryRankEndsWithTheSingleProcessResult) {
  Counter reference_calls;
  const auto reference = run_sequential(*counted_problem(reference_calls), "", false, nullptr);
  const auto tape = std::make_shared<hapsyn::plugins::test::ReplayTape>();
  hapsyn::plugins::test::ReplayCluster rank0(0, tape), rank1(1, tape);
  Counter c0, c1;
  const auto r0 = run_sequential(*counted_problem(c0), "", false, nullptr, &rank0);
  const auto r1 = run_sequential(*counted_problem(c1), "", false, nullptr, &rank1);
  EXPECT_EQ(rank0.farms(), 1);  // one farm of 21 values
  EXPECT_TRUE(tape->events.empty());
  expect_same_choice(r0, reference);
  expect_same_choice(r1, reference);
  EXPECT_LT(c1.calls.load(), c0.calls.load());  // rank 1 ran its share only
}

TEST(Sequential, ResumeFromValuesFinishedOutOfOrderGivesTheUninterruptedResult) {
  const std::string file = temp_file("hapsyn-sequential-holes");
  boost::filesystem::remove(file);
  Counter c;
  const auto reference = run_sequential(*counted_problem(c), file, false, nullptr);
  ASSERT_EQ(reference.status, hapsyn::SolverStatus::kConverged) << reference.message;
  edit_checkpoint(file, [](Json& s) {
    const Json finished = s["finished"];
    s["finished"] = Json::array({finished[3], finished[7], finished[20]});
  });
  Counter again;
  const auto resumed = run_sequential(*counted_problem(again), file, true, nullptr);
  expect_same_choice(resumed, reference);
  EXPECT_EQ(resumed.statistics["resumed"]["finished"], 3);
  // The study's value 7 is named when an entry's value is edited (the entry's place: 1).
  edit_checkpoint(file, [](Json& s) {
    const Json finished = s["finished"];
    s["finished"] = Json::array({finished[3], finished[7]});
    s["finished"][1]["record"]["value"] = 0.5;
  });
  Counter edited;
  expect_error([&] { run_sequential(*counted_problem(edited), file, true, nullptr); },
               {"finished[1].record.value = 0.5: this study's value 7 of x0 is 0.35"});
  boost::filesystem::remove(file);
}

TEST(Sequential, StopOnRanksIsTheSameOnEveryRankAndResumeFinishesIt) {
  Counter full;
  const auto reference = run_sequential(*counted_problem(full), "", false, nullptr);
  const std::string file = temp_file("hapsyn-sequential-ranks-stop");
  boost::filesystem::remove(file);
  const auto tape = std::make_shared<hapsyn::plugins::test::ReplayTape>();
  std::atomic<bool> visible{false};
  Counter c0, c1;
  hapsyn::plugins::test::ReplayCluster rank0(0, tape, &c0.stop), rank1(1, tape, &visible);
  c0.stop_after = full.calls / 2;
  const auto r0 = run_sequential(*counted_problem(c0), file, false, &c0.stop, &rank0);
  const auto r1 = run_sequential(*counted_problem(c1), file, false, &visible, &rank1);
  ASSERT_EQ(r0.status, hapsyn::SolverStatus::kStopped) << r0.message;
  EXPECT_EQ(r1.status, hapsyn::SolverStatus::kStopped) << r1.message;
  EXPECT_EQ(r1.statistics["per_value"], r0.statistics["per_value"]);
  EXPECT_TRUE(tape->events.empty());
  Counter again;
  expect_same_choice(run_sequential(*counted_problem(again), file, true, nullptr), reference);
  boost::filesystem::remove(file);
}
