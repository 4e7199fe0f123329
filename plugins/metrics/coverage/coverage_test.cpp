// Tests of the coverage metric: each eta against a naive implementation of eqs. 13, 16, 18,
// the denominators of eqs. 11 and 14, needs per term, and that the evaluator computes only what
// the selected terms need (through a counting mechanism wrapper and the scene's attributes).
#include "coverage.hpp"
#include "haptic6r.hpp"

#include "test_support.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/options.hpp>
#include <hapsyn/problem.hpp>
#include <hapsyn/internal/study.hpp>

#include <gtest/gtest.h>

#include "vector_targets.hpp"

#include <Eigen/LU>
#include <atomic>
#include <cmath>
#include <random>

using namespace hapsyn;
using namespace hapsyn::plugins;
using Matrix6 = Coverage::Matrix6;
using Vector6 = Coverage::Vector6;

namespace {

// eqs. 13, 16, 18 written out literally: explicit inverse, every (i, j) ratio.
double naive_eta(const Matrix6& m, const Vector6& limit, const Vector6& extra) {
  double eta = 1.0;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) eta = std::min(eta, limit(i) / (std::abs(m(i, j)) + std::abs(extra(i))));
  }
  return eta;
}

// The metric as the registry builds it from a problem file's options (validated, defaults filled).
Coverage coverage(const Json& options = Json::object()) { return Coverage(make_options<CoverageOptions>(options)); }

Json study(const Json& terms, bool with_terms = true) {
  Json doc = Json::parse(R"({
    "name": "coverage-test",
    "mechanism": {"plugin": "haptic6r"},
    "scene": {"plugin": "human_arm", "options": {"lattice_step": 0.35, "orientations": 20, "joint3_steps": 5, "cache": false, "threads": 1}},
    "design": {"l": {"value": [0.45, 0.45, 0.65, 0.55, 0.15]}, "s": {"value": [3, 3, 2, 2, 1, 1]}, "r": {"value": [2, 2, 3, 2, 3, 3]}},
    "objectives": [{"metric": "coverage"}],
    "solver": {"plugin": "evaluate"},
    "seed": 1
  })");
  if (with_terms) doc["objectives"][0]["options"] = {{"terms", terms}};
  return doc;
}

// Records the union of the Need flags the evaluator passes to solve().
std::atomic<Needs> g_needs_seen{0};

class CountingModel final : public MechanismModel {
 public:
  explicit CountingModel(std::unique_ptr<const MechanismModel> inner) : inner_(std::move(inner)) {}
  void solve(const double* pose, Needs needs, MechanismScratch& scratch, SampleQuantities& out) const override {
    g_needs_seen |= needs;
    inner_->solve(pose, needs, scratch, out);
  }

 private:
  std::unique_ptr<const MechanismModel> inner_;
};

class CountingMechanism final : public Mechanism {
 public:
  explicit CountingMechanism(std::shared_ptr<const Mechanism> inner) : inner_(std::move(inner)) {}
  std::unique_ptr<const MechanismModel> build(const double* design) const override {
    return std::make_unique<CountingModel>(inner_->build(design));
  }
  std::vector<VariableDecl> variables() const override { return inner_->variables(); }
  std::vector<ConstraintDecl> constraints() const override { return inner_->constraints(); }
  void evaluate_constraints(const double* design, const SampleSet& scene, double* g) const override {
    inner_->evaluate_constraints(design, scene, g);
  }
  std::unique_ptr<MechanismScratch> make_scratch() const override { return inner_->make_scratch(); }
  void check_scene(const SampleSet& scene) const override { inner_->check_scene(scene); }
  MechanismSpecs specs() const override { return inner_->specs(); }

 private:
  std::shared_ptr<const Mechanism> inner_;
};

}  // namespace

