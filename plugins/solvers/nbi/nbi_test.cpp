// NBI against closed-form fronts (two objectives with concave and convex parts, three
// objectives on a sphere) and against exhaustive search of the five-bar.
#include "nbi.hpp"

#include "analytic_problems.hpp"
#include "test_support.hpp"

#include <hapsyn/pareto.hpp>

#include <cmath>

using hapsyn::Json;
using hapsyn::test::expect_error;

namespace {
hapsyn::SolverResult solve_nbi(const hapsyn::Problem& problem, Json options) {
  options["shadow_solver"] = {{"plugin", "culling"}, {"options", {{"start_points", 3}, {"progress_interval", 1e9}}}};
  const auto nbi = hapsyn::test::registry().create_solver("nbi", options, "solver");  // creates the shadow solver
  nbi->check(problem);
  hapsyn::SolverContext context;
  context.threads = 2;
  return nbi->solve(problem, context);
}
}  // namespace

TEST(Nbi, TwoObjectivePointsLieOnTheAnalyticFrontIncludingItsConvexPart) {
  const auto problem = hapsyn::test::two_objective_problem();
  const auto result = solve_nbi(*problem, {{"points", 11}});
  ASSERT_EQ(result.status, hapsyn::SolverStatus::kConverged) << result.message;
  ASSERT_GE(result.front.size(), 10u) << result.statistics.dump(1);
  int in_convex_part = 0;
  for (const auto& p : result.front) {
    const double f1 = p.objectives[0], f2 = p.objectives[1];
    EXPECT_NEAR(f2, hapsyn::test::two_objective_front_f2(f1), 2e-4) << "f1 = " << f1;
    EXPECT_NEAR(p.design[1], 0.0, 0.02);
    if (f1 > 0.55 && f1 < 0.95) ++in_convex_part;
  }
  // The grid points spread over the whole front, including the part weighted sums cannot reach.
  EXPECT_GE(in_convex_part, 3);
  EXPECT_NEAR(result.front.front().objectives[0], 1.0, 1e-3);
  EXPECT_NEAR(result.front.back().objectives[0], 0.0, 1e-3);
}

TEST(Nbi, TwoObjectivePointsAreEvenlySpacedAlongTheNormals) {
  const auto problem = hapsyn::test::two_objective_problem();
  const auto result = solve_nbi(*problem, {{"points", 6}});
  ASSERT_EQ(result.front.size(), 6u);
  // Each point lies on the normal through its CHIM point: with the normalized objectives,
  // Ft1 - Ft2 = 2 beta_1 - 1 (the CHIM runs from (1,0) to (0,1), the normal is (1,1)).
  const Json& subs = result.statistics["subproblems"];
  ASSERT_EQ(subs.size(), 4u);
  const double u1 = 1.0, n1 = 0.0;  // f1 range [0, 1]
  const double u2 = hapsyn::test::two_objective_front_f2(0.0), n2 = hapsyn::test::two_objective_front_f2(1.0);
  for (const Json& s : subs) {
    const double b1 = s["beta"][0];
    const double f1 = s["objectives"][0], f2 = s["objectives"][1];
    EXPECT_NEAR((f1 - n1) / (u1 - n1) - (f2 - n2) / (u2 - n2), 2 * b1 - 1, 1e-3) << s.dump();
  }
}

TEST(Nbi, ThreeObjectivePointsLieOnTheSphereAndCoverTheSimplexGrid) {
  const auto problem = hapsyn::test::three_objective_problem();
  const auto result = solve_nbi(*problem, {{"points", 5}});
  ASSERT_EQ(result.status, hapsyn::SolverStatus::kConverged) << result.message;
  EXPECT_EQ(result.statistics["grid_points"].get<int>(), 15);
  EXPECT_GE(result.front.size(), 13u) << result.statistics.dump(1);
  for (const auto& p : result.front) {
    const double norm = std::sqrt(p.objectives[0] * p.objectives[0] + p.objectives[1] * p.objectives[1] +
                                  p.objectives[2] * p.objectives[2]);
    EXPECT_NEAR(norm, 1.0, 1e-3);
  }
  // Spread: no two points closer than a third of the grid spacing on the sphere.
  for (std::size_t i = 0; i < result.front.size(); ++i) {
    for (std::size_t j = i + 1; j < result.front.size(); ++j) {
      double d2 = 0;
      for (int k = 0; k < 3; ++k) d2 += std::pow(result.front[i].objectives[k] - result.front[j].objectives[k], 2);
      EXPECT_GT(std::sqrt(d2), 0.08);
    }
  }
}

TEST(Nbi, FrontIsNonDominatedAndFilteringCanBeSwitchedOff) {
  const auto problem = hapsyn::test::two_objective_problem();
  const auto result = solve_nbi(*problem, {{"points", 5}, {"filter_dominated", false}});
  std::vector<hapsyn::ObjectivePoint> values;
  for (const auto& p : result.front) values.push_back(p.objectives);
  EXPECT_EQ(result.front.size(), result.statistics["candidates"].get<std::size_t>());
  const auto filtered = solve_nbi(*problem, {{"points", 5}});
  std::vector<hapsyn::ObjectivePoint> kept;
  for (const auto& p : filtered.front) kept.push_back(p.objectives);
  EXPECT_EQ(hapsyn::non_dominated(kept, {hapsyn::Sense::kMaximize, hapsyn::Sense::kMaximize}).size(), kept.size());
}

