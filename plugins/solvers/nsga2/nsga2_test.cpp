// nsga2 through the shared pagmo adapter: a known front, determinism, errors.
#include "nsga2.hpp"

#include "test_support.hpp"

#include <cmath>

using hapsyn::Json;

namespace {
Json pareto_study(const Json& options) {
  Json doc = hapsyn::read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/problems/fivebar-pareto-nsga2.json");
  doc["scene"]["options"]["step"] = 0.01;
  doc["solver"]["options"] = options.is_null() ? Json::object() : options;
  return doc;
}

hapsyn::SolverResult solve(const Json& doc, int threads, std::uint64_t seed = 3) {
  hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  hapsyn::SolverContext context;
  context.threads = threads;
  context.seed = seed;
  return study.solver->solve(*study.problem, context);
}
}  // namespace

TEST(Nsga2, FrontIsNonDominatedFeasibleAndSpansTheTradeOff) {
  const auto r = solve(pareto_study({{"population", 32}, {"generations", 40}}), 2);
  ASSERT_FALSE(r.front.empty()) << r.message;
  EXPECT_EQ(r.status, hapsyn::SolverStatus::kBudgetExhausted);
  EXPECT_GE(r.front.size(), 5u);
  for (const auto& a : r.front) {
    for (const auto& b : r.front) {
      const bool dominates = b.objectives[0] >= a.objectives[0] && b.objectives[1] >= a.objectives[1] &&
                             (b.objectives[0] > a.objectives[0] || b.objectives[1] > a.objectives[1]);
      EXPECT_FALSE(dominates);
    }
  }
  // The extremes approach the single-objective optima of Table 2 (GII 0.783, GDI 0.766).
  double best_gii = 0, best_gdi = 0;
  for (const auto& p : r.front) {
    best_gii = std::max(best_gii, p.objectives[0]);
    best_gdi = std::max(best_gdi, p.objectives[1]);
  }
  EXPECT_GT(best_gii, 0.72);
  EXPECT_GT(best_gdi, 0.72);
  EXPECT_LT(best_gii, 0.7835);
  EXPECT_LT(best_gdi, 0.7665);
}

TEST(Nsga2, SameSeedSameFrontWhateverTheThreadCount) {
  const Json doc = pareto_study({{"population", 16}, {"generations", 10}});
  const auto a = solve(doc, 2), b = solve(doc, 1);
  ASSERT_EQ(a.front.size(), b.front.size());
  for (std::size_t i = 0; i < a.front.size(); ++i) {
    EXPECT_EQ(a.front[i].objectives, b.front[i].objectives);
    EXPECT_TRUE(a.front[i].design == b.front[i].design);
  }
  EXPECT_NE(solve(doc, 2, 4).front.front().objectives, a.front.front().objectives);
}

TEST(Nsga2, BadInputNamesThePathTheValueAndTheRule) {
  using hapsyn::test::expect_error;
  expect_error([] { solve(pareto_study({{"population", 18}}), 1); },
               {"nsga2: options.population = 18", "must be a multiple of 4"});
  Json single = pareto_study({});
  single["objectives"] = Json::array({{{"metric", "gii"}}});
  expect_error([&] { solve(single, 1); }, {"nsga2: objectives: 1 objective(s)", "at least two"});
  Json repair = pareto_study({{"sort_descending", {"l9"}}});
  expect_error([&] { solve(repair, 1); }, {"nsga2: options.sort_descending[0] = \"l9\": no such design variable"});
}
