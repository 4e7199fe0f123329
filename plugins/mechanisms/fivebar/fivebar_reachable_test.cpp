// The five-bar's reachable interval of a sample along r (FiveBar::reachable_interval,
// KERNELS.md section 13.6), checked against the model itself: no value of r outside the
// interval may let FiveBarModel solve the sample (the claim a grid solver rules designs out
// on), and on analytic cases the interval's ends are where the legs' reach puts them.
#include "fivebar.hpp"

#include <hapsyn/options.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace {

using hapsyn::Json;
using hapsyn::SampleStatus;
using hapsyn::plugins::FiveBar;
using hapsyn::plugins::FiveBarDesign;
using hapsyn::plugins::FiveBarModel;
using hapsyn::plugins::FiveBarOptions;

SampleStatus status_at(const FiveBarOptions& options, FiveBarDesign design, double r, const double* pose) {
  design.r = r;
  const FiveBarModel model(design, options);
  hapsyn::MechanismScratch scratch;
  hapsyn::SampleQuantities q;
  model.solve(pose, hapsyn::kNeedJacobian, scratch, q);
  return q.status;
}

TEST(FiveBarReachableInterval, NoValueOfROutsideItSolvesTheSample) {
  // Random designs (some with l0 = 0 or l1 = l2) and samples of a 0.1 m square; r runs densely
  // over the whole design range, and in steps of a few ulps and of 1e-12..1e-6 m just outside
  // both ends, where rounding could decide.
  const FiveBarOptions options = hapsyn::make_options<FiveBarOptions>(Json::object());
  const FiveBar fivebar(options);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int reachable = 0, outside = 0, empty = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    FiveBarDesign d;
    d.l0 = u(rng) < 0.2 ? 0.0 : 0.3 * u(rng);
    d.l1 = 0.01 + 0.29 * u(rng);
    d.l2 = u(rng) < 0.1 ? d.l1 : 0.01 + 0.29 * u(rng);
    const double pose[2] = {-0.05 + 0.1 * u(rng), u(rng) < 0.3 ? -0.05 : -0.05 + 0.1 * u(rng)};
    const double design[4] = {d.l0, d.l1, d.l2, 0.0};
    double lower = 0.0, upper = 0.0;
    ASSERT_TRUE(fivebar.reachable_interval(design, 3, pose, lower, upper));
    const auto expect_fails = [&](double r) {
      if (r >= lower && r <= upper) return;
      ++outside;
      EXPECT_NE(status_at(options, d, r, pose), SampleStatus::kReachable)
          << "trial " << trial << ": r = " << r << " outside [" << lower << ", " << upper << "] solves the sample";
    };
    for (int k = 0; k <= 400; ++k) {
      const double r = -0.2 + 1.0 * k / 400.0;
      const SampleStatus s = status_at(options, d, r, pose);
      if (s == SampleStatus::kReachable) {
        ++reachable;
        EXPECT_TRUE(r >= lower && r <= upper) << "trial " << trial << ": r = " << r << " solves the sample";
      }
    }
    if (!(lower <= upper)) {
      ++empty;
      continue;
    }
    double below = lower, above = upper;
    for (int k = 0; k < 8; ++k) {
      below = std::nextafter(below, -1.0);
      above = std::nextafter(above, 2.0);
      expect_fails(below);
      expect_fails(above);
    }
    for (double delta = 1e-12; delta < 2e-6; delta *= 10.0) {
      expect_fails(lower - delta);
      expect_fails(upper + delta);
    }
  }
  EXPECT_GT(reachable, 10000);  // the scan meets the samples' reachable runs
  EXPECT_GT(outside, 3000 * 20);
  EXPECT_GT(empty, 10);  // and designs too short for a sample
}

TEST(FiveBarReachableInterval, EndsAreWhereTheLegsReachOnAnalyticCases) {
  const FiveBar fivebar(hapsyn::make_options<FiveBarOptions>(Json::object()));
  double lower = 0.0, upper = 0.0;
  // h0 = 0.05, sample (0.05, 0): the right joint below it (b = 0), the left one 0.1 away. The
  // right leg needs Y >= |l1 - l2| = 0.2, the left one Y <= sqrt(0.4^2 - 0.1^2).
  const double design[4] = {0.1, 0.3, 0.1, 0.0};
  const double pose[2] = {0.05, 0.0};
  ASSERT_TRUE(fivebar.reachable_interval(design, 3, pose, lower, upper));
  EXPECT_NEAR(lower, 0.2, 1e-8);
  EXPECT_LT(lower, 0.2);
  EXPECT_NEAR(upper, std::sqrt(0.15), 1e-8);
  EXPECT_GT(upper, std::sqrt(0.15));
  // A sample 0.05 below the box centre with l1 = l2: only the side of the joints' axis binds
  // below (Y >= 0, r >= 0.05).
  const double folded[4] = {0.0, 0.2, 0.2, 0.0};
  const double low[2] = {0.0, -0.05};
  ASSERT_TRUE(fivebar.reachable_interval(folded, 3, low, lower, upper));
  EXPECT_NEAR(lower, 0.05, 1e-8);
  EXPECT_LT(lower, 0.05);
  EXPECT_NEAR(upper, 0.4 + 0.05, 1e-8);
  // Out of reach of the farther joint for every r: empty.
  const double short_legs[4] = {0.3, 0.05, 0.05, 0.0};
  const double side[2] = {0.05, 0.0};
  ASSERT_TRUE(fivebar.reachable_interval(short_legs, 3, side, lower, upper));
  EXPECT_GT(lower, upper);
}

TEST(FiveBarReachableInterval, OnlyForR) {
  const FiveBar fivebar(hapsyn::make_options<FiveBarOptions>(Json::object()));
  const double design[4] = {0.01, 0.2, 0.25, 0.3};
  const double pose[2] = {0.02, -0.05};
  double lower = 0.0, upper = 0.0;
  for (int component : {0, 1, 2}) EXPECT_FALSE(fivebar.reachable_interval(design, component, pose, lower, upper));
  EXPECT_TRUE(fivebar.reachable_interval(design, 3, pose, lower, upper));
}

}  // namespace