TEST(Coverage, EtaMatchesNaiveEquations) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    Matrix6 j, mv, ma, h;
    Vector6 qdot, tau, g;
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) {
        j(r, c) = u(rng);
        mv(r, c) = 3 * u(rng);
        ma(r, c) = 20 * u(rng);
        h(r, c) = u(rng);
      }
      qdot(r) = 1 + 5 * std::abs(u(rng));
      tau(r) = 5 + 40 * std::abs(u(rng));
      g(r) = 10 * u(rng);
    }
    j += 3 * Matrix6::Identity();
    h = h * h.transpose() + Matrix6::Identity();
    const Matrix6 jinv = j.inverse();
    EXPECT_NEAR(Coverage::eta_velocity(j, mv, qdot), naive_eta(jinv * mv, qdot, Vector6::Zero()), 1e-12);
    EXPECT_NEAR(Coverage::eta_acceleration(j, h, g, ma, tau), naive_eta(h * jinv * ma, tau, g), 1e-12);
    Matrix6 mf = Matrix6::Zero();
    mf.topLeftCorner<3, 3>() = 10 * Eigen::Matrix3d::Identity();
    mf.bottomRightCorner<3, 3>() = 50 * Eigen::Matrix3d::Identity();
    EXPECT_NEAR(Coverage::eta_force(j, g, tau, 10, 50), naive_eta(j.transpose() * mf, tau, g), 1e-12);
  }
  // Zero demand leaves 1; a singular Jacobian gives a finite value (0 or a ratio), never NaN.
  EXPECT_EQ(Coverage::eta_velocity(Matrix6::Identity(), Matrix6::Zero(), Vector6::Ones()), 1.0);
  const double singular = Coverage::eta_velocity(Matrix6::Zero(), Matrix6::Identity(), Vector6::Ones());
  EXPECT_TRUE(std::isfinite(singular));
  EXPECT_GE(singular, 0.0);
}

TEST(Coverage, LocalValuesOnScenePosesMatchNaiveEquations) {
  // The human_arm scene's poses with their ellipsoids; the sample and scene given as the evaluator does.
  auto doc = study(Json::array({"pose", "velocity", "acceleration", "force"}));
  Study s = load_study(doc, test::registry());
  const SampleSet& scene = s.problem->samples();
  ASSERT_TRUE(scene.attributes.count("M_v") && scene.attributes.count("M_a"));
  const Haptic6R mech(default_options<Haptic6ROptions>());
  mech.check_scene(scene);
  const std::vector<double> design{0.45, 0.45, 0.65, 0.55, 0.15, 3, 3, 2, 2, 1, 1, 2, 2, 3, 2, 3, 3};
  auto model = mech.build(design.data());
  auto scratch = mech.make_scratch();
  const Coverage metric = coverage();
  ASSERT_EQ(metric.locals().size(), 5u);
  int checked = 0;
  for (int i = 0; i < scene.size() && checked < 20; ++i) {
    SampleQuantities q;
    model->solve(scene.pose(i), metric.needs(), *scratch, q);
    q.sample = i;
    q.scene = &scene;
    double out[5];
    metric.local(q, out);
    EXPECT_EQ(out[0], 1.0);
    if (q.status != SampleStatus::kReachable) {
      EXPECT_EQ(out[1] + out[2] + out[3] + out[4], 0.0);
      continue;
    }
    const Matrix6 mv = Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(scene.attributes.at("M_v").row(i).data());
    const Matrix6 ma = Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(scene.attributes.at("M_a").row(i).data());
    const Matrix6 j = q.jacobian, h = q.inertia;
    const Vector6 g = q.gravity, qdot = q.max_velocity, tau = q.max_torque;
    Matrix6 mf = Matrix6::Zero();
    mf.topLeftCorner<3, 3>() = 10 * Eigen::Matrix3d::Identity();
    mf.bottomRightCorner<3, 3>() = 50 * Eigen::Matrix3d::Identity();
    const Matrix6 jinv = j.inverse();
    EXPECT_NEAR(out[2], naive_eta(jinv * mv, qdot, Vector6::Zero()), 1e-9);
    EXPECT_NEAR(out[3], naive_eta(h * jinv * ma, tau, g), 1e-9);
    EXPECT_NEAR(out[4], naive_eta(j.transpose() * mf, tau, g), 1e-9);
    for (int k = 1; k < 5; ++k) {
      EXPECT_GE(out[k], 0.0);
      EXPECT_LE(out[k], 1.0);
    }
    ++checked;
  }
  EXPECT_EQ(checked, 20);
}

