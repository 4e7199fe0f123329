// The grid solver is the oracle of later solvers: check it against a plain loop over the grid.
#include "grid.hpp"
#include "shared/bounds/line_bound.hpp"
#include "shared/bounds/run_bounds.hpp"

#include "analytic_problems.hpp"
#include "shared/testing/forwarding_mechanism.hpp"
#include "shared/testing/rank_test_support.hpp"
#include "shared/testing/stop_test_support.hpp"
#include "test_support.hpp"

#include <hapsyn/accel/mechanism_acceleration.hpp>
#include <hapsyn/accel/metric_acceleration.hpp>
#include <hapsyn/pareto.hpp>

#include <cmath>
#include <random>
#include <set>

using hapsyn::Json;

namespace {
// A grid solver with these options (the rest default).
hapsyn::plugins::GridSolver grid_solver(const Json& options) {
  return hapsyn::plugins::GridSolver(hapsyn::make_options<hapsyn::plugins::GridOptions>(options));
}

struct Brute {
  double score = -INFINITY;
  Eigen::VectorXd design;
  long long feasible = 0;
};

// Every grid design evaluated in full, in grid order (last component fastest), first best kept.
Brute brute_force(const hapsyn::Problem& problem) {
  const auto& space = problem.design_space();
  const std::size_t n = space.free_size();
  std::vector<long long> counts(n), index(n, 0);
  long long total = 1;
  for (std::size_t k = 0; k < n; ++k) total *= (counts[k] = space.grid_count(k));
  auto ws = problem.make_eval_scratch();
  Brute best;
  std::vector<double> x(n);
  for (long long i = 0; i < total; ++i) {
    long long rest = i;
    for (std::size_t k = n; k-- > 0;) {
      x[k] = space.grid_value(k, rest % counts[k]);
      rest /= counts[k];
    }
    const hapsyn::Evaluation& e = problem.evaluate(x.data(), *ws);
    if (e.status != hapsyn::EvalStatus::kFeasible) continue;
    ++best.feasible;
    if (e.score > best.score) {
      best.score = e.score;
      best.design = problem.full_design(x.data());
    }
  }
  return best;
}

Json random_box(std::mt19937& rng) {
  std::uniform_int_distribution<int> cells(0, 6);
  Json doc = hapsyn::test::fivebar_study();
  // Sub-boxes of the paper's bounds on a 25 mm grid, each 3-5 grid points wide, placed where
  // most designs reach the workspace (so that the comparison is not about infeasibility alone).
  const std::vector<std::tuple<std::string, double, double>> vars = {
      {"l0", 0.0, 0.3}, {"l1", 0.1, 0.3}, {"l2", 0.1, 0.3}, {"r", 0.1, 0.6}};
  for (const auto& [name, lo, hi] : vars) {
    const double step = 0.025;
    const double lower = std::min(lo + step * cells(rng) * (name == "r" ? 2 : 1), hi - 2 * step);
    const double upper = std::min(hi, lower + step * (2 + cells(rng) % 3));
    doc["design"][name] = {{"lower", lower}, {"upper", upper}, {"step", step}};
  }
  return doc;
}
}  // namespace

TEST(Grid, MatchesBruteForceOnRandomSubBoxesForGiiGdiAndWeightedSum) {
  std::mt19937 rng(7);
  const std::vector<Json> objective_sets = {
      Json::array({{{"metric", "gii"}}}),
      Json::array({{{"metric", "gdi"}}}),
      Json::array({{{"metric", "gii"}, {"weight", 0.3}}, {{"metric", "gdi"}, {"weight", 0.7}}})};
  int compared = 0;
  for (int box = 0; box < 10; ++box) {
    Json doc = random_box(rng);
    for (const Json& objectives : objective_sets) {
      doc["objectives"] = objectives;
      const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
      const Brute brute = brute_force(*study.problem);
      for (bool prune : {true, false}) {
        for (int threads : {1, 2}) {
          hapsyn::plugins::GridSolver solver = grid_solver(Json{{"prune", prune}, {"progress_interval", 2.0}});
          hapsyn::SolverContext context;
          context.threads = threads;
          const hapsyn::SolverResult result = solver.solve(*study.problem, context);
          // A pruned design may also have failed at a later sample, so pruning can only blur the
          // feasible count upwards; without pruning it is exact.
          const long long feasible = result.statistics["feasible"].get<long long>();
          const long long pruned = result.statistics["pruned"].get<long long>();
          EXPECT_LE(feasible, brute.feasible);
          EXPECT_GE(feasible + pruned, brute.feasible);
          if (!prune) {
            EXPECT_EQ(feasible, brute.feasible);
          }
          if (brute.feasible == 0) {
            EXPECT_EQ(result.status, hapsyn::SolverStatus::kInfeasible);
            EXPECT_FALSE(result.best.has_value());
            continue;
          }
          ASSERT_TRUE(result.best.has_value());
          EXPECT_EQ(result.status, hapsyn::SolverStatus::kConverged);
          EXPECT_EQ(result.best->score, brute.score) << doc.dump();
          EXPECT_EQ(result.best->design, brute.design) << doc.dump();
          ++compared;
        }
      }
    }
  }
  EXPECT_GT(compared, 60);  // most random boxes hold feasible designs
}

TEST(Grid, StatusCountsAddUpToTheGridSize) {
  const hapsyn::Study study = hapsyn::load_study(hapsyn::test::fivebar_study(), hapsyn::test::registry());
  hapsyn::plugins::GridSolver solver = grid_solver(Json{{"prune", true}, {"progress_interval", 2.0}});
  hapsyn::SolverContext context;
  context.threads = 2;
  const auto result = solver.solve(*study.problem, context);
  const auto& s = result.statistics;
  EXPECT_EQ(s["feasible"].get<long long>() + s["pruned"].get<long long>() + s["sample_failed"].get<long long>() +
                s["constraint_violated"].get<long long>(),
            s["grid_designs"].get<long long>());
  EXPECT_EQ(s["grid_designs"].get<long long>(), 4LL * 6 * 6 * 7);
  EXPECT_GT(s["pruned"].get<long long>(), 0);
}

TEST(Grid, InfeasibleGridIsAStatusWithAMessage) {
  Json doc = hapsyn::test::fivebar_study();
  doc["design"]["l1"] = {{"lower", 0.01}, {"upper", 0.02}, {"step", 0.01}};
  doc["design"]["l2"] = {{"lower", 0.01}, {"upper", 0.02}, {"step", 0.01}};
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  hapsyn::plugins::GridSolver solver = grid_solver(Json{{"prune", true}, {"progress_interval", 2.0}});
  const auto result = solver.solve(*study.problem, hapsyn::SolverContext{});
  EXPECT_EQ(result.status, hapsyn::SolverStatus::kInfeasible);
  EXPECT_NE(result.message.find("no feasible design"), std::string::npos) << result.message;
}

