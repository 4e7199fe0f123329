// Dominance, non-dominated filtering, simplex grids and every front indicator on fronts small
// enough to check by hand; the problem file's "indicators" section and its error paths.
#include "test_support.hpp"

#include <hapsyn/pareto.hpp>

#include <boost/filesystem.hpp>

#include <cmath>
#include <fstream>

using hapsyn::Json;
using hapsyn::ObjectivePoint;
using hapsyn::Sense;
using hapsyn::test::expect_error;

namespace {
const std::vector<Sense> kMaxMax = {Sense::kMaximize, Sense::kMaximize};
const std::vector<Sense> kMinMin = {Sense::kMinimize, Sense::kMinimize};
}  // namespace

TEST(Pareto, DominanceRespectsSenses) {
  EXPECT_TRUE(hapsyn::dominates({2, 2}, {1, 2}, kMaxMax));
  EXPECT_FALSE(hapsyn::dominates({1, 2}, {2, 2}, kMaxMax));
  EXPECT_FALSE(hapsyn::dominates({2, 2}, {2, 2}, kMaxMax));  // equal: neither dominates
  EXPECT_FALSE(hapsyn::dominates({3, 1}, {1, 3}, kMaxMax));  // a trade-off
  EXPECT_TRUE(hapsyn::dominates({1, 2}, {2, 2}, kMinMin));
  EXPECT_TRUE(hapsyn::dominates({2, 1}, {1, 2}, {Sense::kMaximize, Sense::kMinimize}));
}

TEST(Pareto, NonDominatedFilterKeepsTradeOffsDropsDominatedAndDuplicates) {
  const std::vector<ObjectivePoint> points = {{1, 3}, {2, 2}, {1.5, 1.5}, {3, 1}, {2, 2}, {0, 0}, {3, 0.5}};
  EXPECT_EQ(hapsyn::non_dominated(points, kMaxMax), (std::vector<std::size_t>{0, 1, 3}));
  // Minimizing both, the same points give the other corner.
  EXPECT_EQ(hapsyn::non_dominated(points, kMinMin), (std::vector<std::size_t>{5}));
  // Three objectives: (1,1,1) is dominated by (1,1,2) only.
  const std::vector<ObjectivePoint> three = {{1, 1, 1}, {1, 1, 2}, {0, 2, 0}, {2, 0, 0}};
  EXPECT_EQ(hapsyn::non_dominated(three, {Sense::kMaximize, Sense::kMaximize, Sense::kMaximize}),
            (std::vector<std::size_t>{1, 2, 3}));
  EXPECT_TRUE(hapsyn::non_dominated({}, kMaxMax).empty());
}

TEST(Pareto, SimplexGridHasTheBinomialCountAndSumsToOne) {
  const auto two = hapsyn::simplex_grid(2, 9);
  ASSERT_EQ(two.size(), 10u);
  EXPECT_EQ(two.front(), (std::vector<double>{1.0, 0.0}));
  EXPECT_EQ(two.back(), (std::vector<double>{0.0, 1.0}));
  EXPECT_DOUBLE_EQ(two[3][1], 3.0 / 9.0);
  const auto three = hapsyn::simplex_grid(3, 4);
  EXPECT_EQ(three.size(), 15u);  // C(6, 2)
  for (const auto& beta : three) EXPECT_NEAR(beta[0] + beta[1] + beta[2], 1.0, 1e-15);
  EXPECT_EQ(hapsyn::simplex_grid(4, 3).size(), 20u);  // C(6, 3)
  expect_error([] { hapsyn::simplex_grid(0, 3); }, {"pareto: simplex grid: objectives = 0: must be >= 1"});
  expect_error([] { hapsyn::simplex_grid(6, 500); }, {"pareto: simplex grid:", "at most 1000000"});
}

