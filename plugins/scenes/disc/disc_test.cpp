// Tests of the disc scene: the samples against a brute-force scan of the grid (distances of
// the actual coordinates), the boundary tolerance, order, symmetry, the optional orientation,
// refused options (with their messages) and the schema.
#include "disc.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/schema.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace {

using hapsyn::Json;
using hapsyn::SampleSet;
using hapsyn::plugins::Disc;
using hapsyn::plugins::DiscOptions;

DiscOptions options_of(const Json& options) { return hapsyn::make_options<DiscOptions>(options); }

std::string error_of(const Json& options) {
  try {
    Disc scene(options_of(options));
  } catch (const hapsyn::Error& e) {
    return e.what();
  }
  return "no error";
}

// Every grid point c + step (i, j, k) of a generous cube, kept when its Euclidean distance
// from the centre (of the coordinates as doubles, not of the whole numbers) is <= radius
// (1 + 1e-9); z slowest, x fastest, as the scene documents.
std::vector<std::vector<double>> brute_force(const std::vector<double>& c, double radius, double step) {
  const int span = static_cast<int>(radius / step) + 2;
  const int dim = static_cast<int>(c.size());
  std::vector<std::vector<double>> points;
  for (int k = dim == 3 ? -span : 0; k <= (dim == 3 ? span : 0); ++k) {
    for (int j = -span; j <= span; ++j) {
      for (int i = -span; i <= span; ++i) {
        std::vector<double> p = {c[0] + i * step, c[1] + j * step};
        if (dim == 3) p.push_back(c[2] + k * step);
        double d2 = 0.0;
        for (int a = 0; a < dim; ++a) d2 += (p[static_cast<std::size_t>(a)] - c[static_cast<std::size_t>(a)]) *
                                             (p[static_cast<std::size_t>(a)] - c[static_cast<std::size_t>(a)]);
        if (std::sqrt(d2) <= radius * (1 + 1e-9)) points.push_back(p);
      }
    }
  }
  return points;
}

void expect_brute_force(const std::vector<double>& c, double radius, double step) {
  const Json options = {{"dimension", c.size()}, {"center", c}, {"radius", radius}, {"step", step}};
  const Disc scene(options_of(options));
  const SampleSet set = scene.build({});
  const auto expected = brute_force(c, radius, step);
  ASSERT_EQ(set.size(), static_cast<int>(expected.size())) << options.dump();
  EXPECT_EQ(scene.sample_count(), set.size());
  for (int i = 0; i < set.size(); ++i) {
    for (std::size_t a = 0; a < c.size(); ++a) {
      ASSERT_EQ(set.pose(i)[a], expected[static_cast<std::size_t>(i)][a]) << options.dump() << " sample " << i;
    }
  }
}

TEST(Disc, DefaultOptionsGiveTheGridPointsOfA50MmDisc) {
  const SampleSet set = Disc(options_of(Json::object())).build({});
  EXPECT_EQ(set.coordinates, (std::vector<std::string>{"x", "y"}));
  EXPECT_EQ(set.unit, "m");
  EXPECT_TRUE(set.attributes.empty());
  EXPECT_TRUE(set.weights.empty());
  EXPECT_EQ(set.size(), static_cast<int>(brute_force({0.0, 0.0}, 0.05, 0.005).size()));
  EXPECT_EQ(set.info.at("samples"), set.size());
}

TEST(Disc, SamplesAreTheGridPointsInsideABruteForceScanFinds) {
  expect_brute_force({0.0, 0.0}, 0.05, 0.01);    // radius 5 steps: (3, 4) and (5, 0) on the boundary
  expect_brute_force({0.0, 0.0}, 0.047, 0.01);   // radius not a whole number of steps
  expect_brute_force({0.1, -0.2}, 0.05, 0.005);  // off-centre
  expect_brute_force({0.0, 0.0}, 0.03, 0.04);    // step > radius: the centre alone
  EXPECT_EQ(Disc(options_of(Json{{"radius", 0.03}, {"step", 0.04}})).build({}).size(), 1);
}

TEST(Disc, BallSamplesAreTheGridPointsInsideABruteForceScanFinds) {
  expect_brute_force({0.0, 0.0, 0.0}, 0.05, 0.01);
  expect_brute_force({0.3, 0.0, -0.1}, 0.031, 0.01);
  // radius = step: the centre and its 6 neighbours.
  EXPECT_EQ(Disc(options_of(Json{{"dimension", 3}, {"center", {0, 0, 0}}, {"radius", 0.1}, {"step", 0.1}})).build({}).size(), 7);
}

TEST(Disc, BoundaryPointsCountWithinARelativeTolerance) {
  // The 12 grid points at exactly 5 steps ((+-5, 0), (0, +-5), (+-3, +-4), (+-4, +-3)) stay for a
  // radius short by 1e-10 relative and go for one short by 1e-8.
  const auto count = [](double radius) {
    return Disc(options_of(Json{{"radius", radius}, {"step", 0.01}})).build({}).size();
  };
  EXPECT_EQ(count(0.05 * (1 - 1e-10)), count(0.05));
  EXPECT_EQ(count(0.05 * (1 - 1e-8)), count(0.05) - 12);
  EXPECT_EQ(count(0.05 * (1 - 1e-8)), static_cast<int>(brute_force({0.0, 0.0}, 0.05 * (1 - 1e-8), 0.01).size()));
}

