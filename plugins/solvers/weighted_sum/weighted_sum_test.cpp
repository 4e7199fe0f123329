// Weighted sums against the closed-form two-objective front: every point lies on the front, but
// none in its convex part (where no weight makes an interior point optimal); bad weights.
#include "weighted_sum.hpp"

#include "analytic_problems.hpp"
#include "test_support.hpp"

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