TEST(Pareto, HypervolumeOfHandCheckableFronts) {
  // Staircase (1,3), (2,2), (3,1) above (0,0): 3 + 2 + 1 = 6.
  EXPECT_NEAR(hapsyn::hypervolume({{1, 3}, {2, 2}, {3, 1}}, {0, 0}, kMaxMax), 6.0, 1e-12);
  // Dominated and out-of-box points add nothing.
  EXPECT_NEAR(hapsyn::hypervolume({{1, 3}, {2, 2}, {3, 1}, {1, 1}, {-1, 5}}, {0, 0}, kMaxMax), 6.0, 1e-12);
  // Minimizing: the same staircase mirrored below (4, 4): 3*1 + 2*1 + 1*1 = 6.
  EXPECT_NEAR(hapsyn::hypervolume({{3, 1}, {2, 2}, {1, 3}}, {4, 4}, kMinMin), 6.0, 1e-12);
  // Three objectives: a unit cube and a 2x1x1 box overlapping in a unit cube: 2.
  EXPECT_NEAR(hapsyn::hypervolume({{1, 1, 1}, {2, 1, 1}}, {0, 0, 0}, {Sense::kMaximize, Sense::kMaximize, Sense::kMaximize}),
              2.0, 1e-12);
  EXPECT_EQ(hapsyn::hypervolume({}, {0, 0}, kMaxMax), 0.0);
  expect_error([] { hapsyn::hypervolume({{1, 1}}, {0}, kMaxMax); }, {"pareto: hypervolume: the reference point has 1 values for 2"});
  expect_error([] { hapsyn::hypervolume({{1, NAN}}, {0, 0}, kMaxMax); }, {"a front point is not finite"});
}

TEST(Pareto, SpacingIsZeroForEvenFrontsAndMatchesAHandValue) {
  EXPECT_NEAR(hapsyn::spacing({{0, 3}, {1, 2}, {2, 1}, {3, 0}}), 0.0, 1e-15);
  // L1 nearest distances: (0,0)->(1,0): 1; (1,0): 1; (3,0)->(1,0): 2. Mean 4/3;
  // S = sqrt(((1/3)^2 + (1/3)^2 + (2/3)^2) / 2) = sqrt(1/3).
  EXPECT_NEAR(hapsyn::spacing({{0, 0}, {1, 0}, {3, 0}}), std::sqrt(1.0 / 3.0), 1e-15);
  EXPECT_TRUE(std::isnan(hapsyn::spacing({{1, 1}})));
}

TEST(Pareto, GenerationalDistancesAgainstAHandFront) {
  const std::vector<ObjectivePoint> reference = {{0, 1}, {1, 0}};
  // GD: (0, 0.5) is 0.5 from (0,1); (1,0) is on it: mean 0.25.
  EXPECT_NEAR(hapsyn::generational_distance({{0, 0.5}, {1, 0}}, reference), 0.25, 1e-15);
  // IGD: (0,1) -> 0.5, (1,0) -> 0: mean 0.25; a one-point front at (1,0): (sqrt 2 + 0)/2.
  EXPECT_NEAR(hapsyn::inverted_generational_distance({{0, 0.5}, {1, 0}}, reference), 0.25, 1e-15);
  EXPECT_NEAR(hapsyn::inverted_generational_distance({{1, 0}}, reference), std::sqrt(2.0) / 2, 1e-15);
  EXPECT_TRUE(std::isinf(hapsyn::generational_distance({{1, 0}}, {})));
  EXPECT_TRUE(std::isinf(hapsyn::inverted_generational_distance({}, reference)));
}

TEST(Pareto, DominationGapIsTheLargestImprovementPerObjective) {
  const std::vector<ObjectivePoint> front = {{0.78, 0.62}, {0.70, 0.70}, {0.62, 0.74}, {0.41, 0.77}};
  // (0.60, 0.65) is dominated by (0.78, 0.62)? no (0.62 < 0.65); by (0.70, 0.70) and (0.62, 0.74).
  const auto gap = hapsyn::domination_gap({0.60, 0.65}, front, kMaxMax);
  EXPECT_NEAR(gap[0], 0.10, 1e-12);  // (0.70, 0.70)
  EXPECT_NEAR(gap[1], 0.09, 1e-12);  // (0.62, 0.74)
  const auto none = hapsyn::domination_gap({0.78, 0.62}, front, kMaxMax);
  EXPECT_EQ(none, (std::vector<double>{0.0, 0.0}));
}

