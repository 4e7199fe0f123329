// The grid solver is the oracle of later solvers: check it against a plain loop over the grid.
#include "grid.hpp"

#include "analytic_problems.hpp"
#include "test_support.hpp"

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