TEST(Grid, ParetoModeReturnsTheBruteForceFrontWithAndWithoutPruning) {
  Json doc = hapsyn::test::fivebar_study("grid");
  for (const char* v : {"l0", "l1", "l2"}) doc["design"][v]["step"] = 0.025;
  doc["design"]["r"]["step"] = 0.05;
  doc["objectives"] = Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  doc["solver"]["options"] = {{"pareto", true}, {"progress_interval", 1e9}};
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  const auto& problem = *study.problem;
  // Brute force: every grid design in full, then the non-dominated set (first of duplicates).
  const auto counts = problem.design_space().grid_counts();
  long long total = 1;
  for (long long c : counts) total *= c;
  std::vector<hapsyn::ObjectivePoint> all;
  std::vector<long long> index;
  auto ws = problem.make_eval_scratch();
  std::vector<double> x(problem.dimension());
  for (long long i = 0; i < total; ++i) {
    problem.design_space().grid_point(i, counts, x.data());
    const auto& e = problem.evaluate(x.data(), *ws);
    if (e.status != hapsyn::EvalStatus::kFeasible) continue;
    all.push_back(e.objectives);
    index.push_back(i);
  }
  const auto keep = hapsyn::non_dominated(all, {hapsyn::Sense::kMaximize, hapsyn::Sense::kMaximize});
  std::set<std::vector<double>> expected;
  for (std::size_t k : keep) expected.insert(all[k]);
  ASSERT_GE(expected.size(), 5u);
  for (bool prune : {true, false}) {
    for (int threads : {1, 2}) {
      const hapsyn::plugins::GridSolver grid = grid_solver(Json{{"prune", prune}, {"pareto", true}, {"progress_interval", 1e9}});
      hapsyn::SolverContext context;
      context.threads = threads;
      const auto result = grid.solve(problem, context);
      ASSERT_EQ(result.status, hapsyn::SolverStatus::kConverged) << result.message;
      std::set<std::vector<double>> found;
      for (const auto& p : result.front) found.insert(p.objectives);
      EXPECT_EQ(found, expected) << "prune " << prune << ", threads " << threads;
      EXPECT_EQ(result.front.size(), expected.size());
      if (prune) {
        EXPECT_LT(result.sample_evaluations * 3, static_cast<long long>(all.size()) * problem.samples().size());
      }
    }
  }
}

TEST(Grid, ParetoModeNeedsTwoObjectives) {
  Json doc = hapsyn::test::fivebar_study("grid");
  doc["solver"]["options"] = {{"pareto", true}};
  hapsyn::test::expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); },
                             {"grid: solver.options.pareto = true: needs two or more objectives (the study has 1)"});
}

TEST(Grid, ParetoModeHandlesThreeObjectives) {
  const auto problem = hapsyn::test::three_objective_problem(0.1);
  const auto counts = problem->design_space().grid_counts();
  long long total = 1;
  for (long long c : counts) total *= c;
  std::vector<hapsyn::ObjectivePoint> all;
  auto ws = problem->make_eval_scratch();
  std::vector<double> x(problem->dimension());
  for (long long i = 0; i < total; ++i) {
    problem->design_space().grid_point(i, counts, x.data());
    all.push_back(problem->evaluate(x.data(), *ws).objectives);
  }
  const std::vector<hapsyn::Sense> max3(3, hapsyn::Sense::kMaximize);
  std::set<std::vector<double>> expected;
  for (std::size_t k : hapsyn::non_dominated(all, max3)) expected.insert(all[k]);
  const hapsyn::plugins::GridSolver grid = grid_solver(Json{{"prune", true}, {"pareto", true}, {"progress_interval", 1e9}});
  hapsyn::SolverContext context;
  context.threads = 2;
  const auto result = grid.solve(*problem, context);
  std::set<std::vector<double>> found;
  for (const auto& p : result.front) found.insert(p.objectives);
  EXPECT_EQ(found, expected);
  EXPECT_GT(expected.size(), 50u);  // the sphere octant's grid points (r = 0)
}

namespace {
// A grid solver on the context a stop test needs: `threads`, the checkpoint file, resume, and the
// counter's stop flag.
hapsyn::SolverResult solve_with(const hapsyn::Problem& problem, const Json& options, hapsyn::test::StopAfter& counter,
                                const std::string& checkpoint, bool resume, int threads = 2) {
  hapsyn::SolverContext context;
  context.threads = threads;
  context.seed = 11;
  context.stop = &counter.stop;
  context.checkpoint_file = checkpoint;
  context.resume = resume;
  return grid_solver(options).solve(problem, context);
}

void expect_same_points(const std::vector<hapsyn::SolutionPoint>& a, const std::vector<hapsyn::SolutionPoint>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].objectives, b[i].objectives);
    EXPECT_EQ(a[i].design, b[i].design);
    EXPECT_EQ(a[i].score, b[i].score);
  }
}
}  // namespace

TEST(Grid, StopMidRunCheckpointsAndResumeGivesTheUninterruptedBest) {
  for (int threads : {1, 2}) {
    hapsyn::test::StopAfter counter;
    const auto problem = hapsyn::test::stopping_problem(counter);
    const std::string dir = hapsyn::test::fresh_directory("grid-stop");
    const std::string file = dir + "/checkpoint.json";
    const Json options = {{"progress_interval", 1e9}};
    const auto uninterrupted = solve_with(*problem, options, counter, "", false, threads);
    ASSERT_EQ(uninterrupted.status, hapsyn::SolverStatus::kConverged) << uninterrupted.message;

    const long long all_calls = counter.calls;
    counter.calls = 0;
    counter.limit = all_calls / 3;
    const auto stopped = solve_with(*problem, options, counter, file, false, threads);
    EXPECT_EQ(stopped.status, hapsyn::SolverStatus::kStopped);
    ASSERT_TRUE(stopped.best.has_value());
    EXPECT_NE(stopped.message.find("stopped on request after "), std::string::npos) << stopped.message;
    EXPECT_NE(stopped.message.find("% of 2,601 grid designs; best so far: score "), std::string::npos) << stopped.message;
    EXPECT_NE(stopped.message.find("checkpoint " + file + " written, resume with --resume"), std::string::npos)
        << stopped.message;
    const Json checkpoint = hapsyn::test::read_json_file(file);
    EXPECT_EQ(checkpoint["solver"], "grid");
    EXPECT_LT(checkpoint["state"]["finished_prefix"].get<long long>(), 41);  // 2601 designs: 41 chunks

    counter.stop = false;
    counter.limit = -1;
    const auto resumed = solve_with(*problem, options, counter, file, true, threads);
    ASSERT_EQ(resumed.status, hapsyn::SolverStatus::kConverged) << resumed.message;
    ASSERT_TRUE(resumed.best.has_value());
    EXPECT_EQ(resumed.best->design, uninterrupted.best->design);
    EXPECT_EQ(resumed.best->score, uninterrupted.best->score);
    EXPECT_EQ(resumed.best->objectives, uninterrupted.best->objectives);
    std::filesystem::remove_all(dir);
  }
}

TEST(Grid, StopMidRunInParetoModeResumesToTheUninterruptedFront) {
  hapsyn::test::StopAfter counter;
  const auto problem = hapsyn::test::stopping_problem(counter, 0.05, true);
  const std::string dir = hapsyn::test::fresh_directory("grid-stop-front");
  const std::string file = dir + "/checkpoint.json";
  const Json options = {{"pareto", true}, {"progress_interval", 1e9}};
  const auto uninterrupted = solve_with(*problem, options, counter, "", false);
  ASSERT_EQ(uninterrupted.status, hapsyn::SolverStatus::kConverged) << uninterrupted.message;
  ASSERT_GE(uninterrupted.front.size(), 3u);
  const long long all_calls = counter.calls;
  counter.calls = 0;
  counter.limit = all_calls / 3;
  const auto stopped = solve_with(*problem, options, counter, file, false);
  EXPECT_EQ(stopped.status, hapsyn::SolverStatus::kStopped);
  EXPECT_FALSE(stopped.front.empty());
  EXPECT_NE(stopped.message.find("front so far: "), std::string::npos) << stopped.message;
  counter.stop = false;
  counter.limit = -1;
  const auto resumed = solve_with(*problem, options, counter, file, true);
  ASSERT_EQ(resumed.status, hapsyn::SolverStatus::kConverged) << resumed.message;
  expect_same_points(resumed.front, uninterrupted.front);

  // A front point's objective value edited (checksum recomputed) is refused on re-evaluation.
  counter.calls = 0;
  counter.limit = all_calls / 3;
  counter.stop = false;
  (void)solve_with(*problem, options, counter, file, false);
  counter.stop = false;
  counter.limit = -1;
  Json edited = hapsyn::test::read_json_file(file);
  ASSERT_FALSE(edited["state"]["front"].empty());
  edited["state"]["front"][0]["objectives"][0] = 99.0;
  hapsyn::test::write_json_file(file, edited, true);
  hapsyn::test::expect_error([&] { solve_with(*problem, options, counter, file, true); },
                             {"checkpoint: " + file + ": state.front[0]: grid design ", "the checkpoint claims [99",
                              "; delete it, or run without --resume"});
  std::filesystem::remove_all(dir);
}

