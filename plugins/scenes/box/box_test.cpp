// Tests of the box scene: sample counts and coordinates against an independent enumeration of
// the grid, inclusive bounds, order, the optional orientation, refused options (with their
// messages) and the schema.
#include "box.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/schema.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace {

using hapsyn::Json;
using hapsyn::SampleSet;
using hapsyn::plugins::Box;
using hapsyn::plugins::BoxOptions;

BoxOptions options_of(const Json& options) { return hapsyn::make_options<BoxOptions>(options); }

SampleSet build(const Json& options) { return Box(options_of(options)).build({}); }

std::string error_of(const Json& options) {
  try {
    Box scene(options_of(options));
  } catch (const hapsyn::Error& e) {
    return e.what();
  }
  return "no error";
}

// The grid enumerated independently: the lower corner plus whole steps, x fastest.
std::vector<std::vector<double>> brute_force_grid(const std::vector<double>& center, const std::vector<double>& size,
                                                  double step) {
  std::vector<int> n;
  for (double s : size) n.push_back(static_cast<int>(std::lround(s / step)) + 1);
  while (n.size() < 3) n.push_back(1);
  std::vector<std::vector<double>> points;
  for (int k = 0; k < n[2]; ++k) {
    for (int j = 0; j < n[1]; ++j) {
      for (int i = 0; i < n[0]; ++i) {
        const int index[3] = {i, j, k};
        std::vector<double> p;
        for (std::size_t a = 0; a < size.size(); ++a) p.push_back(center[a] - size[a] / 2 + index[a] * step);
        points.push_back(p);
      }
    }
  }
  return points;
}

void expect_grid(const Json& options, const std::vector<double>& center, const std::vector<double>& size, double step) {
  const SampleSet set = build(options);
  const auto expected = brute_force_grid(center, size, step);
  ASSERT_EQ(set.size(), static_cast<int>(expected.size())) << options.dump();
  ASSERT_EQ(set.dimension(), static_cast<int>(size.size()));
  for (int i = 0; i < set.size(); ++i) {
    for (std::size_t a = 0; a < size.size(); ++a) {
      ASSERT_NEAR(set.pose(i)[a], expected[static_cast<std::size_t>(i)][a], 1e-12) << options.dump() << " sample " << i;
    }
  }
}

TEST(Box, DefaultOptionsGiveA21By21Rectangle) {
  const Box scene(options_of(Json::object()));
  EXPECT_EQ(scene.dimension(), 2);
  EXPECT_EQ(scene.per_axis()[0], 21);
  EXPECT_EQ(scene.per_axis()[1], 21);
  EXPECT_EQ(scene.per_axis()[2], 1);
  const SampleSet set = scene.build({});
  EXPECT_EQ(set.size(), 441);
  EXPECT_EQ(set.coordinates, (std::vector<std::string>{"x", "y"}));
  EXPECT_EQ(set.unit, "m");
  EXPECT_TRUE(set.attributes.empty());
  EXPECT_TRUE(set.weights.empty());
  EXPECT_EQ(set.info.at("samples"), 441);
}

TEST(Box, RectangleMatchesAnIndependentEnumerationOfTheGrid) {
  expect_grid(Json{{"center", {0.0, 0.0}}, {"size", {0.1, 0.1}}, {"step", 0.01}}, {0.0, 0.0}, {0.1, 0.1}, 0.01);
  expect_grid(Json{{"center", {0.02, -0.3}}, {"size", {0.3, 0.1}}, {"step", 0.1}}, {0.02, -0.3}, {0.3, 0.1}, 0.1);
  expect_grid(Json{{"center", {1.0, 2.0}}, {"size", {0.7, 0.2}}, {"step", 0.1}}, {1.0, 2.0}, {0.7, 0.2}, 0.1);
}

TEST(Box, BoxMatchesAnIndependentEnumerationOfTheGrid) {
  expect_grid(Json{{"dimension", 3}, {"center", {0.0, 0.1, 0.2}}, {"size", {0.2, 0.1, 0.3}}, {"step", 0.05}},
              {0.0, 0.1, 0.2}, {0.2, 0.1, 0.3}, 0.05);
  const SampleSet set = build(Json{{"dimension", 3}, {"center", {0, 0, 0}}, {"size", {0.2, 0.1, 0.3}}, {"step", 0.05}});
  EXPECT_EQ(set.size(), 5 * 3 * 7);
  EXPECT_EQ(set.coordinates, (std::vector<std::string>{"x", "y", "z"}));
}

