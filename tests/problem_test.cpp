// The evaluator: determinism across threads, exactness of the per-sample bound and pruning,
// and the central checks of plugin input and output.
#include <hapsyn/accel/metric_acceleration.hpp>
#include "test_support.hpp"

#include <hapsyn/internal/maps.hpp>

#include <Eigen/SVD>
#include <boost/filesystem.hpp>

#include <algorithm>
#include <atomic>
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

TEST(Problem, NonFiniteMechanismQuantitiesAreBlamedOnTheMechanismNotTheMetric) {
  // A bar width of 1e300 overflows the inertias: the metric's NaN is the mechanism's fault.
  Json doc = fivebar_study();
  doc["mechanism"]["options"]["k"] = 1e300;
  doc["objectives"] = Json::array({{{"metric", "gdi"}}});
  const hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  auto ws = study.problem->make_eval_scratch();
  expect_error([&] { study.problem->evaluate(kGood.data(), *ws); },
               {"problem: mechanism 'fivebar' returned a non-finite effective_mass at sample", "\"l1\":0.2997",
                "check the mechanism's options"});
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

// ---- Per-sample weights (SampleSet::weights) --------------------------------------------------

namespace {

// An averaging metric dividing its sum by the sample count: the mean x coordinate [m].
class MeanX final : public hapsyn::Metric {
 public:
  void local(const hapsyn::SampleQuantities& q, double* out) const override { out[0] = q.scene->pose(q.sample)[0]; }
  hapsyn::MetricSpecs specs() const override { return {0, {}}; }
  std::vector<hapsyn::LocalValue> locals() const override { return {{"x", hapsyn::Reduction::kSum, "m"}}; }
  double combine(const double* reduced, int samples) const override { return samples > 0 ? reduced[0] / samples : 0.0; }
};

// An averaging metric dividing by another sum (the examples/mean_isotropy metric): the mean of
// sigma_min(J) / sigma_max(J) over the reachable samples.
class MeanIsotropy final : public hapsyn::Metric {
 public:
  void local(const hapsyn::SampleQuantities& q, double* out) const override {
    if (q.status != hapsyn::SampleStatus::kReachable) {
      out[0] = out[1] = 0.0;
      return;
    }
    const Eigen::Matrix2d j = q.jacobian;
    const Eigen::Vector2d s = Eigen::JacobiSVD<Eigen::Matrix2d>(j).singularValues();
    out[0] = s(1) / s(0);
    out[1] = 1.0;
  }
  std::vector<hapsyn::LocalValue> locals() const override {
    return {{"isotropy", hapsyn::Reduction::kSum, ""}, {"reachable", hapsyn::Reduction::kSum, ""}};
  }
  double combine(const double* reduced, int) const override { return reduced[1] > 0.0 ? reduced[0] / reduced[1] : 0.0; }
};

// Five planar positions in the five-bar's workspace and their weights (one of them 0).
const std::vector<std::array<double, 3>> kWeighted = {
    {-0.04, -0.03, 1.0}, {0.0, 0.0, 3.0}, {0.045, 0.02, 0.0}, {0.01, 0.05, 0.5}, {-0.02, 0.035, 2.5}};

// A point_list file of kWeighted (the weight column only when `weights`), removed on destruction.
struct PointFile {
  explicit PointFile(bool weights, const std::vector<std::array<double, 3>>& rows = kWeighted) {
    path = (boost::filesystem::temp_directory_path() / boost::filesystem::unique_path("hapsyn-weights-%%%%-%%%%.csv")).string();
    std::ofstream out(path);
    out.precision(17);
    out << (weights ? "x,y,weight\n" : "x,y\n");
    for (const auto& r : rows) {
      out << r[0] << "," << r[1];
      if (weights) out << "," << r[2];
      out << "\n";
    }
  }
  ~PointFile() { std::remove(path.c_str()); }
  std::string path;
};

std::shared_ptr<hapsyn::SampleSet> point_list_samples(const std::string& path) {
  auto samples = std::make_shared<hapsyn::SampleSet>(
      hapsyn::test::registry().create_scene("point_list", Json{{"file", path}}, "scene")->build({}));
  samples->cache_bounds();
  return samples;
}

// The five-bar over `samples` with one metric, on the test study's design space.
std::shared_ptr<hapsyn::Problem> problem_over(std::shared_ptr<const hapsyn::SampleSet> samples,
                                              std::shared_ptr<const hapsyn::Metric> metric) {
  const hapsyn::Study base = hapsyn::load_study(fivebar_study(), hapsyn::test::registry());
  auto mechanism = hapsyn::test::registry().create_mechanism("fivebar", Json{{"rho", 1.08}}, "mechanism");
  hapsyn::Objective objective;
  objective.name = "metric";
  return std::make_shared<hapsyn::Problem>("fivebar", mechanism, std::move(samples),
                                           std::vector<hapsyn::MetricEntry>{{"metric", std::move(metric)}},
                                           std::vector<hapsyn::Objective>{objective}, base.problem->design_space());
}

double value_of(const hapsyn::Problem& problem) {
  auto ws = problem.make_eval_scratch();
  const hapsyn::Evaluation& e = problem.evaluate(kGood.data(), *ws);
  EXPECT_EQ(e.status, EvalStatus::kFeasible);
  return e.objectives[0];
}

}  // namespace

TEST(WeightedSamples, AveragingMetricDividingByTheSampleCountIsTheWeightedMean) {
  const PointFile file(true);
  const auto samples = point_list_samples(file.path);
  ASSERT_EQ(samples->weights.size(), kWeighted.size());
  // By hand, from the file's own numbers: sum w x / sum w.
  double wx = 0.0, w = 0.0;
  for (const auto& r : kWeighted) {
    wx += r[2] * r[0];
    w += r[2];
  }
  const auto problem = problem_over(samples, std::make_shared<MeanX>());
  EXPECT_NEAR(value_of(*problem), wx / w, 1e-15);
  // Differs from the unweighted mean, which the same scene without weights gives.
  double x = 0.0;
  for (const auto& r : kWeighted) x += r[0];
  const PointFile plain(false);
  EXPECT_NEAR(value_of(*problem_over(point_list_samples(plain.path), std::make_shared<MeanX>())), x / 5, 1e-15);
  EXPECT_GT(std::abs(wx / w - x / 5), 1e-3);
}

TEST(WeightedSamples, MeanIsotropyIsTheWeightedMeanOfThePerSampleValues) {
  const PointFile weighted(true), plain(false);
  const auto unweighted_problem = problem_over(point_list_samples(plain.path), std::make_shared<MeanIsotropy>());
  // The per-sample local values, recorded independently of any reduction.
  const hapsyn::SampleRecords records =
      hapsyn::record_samples(*unweighted_problem, unweighted_problem->full_design(kGood.data()));
  double numerator = 0.0, denominator = 0.0;
  for (std::size_t i = 0; i < kWeighted.size(); ++i) {
    ASSERT_EQ(records.status[i], "reachable") << i;
    numerator += kWeighted[i][2] * records.locals(static_cast<Eigen::Index>(i), 0);
    denominator += kWeighted[i][2] * records.locals(static_cast<Eigen::Index>(i), 1);
  }
  const auto problem = problem_over(point_list_samples(weighted.path), std::make_shared<MeanIsotropy>());
  const double value = value_of(*problem);
  EXPECT_NEAR(value, numerator / denominator, 1e-14);
  EXPECT_GT(std::abs(value - value_of(*unweighted_problem)), 1e-6);  // the weights matter here
  // Chunked parallel evaluation merges the weighted sums to the same value.
  hapsyn::Problem::ParallelOptions options;
  options.chunks = 3;
  EXPECT_NEAR(problem->evaluate_parallel(kGood.data(), 2, options).objectives[0], value, 1e-14);
}

TEST(WeightedSamples, EqualWeightsGiveExactlyTheUnweightedValue) {
  const PointFile plain(false);
  const auto unweighted = point_list_samples(plain.path);
  for (double weight : {0.1, 1.0, 7.0, 1e-3}) {
    std::vector<std::array<double, 3>> rows = kWeighted;
    for (auto& r : rows) r[2] = weight;  // 0.1 five times does not sum to exactly 0.5
    const PointFile file(true, rows);
    const auto samples = point_list_samples(file.path);
    for (const auto& metric : std::vector<std::shared_ptr<const hapsyn::Metric>>{std::make_shared<MeanX>(),
                                                                                 std::make_shared<MeanIsotropy>()}) {
      EXPECT_EQ(value_of(*problem_over(samples, metric)), value_of(*problem_over(unweighted, metric))) << weight;
    }
  }
}

TEST(WeightedSamples, MinAndMaxReductionsIgnoreTheWeights) {
  const PointFile weighted(true), plain(false);
  for (const char* metric : {"gii", "gdi"}) {
    Json doc = fivebar_study("evaluate");
    doc["objectives"] = Json::array({{{"metric", metric}}});
    doc["design"] = {{"l0", {{"value", kGood[0]}}}, {"l1", {{"value", kGood[1]}}}, {"l2", {{"value", kGood[2]}}},
                     {"r", {{"value", kGood[3]}}}};
    doc["scene"] = {{"plugin", "point_list"}, {"options", {{"file", weighted.path}}}};
    const hapsyn::Study a = hapsyn::load_study(doc, hapsyn::test::registry());
    doc["scene"]["options"]["file"] = plain.path;
    const hapsyn::Study b = hapsyn::load_study(doc, hapsyn::test::registry());
    ASSERT_FALSE(a.problem->samples().weights.empty());
    auto wa = a.problem->make_eval_scratch(), wb = b.problem->make_eval_scratch();
    const std::vector<double> none;
    const hapsyn::Evaluation ea = a.problem->evaluate(none.data(), *wa);
    const hapsyn::Evaluation eb = b.problem->evaluate(none.data(), *wb);
    ASSERT_EQ(ea.status, EvalStatus::kFeasible);
    EXPECT_EQ(ea.objectives, eb.objectives) << metric;
    EXPECT_EQ(ea.critical_samples, eb.critical_samples) << metric;
  }
}

TEST(WeightedSamples, UnusableWeightsAreRefusedCentrally) {
  const PointFile plain(false);
  const auto samples = point_list_samples(plain.path);
  const auto refused = [&](const std::vector<double>& weights) {
    auto copy = std::make_shared<hapsyn::SampleSet>(*samples);
    copy->weights = weights;
    return hapsyn::test::error_of([&] { problem_over(copy, std::make_shared<MeanX>()); });
  };
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(refused({1, 2, 3}),
            "problem: scene: weights has 3 entries for 5 samples (one per sample, or none for equal weights)");
  EXPECT_EQ(refused({1, 2, -3, 4, 5}), "problem: scene: weights[2] = -3.0: must be finite and >= 0");
  EXPECT_EQ(refused({1, nan, 1, 1, 1}), "problem: scene: weights[1] = nan: must be finite and >= 0");
  EXPECT_EQ(refused({1, 1, 1, 1, inf}), "problem: scene: weights[4] = inf: must be finite and >= 0");
  EXPECT_EQ(refused({0, 0, 0, 0, 0}),
            "problem: scene: weights sum to 0.0: the sum must be finite and > 0 (at least one weight > 0)");
  EXPECT_EQ(refused({1e308, 1e308, 0, 0, 0}),
            "problem: scene: weights sum to inf: the sum must be finite and > 0 (at least one weight > 0)");
  EXPECT_EQ(refused({}), "(no error)");
}

TEST(WeightedSamples, SamplesCsvHasAWeightColumnOnlyWithWeights) {
  const PointFile weighted(true), plain(false);
  const auto with = problem_over(point_list_samples(weighted.path), std::make_shared<MeanX>());
  const std::string csv = hapsyn::samples_csv(*with, hapsyn::record_samples(*with, with->full_design(kGood.data())));
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "sample,x,y,weight,status,metric.x");
  EXPECT_EQ(csv.substr(csv.find('\n') + 1, csv.find('\n', csv.find('\n') + 1) - csv.find('\n') - 1),
            "0,-0.04,-0.03,1,reachable,-0.04");
  const auto without = problem_over(point_list_samples(plain.path), std::make_shared<MeanX>());
  const std::string plain_csv =
      hapsyn::samples_csv(*without, hapsyn::record_samples(*without, without->full_design(kGood.data())));
  EXPECT_EQ(plain_csv.substr(0, plain_csv.find('\n')), "sample,x,y,status,metric.x");
}