TEST(Coverage, CombineUsesHumanAndManipulatorReachableCounts) {
  const Coverage all = coverage();
  const double reduced[5] = {200, 50, 25, 10, 50};  // n_h, n_m, sum eta_v, eta_a, eta_f
  EXPECT_DOUBLE_EQ(all.combine(reduced, 200), 50.0 / 200 + 25.0 / 50 + 10.0 / 50 + 50.0 / 50);
  const Coverage vel = coverage(Json{{"terms", {"velocity"}}});
  const double r2[3] = {200, 50, 25};
  EXPECT_DOUBLE_EQ(vel.combine(r2, 200), 0.5);
  const Coverage pose = coverage(Json{{"terms", {"pose"}}});
  const double r3[2] = {200, 50};
  EXPECT_DOUBLE_EQ(pose.combine(r3, 200), 0.25);
  const double none[5] = {200, 0, 0, 0, 0};
  EXPECT_EQ(all.combine(none, 200), 0.0) << "no reachable pose: every term 0, no NaN";
  const double ideal[5] = {200, 200, 200, 200, 200};
  EXPECT_DOUBLE_EQ(all.combine(ideal, 200), 4.0);
}

TEST(Coverage, NeedsAndSceneAttributesFollowTheTerms) {
  EXPECT_EQ(coverage(Json{{"terms", {"pose"}}}).needs(), Needs{kNeedPose});
  EXPECT_TRUE(coverage(Json{{"terms", {"pose"}}}).scene_attributes().empty());
  EXPECT_EQ(coverage(Json{{"terms", {"velocity"}}}).needs(), Needs{kNeedJacobian | kNeedActuatorLimits});
  EXPECT_EQ(coverage(Json{{"terms", {"velocity"}}}).scene_attributes(), std::vector<std::string>{"M_v"});
  EXPECT_EQ(coverage(Json{{"terms", {"acceleration"}}}).needs(),
            Needs{kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits});
  EXPECT_EQ(coverage(Json{{"terms", {"acceleration"}}}).scene_attributes(), std::vector<std::string>{"M_a"});
  EXPECT_EQ(coverage(Json{{"terms", {"force"}}}).needs(), Needs{kNeedJacobian | kNeedGravity | kNeedActuatorLimits});
  EXPECT_TRUE(coverage(Json{{"terms", {"force"}}}).scene_attributes().empty());
  EXPECT_EQ(coverage().aggregation(), Aggregation::kAveraging);
}

TEST(Coverage, EvaluatorComputesOnlyWhatTheTermsNeed) {
  struct Case {
    Json terms;
    Needs expected;
    bool m_v, m_a;
  };
  const std::vector<Case> cases = {
      {Json::array({"pose"}), kNeedPose, false, false},
      {Json::array({"pose", "velocity"}), kNeedJacobian | kNeedActuatorLimits, true, false},
      {Json::array({"force"}), kNeedJacobian | kNeedGravity | kNeedActuatorLimits, false, false},
      {Json::array({"pose", "velocity", "acceleration", "force"}),
       kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits, true, true},
  };
  std::vector<double> values;
  for (const Case& c : cases) {
    Study s = load_study(study(c.terms), test::registry());
    const Problem& p = *s.problem;
    EXPECT_EQ(p.samples().attributes.count("M_v") == 1, c.m_v) << c.terms.dump();
    EXPECT_EQ(p.samples().attributes.count("M_a") == 1, c.m_a) << c.terms.dump();
    auto mech = std::make_shared<CountingMechanism>(std::make_shared<Haptic6R>(default_options<Haptic6ROptions>()));
    Problem counted("haptic6r", mech, std::make_shared<const SampleSet>(p.samples()), p.metrics(), p.objectives(),
                    p.design_space());
    g_needs_seen = 0;
    const Evaluation e = counted.evaluate_parallel(nullptr, 2);
    ASSERT_EQ(e.status, EvalStatus::kFeasible);
    EXPECT_EQ(g_needs_seen.load(), c.expected) << c.terms.dump();
    values.push_back(e.objectives[0]);
    // The same value through the study's own (plugin) mechanism.
    const Evaluation direct = p.evaluate_parallel(nullptr, 1);
    EXPECT_NEAR(direct.objectives[0], e.objectives[0], 1e-12);
  }
  // J_x in [0, 1]; J_x + J_v + J_a + J_f in [0, 4]; J_v in [0, 1] (difference of two studies).
  EXPECT_GE(values[0], 0.0);
  EXPECT_LE(values[0], 1.0);
  EXPECT_GT(values[0], 0.05) << "a plausible design reaches some human poses";
  EXPECT_GE(values[1] - values[0], 0.0);
  EXPECT_LE(values[1] - values[0], 1.0);
  EXPECT_GE(values[3], values[1] - 1e-12);
  EXPECT_LE(values[3], 4.0);
}

