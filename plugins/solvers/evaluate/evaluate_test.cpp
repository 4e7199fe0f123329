// Table 2 of Unal et al. through the whole framework: problem file -> registry -> evaluate.
#include "evaluate.hpp"

#include "test_support.hpp"

using hapsyn::Json;

namespace {
hapsyn::SolverResult run(const Json& doc, int threads = 2) {
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  hapsyn::SolverContext context;
  context.threads = threads;
  return study.solver->solve(*study.problem, context);
}
Json problem(const std::string& file) { return hapsyn::read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/problems/" + file); }
}  // namespace

TEST(Evaluate, ReproducesTable2BestGiiDesign) {
  const auto result = run(problem("fivebar-table2-best-gii.json"));
  ASSERT_EQ(result.status, hapsyn::SolverStatus::kConverged) << result.message;
  EXPECT_NEAR(result.best->objectives[0], 0.783, 0.0005);  // GII
  EXPECT_NEAR(result.best->objectives[1], 0.622, 0.0005);  // GDI
  EXPECT_EQ(result.sample_evaluations, 101 * 101);
}

TEST(Evaluate, ReproducesTable2BestGdiDesign) {
  const auto result = run(problem("fivebar-table2-best-gdi.json"));
  ASSERT_EQ(result.status, hapsyn::SolverStatus::kConverged) << result.message;
  EXPECT_NEAR(result.best->objectives[0], 0.407, 0.0005);
  EXPECT_NEAR(result.best->objectives[1], 0.766, 0.0005);
}

TEST(Evaluate, ResultDoesNotDependOnTheThreadCount) {
  const auto one = run(problem("fivebar-table2-best-gdi.json"), 1);
  const auto three = run(problem("fivebar-table2-best-gdi.json"), 3);
  EXPECT_EQ(one.best->objectives, three.best->objectives);
  EXPECT_EQ(one.statistics, three.statistics);
}

TEST(Evaluate, ViolatedConstraintIsAnInfeasibleStatusNotAnException) {
  Json doc = problem("fivebar-table2-best-gii.json");
  doc["design"]["l1"]["value"] = 0.05;
  doc["design"]["l2"]["value"] = 0.05;
  const auto result = run(doc);
  EXPECT_EQ(result.status, hapsyn::SolverStatus::kInfeasible);
  EXPECT_FALSE(result.best.has_value());
  EXPECT_NE(result.message.find("design constraint 'reach' is violated"), std::string::npos) << result.message;
}

TEST(Evaluate, FailingSampleIsNamedWithItsPosition) {
  Json doc = problem("fivebar-table2-best-gii.json");
  // Long proximal, short distal links: samples near the base fall inside the inner reach radius.
  doc["design"]["l1"]["value"] = 0.3;
  doc["design"]["l2"]["value"] = 0.1;
  doc["design"]["r"]["value"] = 0.25;
  const auto result = run(doc);
  EXPECT_EQ(result.status, hapsyn::SolverStatus::kInfeasible);
  EXPECT_NE(result.message.find("sample "), std::string::npos) << result.message;
  EXPECT_NE(result.message.find("(x = "), std::string::npos) << result.message;
}