TEST(Grid, DamagedEditedAndForeignCheckpointsAreRefused) {
  hapsyn::test::StopAfter counter;
  const auto problem = hapsyn::test::stopping_problem(counter);
  const std::string dir = hapsyn::test::fresh_directory("grid-bad");
  const std::string file = dir + "/checkpoint.json";
  const Json options = {{"progress_interval", 1e9}};
  (void)solve_with(*problem, options, counter, "", false);
  const long long all_calls = counter.calls;
  auto stop_midway = [&] {
    counter.calls = 0;
    counter.limit = all_calls / 3;
    counter.stop = false;
    const auto r = solve_with(*problem, options, counter, file, false);
    ASSERT_EQ(r.status, hapsyn::SolverStatus::kStopped);
    counter.limit = -1;
    counter.stop = false;
  };
  auto resume = [&] { solve_with(*problem, options, counter, file, true); };
  using hapsyn::test::expect_error;

  stop_midway();
  hapsyn::test::truncate_file(file);
  expect_error(resume, {"checkpoint: " + file + ": not valid JSON (truncated or damaged); delete it, or run without --resume"});

  stop_midway();
  Json edited = hapsyn::test::read_json_file(file);
  ASSERT_TRUE(edited["state"]["best"].is_object());
  edited["state"]["best"]["score"] = 99.0;
  hapsyn::test::write_json_file(file, edited, false);
  expect_error(resume, {"checkpoint: " + file + ": damaged or edited (its checksum does not match its content)"});
  hapsyn::test::write_json_file(file, edited, true);
  expect_error(resume, {"checkpoint: " + file + ": state.best: grid design ", "on re-evaluation, the checkpoint claims 99",
                        "; delete it, or run without --resume"});

  stop_midway();
  edited = hapsyn::test::read_json_file(file);
  edited["state"].erase("finished_prefix");
  hapsyn::test::write_json_file(file, edited, true);
  expect_error(resume, {"checkpoint: " + file + ": state.finished_prefix is missing"});
  edited["state"]["finished_prefix"] = "ten";
  hapsyn::test::write_json_file(file, edited, true);
  expect_error(resume, {"checkpoint: " + file + ": state.finished_prefix = \"ten\": not of the expected type"});

  stop_midway();
  edited = hapsyn::test::read_json_file(file);
  edited["solver"] = "culling";
  hapsyn::test::write_json_file(file, edited, true);
  expect_error(resume, {"checkpoint: " + file + ": written by solver \"culling\", this study's solver is \"grid\""});

  stop_midway();
  expect_error([&] { solve_with(*problem, {{"prune", false}, {"progress_interval", 1e9}}, counter, file, true); },
               {"checkpoint: " + file + ": written for another study"});
  // The intervals are not part of the study: a resumed run may change them.
  const auto r = solve_with(*problem, {{"progress_interval", 5.0}, {"checkpoint_interval", 1.0}}, counter, file, true);
  EXPECT_EQ(r.status, hapsyn::SolverStatus::kConverged) << r.message;
  std::filesystem::remove_all(dir);
}

TEST(Grid, NonMonotoneMetricFailsWithPruningAndRunsWithout) {
  const auto problem = hapsyn::test::non_monotone_problem();
  hapsyn::SolverContext context;
  context.threads = 2;
  const auto failed = grid_solver({{"progress_interval", 1e9}}).solve(*problem, context);
  EXPECT_EQ(failed.status, hapsyn::SolverStatus::kFailed);
  EXPECT_FALSE(failed.best.has_value());
  for (const char* part : {"metric 'bad' (objective 'bad') breaks the worst-case monotonicity rule: its value over ",
                           " of the 8 samples is ", "below its value over the whole scene ", "(design {",
                           "grid pruning relies on that rule", "prune: false"}) {
    EXPECT_NE(failed.message.find(part), std::string::npos) << failed.message << "\nmissing: " << part;
  }
  const auto unpruned = grid_solver({{"prune", false}, {"progress_interval", 1e9}}).solve(*problem, context);
  EXPECT_EQ(unpruned.status, hapsyn::SolverStatus::kConverged) << unpruned.message;
}

TEST(Grid, StopBeforeAnyFeasibleDesignIsAStatusWithACheckpoint) {
  hapsyn::test::StopAfter counter;
  counter.stop = true;  // before the first design (a stop is honoured between designs)
  const auto problem = hapsyn::test::stopping_problem(counter);
  const std::string dir = hapsyn::test::fresh_directory("grid-stop-early");
  const std::string file = dir + "/checkpoint.json";
  const auto stopped = solve_with(*problem, {{"progress_interval", 1e9}}, counter, file, false, 1);
  EXPECT_EQ(stopped.status, hapsyn::SolverStatus::kStopped);
  EXPECT_FALSE(stopped.best.has_value());
  EXPECT_NE(stopped.message.find("stopped on request after 0.0% of 2,601 grid designs; no feasible design yet; "
                                 "checkpoint " + file + " written, resume with --resume"),
            std::string::npos)
      << stopped.message;
  EXPECT_TRUE(hapsyn::test::read_json_file(file)["state"]["best"].is_null());
  counter.stop = false;
  counter.limit = -1;
  const auto resumed = solve_with(*problem, {{"progress_interval", 1e9}}, counter, file, true, 1);
  EXPECT_EQ(resumed.status, hapsyn::SolverStatus::kConverged) << resumed.message;
  std::filesystem::remove_all(dir);
}

TEST(Grid, NonMonotoneMetricFailsInParetoModeWithPruning) {
  const auto problem = hapsyn::test::metric_problem(
      0.1, {std::make_shared<hapsyn::test::NonMonotoneMetric>(), std::make_shared<hapsyn::test::NonMonotoneMetric>()},
      {"bad1", "bad2"});
  hapsyn::SolverContext context;
  context.threads = 2;
  const auto failed = grid_solver({{"pareto", true}, {"progress_interval", 1e9}}).solve(*problem, context);
  EXPECT_EQ(failed.status, hapsyn::SolverStatus::kFailed);
  EXPECT_TRUE(failed.front.empty());
  EXPECT_NE(failed.message.find("breaks the worst-case monotonicity rule"), std::string::npos) << failed.message;
  EXPECT_NE(failed.message.find("metric 'bad"), std::string::npos) << failed.message;
  const auto unpruned = grid_solver({{"pareto", true}, {"prune", false}, {"progress_interval", 1e9}}).solve(*problem, context);
  EXPECT_EQ(unpruned.status, hapsyn::SolverStatus::kConverged) << unpruned.message;
}