TEST(Coverage, ReducedCountsMatchTheirDefinitions) {
  Study s = load_study(study(Json::array({"pose", "velocity"})), test::registry());
  const Problem& p = *s.problem;
  auto ws = p.make_eval_scratch();
  const Evaluation& e = p.evaluate(nullptr, *ws);
  ASSERT_EQ(e.status, EvalStatus::kFeasible);
  const std::vector<double>& r = e.reduced[0];
  EXPECT_EQ(r[0], p.samples().size()) << "n_reach^h: every scene sample is human-reachable";
  EXPECT_EQ(r[0], p.samples().info.at("n_reach").get<double>()) << "the scene's own n_reach^h";
  EXPECT_LE(r[1], r[0]);
  EXPECT_LE(r[2], r[1]) << "sum of eta_v <= n_reach^m";
  EXPECT_NEAR(e.objectives[0], r[1] / r[0] + r[2] / r[1], 1e-12);
}

TEST(Coverage, ErrorMessagesNameTheOptionValueAndRule) {
  using test::expect_error;
  // The declared rules (the framework's messages), a repeat among them.
  expect_error([] { coverage(Json{{"terms", {"speed"}}}); }, {"problem", "options.terms[0] = \"speed\"", "\"velocity\""});
  // (A list's size through the registry: the schema as the plugin file exports it.)
  expect_error([] { test::registry().create_metric("coverage", Json{{"terms", Json::array()}}, "metrics[0]"); },
               {"options.terms", "must have at least 1 item"});
  expect_error([] { coverage(Json{{"terms", {"pose", "pose"}}}); }, {"problem: options.terms[1] = \"pose\": listed twice"});
  expect_error([] { coverage(Json{{"m_max", 0}}); }, {"options.m_max = 0", "> 0"});
  expect_error([] { coverage(Json{{"bogus", 0}}); }, {"options.bogus", "unknown key"});
  // A velocity term without a sample (called outside the evaluator), and with a scene lacking M_v.
  const Coverage c = coverage(Json{{"terms", {"velocity"}}});
  SampleQuantities q;
  q.status = SampleStatus::kReachable;
  q.jacobian = Matrix6::Identity();
  q.max_velocity = Vector6::Ones();
  double out[3];
  expect_error([&] { c.local(q, out); }, {"coverage", "M_v", "no sample was given"});
  SampleSet bare;
  bare.poses = SampleSet::RowMatrix::Zero(1, 7);
  q.scene = &bare;
  q.sample = 0;
  expect_error([&] { c.local(q, out); }, {"coverage", "M_v", "the scene does not provide it"});
}

TEST(Coverage, EvaluatorResolvedAttributesGiveTheSameValuesAsLookupByName) {
  // The evaluator hands each metric its scene attributes by position (no lookup per sample);
  // with only the acceleration term M_a is attribute 0, with both terms it is attribute 1.
  for (const Json& terms : {Json::array({"acceleration"}), Json::array({"velocity", "acceleration"}),
                            Json::array({"velocity"})}) {
    Study s = load_study(study(terms), test::registry());
    const SampleSet& scene = s.problem->samples();
    const Coverage metric = coverage(Json{{"terms", terms}});
    const Haptic6R mech(default_options<Haptic6ROptions>());
    const std::vector<double> design{0.45, 0.45, 0.65, 0.55, 0.15, 3, 3, 2, 2, 1, 1, 2, 2, 3, 2, 3, 3};
    auto model = mech.build(design.data());
    auto scratch = mech.make_scratch();
    std::vector<double> sums(metric.locals().size(), 0.0), out(metric.locals().size());
    for (int i = 0; i < scene.size(); ++i) {
      SampleQuantities q;
      model->solve(scene.pose(i), metric.needs(), *scratch, q);
      q.sample = i;
      q.scene = &scene;  // no q.attributes: the metric finds M_v / M_a by name
      metric.local(q, out.data());
      for (std::size_t k = 0; k < out.size(); ++k) sums[k] += out[k];
    }
    const double by_name = metric.combine(sums.data(), scene.size());
    const Evaluation e = s.problem->evaluate_parallel(nullptr, 1);
    ASSERT_EQ(e.status, EvalStatus::kFeasible);
    EXPECT_GT(by_name, 0.3) << terms.dump();
    EXPECT_NEAR(e.objectives[0], by_name, 1e-12) << terms.dump();
  }
}

