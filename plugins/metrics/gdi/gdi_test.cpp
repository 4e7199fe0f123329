// Tests of the GDI metric: closed-form largest singular value against Eigen's SVD,
// hand-checkable one- and two-sample scenes, a five-bar sample, declarations and options.
#include "gdi.hpp"

#include <fivebar.hpp>

#include "test_support.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/schema.hpp>

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>
#include <limits>
#include <random>
#include <type_traits>
#include <vector>

namespace {

using hapsyn::Json;
using hapsyn::Reduction;
using hapsyn::SampleQuantities;
using hapsyn::TaskMatrix;
using hapsyn::plugins::Gdi;

TaskMatrix matrix2(double a, double b, double c, double d) {
  TaskMatrix m(2, 2);
  m << a, b, c, d;
  return m;
}

double gdi_of(const std::vector<TaskMatrix>& masses) {
  const Gdi gdi;
  double reduced = 0.0;
  for (const auto& m : masses) {
    SampleQuantities q;
    q.effective_mass = m;
    double local = 0.0;
    gdi.local(q, &local);
    reduced = std::max(reduced, local);
  }
  return gdi.combine(&reduced, static_cast<int>(masses.size()));
}

TEST(GdiSingularValue, ClosedFormMatchesJacobiSvdOnRandomMatrices) {
  std::mt19937 rng(42);
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<int> exponent(-8, 8);
  for (int i = 0; i < 10000; ++i) {
    const double scale = std::pow(10.0, exponent(rng));
    // Symmetric positive semi-definite (an effective mass) and general matrices alike.
    Eigen::Matrix2d a;
    a << normal(rng), normal(rng), normal(rng), normal(rng);
    a *= scale;
    const Eigen::Matrix2d m = (i % 2) ? Eigen::Matrix2d(a.transpose() * a) : a;
    const double value = Gdi::largest_singular_value(TaskMatrix(m));
    const double expected = Eigen::JacobiSVD<Eigen::Matrix2d>(m).singularValues()(0);
    ASSERT_NEAR(value, expected, 1e-14 * expected) << m;
  }
}

TEST(GdiSingularValue, ZeroRankOneAndOtherShapesNeverNan) {
  EXPECT_EQ(Gdi::largest_singular_value(matrix2(0, 0, 0, 0)), 0.0);
  EXPECT_NEAR(Gdi::largest_singular_value(matrix2(1, 2, 2, 4)), 5.0, 1e-15);
  EXPECT_EQ(Gdi::largest_singular_value(TaskMatrix(0, 0)), 0.0);
  TaskMatrix cube(3, 3);
  cube << 2, -1, 0, -1, 2, -1, 0, -1, 2;  // eigenvalues 2 - sqrt(2), 2, 2 + sqrt(2)
  EXPECT_NEAR(Gdi::largest_singular_value(cube), 2.0 + std::sqrt(2.0), 1e-14);
}

TEST(Gdi, OneSampleSceneIsOneOverOnePlusTheLargestMass) {
  EXPECT_DOUBLE_EQ(gdi_of({matrix2(0.5, 0.0, 0.0, 1.0)}), 0.5);  // sigma_max = 1 kg
  EXPECT_DOUBLE_EQ(gdi_of({matrix2(0.0, 0.0, 0.0, 0.0)}), 1.0);  // massless
  // [[2, 1], [1, 2]]: eigenvalues 1 and 3 -> 1 / 4.
  EXPECT_NEAR(gdi_of({matrix2(2.0, 1.0, 1.0, 2.0)}), 0.25, 1e-15);
}

TEST(Gdi, TwoSampleSceneTakesTheHeaviestSample) {
  EXPECT_DOUBLE_EQ(gdi_of({matrix2(0.5, 0.0, 0.0, 0.25), matrix2(3.0, 0.0, 0.0, 1.0)}), 0.25);
  EXPECT_DOUBLE_EQ(gdi_of({matrix2(3.0, 0.0, 0.0, 1.0), matrix2(0.5, 0.0, 0.0, 0.25)}), 0.25);
}

TEST(Gdi, FiveBarSampleMatchesTheSvdOfItsEffectiveMass) {
  using namespace hapsyn::plugins;
  const FiveBarModel model(FiveBarDesign{0.0001, 0.0899, 0.1152, 0.1236}, hapsyn::default_options<FiveBarOptions>());
  hapsyn::MechanismScratch scratch;
  SampleQuantities q;
  const double pose[2] = {0.05, 0.05};
  model.solve(pose, hapsyn::kNeedEffectiveMass, scratch, q);
  ASSERT_EQ(q.status, hapsyn::SampleStatus::kReachable);
  double local = 0.0;
  Gdi().local(q, &local);
  const Eigen::Matrix2d m = q.effective_mass;
  const double expected = Eigen::JacobiSVD<Eigen::Matrix2d>(m).singularValues()(0);
  EXPECT_NEAR(local, expected, 1e-15);
  // For the symmetric positive-definite M this is its largest eigenvalue.
  const Eigen::Vector2d eigen = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(m).eigenvalues();
  EXPECT_NEAR(local, eigen(1), 1e-14);
  EXPECT_GT(eigen(0), 0.0);
  EXPECT_NEAR(gdi_of({q.effective_mass}), 1.0 / (1.0 + expected), 1e-15);
}

TEST(Gdi, DeclaresItsLocalNeedsAndWorstCaseAggregation) {
  const Gdi gdi;
  const auto locals = gdi.locals();
  ASSERT_EQ(locals.size(), 1u);
  EXPECT_EQ(locals[0].name, "sigma_max_M");
  EXPECT_EQ(locals[0].reduction, Reduction::kMax);
  EXPECT_EQ(locals[0].unit, "kg");
  EXPECT_EQ(gdi.needs(), hapsyn::kNeedEffectiveMass);
  EXPECT_EQ(gdi.aggregation(), hapsyn::Aggregation::kWorstCase);
}

TEST(Gdi, CombineIsFiniteForAnInfiniteMass) {
  const Gdi gdi;
  const double infinite = std::numeric_limits<double>::infinity();
  EXPECT_EQ(gdi.combine(&infinite, 1), 0.0);
}

TEST(Gdi, HasNoOptionsAndRefusesAnyKey) {
  // No Options type: the framework default-constructs the metric, and the schema it derives
  // (what the plugin file exports) is an empty object that refuses every key.
  static_assert(std::is_default_constructible_v<Gdi>);
  const hapsyn::Registry& registry = hapsyn::test::registry();
  const Json& schema = registry.find("gdi").schema;
  EXPECT_NO_THROW(hapsyn::check_schema(schema, "gdi"));
  EXPECT_EQ(schema.at("properties"), Json::object());
  EXPECT_EQ(hapsyn::validate_and_fill(schema, Json::object(), "metrics[0].options"), Json::object());
  EXPECT_NO_THROW(registry.create_metric("gdi", Json(nullptr), "metrics[0]"));
  EXPECT_EQ(hapsyn::test::error_of([&] { registry.create_metric("gdi", Json{{"scale", 2.0}}, "metrics[0]"); }),
            "problem: metrics[0].options.scale: unknown key; this object takes no keys");
}

}  // namespace

TEST(Gdi, EnvelopeBoundIsOneOverOnePlusTheSmallestMass) {
  hapsyn::SampleEnvelope envelope;
  EXPECT_EQ(Gdi().envelope_bound(envelope), 1.0);  // nothing known: GDI <= 1 always
  envelope.effective_mass_sigma_max_min = 1.0;
  EXPECT_EQ(Gdi().envelope_bound(envelope), 0.5);
  // A sample of mass 3 kg scores 0.25 <= 0.5.
  EXPECT_LE(gdi_of({matrix2(3.0, 0.0, 0.0, 1.0)}), Gdi().envelope_bound(envelope));
}