TEST(Grid, RefusesAGridLargerThanMaxDesignsAtLoad) {
  Json doc = hapsyn::test::fivebar_study("grid");
  doc["solver"]["options"]["max_designs"] = 100;  // the test grid has 4 x 6 x 6 x 7 = 1008 designs
  hapsyn::test::expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); },
                             {"grid: the design grid has 1.01e+03 designs (l0: 4 x l1: 6 x l2: 6 x r: 7), more than "
                              "solver.options.max_designs = 100; use larger steps or fix variables, or raise max_designs "
                              "deliberately"});
  doc["solver"]["options"]["max_designs"] = 1008;
  EXPECT_NO_THROW(hapsyn::load_study(doc, hapsyn::test::registry()));
}

namespace {
// Status, best (design, score, objectives) and front of two results, bit for bit.
void expect_same_result(const hapsyn::SolverResult& a, const hapsyn::SolverResult& b) {
  EXPECT_EQ(a.status, b.status) << a.message << "\n" << b.message;
  ASSERT_EQ(a.best.has_value(), b.best.has_value());
  if (a.best) {
    EXPECT_EQ(a.best->design, b.best->design);
    EXPECT_EQ(a.best->score, b.best->score);
    EXPECT_EQ(a.best->objectives, b.best->objectives);
  }
  expect_same_points(a.front, b.front);
}

// The analytic problem of the stop tests: one objective on a 2,601-design grid (41 chunks), or
// two on a 441-design grid (7 chunks).
std::shared_ptr<hapsyn::Problem> shard_problem(hapsyn::test::StopAfter& counter, bool pareto) {
  return hapsyn::test::stopping_problem(counter, pareto ? 0.05 : 0.02, pareto);
}
}  // namespace

TEST(Grid, ShardsMergedAndResumedGiveThePlainRunInBothModes) {
  for (bool pareto : {false, true}) {
    for (bool prune : {true, false}) {
      hapsyn::test::StopAfter counter;
      const auto problem = shard_problem(counter, pareto);
      const Json options = {{"pareto", pareto}, {"prune", prune}, {"progress_interval", 1e9}};
      const hapsyn::plugins::GridSolver solver = grid_solver(options);
      const auto plain = solve_with(*problem, options, counter, "", false);
      ASSERT_EQ(plain.status, hapsyn::SolverStatus::kConverged) << plain.message;
      const auto solve = [&](const hapsyn::SolverContext& context) { return solver.solve(*problem, context); };
      for (int count : {1, 2, 3}) {
        SCOPED_TRACE("pareto " + std::to_string(pareto) + ", prune " + std::to_string(prune) + ", shards " +
                     std::to_string(count));
        const std::string dir = hapsyn::test::fresh_directory("grid-shards");
        const auto merged = hapsyn::test::shard_merge_resume(solver, *problem, count, dir, solve,
                                                             [&](int k, const hapsyn::SolverResult& r) {
          if (count == 1) {
            expect_same_result(r, plain);  // one share is the whole run
            return;
          }
          EXPECT_EQ(r.status, hapsyn::SolverStatus::kStopped);
          EXPECT_NE(r.message.find("shard " + std::to_string(k + 1) + "/" + std::to_string(count) +
                                   " done: combine the shards' output directories with hapsyn merge"),
                    std::string::npos)
              << r.message;
        });
        expect_same_result(merged, plain);
        if (!prune) {  // without pruning the counts do not depend on the split
          EXPECT_EQ(merged.statistics["feasible"], plain.statistics["feasible"]);
          EXPECT_EQ(merged.sample_evaluations, plain.sample_evaluations);
        }
        if (count == 3 && !pareto) {
          // The middle share is one range of chunks, 41 * 1/3 .. 41 * 2/3.
          const Json state = hapsyn::test::read_json_file(dir + "/shard-1.json")["state"];
          EXPECT_EQ(state["finished_prefix"], 0);
          EXPECT_EQ(state["finished_ranges"], Json::array({Json::array({13, 27})}));
          // A share left out of the merge: the resumed run visits its chunks itself.
          const auto missing = hapsyn::test::shard_merge_resume(solver, *problem, 3, dir, solve,
                                                                [](int, const hapsyn::SolverResult&) {}, {0, 2});
          expect_same_result(missing, plain);
        }
        std::filesystem::remove_all(dir);
      }
    }
  }
}

TEST(Grid, MergeRefusesOverlappingSharesAndStatesThatDoNotFit) {
  hapsyn::test::StopAfter counter;
  const auto problem = shard_problem(counter, false);
  const hapsyn::plugins::GridSolver solver = grid_solver({{"progress_interval", 1e9}});
  const std::string dir = hapsyn::test::fresh_directory("grid-merge-bad");
  std::vector<Json> states;
  for (int k : {0, 1}) {
    hapsyn::ShardCluster shard(k, 2);
    hapsyn::SolverContext context;
    context.ranks = &shard;
    context.checkpoint_file = dir + "/shard.json";
    (void)solver.solve(*problem, context);
    states.push_back(hapsyn::test::read_json_file(context.checkpoint_file)["state"]);
  }
  using hapsyn::test::expect_error;
  expect_error([&] { solver.merge_shards(*problem, {states[0], states[0]}); },
               {"merge: chunk 0 (grid designs 0..63) is finished in shard 1 and in shard 2 of 2: the shares overlap; "
                "merge the shards of one --shard i/N split, each once"});
  expect_error([&] { solver.merge_shards(*problem, {states[0], states[1], states[1]}); },
               {"merge: chunk 20 (grid designs 1280..1343) is finished in shard 2 and in shard 3 of 3"});
  expect_error([&] { solver.merge_shards(*problem, {}); }, {"merge: no shard states to merge"});
  Json broken = states[1];
  broken.erase("tally");
  expect_error([&] { solver.merge_shards(*problem, {states[0], broken}); }, {"merge: shard 2/2: state.tally is missing"});
  broken = states[1];
  broken["finished_ranges"] = Json::array({Json::array({30, 99})});
  expect_error([&] { solver.merge_shards(*problem, {states[0], broken}); },
               {"merge: shard 2/2: state.finished_ranges: chunk 98 must lie in (0, 41)"});
  hapsyn::test::StopAfter counter2;
  const auto two = shard_problem(counter2, true);
  expect_error([&] { grid_solver({{"pareto", true}}).merge_shards(*two, {states[0]}); },
               {"merge: shard 1/1: state.mode = \"best\", this run's mode is \"front\""});
  // The shares of one split merge whatever their order.
  EXPECT_EQ(solver.merge_shards(*problem, {states[1], states[0]})["best"],
            solver.merge_shards(*problem, {states[0], states[1]})["best"]);
  std::filesystem::remove_all(dir);
}

