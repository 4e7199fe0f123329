// Tests of the planar_square scene: sample count, inclusive and exact bounds, order, symmetry,
// refused options (with their messages) and the schema.
#include "planar_square.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/schema.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace {

using hapsyn::Json;
using hapsyn::SampleSet;
using hapsyn::plugins::PlanarSquare;
using hapsyn::plugins::PlanarSquareOptions;

// The options as the registry hands them over: validated against the declarations, defaults filled.
PlanarSquareOptions options_of(const Json& options) { return hapsyn::make_options<PlanarSquareOptions>(options); }

SampleSet build(double side, double step) { return PlanarSquare(options_of(Json{{"side", side}, {"step", step}})).build({}); }

std::string error_of(const Json& options) {
  try {
    PlanarSquare scene(options_of(options));
  } catch (const hapsyn::Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(PlanarSquare, DefaultOptionsGiveA21By21Grid) {
  const PlanarSquare scene(options_of(Json::object()));
  EXPECT_EQ(scene.side(), 0.1);
  EXPECT_EQ(scene.step(), 0.005);
  EXPECT_EQ(scene.per_axis(), 21);
  const SampleSet set = scene.build({});
  EXPECT_EQ(set.size(), 441);
  EXPECT_EQ(set.dimension(), 2);
  EXPECT_EQ(set.coordinates, (std::vector<std::string>{"x", "y"}));
  EXPECT_EQ(set.unit, "m");
  EXPECT_TRUE(set.attributes.empty());
}

TEST(PlanarSquare, SampleCountIsRoundSideOverStepPlusOneSquared) {
  EXPECT_EQ(build(0.1, 0.001).size(), 101 * 101);  // the paper's workspace grid
  EXPECT_EQ(build(0.2, 0.05).size(), 5 * 5);
  EXPECT_EQ(build(0.1, 0.1).size(), 2 * 2);        // step = side: the four corners
  EXPECT_EQ(build(0.3, 0.1).size(), 4 * 4);        // 0.3 / 0.1 = 2.9999999999999996
  EXPECT_EQ(build(0.7, 0.1).size(), 8 * 8);        // 0.7 / 0.1 = 6.999999999999999
}

TEST(PlanarSquare, BoundsAreInclusiveExactAndCentredAtTheOrigin) {
  for (double side : {0.1, 0.3, 0.7, 1.0 / 3.0}) {
    const SampleSet set = build(side, side / 10);
    const Eigen::VectorXd lo = set.lower_corner(), hi = set.upper_corner();
    EXPECT_EQ(lo(0), -side / 2);
    EXPECT_EQ(lo(1), -side / 2);
    EXPECT_EQ(hi(0), side / 2);
    EXPECT_EQ(hi(1), side / 2);
    EXPECT_EQ(set.pose(0)[0], -side / 2);
    EXPECT_EQ(set.pose(set.size() - 1)[1], side / 2);
    // 11 x 11 grid: the middle sample is exactly the centre.
    EXPECT_EQ(set.pose(60)[0], 0.0);
    EXPECT_EQ(set.pose(60)[1], 0.0);
  }
}

TEST(PlanarSquare, OrderIsRowMajorWithXFastest) {
  const SampleSet set = build(0.1, 0.05);  // 3 x 3
  const double expected[9][2] = {{-0.05, -0.05}, {0.0, -0.05}, {0.05, -0.05}, {-0.05, 0.0}, {0.0, 0.0},
                                 {0.05, 0.0},    {-0.05, 0.05}, {0.0, 0.05},  {0.05, 0.05}};
  ASSERT_EQ(set.size(), 9);
  for (int i = 0; i < 9; ++i) {
    EXPECT_EQ(set.pose(i)[0], expected[i][0]) << i;
    EXPECT_EQ(set.pose(i)[1], expected[i][1]) << i;
  }
}

TEST(PlanarSquare, GridIsMirrorSymmetricAndSpacedByStep) {
  const SampleSet set = build(0.1, 0.001);
  const int n = 101;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double* p = set.pose(i * n + j);
      const double* mirror = set.pose(i * n + (n - 1 - j));
      ASSERT_EQ(p[0], -mirror[0]);
      ASSERT_EQ(p[1], set.pose(j * n + i)[0]);  // same abscissae on both axes
      if (j > 0) {
        ASSERT_NEAR(p[0] - set.pose(i * n + j - 1)[0], 0.001, 1e-15);
      }
    }
  }
}

