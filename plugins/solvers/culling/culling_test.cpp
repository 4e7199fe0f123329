// Culling must return exactly what the exhaustive grid search returns.
#include "culling.hpp"

#include "shared/testing/forwarding_mechanism.hpp"
#include "shared/testing/rank_test_support.hpp"
#include "shared/testing/stop_test_support.hpp"
#include "test_support.hpp"

#include <filesystem>

#include <random>

using hapsyn::Json;
using hapsyn::test::expect_error;

namespace {
// The grid plugin with these options (the rest default), created through the registry: the
// oracle is the shipped grid solver, and culling's code does not link grid's.
std::shared_ptr<hapsyn::Solver> grid_solver(const Json& options) {
  return hapsyn::test::registry().create_solver("grid", options, "solver");
}

hapsyn::SolverResult solve(const hapsyn::Solver& solver, const hapsyn::Problem& problem, int threads) {
  hapsyn::SolverContext context;
  context.threads = threads;
  return solver.solve(problem, context);
}

Json culling_options(bool seed, bool polish) {
  return Json{{"seed", seed}, {"polish", polish}, {"start_points", 3}, {"sqp_xtol", 1e-7}, {"sqp_ftol", 1e-10},
              {"sqp_max_evaluations", 60}, {"progress_interval", 1e9}};
}

// GII, GDI and a weighted sum of both.
std::vector<Json> worst_case_objective_sets() {
  return {Json::array({{{"metric", "gii"}}}), Json::array({{{"metric", "gdi"}}}),
          Json::array({{{"metric", "gii"}, {"weight", 0.6}}, {{"metric", "gdi"}, {"weight", 0.4}}})};
}

}  // namespace

TEST(Culling, ReturnsTheExhaustiveOptimumOnRandomSubBoxes) {
  std::mt19937 rng(2024);
  const std::vector<Json> objective_sets = worst_case_objective_sets();
  int compared = 0;
  for (int box = 0; box < 12; ++box) {
    Json doc = hapsyn::test::fivebar_random_box(rng, box < 6 ? 0.02 : 0.01, 4, 9);
    doc["scene"]["options"]["step"] = 0.02;
    for (const Json& objectives : objective_sets) {
      doc["objectives"] = objectives;
      const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
      const auto grid = grid_solver(Json{{"prune", false}, {"progress_interval", 1e9}});
      const auto exhaustive = solve(*grid, *study.problem, 2);
      for (bool seed : {false, true}) {
        for (int threads : {1, 2}) {
          const hapsyn::plugins::CullingSolver culling(hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(seed, false)));
          const auto culled = solve(culling, *study.problem, threads);
          ASSERT_EQ(culled.status, exhaustive.status) << culled.message << "\n" << doc.dump();
          if (!exhaustive.best) continue;
          EXPECT_EQ(culled.best->design, exhaustive.best->design) << doc.dump();
          EXPECT_EQ(culled.best->score, exhaustive.best->score) << doc.dump();
          EXPECT_EQ(culled.best->objectives, exhaustive.best->objectives);
          EXPECT_LE(culled.statistics["full_workspace_searches"].get<long long>(),
                    exhaustive.statistics["feasible"].get<long long>() + 1);
          ++compared;
        }
      }
    }
  }
  EXPECT_GE(compared, 80);  // most random boxes hold feasible designs
}

TEST(Culling, SearchesFarFewerWorkspacesThanExhaustiveSearch) {
  Json doc = hapsyn::test::fivebar_study("culling");
  for (const char* v : {"l0", "l1", "l2"}) doc["design"][v]["step"] = 0.025;
  doc["design"]["l1"]["lower"] = 0.05;
  doc["design"]["r"]["step"] = 0.05;
  doc["scene"]["options"]["step"] = 0.01;
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  const auto grid = grid_solver(Json{{"prune", false}, {"progress_interval", 1e9}});
  const hapsyn::plugins::CullingSolver culling(hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(true, false)));
  const auto exhaustive = solve(*grid, *study.problem, 2);
  const auto culled = solve(culling, *study.problem, 2);
  ASSERT_TRUE(culled.best && exhaustive.best);
  EXPECT_EQ(culled.best->design, exhaustive.best->design);
  const long long exhaustive_searches = exhaustive.statistics["feasible"];
  const long long culling_searches = culled.statistics["full_workspace_searches"];
  EXPECT_LT(culling_searches * 10, exhaustive_searches);
  EXPECT_LT(culled.sample_evaluations * 5, exhaustive.sample_evaluations);
}