TEST(Grid, EmulatedRanksGiveThePlainRunInBothModes) {
  for (bool pareto : {false, true}) {
    hapsyn::test::StopAfter counter;
    const auto problem = shard_problem(counter, pareto);
    const Json options = {{"pareto", pareto}, {"progress_interval", 1e9}};
    const hapsyn::plugins::GridSolver solver = grid_solver(options);
    const auto plain = solve_with(*problem, options, counter, "", false);
    ASSERT_EQ(plain.status, hapsyn::SolverStatus::kConverged) << plain.message;
    const std::string dir = hapsyn::test::fresh_directory("grid-ranks");
    for (int ranks : {2, 3}) {
      SCOPED_TRACE("pareto " + std::to_string(pareto) + ", ranks " + std::to_string(ranks));
      hapsyn::test::EmulatedRanks job(ranks);
      const auto results = job.run([&](hapsyn::Cluster& cluster) {
        hapsyn::SolverContext context;
        context.threads = 2;
        context.seed = 11;
        context.ranks = &cluster;
        context.checkpoint_file = dir + "/checkpoint.json";
        return solver.solve(*problem, context);
      });
      expect_same_result(results[0], plain);
      const auto& s = results[0].statistics;
      EXPECT_EQ(s["feasible"].get<long long>() + s["pruned"].get<long long>() + s["sample_failed"].get<long long>() +
                    s["constraint_violated"].get<long long>(),
                s["grid_designs"].get<long long>());
      EXPECT_EQ(results[1].message, "rank 1: the result is rank 0's");
    }
    // A shard's checkpoint resumed on three ranks: they agree on the chunks left and finish them.
    hapsyn::ShardCluster shard(1, 2);
    hapsyn::SolverContext context;
    context.ranks = &shard;
    context.seed = 11;
    context.checkpoint_file = dir + "/checkpoint.json";
    ASSERT_EQ(solver.solve(*problem, context).status, hapsyn::SolverStatus::kStopped);
    hapsyn::test::EmulatedRanks job(3);
    const auto resumed = job.run([&](hapsyn::Cluster& cluster) {
      hapsyn::SolverContext c = context;
      c.ranks = &cluster;
      c.resume = true;
      return solver.solve(*problem, c);
    });
    expect_same_result(resumed[0], plain);
    std::filesystem::remove_all(dir);
  }
}

TEST(Grid, LargeGridsRunGroupsOfChunksPerTaskWithTheSameResult) {
  // 501 x 501 designs: 3,922 chunks, 15 per task (hapsyn::plugins::units_per_task).
  hapsyn::test::StopAfter counter;
  const auto problem = hapsyn::test::stopping_problem(counter, 0.002);
  const Json options = {{"progress_interval", 1e9}};
  const hapsyn::plugins::GridSolver solver = grid_solver(options);
  const auto plain = solve_with(*problem, options, counter, "", false);
  ASSERT_EQ(plain.status, hapsyn::SolverStatus::kConverged) << plain.message;
  const std::string dir = hapsyn::test::fresh_directory("grid-groups");
  const auto solve = [&](const hapsyn::SolverContext& context) { return solver.solve(*problem, context); };
  const auto merged = hapsyn::test::shard_merge_resume(solver, *problem, 3, dir, solve, [](int, const hapsyn::SolverResult&) {});
  expect_same_result(merged, plain);
  // The shares are whole tasks: 262 tasks of 15 chunks (the last of 7), the middle share tasks 87..173.
  const Json state = hapsyn::test::read_json_file(dir + "/shard-1.json")["state"];
  EXPECT_EQ(state["finished_ranges"], Json::array({Json::array({1305, 2610})}));
  hapsyn::test::EmulatedRanks job(2);
  const auto results = job.run([&](hapsyn::Cluster& cluster) {
    hapsyn::SolverContext context;
    context.threads = 2;
    context.ranks = &cluster;
    return solver.solve(*problem, context);
  });
  expect_same_result(results[0], plain);
  std::filesystem::remove_all(dir);
}

TEST(Grid, ABreachFoundOnAnyRankFailsTheRunOnRankZero) {
  const auto one = hapsyn::test::non_monotone_problem();
  const auto two = hapsyn::test::metric_problem(
      0.1, {std::make_shared<hapsyn::test::NonMonotoneMetric>(), std::make_shared<hapsyn::test::NonMonotoneMetric>()},
      {"bad1", "bad2"});
  for (bool pareto : {false, true}) {
    const hapsyn::plugins::GridSolver solver = grid_solver({{"pareto", pareto}, {"progress_interval", 1e9}});
    const hapsyn::Problem& problem = pareto ? *two : *one;
    for (int ranks : {2, 3}) {
      hapsyn::test::EmulatedRanks job(ranks);
      const auto results = job.run([&](hapsyn::Cluster& cluster) {
        hapsyn::SolverContext context;
        context.threads = 1;
        context.ranks = &cluster;
        return solver.solve(problem, context);
      });
      EXPECT_EQ(results[0].status, hapsyn::SolverStatus::kFailed) << results[0].message;
      EXPECT_NE(results[0].message.find("breaks the worst-case monotonicity rule"), std::string::npos) << results[0].message;
      EXPECT_NE(results[0].message.find("grid pruning relies on that rule"), std::string::npos) << results[0].message;
    }
  }
}

namespace {

// The five-bar study on a finer design grid (r in 10 mm steps): many lines start and end with
// designs the reach constraint rules out.
Json line_bound_study() {
  Json doc = hapsyn::test::fivebar_study();
  doc["design"]["l0"] = {{"lower", 0.0}, {"upper", 0.3}, {"step", 0.05}};
  doc["design"]["r"] = {{"lower", 0.0}, {"upper", 0.6}, {"step", 0.01}};
  return doc;
}

Json without_seconds(Json statistics) {
  statistics.erase("seconds");
  return statistics;
}

// The five-bar's model, constraints and constraint interval, without its one-run promise
// (constraints_quasiconvex keeps the default false).
using WithoutPromise = hapsyn::test::ForwardingMechanism;

// The five-bar with a constraint interval that cuts 0.1 m off the top of the true one.
class NarrowedBound final : public WithoutPromise {
 public:
  using WithoutPromise::ForwardingMechanism;
  bool constraint_interval(const double* design, int component, const hapsyn::SampleSet& scene, double& lower,
                           double& upper) const override {
    if (!WithoutPromise::constraint_interval(design, component, scene, lower, upper)) return false;
    upper -= 0.1;
    return true;
  }
};

}  // namespace

TEST(GridLineBound, SkippingRuledOutDesignsGivesTheSameResultAndStatistics) {
  const hapsyn::Study study = hapsyn::load_study(line_bound_study(), hapsyn::test::registry());
  for (const bool prune : {false, true}) {
    for (const bool pareto : {false, true}) {
      // Block bounds act on verified lines only, so they would change the counts: off here.
      Json base = {{"prune", prune}, {"pareto", pareto}, {"block_bounds", false}, {"progress_interval", 2.0}};
      Json off = base;
      off["line_bounds"] = false;
      Json on = base;
      on["line_bounds"] = true;
      const hapsyn::Study& s = study;
      Json doc = line_bound_study();
      if (pareto) doc["objectives"] = Json::array({Json{{"metric", "gii"}}, Json{{"metric", "gdi"}}});
      const hapsyn::Study two = hapsyn::load_study(doc, hapsyn::test::registry());
      const hapsyn::Problem& problem = pareto ? *two.problem : *s.problem;
      hapsyn::SolverContext context;
      context.threads = prune ? 1 : 2;  // what pruning cuts depends on the threads' timing
      const auto with = grid_solver(on).solve(problem, context);
      const auto without = grid_solver(off).solve(problem, context);
      EXPECT_EQ(without_seconds(with.statistics), without_seconds(without.statistics)) << base.dump();
      EXPECT_EQ(with.status, without.status);
      ASSERT_EQ(with.best.has_value(), without.best.has_value());
      if (with.best) {
        EXPECT_EQ(with.best->design, without.best->design);
      }
      ASSERT_EQ(with.front.size(), without.front.size());
      for (std::size_t i = 0; i < with.front.size(); ++i) EXPECT_EQ(with.front[i].design, without.front[i].design);
      // The bound did rule out designs: most of this grid violates reach.
      EXPECT_GT(with.statistics["constraint_violated"].get<long long>(), with.statistics["grid_designs"].get<long long>() / 3);
    }
  }
}