TEST(Box, BoundsAreInclusiveAndExactAtAZeroCentre) {
  for (double side : {0.1, 0.3, 0.7, 1.0 / 3.0}) {
    const SampleSet set = build(Json{{"dimension", 3}, {"center", {0, 0, 0}}, {"size", {side, side, 2 * side}},
                                     {"step", side / 10}});
    const Eigen::VectorXd lo = set.lower_corner(), hi = set.upper_corner();
    EXPECT_EQ(lo(0), -side / 2);
    EXPECT_EQ(hi(0), side / 2);
    EXPECT_EQ(lo(2), -side);
    EXPECT_EQ(hi(2), side);
    // Mirror symmetric bit for bit: sample 0 and the last are opposite corners.
    for (int a = 0; a < 3; ++a) EXPECT_EQ(set.pose(0)[a], -set.pose(set.size() - 1)[a]);
  }
}

TEST(Box, OrderIsXFastestThenYThenZ) {
  const SampleSet set = build(Json{{"dimension", 3}, {"center", {0, 0, 0}}, {"size", {0.1, 0.2, 0.1}}, {"step", 0.1}});
  ASSERT_EQ(set.size(), 2 * 3 * 2);
  for (int i = 0; i < set.size(); ++i) {
    const int ix = i % 2, iy = (i / 2) % 3, iz = i / 6;
    EXPECT_NEAR(set.pose(i)[0], -0.05 + 0.1 * ix, 1e-15) << i;
    EXPECT_NEAR(set.pose(i)[1], -0.1 + 0.1 * iy, 1e-15) << i;
    EXPECT_NEAR(set.pose(i)[2], -0.05 + 0.1 * iz, 1e-15) << i;
  }
}

TEST(Box, OrientationGivesFullPosesWithThatNormalizedOrientation) {
  const double s = std::sqrt(0.5);
  const std::vector<double> q = {s * (1 + 1e-7), 0.0, s, 0.0};  // norm 1 + 1e-7: accepted, normalized
  const Box scene(options_of(Json{{"dimension", 3}, {"center", {0, 0, 0.5}}, {"size", {0.1, 0.1, 0.1}}, {"step", 0.05},
                                  {"orientation", q}}));
  const double norm = std::sqrt(q[0] * q[0] + q[2] * q[2]);
  ASSERT_EQ(scene.orientation().size(), 4u);
  const SampleSet set = scene.build({});
  EXPECT_EQ(set.coordinates, (std::vector<std::string>{"x", "y", "z", "qw", "qx", "qy", "qz"}));
  ASSERT_EQ(set.size(), 27);
  for (int i = 0; i < set.size(); ++i) {
    EXPECT_EQ(set.pose(i)[3], q[0] / norm);
    EXPECT_EQ(set.pose(i)[4], 0.0);
    EXPECT_EQ(set.pose(i)[5], q[2] / norm);
    EXPECT_EQ(set.pose(i)[6], 0.0);
  }
  EXPECT_NEAR(set.pose(0)[3] * set.pose(0)[3] + set.pose(0)[5] * set.pose(0)[5], 1.0, 1e-15);
  EXPECT_EQ(set.pose(13)[2], 0.5);  // the middle sample is the centre
}

TEST(Box, RefusesCenterAndSizeThatDoNotMatchTheDimension) {
  EXPECT_EQ(error_of(Json{{"dimension", 3}, {"size", {0.1, 0.1, 0.1}}}),
            "problem: options.center = [0.0,0.0]: must have 3 numbers (one per dimension)");
  EXPECT_EQ(error_of(Json{{"center", {0, 0}}, {"size", {0.1, 0.1, 0.1}}}),
            "problem: options.size = [0.1,0.1,0.1]: must have 2 numbers (one per dimension)");
}

