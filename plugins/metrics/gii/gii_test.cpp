// Tests of the GII metric: closed-form singular values against Eigen's SVD, hand-checkable
// one- and two-sample scenes, a five-bar sample, declarations and options.
#include "gii.hpp"

#include <fivebar.hpp>

#include "test_support.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/schema.hpp>

#include <gtest/gtest.h>

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
using hapsyn::TaskJointMatrix;
using hapsyn::plugins::Gii;
using hapsyn::plugins::GiiOptions;

TaskJointMatrix matrix2(double a, double b, double c, double d) {
  TaskJointMatrix m(2, 2);
  m << a, b, c, d;
  return m;
}

// GII of a scene given as the Jacobians of its samples, through local() and combine().
double gii_of(const std::vector<TaskJointMatrix>& jacobians) {
  const Gii gii;
  double reduced[2] = {std::numeric_limits<double>::infinity(), 0.0};
  for (const auto& j : jacobians) {
    SampleQuantities q;
    q.jacobian = j;
    double local[2];
    gii.local(q, local);
    reduced[0] = std::min(reduced[0], local[0]);
    reduced[1] = std::max(reduced[1], local[1]);
  }
  return gii.combine(reduced, static_cast<int>(jacobians.size()));
}

TEST(GiiSingularValues, ClosedFormMatchesJacobiSvdOnRandomMatrices) {
  std::mt19937 rng(42);
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<int> exponent(-8, 8);
  for (int i = 0; i < 10000; ++i) {
    const double scale = std::pow(10.0, exponent(rng));
    const TaskJointMatrix m = scale * matrix2(normal(rng), normal(rng), normal(rng), normal(rng));
    double lo = 0.0, hi = 0.0;
    Gii::singular_values(m, lo, hi);
    const Eigen::Matrix2d dense = m;
    const Eigen::Vector2d s = Eigen::JacobiSVD<Eigen::Matrix2d>(dense).singularValues();
    ASSERT_NEAR(hi, s(0), 1e-14 * s(0)) << dense;
    ASSERT_NEAR(lo, s(1), 1e-13 * s(0)) << dense;
    ASSERT_LE(lo, hi);
  }
}

TEST(GiiSingularValues, DiagonalAndRotatedMatricesGiveTheirKnownValues) {
  double lo = 0.0, hi = 0.0;
  Gii::singular_values(matrix2(3.0, 0.0, 0.0, -2.0), lo, hi);
  EXPECT_DOUBLE_EQ(hi, 3.0);
  EXPECT_DOUBLE_EQ(lo, 2.0);
  const double c = std::cos(0.7), s = std::sin(0.7);
  // R(0.7) diag(5, 0.5)
  Gii::singular_values(matrix2(5 * c, -0.5 * s, 5 * s, 0.5 * c), lo, hi);
  EXPECT_NEAR(hi, 5.0, 1e-14);
  EXPECT_NEAR(lo, 0.5, 1e-14);
  // A tiny but well-determined smallest value keeps its relative accuracy.
  Gii::singular_values(matrix2(1.0, 0.0, 0.0, 1e-20), lo, hi);
  EXPECT_EQ(hi, 1.0);
  EXPECT_EQ(lo, 1e-20);
}

TEST(GiiSingularValues, ZeroAndRankOneMatricesGiveZeroNeverNan) {
  double lo = -1.0, hi = -1.0;
  Gii::singular_values(matrix2(0.0, 0.0, 0.0, 0.0), lo, hi);
  EXPECT_EQ(lo, 0.0);
  EXPECT_EQ(hi, 0.0);
  Gii::singular_values(matrix2(1.0, 2.0, 2.0, 4.0), lo, hi);
  EXPECT_EQ(lo, 0.0);
  EXPECT_NEAR(hi, 5.0, 1e-15);
  Gii::singular_values(matrix2(0.0, 3.0, 0.0, 4.0), lo, hi);
  EXPECT_EQ(lo, 0.0);
  EXPECT_NEAR(hi, 5.0, 1e-15);
  // Nearly rank one: rounding must not produce a NaN or a negative value.
  std::mt19937 rng(1);
  std::normal_distribution<double> normal;
  for (int i = 0; i < 1000; ++i) {
    const double a = normal(rng), b = normal(rng), t = normal(rng);
    Gii::singular_values(matrix2(a, b, t * a, t * b), lo, hi);
    ASSERT_TRUE(std::isfinite(lo) && std::isfinite(hi));
    ASSERT_GE(lo, 0.0);
    ASSERT_LE(lo, 1e-15 * hi);
  }
}