TEST(GridLineBound, OneRunPromiseMakesTheBoundExactOnEveryLine) {
  // The five-bar promises one feasible run along r: the bound then excludes exactly the designs
  // whose constraints fail (checked design by design) and verifies the rest; without the
  // promise (NarrowedBound forwards no constraints_quasiconvex) nothing is verified.
  const hapsyn::Study study = hapsyn::load_study(line_bound_study(), hapsyn::test::registry());
  const hapsyn::Problem& p = *study.problem;
  const hapsyn::DesignSpace& space = p.design_space();
  const std::vector<long long> counts = space.grid_counts();
  long long total = 1;
  for (long long c : counts) total *= c;
  const long long line_length = counts.back(), lines = total / line_length;
  hapsyn::plugins::LineBound bound(p, true, "grid");
  std::vector<double> x(space.free_size()), g(p.constraint_count());
  long long verified = 0, excluded = 0;
  for (long long line = 0; line < lines; ++line) {
    space.grid_point(line * line_length, counts, x.data());
    bound.update(x.data());
    bool any = false;
    for (long long i = 0; i < line_length; ++i) {
      x.back() = space.grid_value(x.size() - 1, i);
      const bool holds = p.constraints(x.data(), g.data());
      ASSERT_EQ(bound.excludes(i), !holds) << "line " << line << ", r index " << i;
      any = any || holds;
      excluded += !holds;
    }
    EXPECT_EQ(bound.verified(), any) << "line " << line;
    verified += bound.verified();
  }
  EXPECT_GT(verified, lines / 4);
  EXPECT_GT(excluded, total / 3);

  const std::shared_ptr<const hapsyn::Mechanism> fivebar(std::shared_ptr<const hapsyn::Mechanism>{}, &p.mechanism());
  const auto unpromised = std::make_shared<hapsyn::Problem>(
      "no-promise", std::make_shared<WithoutPromise>(fivebar), std::make_shared<hapsyn::SampleSet>(p.samples()),
      p.metrics(), p.objectives(), p.design_space());
  hapsyn::plugins::LineBound plain(*unpromised, true, "grid");
  for (long long line = 0; line < lines; ++line) {
    space.grid_point(line * line_length, counts, x.data());
    plain.update(x.data());
    EXPECT_FALSE(plain.verified());
  }
}

TEST(GridLineBound, ABoundThatCutsAFeasibleDesignStopsTheRunNamingIt) {
  const hapsyn::Study study = hapsyn::load_study(line_bound_study(), hapsyn::test::registry());
  const hapsyn::Problem& p = *study.problem;
  const std::shared_ptr<const hapsyn::Mechanism> fivebar(std::shared_ptr<const hapsyn::Mechanism>{}, &p.mechanism());
  const auto problem = std::make_shared<hapsyn::Problem>(
      "narrowed", std::make_shared<NarrowedBound>(fivebar), std::make_shared<hapsyn::SampleSet>(p.samples()), p.metrics(),
      p.objectives(), p.design_space());
  hapsyn::test::expect_error([&] { grid_solver(Json{{"progress_interval", 2.0}}).solve(*problem, hapsyn::SolverContext{}); },
                             {"grid: the mechanism's constraint_interval for design component 3 excludes the design",
                              "whose constraints hold", "line_bounds = false"});
  // Without the bound the same problem runs.
  const auto result = grid_solver(Json{{"line_bounds", false}, {"progress_interval", 2.0}}).solve(*problem, hapsyn::SolverContext{});
  EXPECT_TRUE(result.best.has_value());
}

// ---------------------------------------------------------------------------------------------
// Block bounds (shared/bounds/run_bounds.hpp, shared/bounds/BLOCK_BOUNDS.md section 13.5).

TEST(GridBlockBounds, GiveTheExhaustiveOptimumOnLongLines) {
  // Random sub-boxes with long lines of r, GII, GDI and a weighted sum of both: the pruned grid
  // with block bounds returns the unpruned grid's optimum (design and score, bit for bit), on
  // one thread and two, and its counts add up to the grid.
  std::mt19937 rng(91);
  const std::vector<Json> objective_sets = {
      Json::array({{{"metric", "gii"}}}), Json::array({{{"metric", "gdi"}}}),
      Json::array({{{"metric", "gii"}, {"weight", 0.6}}, {{"metric", "gdi"}, {"weight", 0.4}}})};
  int compared = 0;
  long long ruled_out = 0, failed_or_pruned = 0;
  for (int box = 0; box < 8; ++box) {
    Json doc = hapsyn::test::fivebar_random_long_lines(rng, "grid");
    for (const Json& objectives : objective_sets) {
      doc["objectives"] = objectives;
      const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
      hapsyn::SolverContext context;
      context.threads = 2;
      const auto exhaustive = grid_solver(Json{{"prune", false}, {"progress_interval", 1e9}}).solve(*study.problem, context);
      for (int threads : {1, 2}) {
        context.threads = threads;
        const auto with = grid_solver(Json{{"block_bounds", true}, {"progress_interval", 1e9}}).solve(*study.problem, context);
        ASSERT_EQ(with.status, exhaustive.status) << with.message << "\n" << doc.dump();
        const Json& st = with.statistics;
        EXPECT_EQ(st["feasible"].get<long long>() + st["constraint_violated"].get<long long>() +
                      st["sample_failed"].get<long long>() + st["pruned"].get<long long>(),
                  st["grid_designs"].get<long long>());
        EXPECT_EQ(st["constraint_violated"], exhaustive.statistics["constraint_violated"]) << doc.dump();
        ruled_out += st["block_ruled_out"].get<long long>();
        failed_or_pruned += st["sample_failed"].get<long long>() + st["pruned"].get<long long>();
        if (!exhaustive.best) continue;
        ASSERT_TRUE(with.best.has_value());
        EXPECT_EQ(with.best->design, exhaustive.best->design) << doc.dump();
        EXPECT_EQ(with.best->score, exhaustive.best->score) << doc.dump();
        ++compared;
      }
    }
  }
  EXPECT_GE(compared, 20);
  EXPECT_GT(ruled_out, failed_or_pruned / 4) << "the block bounds should rule out a good part of these lines";
}

TEST(GridBlockBounds, OffLeavesTheCountsOfThePrunedSearch) {
  // block_bounds = false is the pruned search of before (no runs tried); on one thread, with
  // them, the same optimum and constraint counts, fewer samples solved.
  Json doc = line_bound_study();
  doc["design"]["r"]["step"] = 0.005;
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  hapsyn::SolverContext context;
  context.threads = 1;
  const auto with = grid_solver(Json{{"progress_interval", 1e9}}).solve(*study.problem, context);
  const auto without = grid_solver(Json{{"block_bounds", false}, {"progress_interval", 1e9}}).solve(*study.problem, context);
  ASSERT_TRUE(with.best && without.best);
  EXPECT_EQ(with.best->design, without.best->design);
  EXPECT_EQ(with.best->score, without.best->score);
  EXPECT_EQ(without.statistics["block_bounds"], 0);
  EXPECT_EQ(without.statistics["block_ruled_out"], 0);
  EXPECT_GT(with.statistics["block_ruled_out"].get<long long>(), 0);
  EXPECT_EQ(with.statistics["constraint_violated"], without.statistics["constraint_violated"]);
  EXPECT_LT(with.sample_evaluations, without.sample_evaluations);
}