namespace {
// Counts the samples whose q.attribute_row(k) is exactly the scene's row of its k-th attribute.
class AttributeProbe final : public Metric {
 public:
  explicit AttributeProbe(std::vector<std::string> names) : names_(std::move(names)) {}
  void local(const SampleQuantities& q, double* out) const override {
    bool all = q.attribute_count == static_cast<int>(names_.size());
    for (int k = 0; all && k < q.attribute_count; ++k) {
      const auto it = q.scene->attributes.find(names_[static_cast<std::size_t>(k)]);
      const double* expected = it == q.scene->attributes.end() ? nullptr : it->second.row(q.sample).data();
      all = q.attribute_row(k) == expected;
    }
    out[0] = all ? 1.0 : 0.0;
  }
  MetricSpecs specs() const override { return {kNeedPose, names_}; }
  std::vector<LocalValue> locals() const override { return {{"resolved", Reduction::kSum, ""}}; }
  double combine(const double* reduced, int) const override { return reduced[0]; }
  Aggregation aggregation() const override { return Aggregation::kAveraging; }

 private:
  std::vector<std::string> names_;
};
}  // namespace

TEST(Coverage, EvaluatorHandsEachMetricItsAttributeRowsInDeclaredOrder) {
  Study s = load_study(study(Json::array({"velocity", "acceleration"})), test::registry());
  auto scene = std::make_shared<SampleSet>(s.problem->samples());
  auto mech = std::make_shared<Haptic6R>(default_options<Haptic6ROptions>());
  // Two metrics with the attributes in opposite orders: each sees its own order.
  std::vector<MetricEntry> metrics = {{"probe_va", std::make_shared<AttributeProbe>(std::vector<std::string>{"M_v", "M_a"})},
                                      {"probe_av", std::make_shared<AttributeProbe>(std::vector<std::string>{"M_a", "M_v"})}};
  std::vector<Objective> objectives = {{"va", 0, Sense::kMaximize, 1.0}, {"av", 1, Sense::kMaximize, 1.0}};
  const Problem problem("haptic6r", mech, scene, metrics, objectives, s.problem->design_space());
  const Evaluation e = problem.evaluate_parallel(nullptr, 1);
  ASSERT_EQ(e.status, EvalStatus::kFeasible);
  EXPECT_EQ(e.objectives[0], static_cast<double>(scene->size()));
  EXPECT_EQ(e.objectives[1], static_cast<double>(scene->size()));
  // A name the scene lacks resolves to no row (the metric then looks it up and reports it).
  std::vector<MetricEntry> missing = {{"probe_x", std::make_shared<AttributeProbe>(std::vector<std::string>{"M_x"})}};
  const Problem without("haptic6r", mech, scene, missing, {{"x", 0, Sense::kMaximize, 1.0}}, s.problem->design_space());
  EXPECT_EQ(without.evaluate_parallel(nullptr, 1).objectives[0], static_cast<double>(scene->size()));
  SampleQuantities q;  // outside the evaluator: no rows at all
  q.sample = 0;
  EXPECT_EQ(q.attribute_row(0), nullptr);
}

