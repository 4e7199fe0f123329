// The evaluator: determinism across threads, exactness of the per-sample bound and pruning,
// and the central checks of plugin input and output.
#include "test_support.hpp"

#include <cmath>
#include <limits>
#include <random>

using hapsyn::EvalStatus;
using hapsyn::Json;
using hapsyn::test::expect_error;
using hapsyn::test::fivebar_study;

namespace {
hapsyn::Study study_with(const std::vector<std::string>& metrics, double scene_step = 0.01) {
  Json doc = fivebar_study();
  doc["scene"]["options"]["step"] = scene_step;
  doc["objectives"] = Json::array();
  for (const auto& m : metrics) doc["objectives"].push_back({{"metric", m}});
  return hapsyn::load_study(doc, hapsyn::test::registry());
}
// A feasible design (the Table 2 best-GII design) as a free vector (l0, l1, l2, r).
const std::vector<double> kGood = {0.0004, 0.2997, 0.3, 0.4196};
}  // namespace

TEST(Problem, ParallelEvaluationEqualsSequentialForAnyThreadCount) {
  const auto study = study_with({"gii", "gdi"});
  auto ws = study.problem->make_eval_scratch();
  const hapsyn::Evaluation sequential = study.problem->evaluate(kGood.data(), *ws);
  ASSERT_EQ(sequential.status, EvalStatus::kFeasible);
  for (int threads : {1, 2, 3, 4, 7}) {
    const hapsyn::Evaluation parallel = study.problem->evaluate_parallel(kGood.data(), threads);
    EXPECT_EQ(parallel.status, EvalStatus::kFeasible);
    EXPECT_EQ(parallel.objectives, sequential.objectives) << threads;
    EXPECT_EQ(parallel.critical_samples, sequential.critical_samples) << threads;
    EXPECT_EQ(parallel.samples_evaluated, study.problem->samples().size());
  }
}

TEST(Problem, SubsetValueIsAnUpperBoundOfTheWorstCaseValue) {
  const auto study = study_with({"gii", "gdi"});
  auto ws = study.problem->make_eval_scratch();
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int feasible = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const std::vector<double> x = {0.3 * u(rng), 0.05 + 0.25 * u(rng), 0.05 + 0.25 * u(rng), 0.6 * u(rng)};
    const hapsyn::Evaluation full = study.problem->evaluate(x.data(), *ws);
    if (full.status != EvalStatus::kFeasible) continue;
    ++feasible;
    std::vector<int> subset;
    for (int s = 0; s < study.problem->samples().size(); ++s) {
      if (u(rng) < 0.2) subset.push_back(s);
    }
    if (subset.empty()) subset.push_back(0);
    hapsyn::EvalOptions options;
    options.subset = &subset;
    const hapsyn::Evaluation part = study.problem->evaluate(x.data(), *ws, options);
    ASSERT_EQ(part.status, EvalStatus::kFeasible);
    for (std::size_t o = 0; o < full.objectives.size(); ++o) EXPECT_GE(part.objectives[o], full.objectives[o]);
    // The critical samples alone reproduce the full value exactly (what culling relies on).
    std::vector<int> critical;
    for (const auto& per_metric : full.critical_samples) critical.insert(critical.end(), per_metric.begin(), per_metric.end());
    options.subset = &critical;
    const hapsyn::Evaluation at_critical = study.problem->evaluate(x.data(), *ws, options);
    EXPECT_EQ(at_critical.objectives, full.objectives);
  }
  EXPECT_GT(feasible, 20);
}

TEST(Problem, PruningStopsOnlyBelowTheThreshold) {
  const auto study = study_with({"gii"});
  auto ws = study.problem->make_eval_scratch();
  const double value = study.problem->evaluate(kGood.data(), *ws).score;
  hapsyn::EvalOptions options;
  options.prune_below = value;  // a design that ties is never pruned
  EXPECT_EQ(study.problem->evaluate(kGood.data(), *ws, options).status, EvalStatus::kFeasible);
  options.prune_below = value + 1e-9;
  const hapsyn::Evaluation& pruned = study.problem->evaluate(kGood.data(), *ws, options);
  EXPECT_EQ(pruned.status, EvalStatus::kPruned);
  EXPECT_LE(pruned.samples_evaluated, study.problem->samples().size());
}

