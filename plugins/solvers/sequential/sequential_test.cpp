// Sequential optimization against its definition on a small five-bar grid (brute force per
// value), and its error paths.
#include "sequential.hpp"

#include "analytic_problems.hpp"
#include "test_support.hpp"

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