TEST(Culling, PolishingKeepsTheCellAndNeverLosesValue) {
  Json doc = hapsyn::test::fivebar_study("culling");
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  const hapsyn::plugins::CullingSolver culling(hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(true, true)));
  const auto result = solve(culling, *study.problem, 2);
  ASSERT_TRUE(result.best);
  const Json& grid_optimum = result.statistics["grid_optimum"];
  EXPECT_GE(result.best->score, grid_optimum["score"].get<double>());
  const auto& space = study.problem->design_space();
  for (std::size_t k = 0; k < space.size(); ++k) {
    const auto& c = space.components()[k];
    EXPECT_LE(std::abs(result.best->design[static_cast<Eigen::Index>(k)] - grid_optimum["design"][c.name].get<double>()),
              c.step * (1 + 1e-9))
        << c.name;
  }
  EXPECT_TRUE(result.statistics["polish"].contains("status"));
}

// Issue 51: culling's SQP seed and polish printed nothing for minutes at a time; they report at
// the progress interval like the sweep, each line naming its phase and stage.
TEST(Culling, SeedAndPolishReportProgressAtTheInterval) {
  const hapsyn::Study study = hapsyn::load_study(hapsyn::test::fivebar_study("culling"), hapsyn::test::registry());
  Json options = culling_options(true, true);
  options["progress_interval"] = 1e-9;  // every evaluation
  const hapsyn::plugins::CullingSolver culling(hapsyn::make_options<hapsyn::plugins::CullingOptions>(options));
  std::ostringstream progress;
  hapsyn::SolverContext context;
  context.threads = 2;
  context.progress = &progress;
  ASSERT_TRUE(culling.solve(*study.problem, context).best);
  const std::string text = progress.str();
  EXPECT_NE(text.find("culling: SQP seed, plain stage: 2 evaluations"), std::string::npos) << text;
  EXPECT_NE(text.find("culling: SQP polish, plain stage: "), std::string::npos) << text;
  EXPECT_NE(text.find(", best score 0."), std::string::npos) << text;
  // At the default interval a quick study's SQP says nothing.
  std::ostringstream quiet;
  context.progress = &quiet;
  options["progress_interval"] = 1e9;
  ASSERT_TRUE(hapsyn::plugins::CullingSolver(hapsyn::make_options<hapsyn::plugins::CullingOptions>(options))
                  .solve(*study.problem, context).best);
  EXPECT_EQ(quiet.str().find("SQP"), std::string::npos) << quiet.str();
}

// The seed only needs a grid cell near the optimum: its SLSQP stops at seed_xtol, while the
// polish keeps sqp_xtol, so a loose seed changes neither the grid optimum nor the polished one.
TEST(Culling, SeedStopsAtItsOwnToleranceAndThePolishAtSqpXtol) {
  Json doc = hapsyn::test::fivebar_study("culling");
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  const auto run = [&](double seed_xtol) {
    Json options = culling_options(true, true);
    options["seed_xtol"] = seed_xtol;
    options["sqp_max_evaluations"] = 400;
    const hapsyn::plugins::CullingSolver culling(hapsyn::make_options<hapsyn::plugins::CullingOptions>(options));
    return solve(culling, *study.problem, 2);
  };
  const auto tight = run(1e-9), loose = run(1e-2);
  ASSERT_TRUE(tight.best && loose.best);
  EXPECT_LT(loose.statistics["seed"]["sqp"]["evaluations"].get<long long>(),
            tight.statistics["seed"]["sqp"]["evaluations"].get<long long>());
  EXPECT_EQ(loose.statistics["grid_optimum"], tight.statistics["grid_optimum"]);
  EXPECT_EQ(loose.statistics["polish"]["evaluations"], tight.statistics["polish"]["evaluations"]);
  EXPECT_EQ(loose.best->score, tight.best->score);
  EXPECT_EQ(loose.best->design, tight.best->design);
}

TEST(Culling, WeightedSumOfWorstCaseMetricsHasAValidBound) {
  Json doc = hapsyn::test::fivebar_study("culling");
  doc["objectives"] = Json::array({{{"metric", "gii"}, {"weight", 0.5}}, {{"metric", "gdi"}, {"weight", 2.0}}});
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  auto ws = study.problem->make_eval_scratch();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const std::vector<double> x = {0.3 * u(rng), 0.05 + 0.25 * u(rng), 0.05 + 0.25 * u(rng), 0.6 * u(rng)};
    const double full = study.problem->evaluate(x.data(), *ws).score;
    if (!std::isfinite(full)) continue;
    std::vector<int> subset = {static_cast<int>(u(rng) * 25), static_cast<int>(u(rng) * 25)};
    hapsyn::EvalOptions o;
    o.subset = &subset;
    EXPECT_GE(study.problem->evaluate(x.data(), *ws, o).score, full);
    ++checked;
  }
  EXPECT_GT(checked, 30);
}