TEST(Problem, ConstraintViolationIsAStatusAndSkipsTheSamples) {
  const auto study = study_with({"gii"});
  auto ws = study.problem->make_eval_scratch();
  const std::vector<double> short_links = {0.3, 0.05, 0.05, 0.6};
  const hapsyn::Evaluation& e = study.problem->evaluate(short_links.data(), *ws);
  EXPECT_EQ(e.status, EvalStatus::kConstraintViolated);
  EXPECT_EQ(e.samples_evaluated, 0);
  EXPECT_EQ(study.problem->constraint_names()[static_cast<std::size_t>(e.failed_constraint)], "reach");
  EXPECT_EQ(e.score, -std::numeric_limits<double>::infinity());
}

TEST(Problem, ExtremeSamplesAreEvaluatedFirst) {
  const auto study = study_with({"gii"});
  const auto& order = study.problem->sample_order();
  ASSERT_EQ(order.size(), static_cast<std::size_t>(study.problem->samples().size()));
  for (int k = 0; k < 4; ++k) {
    const double* p = study.problem->samples().pose(order[static_cast<std::size_t>(k)]);
    EXPECT_NEAR(std::abs(p[0]), 0.05, 1e-12);
    EXPECT_NEAR(std::abs(p[1]), 0.05, 1e-12);
  }
}

TEST(Problem, AveragingStudiesVisitSamplesInSceneOrder) {
  hapsyn::Registry registry({HAPSYN_PLUGIN_DIR, HAPSYN_TEST_PLUGIN_DIR});
  Json doc = fivebar_study();
  doc["objectives"] = Json::array({{{"metric", "summetric"}}});
  const hapsyn::Study study = hapsyn::load_study(doc, registry);
  const auto& order = study.problem->sample_order();
  ASSERT_EQ(order.size(), static_cast<std::size_t>(study.problem->samples().size()));
  for (std::size_t k = 0; k < order.size(); ++k) ASSERT_EQ(order[k], static_cast<int>(k)) << "at " << k;
}

TEST(Problem, DesignFromASolverIsCheckedCentrally) {
  const auto study = study_with({"gii"});
  auto ws = study.problem->make_eval_scratch();
  const std::vector<double> nan_design = {std::nan(""), 0.2, 0.2, 0.3};
  expect_error([&] { study.problem->evaluate(nan_design.data(), *ws); }, {"design component l0 = nan", "must be finite"});
  const std::vector<double> outside = {0.0, 0.2, 0.2, 0.7};
  expect_error([&] { study.problem->evaluate(outside.data(), *ws); }, {"design component r = 0.7", "must lie within the bounds [0, 0.6]"});
}

TEST(Problem, NanFromAMetricIsAnErrorNamingTheMetricAndSample) {
  hapsyn::Registry registry({HAPSYN_PLUGIN_DIR, HAPSYN_TEST_PLUGIN_DIR});
  Json doc = fivebar_study();
  doc["objectives"] = Json::array({{{"metric", "nanmetric"}}});
  const hapsyn::Study study = hapsyn::load_study(doc, registry);
  auto ws = study.problem->make_eval_scratch();
  expect_error([&] { study.problem->evaluate(kGood.data(), *ws); },
               {"metric 'nanmetric' returned nan", "at sample", "\"l1\":0.2997"});
}

TEST(Problem, WithObjectivesSharesTheSceneAndChangesTheScore) {
  hapsyn::Json doc = hapsyn::test::fivebar_study();
  doc["objectives"] = hapsyn::Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  std::vector<hapsyn::Objective> objectives = study.problem->objectives();
  objectives[1].weight = 0.0;
  const auto only_gii = study.problem->with_objectives(objectives);
  EXPECT_EQ(&only_gii->samples(), &study.problem->samples());  // shared, not rebuilt
  const std::vector<double> x = {0.0, 0.3, 0.3, 0.4};
  auto a = study.problem->make_eval_scratch();
  auto b = only_gii->make_eval_scratch();
  const hapsyn::Evaluation both = study.problem->evaluate(x.data(), *a);
  const hapsyn::Evaluation one = only_gii->evaluate(x.data(), *b);
  ASSERT_EQ(both.status, hapsyn::EvalStatus::kFeasible);
  EXPECT_EQ(one.objectives, both.objectives);
  EXPECT_DOUBLE_EQ(one.score, both.objectives[0]);
  EXPECT_DOUBLE_EQ(both.score, both.objectives[0] + both.objectives[1]);
}