namespace {
// An averaging metric over a scene attribute "value", dividing by the sample count.
class MeanValue final : public hapsyn::Metric {
 public:
  void local(const hapsyn::SampleQuantities& q, double* out) const override { out[0] = q.attribute_row(0)[0]; }
  hapsyn::MetricSpecs specs() const override { return {0, {"value"}}; }
  std::vector<hapsyn::LocalValue> locals() const override { return {{"value", hapsyn::Reduction::kSum, ""}}; }
  double combine(const double* reduced, int samples) const override { return samples > 0 ? reduced[0] / samples : 0.0; }
};
}  // namespace

TEST(WeightedSamples, PositionMapsAreEachPositionsWeightedMean) {
  // Two positions with three and two samples; the values and weights differ within a position.
  const std::string path =
      (boost::filesystem::temp_directory_path() / boost::filesystem::unique_path("hapsyn-maps-%%%%-%%%%.csv")).string();
  const double rows[5][4] = {{0.0, 0.0, 1.0, 2.0}, {0.0, 0.0, 4.0, 1.0}, {0.0, 0.0, 10.0, 1.0},
                             {0.02, 0.01, 3.0, 0.0}, {0.02, 0.01, 5.0, 0.0}};  // x, y, value, weight
  {
    std::ofstream out(path);
    out << "x,y,value,weight\n";
    for (const auto& r : rows) out << r[0] << "," << r[1] << "," << r[2] << "," << r[3] << "\n";
  }
  hapsyn::SceneRequest request;
  request.attributes = {"value"};
  auto samples = std::make_shared<hapsyn::SampleSet>(
      hapsyn::test::registry().create_scene("point_list", Json{{"file", path}}, "scene")->build(request));
  std::remove(path.c_str());
  samples->cache_bounds();
  const auto problem = problem_over(samples, std::make_shared<MeanValue>());
  const hapsyn::PositionMaps maps =
      hapsyn::position_maps(*problem, hapsyn::record_samples(*problem, problem->full_design(kGood.data())));
  ASSERT_EQ(maps.position.size(), 2u);
  // By hand: (2 * 1 + 1 * 4 + 1 * 10) / 4 at the first position; all weights 0 at the second:
  // the plain mean (3 + 5) / 2.
  EXPECT_NEAR(maps.values(0, 0), (2.0 * 1 + 1.0 * 4 + 1.0 * 10) / 4, 1e-15);
  EXPECT_NEAR(maps.values(1, 0), (3.0 + 5.0) / 2, 1e-15);
  // The whole scene: the weighted mean over all samples (the zero weights count for nothing).
  EXPECT_NEAR(value_of(*problem), (2.0 * 1 + 1.0 * 4 + 1.0 * 10) / 4, 1e-15);
}

