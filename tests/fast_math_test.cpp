// hapsyn/accel/fast_math.hpp against libm: random arguments over many scales and every edge case.
#include <hapsyn/accel/fast_math.hpp>
#include <hapsyn/accel/lanes.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace {

TEST(FastMath, SinCosMatchLibmToTheStatedErrorOverManyScales) {
  std::mt19937_64 rng(11);
  double sine_error = 0.0, cosine_error = 0.0;
  for (const double scale : {1e-8, 1e-3, 0.5, 1.0, 3.2, 10.0, 100.0, 1e4, 1e6}) {
    std::uniform_real_distribution<double> uniform(-scale, scale);
    for (int i = 0; i < 200000; ++i) {
      const double x = uniform(rng);
      double s = 0.0, c = 0.0;
      hapsyn::fast::sin_cos(x, s, c);
      sine_error = std::max(sine_error, std::abs(s - std::sin(x)));
      cosine_error = std::max(cosine_error, std::abs(c - std::cos(x)));
    }
  }
  EXPECT_LE(sine_error, 2.3e-16);
  EXPECT_LE(cosine_error, 2.3e-16);
}

TEST(FastMath, SinCosAtQuadrantBoundariesAndOutsideTheFastRange) {
  const double pi = 3.141592653589793;
  std::vector<double> xs = {0.0, -0.0, 1e-300, -1e-300};
  for (int k = -40; k <= 40; ++k) {
    const double x = k * pi / 4.0;
    xs.insert(xs.end(), {x, std::nextafter(x, 1e9), std::nextafter(x, -1e9)});
  }
  for (const double x : {1e6 + 0.5, -2e6, 1e12, 1e300}) xs.push_back(x);  // libm fallback
  for (const double x : xs) {
    double s = 0.0, c = 0.0;
    hapsyn::fast::sin_cos(x, s, c);
    EXPECT_NEAR(s, std::sin(x), 2.3e-16) << "x = " << x;
    EXPECT_NEAR(c, std::cos(x), 2.3e-16) << "x = " << x;
  }
  for (const double x : {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
    double s = 0.0, c = 0.0;
    hapsyn::fast::sin_cos(x, s, c);
    EXPECT_TRUE(std::isnan(s) && std::isnan(c)) << "x = " << x;
  }
}

TEST(FastMath, Atan2MatchesLibmToTheStatedErrorInEveryQuadrant) {
  std::mt19937_64 rng(12);
  double error = 0.0;
  for (const double scale : {1e-12, 1e-3, 1.0, 1e3, 1e200}) {
    std::uniform_real_distribution<double> uniform(-scale, scale);
    for (int i = 0; i < 200000; ++i) {
      double y = uniform(rng), x = uniform(rng);
      if (i % 3 == 0) y *= 1e-9;  // near the x axis
      if (i % 5 == 0) x *= 1e-9;  // near the y axis
      error = std::max(error, std::abs(hapsyn::fast::atan2(y, x) - std::atan2(y, x)));
    }
  }
  EXPECT_LE(error, 4.5e-16);
}

TEST(FastMath, Atan2KeepsLibmsConventionsForZerosInfinitiesAndNaN) {
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> values = {0.0, -0.0, 1.0, -1.0, 1e-300, -1e-300, 5e-324, inf, -inf, nan};
  for (const double y : values) {
    for (const double x : values) {
      const double fast = hapsyn::fast::atan2(y, x), libm = std::atan2(y, x);
      if (std::isnan(libm)) {
        EXPECT_TRUE(std::isnan(fast)) << "atan2(" << y << ", " << x << ")";
      } else {
        EXPECT_NEAR(fast, libm, 4.5e-16) << "atan2(" << y << ", " << x << ")";
        EXPECT_EQ(std::signbit(fast), std::signbit(libm)) << "atan2(" << y << ", " << x << ")";
      }
    }
  }
}

TEST(FastMath, LaneSinCosEqualsTheScalarCallLaneByLane) {
  // The lane version (hapsyn/accel/lanes.hpp) runs the same reduction and polynomials; compiled with
  // the same flags, every lane is the scalar result bit for bit, in every quadrant, at the
  // reduction's edges and for the arguments that fall back to libm.
  std::mt19937_64 rng(9);
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  const double half_pi = 1.5707963267948966;
  std::vector<double> xs = {0.0, -0.0, half_pi, -half_pi, 2 * half_pi, 3 * half_pi, -3 * half_pi, 1e6, -1e6,
                            1e6 + 1.0, -2e6, 1e300, inf, -inf, nan, 0.25 * half_pi, 0.5 * half_pi, -0.5 * half_pi};
  std::uniform_real_distribution<double> wide(-1e6, 1e6), narrow(-10.0, 10.0);
  for (int i = 0; i < 40000; ++i) xs.push_back(i % 2 ? wide(rng) : narrow(rng));
  while (xs.size() % hapsyn::kBlockLanes != 0) xs.push_back(narrow(rng));
  for (std::size_t first = 0; first < xs.size(); first += hapsyn::kBlockLanes) {
    const hapsyn::Lanes x = hapsyn::Lanes::load(xs.data() + first);
    hapsyn::Lanes s, c;
    hapsyn::sin_cos(x, s, c);
    for (int lane = 0; lane < hapsyn::kBlockLanes; ++lane) {
      double expected_s = 0.0, expected_c = 0.0;
      hapsyn::fast::sin_cos(xs[first + static_cast<std::size_t>(lane)], expected_s, expected_c);
      if (std::isnan(expected_s)) {
        EXPECT_TRUE(std::isnan(s[lane]) && std::isnan(c[lane])) << xs[first + static_cast<std::size_t>(lane)];
        continue;
      }
      EXPECT_EQ(s[lane], expected_s) << "sin(" << xs[first + static_cast<std::size_t>(lane)] << ")";
      EXPECT_EQ(c[lane], expected_c) << "cos(" << xs[first + static_cast<std::size_t>(lane)] << ")";
    }
  }
}

TEST(FastMath, LaneAtan2EqualsTheScalarCallLaneByLane) {
  // The lane version shares fast::atan_reduced with the scalar call: every lane is the scalar
  // result bit for bit, in every octant, on the octant borders, at signed zeros, and for the
  // arguments that fall back to libm (zeros, infinities, NaN in either argument).
  std::mt19937_64 rng(11);
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> special = {0.0, -0.0, 1.0, -1.0, 1e-300, -1e-300, 1e300, -1e300, inf, -inf, nan, 0.5, -2.0};
  std::vector<std::pair<double, double>> args;
  for (double y : special) {
    for (double x : special) args.emplace_back(y, x);
  }
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (int i = 0; i < 40000; ++i) {
    const double x = u(rng);
    args.emplace_back(i % 3 == 0 ? x : u(rng), x);  // a third on the diagonal |y| = |x| or near it
  }
  while (args.size() % hapsyn::kBlockLanes != 0) args.emplace_back(u(rng), u(rng));
  for (std::size_t first = 0; first < args.size(); first += hapsyn::kBlockLanes) {
    double ys[hapsyn::kBlockLanes], xs[hapsyn::kBlockLanes];
    for (int lane = 0; lane < hapsyn::kBlockLanes; ++lane) {
      ys[lane] = args[first + static_cast<std::size_t>(lane)].first;
      xs[lane] = args[first + static_cast<std::size_t>(lane)].second;
    }
    const hapsyn::Lanes angle = hapsyn::atan2(hapsyn::Lanes::load(ys), hapsyn::Lanes::load(xs));
    const hapsyn::Lanes root = hapsyn::sqrt(hapsyn::abs(hapsyn::Lanes::load(xs)));
    // The pair atan2(y, x), atan2(y, -x) sharing their work: the two scalar calls bit for bit.
    hapsyn::Lanes pair_angle, pair_mirrored;
    hapsyn::atan2_and_mirrored(hapsyn::Lanes::load(ys), hapsyn::Lanes::load(xs), pair_angle, pair_mirrored);
    for (int lane = 0; lane < hapsyn::kBlockLanes; ++lane) {
      const double expected = hapsyn::fast::atan2(ys[lane], xs[lane]);
      const double expected_mirrored = hapsyn::fast::atan2(ys[lane], -xs[lane]);
      if (std::isnan(expected)) {
        EXPECT_TRUE(std::isnan(angle[lane])) << "atan2(" << ys[lane] << ", " << xs[lane] << ")";
        EXPECT_TRUE(std::isnan(pair_angle[lane])) << "atan2(" << ys[lane] << ", " << xs[lane] << ")";
        EXPECT_TRUE(std::isnan(pair_mirrored[lane])) << "atan2(" << ys[lane] << ", " << -xs[lane] << ")";
      } else {
        EXPECT_EQ(std::signbit(angle[lane]), std::signbit(expected)) << "atan2(" << ys[lane] << ", " << xs[lane] << ")";
        EXPECT_EQ(angle[lane], expected) << "atan2(" << ys[lane] << ", " << xs[lane] << ")";
        const double got = pair_angle[lane], got_mirrored = pair_mirrored[lane];  // clang: no address of a vector element
        EXPECT_EQ(std::memcmp(&got, &expected, sizeof expected), 0) << "atan2(" << ys[lane] << ", " << xs[lane] << ")";
        EXPECT_EQ(std::memcmp(&got_mirrored, &expected_mirrored, sizeof expected), 0)
            << "atan2(" << ys[lane] << ", " << -xs[lane] << ")";
      }
      const double expected_root = std::sqrt(std::fabs(xs[lane]));
      if (!std::isnan(expected_root)) {
        EXPECT_EQ(root[lane], expected_root) << xs[lane];
      }
    }
  }
}

TEST(FastMath, FloorAndCeilOfSmallValuesEqualLibmAndLargeOnesFallBack) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> xs = {0.0, -0.0, 0.25, 0.5, 1.0, 1.5, -0.25, -1.0, -1.5, 2.0 - 1e-16, -2.0 + 1e-15,
                            4.4e15 + 0.5, -4.4e15 - 0.5, 1e300, -1e300, inf, -inf};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1e6, 1e6);
  for (int k = 0; k < 10000; ++k) xs.push_back(u(rng));
  for (double x : xs) {
    EXPECT_EQ(hapsyn::fast::floor_small(x), std::floor(x)) << x;
    EXPECT_EQ(hapsyn::fast::ceil_small(x), std::ceil(x)) << x;
  }
  EXPECT_TRUE(std::isnan(hapsyn::fast::floor_small(std::nan(""))));
  EXPECT_TRUE(std::isnan(hapsyn::fast::ceil_small(std::nan(""))));
}

TEST(FastMath, LaneFloorOfSmallValues) {
  const std::vector<double> xs = {0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.5, -0.25, -0.5, -1.0, -1.5, -2.5, 1e15 + 0.5, -3e14 - 0.25};
  for (std::size_t first = 0; first < xs.size(); first += hapsyn::kBlockLanes) {
    double in[hapsyn::kBlockLanes];
    for (int lane = 0; lane < hapsyn::kBlockLanes; ++lane) in[lane] = xs[std::min(first + static_cast<std::size_t>(lane), xs.size() - 1)];
    const hapsyn::Lanes f = hapsyn::floor_small(hapsyn::Lanes::load(in));
    for (int lane = 0; lane < hapsyn::kBlockLanes; ++lane) EXPECT_EQ(f[lane], std::floor(in[lane])) << in[lane];
  }
}

}  // namespace