TEST(Nbi, RefusesASingleObjectiveAndIntegerVariables) {
  Json doc = hapsyn::test::fivebar_study("nbi");
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); }, {"nbi: objectives: 1 objective(s)"});
  auto problem = hapsyn::test::two_objective_problem();
  std::vector<hapsyn::DesignComponent> components = problem->design_space().components();
  components[0].integer = true;
  components[0].step = 1.0;
  const auto integer = problem->with_design_space(hapsyn::DesignSpace(components));
  const hapsyn::plugins::NbiSolver nbi(hapsyn::default_options<hapsyn::plugins::NbiOptions>());
  expect_error([&] { nbi.check(*integer); }, {"nbi: design.x0 is integer-valued"});
}

TEST(Nbi, RefusesAnUnknownOrParetoShadowSolver) {
  Json doc = hapsyn::test::fivebar_study("nbi");
  doc["objectives"] = Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  doc["solver"]["options"]["shadow_solver"] = {{"plugin", "cullin"}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); }, {"unknown plugin 'cullin'", "did you mean 'culling'"});
  doc["solver"]["options"]["shadow_solver"] = {{"plugin", "nbi"}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); },
               {"nbi: solver.options.shadow_solver.plugin = \"nbi\"", "must be single-objective"});
  doc["solver"]["options"]["shadow_solver"] = {{"plugin", "gii"}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); },
               {"solver.options.shadow_solver.plugin = \"gii\"", "not a solver plugin"});
  doc["solver"]["options"]["shadow_solver"] = "culling";
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); },
               {"solver.options.shadow_solver", "must be an object"});
}

TEST(Nbi, ShadowSolverThatRefusesTheProblemIsReportedAtLoad) {
  Json doc = hapsyn::test::fivebar_study("nbi");
  doc["objectives"] = Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  doc["design"]["r"].erase("step");
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); },
               {"nbi: solver.options.shadow_solver (objective 'gii')", "design.r has no step"});
}

TEST(Nbi, WithoutARegistryFailsWithAStatus) {
  // Options made without a registry: the shadow solver is never created.
  const auto problem = hapsyn::test::two_objective_problem();
  const hapsyn::plugins::NbiSolver nbi(hapsyn::default_options<hapsyn::plugins::NbiOptions>());
  const auto result = nbi.solve(*problem, hapsyn::SolverContext{});
  EXPECT_EQ(result.status, hapsyn::SolverStatus::kFailed);
  EXPECT_NE(result.message.find("nbi has no shadow solver"), std::string::npos) << result.message;
}

TEST(Nbi, FiveBarFrontIsNotDominatedByExhaustiveSearch) {
  // Coarse five-bar: NBI (continuous designs) against the exhaustive front of a 20 mm grid.
  Json doc = hapsyn::test::fivebar_study("nbi");
  doc["objectives"] = Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  doc["design"] = {{"l0", {{"lower", 0.0}, {"upper", 0.3}, {"step", 0.02}}},
                   {"l1", {{"lower", 0.06}, {"upper", 0.3}, {"step", 0.02}}},
                   {"l2", {{"lower", 0.06}, {"upper", 0.3}, {"step", 0.02}}},
                   {"r", {{"lower", 0.1}, {"upper", 0.5}, {"step", 0.02}}}};
  doc["solver"]["options"] = {{"points", 6}};
  doc["solver"]["options"]["shadow_solver"] = {{"plugin", "culling"}, {"options", {{"progress_interval", 1e9}}}};
  hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  hapsyn::SolverContext context;
  context.threads = 2;
  const auto nbi = study.solver->solve(*study.problem, context);
  ASSERT_EQ(nbi.status, hapsyn::SolverStatus::kConverged) << nbi.message;
  ASSERT_GE(nbi.front.size(), 5u);
  // Exhaustive front of the grid (brute force, every design fully evaluated).
  const auto& problem = *study.problem;
  const auto counts = problem.design_space().grid_counts();
  long long total = 1;
  for (long long c : counts) total *= c;
  std::vector<hapsyn::ObjectivePoint> all;
  auto ws = problem.make_eval_scratch();
  std::vector<double> x(problem.dimension());
  for (long long i = 0; i < total; ++i) {
    problem.design_space().grid_point(i, counts, x.data());
    const auto& e = problem.evaluate(x.data(), *ws);
    if (e.status == hapsyn::EvalStatus::kFeasible) all.push_back(e.objectives);
  }
  const std::vector<hapsyn::Sense> senses(2, hapsyn::Sense::kMaximize);
  for (const auto& p : nbi.front) {
    const auto gap = hapsyn::domination_gap(p.objectives, all, senses);
    EXPECT_LE(gap[0], 0.002) << p.objectives[0] << ", " << p.objectives[1];
    EXPECT_LE(gap[1], 0.002) << p.objectives[0] << ", " << p.objectives[1];
  }
}