TEST(GridBlockBounds, AWrongEnvelopeStopsTheRunNamingIt) {
  // A mechanism whose envelope claims every design of every run fails: the spot check of the
  // first ruled-out run refutes it, and the run stops with an error instead of an optimum.
  const hapsyn::Study study = hapsyn::load_study(line_bound_study(), hapsyn::test::registry());
  const hapsyn::Problem& p = *study.problem;
  const std::shared_ptr<const hapsyn::Mechanism> fivebar(std::shared_ptr<const hapsyn::Mechanism>{}, &p.mechanism());
  const auto problem = std::make_shared<hapsyn::Problem>(
      "false-envelope", std::make_shared<hapsyn::test::AllFailEnvelope>(fivebar),
      std::make_shared<hapsyn::SampleSet>(p.samples()), p.metrics(), p.objectives(), p.design_space());
  hapsyn::SolverContext context;
  context.threads = 1;
  hapsyn::test::expect_error([&] { grid_solver(Json{{"progress_interval", 1e9}}).solve(*problem, context); },
                             {"grid: the mechanism's block bound (MechanismAcceleration::sample_envelope) is wrong: over r in [",
                              "it claims that every design fails, but grid value", "reaches the sample and scores",
                              "grid could cut the optimum: set solver.options.block_bounds = false"});
  const auto result = grid_solver(Json{{"block_bounds", false}, {"progress_interval", 1e9}}).solve(*problem, context);
  EXPECT_TRUE(result.best.has_value());
}

// The five-bar (line bounds and their one-run promise included) whose envelope bounds only
// sample `decider` (GII <= 1, true of every design) and proves nothing elsewhere; it counts the
// envelopes asked for, per sample.
class OneDecidingSample final : public hapsyn::test::ForwardingMechanism {
 public:
  OneDecidingSample(std::shared_ptr<const hapsyn::Mechanism> inner, const hapsyn::SampleSet& scene, int decider)
      : ForwardingMechanism(std::move(inner)), scene_(scene), decider_(decider), calls_(scene.size(), 0) {}
  bool constraints_quasiconvex(int component) const override { return inner_acceleration().constraints_quasiconvex(component); }
  bool sample_envelope(const double*, int, double, double, const double* pose, hapsyn::Needs,
                       hapsyn::SampleEnvelope& out) const override {
    int sample = 0;
    while (scene_.pose(sample) != pose) ++sample;
    ++calls_[static_cast<std::size_t>(sample)];
    if (sample != decider_) return false;
    out = hapsyn::SampleEnvelope{};
    out.jacobian_inverse_condition_max = 1.0;
    return true;
  }
  long long calls(int sample) const { return calls_[static_cast<std::size_t>(sample)]; }

 private:
  const hapsyn::SampleSet& scene_;
  int decider_;
  mutable std::vector<long long> calls_;
};

TEST(RunBounds, ATryStartsWithTheSampleThatDecidedThePreviousLineThere) {
  const hapsyn::Study study = hapsyn::load_study(line_bound_study(), hapsyn::test::registry());
  const hapsyn::Problem& p = *study.problem;
  const std::shared_ptr<const hapsyn::Mechanism> fivebar(std::shared_ptr<const hapsyn::Mechanism>{}, &p.mechanism());
  const auto scene = std::make_shared<hapsyn::SampleSet>(p.samples());
  const int first = 0, decider = 1;
  const auto mechanism = std::make_shared<OneDecidingSample>(fivebar, *scene, decider);
  const hapsyn::Problem problem("one-decider", mechanism, scene, p.metrics(), p.objectives(), p.design_space());
  hapsyn::plugins::LineBound line(problem, true, "grid");
  hapsyn::plugins::RunBounds runs(problem, "grid", hapsyn::plugins::RunPolicy{2, false});
  auto scratch = problem.make_eval_scratch();
  // A line with designs inside its bound: l0 = 0, l1 = l2 = 0.3 (r free).
  const std::vector<double> x = {0.0, 0.3, 0.3, 0.0};
  line.update(x.data());
  ASSERT_LE(line.first(), line.last());
  const double above_every_score = 1.5;  // the envelope's bound 1 is below it: the decider rules out
  // The first line has no history: the thread's order decides, and the first sample proves nothing.
  std::vector<int> order = {first, decider};
  runs.start_line(x.data());
  auto t = runs.try_run(line.first(), line.last(), above_every_score, order, line, *scratch);
  ASSERT_TRUE(t.ruled_out());
  EXPECT_EQ(mechanism->calls(first), 1);
  EXPECT_EQ(mechanism->calls(decider), 1);
  EXPECT_EQ(order.front(), decider);  // the deciding sample moved to the front
  // The next line, with the thread's order put back: the previous line's decider goes first.
  order = {first, decider};
  runs.start_line(x.data());
  t = runs.try_run(line.first(), line.last(), above_every_score, order, line, *scratch);
  ASSERT_TRUE(t.ruled_out());
  EXPECT_EQ(mechanism->calls(first), 1) << "the sample that proved nothing here on the previous line was tried again";
  EXPECT_EQ(mechanism->calls(decider), 2);
  EXPECT_EQ(order.front(), decider);
}

// The five-bar whose envelope bounds every sample (GII at most 1) only over runs of r at most
// `width` wide, and knows nothing otherwise; it counts the envelopes asked for.
class ShortRunsOnly final : public hapsyn::test::ForwardingMechanism {
 public:
  ShortRunsOnly(std::shared_ptr<const hapsyn::Mechanism> inner, double width)
      : ForwardingMechanism(std::move(inner)), width_(width) {}
  bool constraints_quasiconvex(int component) const override { return inner_acceleration().constraints_quasiconvex(component); }
  bool sample_envelope(const double*, int, double lower, double upper, const double*, hapsyn::Needs,
                       hapsyn::SampleEnvelope& out) const override {
    ++calls;
    if (upper - lower > width_) return false;
    out = hapsyn::SampleEnvelope{};
    out.jacobian_inverse_condition_max = 1.0;
    return true;
  }
  mutable long long calls = 0;

 private:
  double width_;
};

TEST(RunBounds, ATryThatRulesNothingOutRetriesItsFirstHalfOnce) {
  const hapsyn::Study study = hapsyn::load_study(line_bound_study(), hapsyn::test::registry());
  const hapsyn::Problem& p = *study.problem;
  const std::shared_ptr<const hapsyn::Mechanism> fivebar(std::shared_ptr<const hapsyn::Mechanism>{}, &p.mechanism());
  const auto scene = std::make_shared<hapsyn::SampleSet>(p.samples());
  const std::vector<double> x = {0.0, 0.3, 0.3, 0.0};  // l0 = 0, l1 = l2 = 0.3, r free (step 0.01)
  const double above_every_score = 1.5;               // a bound of 1 rules a run out
  // A line's first try covers 32 designs (0.31 m of r), its first half 16 (0.15 m).
  const auto first_try = [&](double width, std::vector<int> order) {
    const auto mechanism = std::make_shared<ShortRunsOnly>(fivebar, width);
    const hapsyn::Problem problem("short-runs", mechanism, scene, p.metrics(), p.objectives(), p.design_space());
    hapsyn::plugins::LineBound line(problem, true, "grid");
    hapsyn::plugins::RunBounds runs(problem, "grid", hapsyn::plugins::RunPolicy{1, false});
    auto scratch = problem.make_eval_scratch();
    line.update(x.data());
    EXPECT_GE(line.last() - line.first() + 1, 32);
    runs.start_line(x.data());
    const auto t = runs.try_run(line.first(), line.last(), above_every_score, order, line, *scratch);
    return std::make_tuple(t, line.first(), mechanism->calls);
  };
  // The envelope proves the half: it is ruled out in the same try, after two envelopes.
  const auto [half, first, calls] = first_try(0.2, {0});
  ASSERT_TRUE(half.ruled_out());
  EXPECT_EQ(half.last, first + 15);
  EXPECT_EQ(calls, 2);
  // Nor the half: no further retry (a quarter would be proved), the designs are left to the caller.
  const auto [none, first_none, calls_none] = first_try(0.1, {0});
  EXPECT_FALSE(none.ruled_out());
  EXPECT_EQ(none.outcome, hapsyn::plugins::RunBounds::Outcome::kNotRuledOut);
  EXPECT_EQ(calls_none, 2);
}