TEST(Culling, RefusesAMetricThatIsNotWorstCase) {
  hapsyn::Registry registry({HAPSYN_PLUGIN_DIR, HAPSYN_TEST_PLUGIN_DIR});
  Json doc = hapsyn::test::fivebar_study("culling");
  doc["objectives"] = Json::array({{{"metric", "summetric"}}});
  expect_error([&] { hapsyn::load_study(doc, registry); },
               {"culling: metric 'summetric'", "is not worst-case"});
}

TEST(Culling, RefusesMinimizingAndNegativeWeights) {
  Json doc = hapsyn::test::fivebar_study("culling");
  doc["objectives"][0]["sense"] = "minimize";
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); }, {"objective 'gii'", "is minimized"});
  Json doc2 = hapsyn::test::fivebar_study("culling");
  doc2["objectives"][0]["weight"] = -1.0;
  // The framework's schema refuses a negative weight before culling's own check is reached.
  expect_error([&] { hapsyn::load_study(doc2, hapsyn::test::registry()); }, {"objectives[0].weight", "must be >= 0"});
}

TEST(Culling, NeedsAStepForEveryFreeVariable) {
  Json doc = hapsyn::test::fivebar_study("culling");
  doc["design"]["r"].erase("step");
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); }, {"culling: design.r has no step"});
}

TEST(Culling, InfeasibleGridIsAStatus) {
  Json doc = hapsyn::test::fivebar_study("culling");
  doc["design"]["l1"] = {{"lower", 0.01}, {"upper", 0.02}, {"step", 0.01}};
  doc["design"]["l2"] = {{"lower", 0.01}, {"upper", 0.02}, {"step", 0.01}};
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  const hapsyn::plugins::CullingSolver culling(hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(true, true)));
  const auto result = solve(culling, *study.problem, 2);
  EXPECT_EQ(result.status, hapsyn::SolverStatus::kInfeasible);
  EXPECT_NE(result.message.find("no feasible design"), std::string::npos);
}

namespace {
hapsyn::SolverResult cull_with(const hapsyn::Problem& problem, const Json& options, hapsyn::test::StopAfter& counter,
                               const std::string& checkpoint, bool resume, int threads = 2) {
  hapsyn::SolverContext context;
  context.threads = threads;
  context.seed = 5;
  context.stop = &counter.stop;
  context.checkpoint_file = checkpoint;
  context.resume = resume;
  return hapsyn::plugins::CullingSolver(hapsyn::make_options<hapsyn::plugins::CullingOptions>(options)).solve(problem, context);
}
}  // namespace

TEST(Culling, StopMidRunCheckpointsAndResumeGivesTheUninterruptedOptimum) {
  for (bool seed : {false, true}) {
    for (int threads : {1, 2}) {
      hapsyn::test::StopAfter counter;
      const auto problem = hapsyn::test::stopping_problem(counter);
      const std::string dir = hapsyn::test::fresh_directory("culling-stop");
      const std::string file = dir + "/checkpoint.json";
      const Json options = culling_options(seed, true);
      const auto uninterrupted = cull_with(*problem, options, counter, "", false, threads);
      ASSERT_EQ(uninterrupted.status, hapsyn::SolverStatus::kConverged) << uninterrupted.message;
      const long long all_calls = counter.calls;
      counter.calls = 0;
      counter.limit = all_calls * 2 / 3;
      const auto stopped = cull_with(*problem, options, counter, file, false, threads);
      ASSERT_EQ(stopped.status, hapsyn::SolverStatus::kStopped) << stopped.message;
      ASSERT_TRUE(stopped.best.has_value());
      for (const std::string& part : std::vector<std::string>{"stopped on request after ", "% of 2,601 grid designs; best so far: score ",
                                     "not polished); checkpoint " + file + " written, resume with --resume"}) {
        EXPECT_NE(stopped.message.find(part), std::string::npos) << stopped.message << "\nmissing: " << part;
      }
      EXPECT_EQ(hapsyn::test::read_json_file(file)["solver"], "culling");
      counter.stop = false;
      counter.limit = -1;
      const auto resumed = cull_with(*problem, options, counter, file, true, threads);
      ASSERT_EQ(resumed.status, hapsyn::SolverStatus::kConverged) << resumed.message;
      EXPECT_EQ(resumed.best->design, uninterrupted.best->design);
      EXPECT_EQ(resumed.best->score, uninterrupted.best->score);
      EXPECT_EQ(resumed.statistics["grid_optimum"], uninterrupted.statistics["grid_optimum"]);
      std::filesystem::remove_all(dir);
    }
  }
}