// ---- Batched metrics (MetricAcceleration::batch_size, local_batch) ------------------------------------------

namespace {

// A metric forwarding to another one, declaring a batch size: the evaluator must give exactly
// the per-sample path's results (local_batch calls local() per sample).
class Batched final : public hapsyn::Metric, public hapsyn::MetricAcceleration {
 public:
  Batched(std::shared_ptr<const hapsyn::Metric> inner, int batch) : inner_(std::move(inner)), batch_(batch) {}
  void local(const hapsyn::SampleQuantities& q, double* out) const override { inner_->local(q, out); }
  void local_batch(const hapsyn::SampleQuantities* const* q, int count, double* out) const override {
    ++calls;
    largest = std::max(largest.load(), count);
    const int k = static_cast<int>(inner_->locals().size());
    for (int i = 0; i < count; ++i) inner_->local(*q[i], out + static_cast<long>(i) * k);
  }
  int batch_size() const override { return batch_; }
  const hapsyn::MetricAcceleration* acceleration() const override { return this; }
  hapsyn::MetricSpecs specs() const override { return inner_->specs(); }
  std::vector<hapsyn::LocalValue> locals() const override { return inner_->locals(); }
  double combine(const double* reduced, int samples) const override { return inner_->combine(reduced, samples); }
  hapsyn::Aggregation aggregation() const override { return inner_->aggregation(); }
  mutable std::atomic<int> calls{0};
  mutable std::atomic<int> largest{0};