TEST(GiiSingularValues, OtherShapesUseTheSvd) {
  TaskJointMatrix wide(2, 3);
  wide << 1, 2, 3, 4, 5, 6;
  TaskJointMatrix cube(3, 3);
  cube << 2, -1, 0, -1, 2, -1, 0, -1, 2;
  for (const TaskJointMatrix& m : {wide, cube}) {
    double lo = 0.0, hi = 0.0;
    Gii::singular_values(m, lo, hi);
    const Eigen::MatrixXd dense = m;
    const Eigen::VectorXd s = Eigen::JacobiSVD<Eigen::MatrixXd>(dense).singularValues();
    EXPECT_NEAR(hi, s(0), 1e-14 * s(0));
    EXPECT_NEAR(lo, s(s.size() - 1), 1e-14 * s(0));
  }
  double lo = -1.0, hi = -1.0;
  Gii::singular_values(TaskJointMatrix(0, 0), lo, hi);
  EXPECT_EQ(lo, 0.0);
  EXPECT_EQ(hi, 0.0);
}

TEST(Gii, OneSampleSceneIsTheInverseConditionNumber) {
  EXPECT_DOUBLE_EQ(gii_of({matrix2(2.0, 0.0, 0.0, 1.0)}), 0.5);
  EXPECT_DOUBLE_EQ(gii_of({matrix2(1.0, 0.0, 0.0, 1.0)}), 1.0);
  // [[1, 1], [0, 1]]: singular values (sqrt(5) +- 1) / 2, ratio (3 - sqrt(5)) / 2.
  EXPECT_NEAR(gii_of({matrix2(1.0, 1.0, 0.0, 1.0)}), (3.0 - std::sqrt(5.0)) / 2.0, 1e-15);
}

TEST(Gii, TwoSampleSceneCombinesTheWorstCasesOfDifferentSamples) {
  // Sample a: sigma = (1, 0.5); sample b: sigma = (3, 2). GII = min sigma_min / max sigma_max
  // = 0.5 / 3, smaller than either sample's own ratio (0.5, 0.667).
  EXPECT_DOUBLE_EQ(gii_of({matrix2(1.0, 0.0, 0.0, 0.5), matrix2(0.0, 3.0, 2.0, 0.0)}), 0.5 / 3.0);
  // Order does not matter.
  EXPECT_DOUBLE_EQ(gii_of({matrix2(0.0, 3.0, 2.0, 0.0), matrix2(1.0, 0.0, 0.0, 0.5)}), 0.5 / 3.0);
}

TEST(Gii, FiveBarSampleMatchesTheSvdOfItsJacobian) {
  using namespace hapsyn::plugins;
  const FiveBarModel model(FiveBarDesign{0.0004, 0.2997, 0.3, 0.4196}, hapsyn::default_options<FiveBarOptions>());
  hapsyn::MechanismScratch scratch;
  SampleQuantities q;
  const double pose[2] = {0.05, -0.05};
  model.solve(pose, hapsyn::kNeedJacobian, scratch, q);
  ASSERT_EQ(q.status, hapsyn::SampleStatus::kReachable);
  double local[2];
  Gii().local(q, local);
  const Eigen::Vector2d s = Eigen::JacobiSVD<Eigen::Matrix2d>(Eigen::Matrix2d(q.jacobian)).singularValues();
  EXPECT_NEAR(local[0], s(1), 1e-15);
  EXPECT_NEAR(local[1], s(0), 1e-15);
  // Over a two-sample scene (two opposite corners) the value is computed by hand from the SVDs.
  const double other[2] = {-0.05, 0.05};
  SampleQuantities p;
  model.solve(other, hapsyn::kNeedJacobian, scratch, p);
  const Eigen::Vector2d t = Eigen::JacobiSVD<Eigen::Matrix2d>(Eigen::Matrix2d(p.jacobian)).singularValues();
  EXPECT_NEAR(gii_of({q.jacobian, p.jacobian}), std::min(s(1), t(1)) / std::max(s(0), t(0)), 1e-14);
}

TEST(Gii, DeclaresItsLocalsNeedsAndWorstCaseAggregation) {
  const Gii gii;
  const auto locals = gii.locals();
  ASSERT_EQ(locals.size(), 2u);
  EXPECT_EQ(locals[0].name, "sigma_min_J");
  EXPECT_EQ(locals[0].reduction, Reduction::kMin);
  EXPECT_EQ(locals[1].name, "sigma_max_J");
  EXPECT_EQ(locals[1].reduction, Reduction::kMax);
  EXPECT_EQ(gii.needs(), hapsyn::kNeedJacobian);
  EXPECT_EQ(gii.aggregation(), hapsyn::Aggregation::kWorstCase);
}