TEST(Disc, GridIsMirrorSymmetricAboutAZeroCentre) {
  const SampleSet set = Disc(options_of(Json{{"dimension", 3}, {"center", {0, 0, 0}}, {"radius", 0.1}, {"step", 0.013}})).build({});
  const int n = set.size();
  ASSERT_EQ(n % 2, 1);
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) ASSERT_EQ(set.pose(i)[a], -set.pose(n - 1 - i)[a]) << i;
  }
  for (int a = 0; a < 3; ++a) EXPECT_EQ(set.pose(n / 2)[a], 0.0);  // the centre is the middle sample
}

TEST(Disc, OrientationGivesFullPosesWithThatNormalizedOrientation) {
  const std::vector<double> q = {0.5, 0.5, 0.5, 0.5 * (1 + 4e-7)};
  const Disc scene(options_of(Json{{"dimension", 3}, {"center", {0, 0, 0.4}}, {"radius", 0.02}, {"step", 0.01}, {"orientation", q}}));
  const SampleSet set = scene.build({});
  EXPECT_EQ(set.coordinates, (std::vector<std::string>{"x", "y", "z", "qw", "qx", "qy", "qz"}));
  ASSERT_EQ(set.size(), static_cast<int>(brute_force({0.0, 0.0, 0.4}, 0.02, 0.01).size()));
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (int i = 0; i < set.size(); ++i) {
    for (int k = 0; k < 4; ++k) ASSERT_EQ(set.pose(i)[3 + k], q[static_cast<std::size_t>(k)] / norm);
  }
}

TEST(Disc, RefusesACenterThatDoesNotMatchTheDimensionAndABadOrientation) {
  EXPECT_EQ(error_of(Json{{"dimension", 3}}), "problem: options.center = [0.0,0.0]: must have 3 numbers (one per dimension)");
  EXPECT_EQ(error_of(Json{{"center", {0, 0}}, {"orientation", {1.0, 0.0, 0.0, 0.0}}}),
            "disc: options.orientation = [1.0,0.0,0.0,0.0]: needs dimension 3 (a full pose is x, y, z, qw, qx, qy, qz)");
  const Json ball = {{"dimension", 3}, {"center", {0, 0, 0}}};
  Json o = ball;
  o["orientation"] = {0.0, 1.0};
  EXPECT_EQ(error_of(o), "disc: options.orientation = [0.0,1.0]: must be empty or 4 numbers [qw, qx, qy, qz]");
  o["orientation"] = {0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(error_of(o), "disc: options.orientation = [0.0,0.0,0.0,0.0]: must be a unit quaternion (norm 0.0 differs "
                         "from 1 by more than 1e-6)");
}

TEST(Disc, RefusesMoreSamplesThanTheCapCountedExactly) {
  // Just above the cap: the exact count is in the message (checked against a brute-force count).
  const double radius = 0.8, step = 0.001;
  const int k = 801;
  long long count = 0;
  for (int j = -k; j <= k; ++j) {
    for (int i = -k; i <= k; ++i) count += std::sqrt(1.0 * i * i + 1.0 * j * j) * step <= radius * (1 + 1e-9);
  }
  ASSERT_GT(count, hapsyn::plugins::kDiscMaxSamples);
  EXPECT_EQ(error_of(Json{{"radius", radius}, {"step", step}}),
            "disc: options.step = 0.001: gives " + std::to_string(count) +
                " samples (radius / step = 800.0); at most 2000000 are allowed");
  // Far above: refused from the volume estimate without enumerating (or overflowing) anything.
  EXPECT_EQ(error_of(Json{{"dimension", 3}, {"center", {0, 0, 0}}, {"radius", 1e6}, {"step", 1e-9}}),
            "disc: options.step = 1e-09: gives about 4.188790217352763e+45 samples (radius / step = 1e+15); at "
            "most 2000000 are allowed");
  EXPECT_EQ(error_of(Json{{"radius", 0.7}, {"step", 0.001}}), "no error");  // ~1.54 million samples
}

TEST(Disc, RefusesDeclaredRulesAndRequestedAttributes) {
  EXPECT_EQ(error_of(Json{{"radius", 0.0}}), "problem: options.radius = 0.0: must be > 0");
  EXPECT_EQ(error_of(Json{{"dimension", 1}}), "problem: options.dimension = 1: must be >= 2");
  hapsyn::SceneRequest request;
  request.attributes = {"M_v"};
  try {
    Disc(options_of(Json::object())).build(request);
    FAIL() << "no error";
  } catch (const hapsyn::Error& e) {
    EXPECT_STREQ(e.what(), "disc: per-sample attribute 'M_v' requested: this scene provides none");
  }
}

TEST(Disc, DeclaredSchemaIsValidWithDefaultsAndUnits) {
  const Json schema = hapsyn::options_schema<DiscOptions>();
  EXPECT_NO_THROW(hapsyn::check_schema(schema, "disc"));
  const Json filled = hapsyn::validate_and_fill(schema, Json::object(), "scene.options");
  EXPECT_EQ(filled.at("radius").get<double>(), 0.05);
  for (const char* key : {"center", "radius", "step"}) EXPECT_EQ(schema.at("properties").at(key).at("unit"), "m") << key;
}

}  // namespace