 private:
  std::shared_ptr<const hapsyn::Metric> inner_;
  int batch_;
};

// The study's problem with every metric (or only the first) wrapped in Batched (the study must
// outlive it).
std::shared_ptr<hapsyn::Problem> batched(const hapsyn::Study& study, int batch,
                                         std::vector<std::shared_ptr<Batched>>* wrappers = nullptr,
                                         bool only_first = false) {
  const hapsyn::Problem& p = *study.problem;
  std::vector<hapsyn::MetricEntry> metrics;
  for (const hapsyn::MetricEntry& m : p.metrics()) {
    if (only_first && !metrics.empty()) {
      metrics.push_back(m);
      continue;
    }
    auto b = std::make_shared<Batched>(m.metric, batch);
    if (wrappers) wrappers->push_back(b);
    metrics.push_back({m.plugin, b});
  }
  const std::shared_ptr<const hapsyn::Mechanism> mechanism(std::shared_ptr<const hapsyn::Mechanism>{}, &p.mechanism());
  return std::make_shared<hapsyn::Problem>("fivebar", mechanism, std::make_shared<hapsyn::SampleSet>(p.samples()),
                                           metrics, p.objectives(), p.design_space());
}

void expect_same(const hapsyn::Evaluation& a, const hapsyn::Evaluation& b, const std::string& what) {
  EXPECT_EQ(a.status, b.status) << what;
  EXPECT_EQ(a.failed_sample, b.failed_sample) << what;
  EXPECT_EQ(a.failed_constraint, b.failed_constraint) << what;
  if (a.status == EvalStatus::kFeasible) {
    EXPECT_EQ(a.objectives, b.objectives) << what;  // bit for bit
    EXPECT_EQ(a.reduced, b.reduced) << what;
    EXPECT_EQ(a.critical_samples, b.critical_samples) << what;
    EXPECT_EQ(a.score, b.score) << what;
    EXPECT_EQ(a.samples_evaluated, b.samples_evaluated) << what;
  }
  if (a.status == EvalStatus::kPruned) {
    EXPECT_EQ(a.critical_samples, b.critical_samples) << what;
  }
}

}  // namespace