TEST(Culling, StopDuringTheSeedCheckpointsNoReferenceAndTheResumeSeedsAgain) {
  for (int threads : {1, 2}) {
    hapsyn::test::StopAfter counter;
    const auto problem = hapsyn::test::stopping_problem(counter);
    const std::string dir = hapsyn::test::fresh_directory("culling-stop-seed");
    const std::string file = dir + "/checkpoint.json";
    const Json options = culling_options(true, true);
    const auto uninterrupted = cull_with(*problem, options, counter, "", false, threads);
    ASSERT_EQ(uninterrupted.status, hapsyn::SolverStatus::kConverged) << uninterrupted.message;
    counter.calls = 0;
    counter.limit = 3;  // within the seed's start grid
    const auto stopped = cull_with(*problem, options, counter, file, false, threads);
    ASSERT_EQ(stopped.status, hapsyn::SolverStatus::kStopped) << stopped.message;
    EXPECT_FALSE(stopped.best.has_value());
    EXPECT_EQ(stopped.message, "stopped on request during the seed (the start grid and the SQP), before the sweep; "
                               "checkpoint " + file + " written, resume with --resume (the seed runs again)");
    const Json state = hapsyn::test::read_json_file(file)["state"];
    EXPECT_FALSE(state["seed"]["complete"].get<bool>());
    EXPECT_TRUE(state["reference"].is_null());
    EXPECT_TRUE(state["critical_samples"].empty());
    counter.stop = false;
    counter.limit = -1;
    const auto resumed = cull_with(*problem, options, counter, file, true, threads);
    ASSERT_EQ(resumed.status, hapsyn::SolverStatus::kConverged) << resumed.message;
    EXPECT_EQ(resumed.best->design, uninterrupted.best->design);
    EXPECT_EQ(resumed.statistics["grid_optimum"], uninterrupted.statistics["grid_optimum"]);
    // The whole seed ran again: the evaluations are the uninterrupted run's.
    EXPECT_EQ(resumed.design_evaluations, uninterrupted.design_evaluations);
    EXPECT_EQ(resumed.statistics["seed"]["reference_score"], uninterrupted.statistics["seed"]["reference_score"]);
    EXPECT_EQ(resumed.statistics["seed"]["sqp"]["evaluations"], uninterrupted.statistics["seed"]["sqp"]["evaluations"]);
    if (threads == 1) {  // (at two threads the early exits race, and the sample counts with them)
      EXPECT_EQ(resumed.sample_evaluations, uninterrupted.sample_evaluations);
      EXPECT_EQ(resumed.statistics["culled"], uninterrupted.statistics["culled"]);
    }
    std::filesystem::remove_all(dir);
  }
}

TEST(Culling, DamagedEditedAndForeignCheckpointsAreRefused) {
  hapsyn::test::StopAfter counter;
  const auto problem = hapsyn::test::stopping_problem(counter);
  const std::string dir = hapsyn::test::fresh_directory("culling-bad");
  const std::string file = dir + "/checkpoint.json";
  const Json options = culling_options(false, false);
  (void)cull_with(*problem, options, counter, "", false);
  const long long all_calls = counter.calls;
  auto stop_midway = [&] {
    counter.calls = 0;
    counter.limit = all_calls * 2 / 3;
    counter.stop = false;
    const auto r = cull_with(*problem, options, counter, file, false);
    ASSERT_EQ(r.status, hapsyn::SolverStatus::kStopped) << r.message;
    counter.limit = -1;
    counter.stop = false;
  };
  auto resume = [&] { cull_with(*problem, options, counter, file, true); };

  stop_midway();
  hapsyn::test::truncate_file(file);
  expect_error(resume, {"checkpoint: " + file + ": not valid JSON (truncated or damaged); delete it, or run without --resume"});

  stop_midway();
  Json edited = hapsyn::test::read_json_file(file);
  ASSERT_TRUE(edited["state"]["reference"].is_object());
  edited["state"]["reference"]["score"] = 99.0;
  hapsyn::test::write_json_file(file, edited, false);
  expect_error(resume, {"checkpoint: " + file + ": damaged or edited (its checksum does not match its content)"});
  hapsyn::test::write_json_file(file, edited, true);
  expect_error(resume, {"checkpoint: " + file + ": state.reference: grid design ",
                        "on re-evaluation, the checkpoint claims 99; delete it, or run without --resume"});

  stop_midway();
  edited = hapsyn::test::read_json_file(file);
  edited["state"]["critical_samples"] = Json::array({3, 99});
  hapsyn::test::write_json_file(file, edited, true);
  expect_error(resume, {"checkpoint: " + file + ": state.critical_samples: sample 99 is not one of the 8 samples"});
  edited["state"]["counts"].erase("culled");
  edited["state"]["critical_samples"] = Json::array({3});
  hapsyn::test::write_json_file(file, edited, true);
  expect_error(resume, {"checkpoint: " + file + ": state.counts.culled is missing"});

  stop_midway();
  edited = hapsyn::test::read_json_file(file);
  edited["solver"] = "grid";
  hapsyn::test::write_json_file(file, edited, true);
  expect_error(resume, {"checkpoint: " + file + ": written by solver \"grid\", this study's solver is \"culling\""});

  stop_midway();
  expect_error([&] { cull_with(*problem, culling_options(true, false), counter, file, true); },
               {"checkpoint: " + file + ": written for another study"});
  std::filesystem::remove_all(dir);
}