TEST(Problem, WithDesignSpaceRefusesOtherComponents) {
  const hapsyn::Study study = hapsyn::load_study(hapsyn::test::fivebar_study(), hapsyn::test::registry());
  std::vector<hapsyn::DesignComponent> components = study.problem->design_space().components();
  components.pop_back();
  hapsyn::test::expect_error([&] { study.problem->with_design_space(hapsyn::DesignSpace(components)); },
                             {"problem: with_design_space: the design space must have the same components"});
  components = study.problem->design_space().components();
  components[3].lower = components[3].upper = 0.4;
  components[3].fixed = true;
  components[3].step = 0.0;
  EXPECT_EQ(study.problem->with_design_space(hapsyn::DesignSpace(components))->dimension(), 3u);
}

TEST(Problem, ParetoPruningNeverCutsADesignTheFrontDoesNotDominate) {
  hapsyn::Json doc = hapsyn::test::fivebar_study();
  doc["objectives"] = hapsyn::Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  auto ws = study.problem->make_eval_scratch();
  const std::vector<double> x = {0.0, 0.3, 0.3, 0.4};
  const hapsyn::Evaluation full = study.problem->evaluate(x.data(), *ws);
  ASSERT_EQ(full.status, hapsyn::EvalStatus::kFeasible);
  const double g = full.objectives[0], d = full.objectives[1];
  hapsyn::EvalOptions options;
  // A front point equal to the design, or better in one objective only: never pruned.
  for (const std::vector<double>& front : {std::vector<double>{g, d}, std::vector<double>{g + 0.1, d - 0.1, g - 0.1, d + 0.1}}) {
    options.prune_dominated_by = &front;
    EXPECT_EQ(study.problem->evaluate(x.data(), *ws, options).status, hapsyn::EvalStatus::kFeasible);
  }
  // Dominated (sorted by the first objective, descending): pruned, early.
  const std::vector<double> dominating = {g + 0.01, d + 0.01};
  options.prune_dominated_by = &dominating;
  const hapsyn::Evaluation& pruned = study.problem->evaluate(x.data(), *ws, options);
  EXPECT_EQ(pruned.status, hapsyn::EvalStatus::kPruned);
  EXPECT_LT(pruned.samples_evaluated, full.samples_evaluated);
}

// An averaging metric (coverage: sums) split into a fixed number of chunks gives the same bits
// on any thread count; a subset restricts the evaluation to those samples.
TEST(Problem, FixedChunksMakeAveragingMetricsIndependentOfTheThreadCount) {
  Json doc = hapsyn::read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/plugins/metrics/coverage/conformance.json");
  doc["design"]["l"] = {{"lower", 0.12}, {"upper", 1.0}};
  doc["solver"] = {{"plugin", "ga"}};
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  const std::vector<double> x = {0.45, 0.45, 0.65, 0.55, 0.15};
  hapsyn::Problem::ParallelOptions options;
  options.chunks = 8;
  const hapsyn::Evaluation one = study.problem->evaluate_parallel(x.data(), 1, options);
  ASSERT_EQ(one.status, EvalStatus::kFeasible);
  for (int threads : {2, 3, 5}) {
    const hapsyn::Evaluation many = study.problem->evaluate_parallel(x.data(), threads, options);
    EXPECT_EQ(many.objectives, one.objectives) << threads;  // bit for bit
    EXPECT_EQ(many.samples_evaluated, study.problem->samples().size());
  }
  auto ws = study.problem->make_eval_scratch();
  EXPECT_NEAR(study.problem->evaluate(x.data(), *ws).objectives[0], one.objectives[0], 1e-12);
  const std::vector<int> subset = {0, 2, 4, 6, 8};
  options.subset = &subset;
  const hapsyn::Evaluation part = study.problem->evaluate_parallel(x.data(), 2, options);
  EXPECT_EQ(part.samples_evaluated, 5);
  hapsyn::EvalOptions sequential;
  sequential.subset = &subset;
  EXPECT_NEAR(study.problem->evaluate(x.data(), *ws, sequential).objectives[0], part.objectives[0], 1e-12);
}