TEST(Box, RefusesABadOrientation) {
  const Json box3 = {{"dimension", 3}, {"center", {0, 0, 0}}, {"size", {0.1, 0.1, 0.1}}, {"step", 0.05}};
  Json o = box3;
  o["orientation"] = {1.0, 0.0, 0.0};
  EXPECT_EQ(error_of(o), "box: options.orientation = [1.0,0.0,0.0]: must be empty or 4 numbers [qw, qx, qy, qz]");
  o["orientation"] = {1.0, 1.0, 0.0, 0.0};
  EXPECT_EQ(error_of(o),
            "box: options.orientation = [1.0,1.0,0.0,0.0]: must be a unit quaternion (norm 1.4142135623730951 "
            "differs from 1 by more than 1e-6)");
  o["orientation"] = {1.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(error_of(o), "no error");
  EXPECT_EQ(error_of(Json{{"orientation", {1.0, 0.0, 0.0, 0.0}}}),
            "box: options.orientation = [1.0,0.0,0.0,0.0]: needs dimension 3 (a full pose is x, y, z, qw, qx, qy, qz)");
  o["orientation"] = {1.0, 0.0, 0.0, 0.0, 0.0};  // the declared rule: at most 4 numbers
  EXPECT_EQ(error_of(o).rfind("problem: options.orientation = [1.0,0.0,0.0,0.0,0.0]: ", 0), 0u) << error_of(o);
}

TEST(Box, RefusesAStepThatDoesNotDivideASideOrExceedsIt) {
  EXPECT_EQ(error_of(Json{{"size", {0.1, 0.12}}, {"step", 0.03}}),
            "problem: options.step = 0.03: must divide size[0] (0.1) into whole steps");
  EXPECT_EQ(error_of(Json{{"size", {0.1, 0.12}}, {"step", 0.05}}),
            "problem: options.step = 0.05: must divide size[1] (0.12) into whole steps");
  EXPECT_EQ(error_of(Json{{"size", {0.4, 0.1}}, {"step", 0.2}}), "problem: options.step = 0.2: must be <= size[1] (0.1)");
  // Within 1e-9 relative is accepted, like planar_square.
  EXPECT_EQ(error_of(Json{{"size", {0.1, 0.1}}, {"step", 0.005 * (1 + 1e-12)}}), "no error");
}

TEST(Box, RefusesAGridAboveTheSampleCapWithoutOverflow) {
  EXPECT_EQ(error_of(Json{{"size", {1.0, 1.0}}, {"step", 1e-4}}),
            "box: options.step = 0.0001: gives 10001.0 x 10001.0 samples; at most 2000000 are allowed");
  // 1e12 steps per axis: the count (1e36) is computed in floating point, not in a wrapping integer.
  EXPECT_EQ(error_of(Json{{"dimension", 3}, {"center", {0, 0, 0}}, {"size", {1000.0, 1000.0, 1000.0}}, {"step", 1e-9}}),
            "box: options.step = 1e-09: gives 1000000000001.0 x 1000000000001.0 x 1000000000001.0 samples; at most "
            "2000000 are allowed");
  // Exactly at the cap is accepted: 1000 x 2000 samples.
  EXPECT_EQ(error_of(Json{{"size", {0.999, 1.999}}, {"step", 0.001}}), "no error");
}

TEST(Box, RefusesDeclaredRulesAndRequestedAttributes) {
  EXPECT_EQ(error_of(Json{{"dimension", 4}}), "problem: options.dimension = 4: must be <= 3");
  EXPECT_EQ(error_of(Json{{"size", {0.1, 0.0}}}), "problem: options.size[1] = 0.0: must be > 0");
  EXPECT_EQ(error_of(Json{{"step", -0.001}}), "problem: options.step = -0.001: must be > 0");
  hapsyn::SceneRequest request;
  request.attributes = {"M_v"};
  try {
    Box(options_of(Json::object())).build(request);
    FAIL() << "no error";
  } catch (const hapsyn::Error& e) {
    EXPECT_STREQ(e.what(), "box: per-sample attribute 'M_v' requested: this scene provides none");
  }
}

TEST(Box, DeclaredSchemaIsValidWithDefaultsAndUnits) {
  const Json schema = hapsyn::options_schema<BoxOptions>();
  EXPECT_NO_THROW(hapsyn::check_schema(schema, "box"));
  const Json filled = hapsyn::validate_and_fill(schema, Json::object(), "scene.options");
  EXPECT_EQ(filled.at("dimension"), 2);
  EXPECT_EQ(filled.at("orientation"), Json::array());
  for (const char* key : {"center", "size", "step"}) EXPECT_EQ(schema.at("properties").at(key).at("unit"), "m") << key;
  EXPECT_EQ(Box(options_of(filled)).build({}).size(), 441);
}

}  // namespace