TEST(Culling, NonMonotoneMetricFailsNamingTheMetric) {
  const auto problem = hapsyn::test::non_monotone_problem();
  for (bool seed : {false, true}) {
    const hapsyn::plugins::CullingSolver culling(
        hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(seed, false)));
    const auto result = solve(culling, *problem, 2);
    EXPECT_EQ(result.status, hapsyn::SolverStatus::kFailed) << result.message;
    EXPECT_FALSE(result.best.has_value());
    for (const char* part : {"metric 'bad' (objective 'bad') breaks the worst-case monotonicity rule: its value over ",
                             "below its value over the whole scene ", "culling relies on that rule",
                             "grid solver and prune: false"}) {
      EXPECT_NE(result.message.find(part), std::string::npos) << result.message << "\nmissing: " << part;
    }
  }
}

TEST(Culling, RefusesAGridLargerThanMaxDesignsAtLoad) {
  Json doc = hapsyn::test::fivebar_study("culling");
  doc["solver"]["options"]["max_designs"] = 1000;  // the test grid has 4 x 6 x 6 x 7 = 1008 designs
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); },
               {"culling: the design grid has 1.01e+03 designs", "more than solver.options.max_designs = 1000"});
}

namespace {
// Status, best and grid optimum of two culling results, bit for bit.
void expect_same_optimum(const hapsyn::SolverResult& a, const hapsyn::SolverResult& b) {
  EXPECT_EQ(a.status, b.status) << a.message << "\n" << b.message;
  ASSERT_EQ(a.best.has_value(), b.best.has_value());
  if (!a.best) return;
  EXPECT_EQ(a.best->design, b.best->design);
  EXPECT_EQ(a.best->score, b.best->score);
  EXPECT_EQ(a.best->objectives, b.best->objectives);
  EXPECT_EQ(a.statistics["grid_optimum"], b.statistics["grid_optimum"]);
}
}  // namespace

TEST(Culling, ShardsMergedAndResumedGiveThePlainRun) {
  for (bool seed : {false, true}) {
    hapsyn::test::StopAfter counter;
    const auto problem = hapsyn::test::stopping_problem(counter);  // 51 lines of 51 designs
    const hapsyn::plugins::CullingSolver culling(
        hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(seed, true)));
    const auto plain = cull_with(*problem, culling_options(seed, true), counter, "", false);
    ASSERT_EQ(plain.status, hapsyn::SolverStatus::kConverged) << plain.message;
    const auto solve = [&](const hapsyn::SolverContext& context) { return culling.solve(*problem, context); };
    for (int count : {1, 2, 3}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + ", shards " + std::to_string(count));
      const std::string dir = hapsyn::test::fresh_directory("culling-shards");
      const auto merged = hapsyn::test::shard_merge_resume(culling, *problem, count, dir, solve,
                                                           [&](int k, const hapsyn::SolverResult& r) {
        if (count == 1) {
          expect_same_optimum(r, plain);
          return;
        }
        EXPECT_EQ(r.status, hapsyn::SolverStatus::kStopped);
        EXPECT_NE(r.message.find("shard " + std::to_string(k + 1) + "/" + std::to_string(count) + " done: "),
                  std::string::npos)
            << r.message;
        EXPECT_NE(r.message.find("not polished"), std::string::npos) << r.message;
      });
      expect_same_optimum(merged, plain);
      if (count == 3) {
        const Json state = hapsyn::test::read_json_file(dir + "/shard-2.json")["state"];
        EXPECT_EQ(state["finished_ranges"], Json::array({Json::array({34, 51})}));
        const auto missing = hapsyn::test::shard_merge_resume(culling, *problem, 3, dir, solve,
                                                              [](int, const hapsyn::SolverResult&) {}, {1});
        expect_same_optimum(missing, plain);
      }
      std::filesystem::remove_all(dir);
    }
  }
}