TEST(PlanarSquare, RefusesAStepThatDoesNotDivideTheSide) {
  EXPECT_EQ(error_of(Json{{"side", 0.1}, {"step", 0.03}}),
            "problem: options.step = 0.03: must divide side (0.1) into whole steps");
  EXPECT_EQ(error_of(Json{{"side", 0.1}, {"step", 0.1 / 3 * 1.000001}}).rfind("problem: options.step = ", 0), 0u);
  // Within 1e-9 relative is accepted.
  EXPECT_EQ(error_of(Json{{"side", 0.1}, {"step", 0.005 * (1 + 1e-12)}}), "no error");
}

TEST(PlanarSquare, RefusesAStepLargerThanTheSide) {
  EXPECT_EQ(error_of(Json{{"side", 0.1}, {"step", 0.2}}), "problem: options.step = 0.2: must be <= side (0.1)");
}

TEST(PlanarSquare, RefusesNonPositiveUnknownAndHugeOptions) {
  // The declared rules (> 0, a number, known keys) are the framework's: component "problem".
  EXPECT_EQ(error_of(Json{{"side", 0.0}}), "problem: options.side = 0.0: must be > 0");
  EXPECT_EQ(error_of(Json{{"step", -0.001}}), "problem: options.step = -0.001: must be > 0");
  EXPECT_EQ(error_of(Json{{"step", "fine"}}), "problem: options.step = \"fine\": must be a number");
  EXPECT_EQ(error_of(Json{{"stpe", 0.001}}),
            "problem: options.stpe: unknown key (did you mean 'step'?); known keys: side, step");
  EXPECT_EQ(error_of(Json{{"side", 1.0}, {"step", 1e-4}}),
            "planar_square: options.step = 0.0001: gives 10001.0 x 10001.0 samples; at most 2000000 are allowed");
}

TEST(PlanarSquare, RefusesRequestedAttributes) {
  hapsyn::SceneRequest request;
  request.attributes = {"human_velocity_axes"};
  try {
    PlanarSquare(options_of(Json::object())).build(request);
    FAIL() << "no error";
  } catch (const hapsyn::Error& e) {
    EXPECT_STREQ(e.what(), "planar_square: per-sample attribute 'human_velocity_axes' requested: this scene provides none");
  }
}

TEST(PlanarSquare, DeclaredSchemaIsValidWithThePaperDefaultsAndUnits) {
  const Json schema = hapsyn::options_schema<PlanarSquareOptions>();
  EXPECT_NO_THROW(hapsyn::check_schema(schema, "planar_square"));
  const Json filled = hapsyn::validate_and_fill(schema, Json::object(), "scene.options");
  EXPECT_EQ(filled.at("side").get<double>(), 0.1);
  EXPECT_EQ(filled.at("step").get<double>(), 0.005);
  EXPECT_EQ(schema.at("properties").at("side").at("unit"), "m");
  EXPECT_EQ(schema.at("properties").at("step").at("unit"), "m");
  EXPECT_EQ(schema.at("properties").at("side").at("exclusiveMinimum"), 0);
  EXPECT_EQ(schema.at("properties").at("step").at("exclusiveMinimum"), 0);
  EXPECT_THROW(hapsyn::validate_and_fill(schema, Json{{"side", -1.0}}, "scene.options"), hapsyn::Error);
  EXPECT_EQ(PlanarSquare(options_of(filled)).build({}).size(), 441);
}

}  // namespace