TEST(GridBlockBounds, AWrongReachableIntervalStopsTheRunNamingIt) {
  // A mechanism that claims no sample can be solved at any r: the spot check of the first line
  // it cuts refutes it, and the run stops with an error instead of reporting no feasible design.
  const hapsyn::Study study = hapsyn::load_study(line_bound_study(), hapsyn::test::registry());
  const hapsyn::Problem& p = *study.problem;
  const std::shared_ptr<const hapsyn::Mechanism> fivebar(std::shared_ptr<const hapsyn::Mechanism>{}, &p.mechanism());
  const auto problem = std::make_shared<hapsyn::Problem>(
      "false-reach", std::make_shared<hapsyn::test::NothingReachable>(fivebar),
      std::make_shared<hapsyn::SampleSet>(p.samples()), p.metrics(), p.objectives(), p.design_space());
  hapsyn::SolverContext context;
  context.threads = 1;
  hapsyn::test::expect_error([&] { grid_solver(Json{{"progress_interval", 1e9}}).solve(*problem, context); },
                             {"grid: the mechanism's line bound (MechanismAcceleration::reachable_interval) is wrong: it claims "
                              "that sample ",
                              "fails for every r outside the interval it gives, but grid value",
                              "lies outside it and reaches the sample; grid could cut the optimum: set "
                              "solver.options.block_bounds = false"});
  const auto result = grid_solver(Json{{"block_bounds", false}, {"progress_interval", 1e9}}).solve(*problem, context);
  EXPECT_TRUE(result.best.has_value());
}

TEST(GridBlockBounds, ReachableIntervalsCutLinesWithTheSameOptimumAndCounts) {
  // A five-bar grid with lines of 61 values of r, with and without block bounds: the same optimum, and the designs
  // cut by the samples' reachable intervals are counted as failing at a sample, so that the
  // counts add up to the grid and only sample failures and prunes trade places.
  Json doc = hapsyn::test::fivebar_study("grid");
  doc["design"]["l0"]["step"] = 0.05;
  doc["design"]["l1"]["step"] = 0.025;
  doc["design"]["l2"]["step"] = 0.025;
  doc["design"]["r"]["step"] = 0.01;
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  hapsyn::SolverContext context;
  context.threads = 2;
  const auto with = grid_solver(Json{{"progress_interval", 1e9}}).solve(*study.problem, context);
  const auto without = grid_solver(Json{{"block_bounds", false}, {"progress_interval", 1e9}}).solve(*study.problem, context);
  ASSERT_TRUE(with.best && without.best);
  EXPECT_EQ(with.best->design, without.best->design);
  EXPECT_EQ(with.best->score, without.best->score);
  EXPECT_EQ(with.design_evaluations, without.design_evaluations);
  EXPECT_EQ(with.statistics["constraint_violated"], without.statistics["constraint_violated"]);
  // Most designs that fail do so without a sample solved.
  EXPECT_GT(with.statistics["block_ruled_out"].get<long long>() * 2, with.statistics["sample_failed"].get<long long>());
  EXPECT_LT(with.sample_evaluations * 2, without.sample_evaluations);
}

TEST(GridChunks, LargeGridsGoInWholeLinesWithTheSameOptimum) {
  // 1,701,900 designs (the coarse GII study's grid, a 20 mm workspace): chunks of two lines of
  // 61. The pruned search with block bounds, on two threads, finds the unpruned optimum, and a
  // checkpoint records the chunk size.
  Json doc = hapsyn::test::fivebar_study();
  doc["design"]["l0"] = {{"lower", 0.0}, {"upper", 0.3}, {"step", 0.01}};
  doc["design"]["l1"] = {{"lower", 0.01}, {"upper", 0.3}, {"step", 0.01}};
  doc["design"]["l2"] = {{"lower", 0.01}, {"upper", 0.3}, {"step", 0.01}};
  doc["design"]["r"] = {{"lower", 0.0}, {"upper", 0.6}, {"step", 0.01}};
  doc["scene"]["options"]["step"] = 0.02;
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  const std::string file = testing::TempDir() + "grid_chunks_checkpoint.json";
  std::remove(file.c_str());
  hapsyn::SolverContext context;
  context.threads = 2;
  const auto exhaustive = grid_solver(Json{{"prune", false}, {"progress_interval", 1e9}}).solve(*study.problem, context);
  context.checkpoint_file = file;
  const auto pruned = grid_solver(Json{{"progress_interval", 1e9}}).solve(*study.problem, context);
  ASSERT_TRUE(exhaustive.best && pruned.best);
  EXPECT_EQ(pruned.best->design, exhaustive.best->design);
  EXPECT_EQ(pruned.best->score, exhaustive.best->score);
  EXPECT_EQ(exhaustive.statistics["grid_designs"], 1701900);
  const Json checkpoint = hapsyn::test::read_json_file(file);
  EXPECT_EQ(checkpoint["state"]["chunk_size"], 122);
  std::remove(file.c_str());
}

TEST(Grid, NoFreeVariableSearchesTheOneDesign) {
  // Every design variable fixed: the grid is one design, in every mode, pruned or not (this
  // crashed: the line of the last free variable was read from an empty list).
  Json doc = hapsyn::test::fivebar_study();
  doc["design"] = {{"l0", {{"value", 0.0}}}, {"l1", {{"value", 0.3}}}, {"l2", {{"value", 0.3}}}, {"r", {{"value", 0.42}}}};
  const hapsyn::Study one = hapsyn::load_study(doc, hapsyn::test::registry());
  doc["objectives"] = Json::array({Json{{"metric", "gii"}}, Json{{"metric", "gdi"}}});
  const hapsyn::Study two = hapsyn::load_study(doc, hapsyn::test::registry());
  auto ws = one.problem->make_eval_scratch();
  const double no_free_variable[1] = {0.0};
  const hapsyn::Evaluation& alone = one.problem->evaluate(no_free_variable, *ws);
  ASSERT_EQ(alone.status, hapsyn::EvalStatus::kFeasible);
  for (const bool prune : {false, true}) {
    for (int threads : {1, 2}) {
      hapsyn::SolverContext context;
      context.threads = threads;
      const auto best = grid_solver(Json{{"prune", prune}, {"progress_interval", 1e9}}).solve(*one.problem, context);
      ASSERT_TRUE(best.best.has_value()) << best.message;
      EXPECT_EQ(best.best->score, alone.score);
      EXPECT_EQ(best.statistics["grid_designs"], 1);
      EXPECT_EQ(best.statistics["feasible"], 1);
      const auto front =
          grid_solver(Json{{"prune", prune}, {"pareto", true}, {"progress_interval", 1e9}}).solve(*two.problem, context);
      ASSERT_EQ(front.front.size(), 1u) << front.message;
      EXPECT_EQ(front.front[0].objectives[0], alone.score);
    }
  }
}