TEST(Culling, MergeRefusesOverlappingSharesAndStatesThatDoNotFit) {
  hapsyn::test::StopAfter counter;
  const auto problem = hapsyn::test::stopping_problem(counter);
  const hapsyn::plugins::CullingSolver culling(
      hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(false, false)));
  const std::string dir = hapsyn::test::fresh_directory("culling-merge-bad");
  std::vector<Json> states;
  for (int k : {0, 1}) {
    hapsyn::ShardCluster shard(k, 2);
    hapsyn::SolverContext context;
    context.ranks = &shard;
    context.checkpoint_file = dir + "/shard.json";
    (void)culling.solve(*problem, context);
    states.push_back(hapsyn::test::read_json_file(context.checkpoint_file)["state"]);
  }
  expect_error([&] { culling.merge_shards(*problem, {states[0], states[1], states[0]}); },
               {"merge: line 0 (grid designs 0..50) is finished in shard 1 and in shard 3 of 3: the shares overlap; "
                "merge the shards of one --shard i/N split, each once"});
  expect_error([&] { culling.merge_shards(*problem, {}); }, {"merge: no shard states to merge"});
  Json broken = states[1];
  broken["counts"].erase("culled");
  expect_error([&] { culling.merge_shards(*problem, {states[0], broken}); },
               {"merge: shard 2/2: state.counts.culled is missing"});
  broken = states[1];
  broken["critical_samples"] = Json::array({99});
  expect_error([&] { culling.merge_shards(*problem, {states[0], broken}); },
               {"merge: shard 2/2: state.critical_samples: sample 99 is not one of the 8 samples"});
  const Json merged = culling.merge_shards(*problem, {states[0], states[1]});
  EXPECT_EQ(merged["finished_prefix"], 51);
  EXPECT_EQ(merged["counts"]["full_searches"].get<long long>(),
            states[0]["counts"]["full_searches"].get<long long>() + states[1]["counts"]["full_searches"].get<long long>());
  std::filesystem::remove_all(dir);
}

TEST(Culling, EmulatedRanksGiveThePlainRun) {
  const hapsyn::Study study = hapsyn::load_study(hapsyn::test::fivebar_study("culling"), hapsyn::test::registry());
  for (bool seed : {false, true}) {
    const hapsyn::plugins::CullingSolver culling(
        hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(seed, true)));
    const auto plain = solve(culling, *study.problem, 2);
    ASSERT_EQ(plain.status, hapsyn::SolverStatus::kConverged) << plain.message;
    for (int ranks : {2, 3}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + ", ranks " + std::to_string(ranks));
      hapsyn::test::EmulatedRanks job(ranks);
      const auto results = job.run([&](hapsyn::Cluster& cluster) {
        hapsyn::SolverContext context;
        context.threads = 2;
        context.ranks = &cluster;
        return culling.solve(*study.problem, context);
      });
      expect_same_optimum(results[0], plain);
      if (seed) {  // rank 0 seeded and broadcast its reference: the seed is the single run's
        EXPECT_EQ(results[0].statistics["seed"]["reference_score"], plain.statistics["seed"]["reference_score"]);
      }
      EXPECT_EQ(results[ranks - 1].message, "rank " + std::to_string(ranks - 1) + ": the result is rank 0's");
    }
  }
}

TEST(Culling, LargeGridsRunGroupsOfLinesPerTaskWithTheSameResult) {
  // 16 x 15 x 15 = 3,600 lines: 14 per task (hapsyn::plugins::units_per_task).
  Json doc = hapsyn::test::fivebar_study("culling");
  doc["design"]["l0"] = {{"lower", 0.0}, {"upper", 0.3}, {"step", 0.02}};
  doc["design"]["l1"] = {{"lower", 0.02}, {"upper", 0.3}, {"step", 0.02}};
  doc["design"]["l2"] = {{"lower", 0.02}, {"upper", 0.3}, {"step", 0.02}};
  doc["design"]["r"] = {{"lower", 0.0}, {"upper", 0.6}, {"step", 0.1}};
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  const hapsyn::plugins::CullingSolver culling(
      hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(false, false)));
  const auto plain = solve(culling, *study.problem, 2);
  ASSERT_EQ(plain.status, hapsyn::SolverStatus::kConverged) << plain.message;
  const std::string dir = hapsyn::test::fresh_directory("culling-groups");
  const auto run = [&](const hapsyn::SolverContext& context) { return culling.solve(*study.problem, context); };
  const auto merged = hapsyn::test::shard_merge_resume(culling, *study.problem, 2, dir, run, [](int, const hapsyn::SolverResult&) {});
  expect_same_optimum(merged, plain);
  // The shares are whole tasks: 258 tasks of 14 lines (the last of 2), the second share from task 129.
  const Json state = hapsyn::test::read_json_file(dir + "/shard-1.json")["state"];
  EXPECT_EQ(state["finished_ranges"], Json::array({Json::array({1806, 3600})}));
  hapsyn::test::EmulatedRanks job(3);
  const auto results = job.run([&](hapsyn::Cluster& cluster) {
    hapsyn::SolverContext context;
    context.threads = 1;
    context.ranks = &cluster;
    return culling.solve(*study.problem, context);
  });
  expect_same_optimum(results[0], plain);
  std::filesystem::remove_all(dir);
}