TEST(Gii, CombineNeverDividesByZero) {
  const Gii gii;
  const double zero[2] = {0.0, 0.0};
  EXPECT_EQ(gii.combine(zero, 1), 0.0);
  const double infinite[2] = {1.0, std::numeric_limits<double>::infinity()};
  EXPECT_EQ(gii.combine(infinite, 1), 0.0);
  const double normal[2] = {0.25, 0.5};
  EXPECT_EQ(gii.combine(normal, 1), 0.5);
}

TEST(Gii, DeclaresRowsAndCharacteristicLengthAndRefusesOtherKeys) {
  const hapsyn::Registry& registry = hapsyn::test::registry();
  const Json& schema = registry.find("gii").schema;
  EXPECT_NO_THROW(hapsyn::check_schema(schema, "gii"));
  EXPECT_TRUE(schema.at("properties").contains("rows"));
  EXPECT_NO_THROW(registry.create_metric("gii", Json(nullptr), "metrics[0]"));
  EXPECT_NE(hapsyn::test::error_of([&] { registry.create_metric("gii", Json{{"scale", 2.0}}, "metrics[0]"); })
                .find("problem: metrics[0].options.scale: unknown key"),
            std::string::npos);
  EXPECT_NE(hapsyn::test::error_of([&] { registry.create_metric("gii", Json{{"characteristic_length", -1}}, "metrics[0]"); })
                .find("metrics[0].options.characteristic_length = -1"),
            std::string::npos);
}

// A 6-row (omega, v) Jacobian: the angular rows scaled by L, or one part alone, each against
// the SVD of the matrix built by hand; no length refuses with the rule.
TEST(Gii, MixedJacobianUsesTheDeclaredRowsOrRefuses) {
  SampleQuantities q;
  q.jacobian = TaskJointMatrix::Random(6, 6);
  const auto svd = [](const Eigen::MatrixXd& m) {
    const Eigen::JacobiSVD<Eigen::MatrixXd> s(m);
    return std::make_pair(s.singularValues().minCoeff(), s.singularValues().maxCoeff());
  };
  double out[2];
  GiiOptions all{"all", 0.4};
  Gii(all).local(q, out);
  Eigen::MatrixXd scaled = q.jacobian;
  scaled.topRows(3) *= 0.4;
  EXPECT_NEAR(out[0], svd(scaled).first, 1e-14);
  EXPECT_NEAR(out[1], svd(scaled).second, 1e-14);
  Gii(GiiOptions{"translational", 0.0}).local(q, out);
  EXPECT_NEAR(out[0], svd(q.jacobian.bottomRows(3)).first, 1e-14);
  Gii(GiiOptions{"rotational", 0.0}).local(q, out);
  EXPECT_NEAR(out[1], svd(q.jacobian.topRows(3)).second, 1e-14);
  EXPECT_NE(hapsyn::test::error_of([&] { Gii().local(q, out); })
                .find("gii: the mechanism's Jacobian is 6x6 with 3 angular rows [rad/s] and 3 linear rows [m/s]: set "
                      "options.characteristic_length"),
            std::string::npos);
  SampleQuantities planar;
  planar.jacobian = TaskJointMatrix::Random(2, 2);
  EXPECT_NE(hapsyn::test::error_of([&] { Gii(GiiOptions{"rotational", 0.0}).local(planar, out); })
                .find("options.rows = \"rotational\": the mechanism's Jacobian is 2x2 with no angular rows"),
            std::string::npos);
}

}  // namespace

TEST(Gii, EnvelopeBoundIsTheInverseConditionBoundOnlyForJAsReturned) {
  // One sample of inverse condition number 0.5 scores 0.5: an envelope claiming at most 0.6
  // bounds it; without the field (the default) there is no bound.
  hapsyn::SampleEnvelope envelope;
  EXPECT_EQ(Gii().envelope_bound(envelope), std::numeric_limits<double>::infinity());
  envelope.jacobian_inverse_condition_max = 0.6;
  EXPECT_EQ(Gii().envelope_bound(envelope), 0.6);
  EXPECT_LE(gii_of({matrix2(2.0, 0.0, 0.0, 1.0)}), Gii().envelope_bound(envelope));
  // With rows or a characteristic length that change J, the mechanism's bound of J says nothing.
  const auto with = [](const Json& options) {
    return Gii(hapsyn::make_options<hapsyn::plugins::GiiOptions>(options));
  };
  EXPECT_EQ(with(Json{{"rows", "translational"}}).envelope_bound(envelope), std::numeric_limits<double>::infinity());
  EXPECT_EQ(with(Json{{"characteristic_length", 0.1}}).envelope_bound(envelope), std::numeric_limits<double>::infinity());
}