TEST(BatchedMetric, BesideAMetricWithoutABatchGivesThePerSampleResults) {
  // GII batched (as a Python metric would be), GDI not: the evaluator takes the batch path for
  // the study and must compute GDI's local values per sample there.
  const auto study = study_with({"gii", "gdi"});
  std::vector<std::shared_ptr<Batched>> wrappers;
  const auto problem = batched(study, 7, &wrappers, true);
  ASSERT_EQ(wrappers.size(), 1u);
  auto ws = study.problem->make_eval_scratch();
  auto wb = problem->make_eval_scratch();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int feasible = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const std::vector<double> x = trial == 0 ? kGood
                                             : std::vector<double>{0.3 * u(rng), 0.05 + 0.25 * u(rng),
                                                                   0.05 + 0.25 * u(rng), 0.6 * u(rng)};
    const hapsyn::Evaluation plain = study.problem->evaluate(x.data(), *ws);
    expect_same(plain, problem->evaluate(x.data(), *wb), "mixed batch");
    feasible += plain.status == EvalStatus::kFeasible ? 1 : 0;
  }
  EXPECT_GT(feasible, 5);
  EXPECT_GT(wrappers[0]->calls.load(), 0);
}

namespace {
// Declares a batch but never writes its values: the evaluator must report it, not reduce
// whatever its buffer held.
class SilentBatch final : public hapsyn::Metric, public hapsyn::MetricAcceleration {
 public:
  void local(const hapsyn::SampleQuantities&, double* out) const override { out[0] = 1.0; }
  int batch_size() const override { return 4; }
  const hapsyn::MetricAcceleration* acceleration() const override { return this; }
};
}  // namespace