TEST(Culling, ABreachFoundOnAnyRankFailsTheRunOnRankZero) {
  const auto problem = hapsyn::test::non_monotone_problem();
  for (bool seed : {false, true}) {
    const hapsyn::plugins::CullingSolver culling(
        hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(seed, false)));
    hapsyn::test::EmulatedRanks job(3);
    const auto results = job.run([&](hapsyn::Cluster& cluster) {
      hapsyn::SolverContext context;
      context.threads = 1;
      context.ranks = &cluster;
      return culling.solve(*problem, context);
    });
    EXPECT_EQ(results[0].status, hapsyn::SolverStatus::kFailed) << results[0].message;
    EXPECT_FALSE(results[0].best.has_value());
    EXPECT_NE(results[0].message.find("metric 'bad' (objective 'bad') breaks the worst-case monotonicity rule"),
              std::string::npos)
        << results[0].message;
  }
}

TEST(Culling, LineBoundsSkipRuledOutDesignsWithTheSameResultAndCounts) {
  // Culling statistics are thread-order dependent only through what the reference learns; on one
  // thread the counts are deterministic, so they must be equal with and without the bound.
  Json doc = hapsyn::test::fivebar_study("culling");
  doc["design"]["r"]["step"] = 0.01;
  doc["design"]["l0"]["step"] = 0.05;
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  Json on = culling_options(true, false), off = culling_options(true, false);
  off["line_bounds"] = false;
  on["block_bounds"] = false;  // they rule out designs inside the run (tested below)
  const hapsyn::plugins::CullingSolver with(hapsyn::make_options<hapsyn::plugins::CullingOptions>(on));
  const hapsyn::plugins::CullingSolver without(hapsyn::make_options<hapsyn::plugins::CullingOptions>(off));
  const auto a = solve(with, *study.problem, 1);
  const auto b = solve(without, *study.problem, 1);
  ASSERT_TRUE(a.best && b.best);
  EXPECT_EQ(a.best->design, b.best->design);
  EXPECT_EQ(a.best->score, b.best->score);
  for (const char* key : {"culled", "constraint_violated", "failed_at_critical_sample", "full_workspace_searches",
                          "bound_sample_evaluations", "full_search_sample_evaluations"}) {
    EXPECT_EQ(a.statistics[key], b.statistics[key]) << key;
  }
  EXPECT_EQ(a.sample_evaluations, b.sample_evaluations);
  EXPECT_GT(a.statistics["constraint_violated"].get<long long>(), 1000);
}

TEST(Culling, BlockBoundsGiveTheExhaustiveOptimumOnLongLines) {
  std::mt19937 rng(77);
  const std::vector<Json> objective_sets = worst_case_objective_sets();
  int compared = 0;
  long long ruled_out = 0, bounded = 0;
  for (int box = 0; box < 10; ++box) {
    Json doc = hapsyn::test::fivebar_random_long_lines(rng);
    for (const Json& objectives : objective_sets) {
      doc["objectives"] = objectives;
      const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
      const auto exhaustive = solve(*grid_solver(Json{{"prune", false}, {"progress_interval", 1e9}}), *study.problem, 2);
      for (int threads : {1, 2}) {
        const hapsyn::plugins::CullingSolver culling(
            hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(threads == 2, false)));
        const auto culled = solve(culling, *study.problem, threads);
        ASSERT_EQ(culled.status, exhaustive.status) << culled.message << "\n" << doc.dump();
        ruled_out += culled.statistics["block_ruled_out"].get<long long>();
        bounded += culled.statistics["feasible_designs"].get<long long>();
        if (!exhaustive.best) continue;
        EXPECT_EQ(culled.best->design, exhaustive.best->design) << doc.dump();
        EXPECT_EQ(culled.best->score, exhaustive.best->score) << doc.dump();
        ++compared;
      }
    }
  }
  EXPECT_GE(compared, 30);
  EXPECT_GT(ruled_out, bounded / 4) << "the block bounds should rule out a good part of these lines";
}