void block_locals_equal_local_lane_by_lane_on_the_current_target() {
  // Random J, H, g, limits and M_v, M_a per lane; among them a J with a zero column (a zero pivot:
  // the elimination gives up), a nearly singular J (large but finite solutions), rows needing the
  // pivot swap, and lanes that are not reachable.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  AttributeMatrix m_v(kBlockLanes, 36), m_a(kBlockLanes, 36);
  for (int r = 0; r < kBlockLanes; ++r) {
    for (int c = 0; c < 36; ++c) {
      m_v(r, c) = 2.0 * u(rng);
      m_a(r, c) = 20.0 * u(rng);
    }
  }
  const std::vector<std::vector<std::string>> term_sets = {
      {"pose"}, {"velocity"}, {"acceleration"}, {"force"}, {"pose", "velocity", "acceleration", "force"}, {"acceleration", "velocity"}};
  for (int trial = 0; trial < 40; ++trial) {
    auto block = std::make_unique<QuantityBlock>();
    std::array<SampleQuantities, kBlockLanes> single;
    block->jacobian_rows = block->jacobian_cols = block->inertia_size = block->gravity_size = block->actuator_count = 6;
    Vector6 max_velocity, max_torque;
    for (int i = 0; i < 6; ++i) {
      max_velocity(i) = 1.0 + 4.0 * std::abs(u(rng));
      max_torque(i) = 5.0 + 50.0 * std::abs(u(rng));
      block->max_velocity[i] = max_velocity(i);
      block->max_torque[i] = max_torque(i);
    }
    for (int lane = 0; lane < kBlockLanes; ++lane) {
      Matrix6 j = Matrix6::NullaryExpr([&] { return u(rng); });
      if (lane == 1) j.col(2).setZero();                                  // singular: a zero pivot
      if (lane == 2) j.col(4) = j.col(1) + 1e-13 * Vector6::Ones();       // nearly singular
      if (lane == 3) j.row(0).setZero(), j(0, 5) = 1e-3;                  // pivots far from the diagonal
      const Matrix6 h = [&] {
        const Matrix6 a = Matrix6::NullaryExpr([&] { return u(rng); });
        return Matrix6(a * a.transpose() + Matrix6::Identity());
      }();
      const Vector6 g = Vector6::NullaryExpr([&] { return 3.0 * u(rng); });
      SampleQuantities& q = single[static_cast<std::size_t>(lane)];
      q.status = (lane + trial) % 5 == 4 ? SampleStatus::kSingular : SampleStatus::kReachable;
      q.jacobian = j;
      q.inertia = h;
      q.gravity = g;
      q.max_velocity = max_velocity;
      q.max_torque = max_torque;
      q.sample = lane;
      block->status[lane] = static_cast<std::int32_t>(q.status);
      for (int r = 0; r < 6; ++r) {
        block->gravity[r][lane] = g(r);
        for (int c = 0; c < 6; ++c) {
          block->jacobian[r * 6 + c][lane] = j(r, c);
          block->inertia[r * 6 + c][lane] = h(r, c);
        }
      }
    }
    for (int lane = 0; lane < kBlockLanes; ++lane) block->samples[lane] = lane;
    for (const std::vector<std::string>& terms : term_sets) {
      const Coverage metric = coverage(Json{{"terms", terms}});
      std::vector<const AttributeMatrix*> attributes;
      for (const std::string& name : metric.scene_attributes()) attributes.push_back(name == "M_v" ? &m_v : &m_a);
      block->attributes = attributes.data();
      block->attribute_count = static_cast<int>(attributes.size());
      const std::size_t k = metric.locals().size();
      std::vector<double> lanes(k * kBlockLanes), one(k);
      metric.local_block(*block, lanes.data());
      // The same block with the attributes as the evaluator's block copy: the same values, bit
      // for bit (only the route of the loads differs).
      std::vector<std::vector<double>> copies;
      std::vector<const double*> starts;
      for (const AttributeMatrix* a : attributes) {
        std::vector<double>& copy = copies.emplace_back(36 * kBlockLanes);
        for (int lane = 0; lane < kBlockLanes; ++lane) {
          for (int e = 0; e < 36; ++e) copy[static_cast<std::size_t>(e * kBlockLanes + lane)] = (*a)(block->samples[lane], e);
        }
        starts.push_back(copy.data());
      }
      block->attribute_lane_data = starts.data();
      std::vector<double> copied(k * kBlockLanes);
      metric.local_block(*block, copied.data());
      block->attribute_lane_data = nullptr;
      EXPECT_EQ(copied, lanes) << "trial " << trial << ", terms " << Json(terms).dump();
      for (int lane = 0; lane < kBlockLanes; ++lane) {
        SampleQuantities& q = single[static_cast<std::size_t>(lane)];
        q.attributes = attributes.data();
        q.attribute_count = static_cast<int>(attributes.size());
        metric.local(q, one.data());
        for (std::size_t i = 0; i < k; ++i) {
          const double b = lanes[i * kBlockLanes + static_cast<std::size_t>(lane)];
          EXPECT_NEAR(b, one[i], 1e-12 * std::max(1.0, std::abs(one[i])))
              << "trial " << trial << ", lane " << lane << ", local " << metric.locals()[i].name << ", terms " << Json(terms).dump();
        }
      }
    }
  }
}