TEST(Pareto, FrontIndicatorsCollectEveryIndicator) {
  hapsyn::IndicatorInputs in;
  in.names = {"a", "b"};
  in.senses = kMaxMax;
  in.front = {{1, 3}, {2, 2}, {3, 1}};
  in.reference_front = {{1, 3}, {2, 2.5}, {3, 1}};
  in.reference_point = {0, 0};
  const Json j = hapsyn::front_indicators(in);
  EXPECT_EQ(j["points"], 3);
  EXPECT_NEAR(j["hypervolume"].get<double>(), 6.0, 1e-12);
  EXPECT_NEAR(j["spacing"].get<double>(), 0.0, 1e-12);
  EXPECT_EQ(j["dominated_points"], 1);
  EXPECT_NEAR(j["max_domination_gap"]["b"].get<double>(), 0.5, 1e-12);
  EXPECT_NEAR(j["generational_distance"].get<double>(), 0.5 / 3, 1e-12);
  EXPECT_NEAR(j["inverted_generational_distance"].get<double>(), 0.5 / 3, 1e-12);
  EXPECT_EQ(j["extent"]["a"], Json::array({1, 3}));
  const ObjectivePoint best = {1.5, 1.5};
  in.front.clear();
  in.best = &best;
  const Json single = hapsyn::front_indicators(in);
  EXPECT_EQ(single["best_dominated"], true);
  EXPECT_NEAR(single["best_domination_gap"]["a"].get<double>(), 0.5, 1e-12);
  EXPECT_NEAR(single["best_domination_gap"]["b"].get<double>(), 1.0, 1e-12);
}

namespace {
Json pareto_doc() {
  Json doc = hapsyn::test::fivebar_study("nbi");
  doc["objectives"] = Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  return doc;
}
std::string write_temp(const std::string& name, const Json& content) {
  const auto dir = boost::filesystem::temp_directory_path() / "hapsyn-pareto-test";
  boost::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path) << content.dump();
  return path;
}
}  // namespace

TEST(Pareto, IndicatorsSectionIsValidatedWithPathValueAndRule) {
  Json doc = pareto_doc();
  doc["indicators"] = {{"reference_point", {0.0}}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); },
               {"problem: indicators.reference_point = [0.0]: must have 2 values (one per objective)"});
  doc["indicators"] = {{"reference_point", {0.0, "low"}}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); }, {"indicators.reference_point[1]", "must be a number"});
  doc["indicators"] = {{"reference_pont", {0.0, 0.0}}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); }, {"indicators.reference_pont: unknown key", "reference_point"});
  doc["indicators"] = {{"reference_front", write_temp("malformed.json", Json::object()) + ".d"}};
  boost::filesystem::create_directories(doc["indicators"]["reference_front"].get<std::string>());  // a directory
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); },
               {"indicators.reference_front = \"", "malformed.json.d\": cannot be read as a result.json"});
  doc["indicators"] = {{"reference_front", write_temp("nofront.json", {{"best", Json::object()}})}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); }, {"indicators.reference_front:", "has no \"front\" array"});
  doc["indicators"] = {{"reference_front", write_temp("other.json", {{"front", {{{"objectives", {{"gii", 0.5}}}}}}})}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); }, {"front[0].objectives.gdi: missing"});
  doc["indicators"] = {{"reference_front", write_temp("empty.json", {{"front", Json::array()}})}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); }, {"the front is empty"});
}

TEST(Pareto, AReferenceFrontNotWrittenYetIsRecordedNotRefused) {
  Json doc = pareto_doc();
  doc["indicators"] = {{"reference_front", "/nonexistent/result.json"}};
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  EXPECT_TRUE(study.reference_front.empty());
  EXPECT_EQ(study.reference_front_missing, "/nonexistent/result.json");
}

TEST(Pareto, ReferenceFrontAndPointAreLoaded) {
  Json doc = pareto_doc();
  const std::string path = write_temp("good.json", {{"front", {{{"objectives", {{"gii", 0.5}, {"gdi", 0.7}}}},
                                                               {{"objectives", {{"gii", 0.7}, {"gdi", 0.6}}}}}}});
  doc["indicators"] = {{"reference_front", path}, {"reference_point", {0.0, 0.0}}};
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  ASSERT_EQ(study.reference_front.size(), 2u);
  EXPECT_EQ(study.reference_front[1], (ObjectivePoint{0.7, 0.6}));
  EXPECT_EQ(study.reference_point, (ObjectivePoint{0.0, 0.0}));
}