TEST(Culling, BlockBoundsRuleOutRunsWithTheSameOptimumAndTotals) {
  // On one thread the sweep is deterministic: with and without block bounds the optimum, the
  // constraint counts and the designs ruled out in all are the same; the bounds move designs
  // from culled / failed to block_ruled_out and save sample evaluations.
  Json doc = hapsyn::test::fivebar_study("culling");
  doc["design"]["r"] = {{"lower", 0.0}, {"upper", 0.6}, {"step", 0.005}};
  doc["design"]["l0"]["step"] = 0.05;
  doc["scene"]["options"]["step"] = 0.01;
  for (const char* metric : {"gii", "gdi"}) {
    doc["objectives"] = Json::array({{{"metric", metric}}});
    const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
    Json off = culling_options(true, false);
    off["block_bounds"] = false;
    const hapsyn::plugins::CullingSolver with(hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(true, false)));
    const hapsyn::plugins::CullingSolver without(hapsyn::make_options<hapsyn::plugins::CullingOptions>(off));
    const auto a = solve(with, *study.problem, 1);
    const auto b = solve(without, *study.problem, 1);
    ASSERT_TRUE(a.best && b.best);
    EXPECT_EQ(a.best->design, b.best->design);
    EXPECT_EQ(a.best->score, b.best->score);
    EXPECT_EQ(a.statistics["constraint_violated"], b.statistics["constraint_violated"]);
    const auto ruled = [](const Json& st) {
      return st["culled"].get<long long>() + st["failed_at_critical_sample"].get<long long>() +
             st["block_ruled_out"].get<long long>() + st["full_workspace_searches"].get<long long>();
    };
    EXPECT_EQ(ruled(a.statistics), ruled(b.statistics)) << metric;
    EXPECT_EQ(b.statistics["block_ruled_out"].get<long long>(), 0);
    EXPECT_EQ(b.statistics["block_bounds"].get<long long>(), 0);
    EXPECT_GT(a.statistics["block_ruled_out"].get<long long>(), a.statistics["feasible_designs"].get<long long>() / 3)
        << metric;
    EXPECT_LT(a.statistics["bound_sample_evaluations"].get<long long>() * 4,
              b.statistics["bound_sample_evaluations"].get<long long>() * 3)
        << metric;
  }
}

TEST(Culling, AFalseBlockBoundStopsTheRunNamingIt) {
  Json doc = hapsyn::test::fivebar_study("culling");
  doc["design"]["r"] = {{"lower", 0.0}, {"upper", 0.6}, {"step", 0.005}};
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  const hapsyn::Problem& p = *study.problem;
  const std::shared_ptr<const hapsyn::Mechanism> fivebar(std::shared_ptr<const hapsyn::Mechanism>{}, &p.mechanism());
  const auto problem = std::make_shared<hapsyn::Problem>(
      "false-envelope", std::make_shared<hapsyn::test::AllFailEnvelope>(fivebar), std::make_shared<hapsyn::SampleSet>(p.samples()),
      p.metrics(), p.objectives(), p.design_space());
  const hapsyn::plugins::CullingSolver culling(hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(true, false)));
  expect_error([&] { solve(culling, *problem, 1); },
               {"culling: the mechanism's block bound (MechanismAcceleration::sample_envelope) is wrong: over r in [",
                "it claims that every design fails, but grid value", "reaches the sample and scores",
                "set solver.options.block_bounds = false"});
  // Without block bounds the same problem runs to the optimum.
  Json off = culling_options(true, false);
  off["block_bounds"] = false;
  const auto result = solve(hapsyn::plugins::CullingSolver(hapsyn::make_options<hapsyn::plugins::CullingOptions>(off)), *problem, 1);
  EXPECT_TRUE(result.best.has_value());
}

TEST(Culling, AFalseReachableIntervalStopsTheRunNamingIt) {
  Json doc = hapsyn::test::fivebar_study("culling");
  doc["design"]["r"] = {{"lower", 0.0}, {"upper", 0.6}, {"step", 0.005}};
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  const hapsyn::Problem& p = *study.problem;
  const std::shared_ptr<const hapsyn::Mechanism> fivebar(std::shared_ptr<const hapsyn::Mechanism>{}, &p.mechanism());
  const auto problem = std::make_shared<hapsyn::Problem>(
      "false-reach", std::make_shared<hapsyn::test::NothingReachable>(fivebar), std::make_shared<hapsyn::SampleSet>(p.samples()),
      p.metrics(), p.objectives(), p.design_space());
  const hapsyn::plugins::CullingSolver culling(hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(true, false)));
  expect_error([&] { solve(culling, *problem, 1); },
               {"culling: the mechanism's line bound (MechanismAcceleration::reachable_interval) is wrong: it claims that sample ",
                "fails for every r outside the interval it gives, but grid value", "lies outside it and reaches the sample",
                "set solver.options.block_bounds = false"});
  // Without block bounds the same problem runs to the optimum.
  Json off = culling_options(true, false);
  off["block_bounds"] = false;
  const auto result = solve(hapsyn::plugins::CullingSolver(hapsyn::make_options<hapsyn::plugins::CullingOptions>(off)), *problem, 1);
  EXPECT_TRUE(result.best.has_value());
}