TEST(BatchedMetric, ABatchThatWritesNothingIsReportedAsTheMetricsNan) {
  const auto study = study_with({"gii"});
  const hapsyn::Problem& p = *study.problem;
  const std::shared_ptr<const hapsyn::Mechanism> mechanism(std::shared_ptr<const hapsyn::Mechanism>{}, &p.mechanism());
  const hapsyn::Problem problem("fivebar", mechanism, std::make_shared<hapsyn::SampleSet>(p.samples()),
                                {{"silent", std::make_shared<SilentBatch>()}}, p.objectives(), p.design_space());
  auto ws = problem.make_eval_scratch();
  expect_error([&] { problem.evaluate(kGood.data(), *ws); }, {"metric 'silent' returned nan", "sample"});
}

TEST(BatchedMetric, GivesThePerSampleResultsBitForBitWithPruningSubsetsAndFailures) {
  const auto study = study_with({"gii", "gdi"});
  for (int batch : {1, 7, 64, 100000}) {
    std::vector<std::shared_ptr<Batched>> wrappers;
    const auto problem = batched(study, batch, &wrappers);
    auto ws = study.problem->make_eval_scratch();
    auto wb = problem->make_eval_scratch();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    int statuses[4] = {0, 0, 0, 0};
    int pruned_count = 0;
    for (int trial = 0; trial < 200; ++trial) {
      const std::vector<double> x = trial == 0 ? kGood
                                               : std::vector<double>{0.3 * u(rng), 0.05 + 0.25 * u(rng),
                                                                     0.05 + 0.25 * u(rng), 0.6 * u(rng)};
      const hapsyn::Evaluation plain = study.problem->evaluate(x.data(), *ws);
      expect_same(plain, problem->evaluate(x.data(), *wb), "full, batch " + std::to_string(batch));
      ++statuses[static_cast<int>(plain.status)];
      hapsyn::EvalOptions prune;
      prune.prune_below = 1.2;  // GII + GDI of the good design is 1.40
      const hapsyn::Evaluation pruned = study.problem->evaluate(x.data(), *ws, prune);
      expect_same(pruned, problem->evaluate(x.data(), *wb, prune), "pruned, batch " + std::to_string(batch));
      pruned_count += pruned.status == EvalStatus::kPruned ? 1 : 0;
      std::vector<int> subset;
      for (int s = 0; s < study.problem->samples().size(); s += 3) subset.push_back(s);
      hapsyn::EvalOptions part;
      part.subset = &subset;
      expect_same(study.problem->evaluate(x.data(), *ws, part), problem->evaluate(x.data(), *wb, part),
                  "subset, batch " + std::to_string(batch));
    }
    EXPECT_GT(statuses[static_cast<int>(EvalStatus::kFeasible)], 10);
    EXPECT_GT(statuses[static_cast<int>(EvalStatus::kSampleFailed)], 10);
    EXPECT_GT(statuses[static_cast<int>(EvalStatus::kConstraintViolated)], 10);
    EXPECT_GT(pruned_count, 10);
    EXPECT_LE(wrappers[0]->largest.load(), batch);
    // Per-sample records (the SampleCallback) and the parallel path agree too.
    const auto a = hapsyn::record_samples(*study.problem, study.problem->full_design(kGood.data()));
    const auto b = hapsyn::record_samples(*problem, problem->full_design(kGood.data()));
    EXPECT_EQ(a.status, b.status);
    EXPECT_EQ(a.locals, b.locals);
    expect_same(study.problem->evaluate_parallel(kGood.data(), 3), problem->evaluate_parallel(kGood.data(), 3),
                "parallel, batch " + std::to_string(batch));
  }
}

TEST(BatchedMetric, LocalBatchIsCalledOncePerChunkOfSamples) {
  const auto study = study_with({"gii"});
  std::vector<std::shared_ptr<Batched>> wrappers;
  const auto problem = batched(study, 50, &wrappers);
  auto ws = problem->make_eval_scratch();
  const hapsyn::Evaluation& e = problem->evaluate(kGood.data(), *ws);
  ASSERT_EQ(e.status, EvalStatus::kFeasible);
  const int n = problem->samples().size();
  EXPECT_EQ(wrappers[0]->calls.load(), (n + 49) / 50);
  EXPECT_EQ(wrappers[0]->largest.load(), 50);
}