// On every vector target this machine runs (hapsyn/accel/vector_dispatch.hpp).
TEST(Coverage, BlockLocalsEqualLocalLaneByLane) {
  hapsyn::testing::for_each_vector_target(block_locals_equal_local_lane_by_lane_on_the_current_target);
}

TEST(Coverage, BlockLocalsNameAMissingAttribute) {
  auto block = std::make_unique<QuantityBlock>();
  block->jacobian_rows = block->jacobian_cols = 6;
  for (int lane = 0; lane < kBlockLanes; ++lane) block->status[lane] = static_cast<std::int32_t>(SampleStatus::kReachable);
  std::vector<double> out(3 * kBlockLanes);
  const std::string message = hapsyn::test::error_of([&] { coverage(Json{{"terms", {"velocity"}}}).local_block(*block, out.data()); });
  EXPECT_NE(message.find("coverage: the velocity term needs the scene attribute M_v"), std::string::npos) << message;
  block->jacobian_rows = 3;
  const std::string shape = hapsyn::test::error_of([&] { coverage(Json{{"terms", {"force"}}}).local_block(*block, out.data()); });
  EXPECT_NE(shape.find("coverage: the mechanism's Jacobian is 3x6"), std::string::npos) << shape;
}

void block_solves_equal_the_scalar_solve_lane_by_lane_on_the_current_target() {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto block = std::make_unique<QuantityBlock>();
  std::array<Matrix6, kBlockLanes> j, h, b;
  for (int lane = 0; lane < kBlockLanes; ++lane) {
    j[lane] = Matrix6::NullaryExpr([&] { return u(rng); });
    if (lane == 5) j[lane].col(0).setZero();  // singular: regular = 0
    const Matrix6 a = Matrix6::NullaryExpr([&] { return u(rng); });
    h[lane] = a * a.transpose();
    b[lane] = Matrix6::NullaryExpr([&] { return 10.0 * u(rng); });
    for (int e = 0; e < 36; ++e) {
      block->jacobian[e][lane] = j[lane](e / 6, e % 6);
      block->inertia[e][lane] = h[lane](e / 6, e % 6);
    }
  }
  for (const bool torque : {false, true}) {
    alignas(64) double x[36][kBlockLanes], regular[kBlockLanes];
    for (int lane = 0; lane < kBlockLanes; ++lane) {
      for (int e = 0; e < 36; ++e) x[e][lane] = b[lane](e / 6, e % 6);
    }
    if (torque) {
      Coverage::acceleration_torque_block(*block, x, regular);
    } else {
      Coverage::solve_jacobian_block(*block, x, regular);
    }
    for (int lane = 0; lane < kBlockLanes; ++lane) {
      Eigen::Matrix<double, 6, 6> expected = b[lane];
      const bool solved = Coverage::solve_jacobian(j[lane], expected);
      EXPECT_EQ(regular[lane], solved ? 1.0 : 0.0) << "lane " << lane;
      if (!solved) continue;
      if (torque) expected = Matrix6(h[lane] * expected);
      for (int e = 0; e < 36; ++e) {
        const double want = expected(e / 6, e % 6);
        EXPECT_NEAR(x[e][lane], want, 1e-12 * std::max(1.0, std::abs(want))) << "lane " << lane << ", entry " << e;
      }
    }
  }
}

// On every vector target this machine runs (hapsyn/accel/vector_dispatch.hpp).
TEST(Coverage, BlockSolvesEqualTheScalarSolveLaneByLane) {
  hapsyn::testing::for_each_vector_target(block_solves_equal_the_scalar_solve_lane_by_lane_on_the_current_target);
}
