// The five-bar's block bound of a sample over a run of r (fivebar_envelope.hpp, KERNELS.md
// section 13.5), checked against the model itself: every design of random runs, solved by
// FiveBarModel, must obey what the envelope claims; on a run of one design the GII bound must
// equal the design's own sigma_min / sigma_max (up to the margins), which checks the formulas,
// not only that they are loose enough.
#include "fivebar.hpp"

#include <gdi.hpp>
#include <gii.hpp>

#include <hapsyn/options.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace {

using hapsyn::Json;
using hapsyn::SampleEnvelope;
using hapsyn::SampleStatus;
using hapsyn::plugins::FiveBar;
using hapsyn::plugins::FiveBarDesign;
using hapsyn::plugins::FiveBarModel;
using hapsyn::plugins::FiveBarOptions;

constexpr hapsyn::Needs kAll = hapsyn::kNeedJacobian | hapsyn::kNeedInertia | hapsyn::kNeedEffectiveMass;

struct Exact {
  SampleStatus status = SampleStatus::kUnreachable;
  double inverse_condition = 0.0;  // sigma_min(J) / sigma_max(J)
  double mass = 0.0;               // sigma_max(M) [kg]
};

Exact solve(const FiveBarOptions& options, const FiveBarDesign& design, const double* pose) {
  const FiveBarModel model(design, options);
  hapsyn::MechanismScratch scratch;
  hapsyn::SampleQuantities q;
  model.solve(pose, kAll, scratch, q);
  Exact e;
  e.status = q.status;
  if (q.status != SampleStatus::kReachable) return e;
  double sigma_min = 0.0, sigma_max = 0.0;
  hapsyn::plugins::Gii::singular_values(q.jacobian, sigma_min, sigma_max);
  e.inverse_condition = sigma_min / sigma_max;
  e.mass = hapsyn::plugins::Gdi::largest_singular_value(q.effective_mass);
  return e;
}

// Random designs of the paper's kind (some with l0 = 0 or l1 = l2), runs of r of random width,
// samples of a 0.1 m square (corners and edges included).
struct RandomRun {
  FiveBarDesign design;
  double lower = 0.0, upper = 0.0;
  double pose[2] = {0.0, 0.0};
};

RandomRun random_run(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  RandomRun run;
  run.design.l0 = u(rng) < 0.2 ? 0.0 : 0.3 * u(rng);
  run.design.l1 = 0.01 + 0.29 * u(rng);
  run.design.l2 = u(rng) < 0.1 ? run.design.l1 : 0.01 + 0.29 * u(rng);
  const double widths[] = {0.0, 0.002, 0.016, 0.064, 0.3};
  const double width = widths[static_cast<int>(u(rng) * 5)];
  run.lower = 0.6 * u(rng);
  run.upper = run.lower + width;
  const auto coordinate = [&] {
    const double v = u(rng);
    return v < 0.3 ? -0.05 : v < 0.6 ? 0.05 : -0.05 + 0.1 * u(rng);
  };
  run.pose[0] = coordinate();
  run.pose[1] = coordinate();
  return run;
}

TEST(FiveBarEnvelope, EveryDesignOfRandomRunsObeysTheBounds) {
  const FiveBarOptions options = hapsyn::make_options<FiveBarOptions>(Json::object());
  const FiveBar fivebar(options);
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  long long all_fail = 0, bounded = 0, informative_gii = 0, informative_gdi = 0, reached = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const RandomRun run = random_run(rng);
    const double design[4] = {run.design.l0, run.design.l1, run.design.l2, run.lower};
    SampleEnvelope envelope;
    if (!fivebar.sample_envelope(design, 3, run.lower, run.upper, run.pose, kAll, envelope)) {
      EXPECT_LE(run.pose[1] + run.lower, 0.0) << "an envelope is refused only at or below the joints' axis";
      continue;
    }
    all_fail += envelope.all_fail;
    bounded += !envelope.all_fail;
    informative_gii += !envelope.all_fail && envelope.jacobian_inverse_condition_max < 0.5;
    informative_gdi += !envelope.all_fail && envelope.effective_mass_sigma_max_min > 0.1;
    for (int k = 0; k <= 40; ++k) {
      FiveBarDesign d = run.design;
      d.r = k == 40 ? run.upper : k == 39 ? run.lower : run.lower + (run.upper - run.lower) * u(rng);
      const Exact e = solve(options, d, run.pose);
      if (envelope.all_fail) {
        ASSERT_NE(e.status, SampleStatus::kReachable) << "trial " << trial << ": r = " << d.r;
        continue;
      }
      if (e.status != SampleStatus::kReachable) continue;
      ++reached;
      ASSERT_LE(e.inverse_condition, envelope.jacobian_inverse_condition_max) << "trial " << trial << ", r = " << d.r;
      ASSERT_GE(e.mass, envelope.effective_mass_sigma_max_min) << "trial " << trial << ", r = " << d.r;
    }
  }
  // The cases occur often enough for the test to mean something.
  EXPECT_GT(all_fail, 2000);
  EXPECT_GT(bounded, 5000);
  EXPECT_GT(informative_gii, 1000);
  EXPECT_GT(informative_gdi, 1000);
  EXPECT_GT(reached, 100000);
}

// Runs of one design (r_lo = r_hi = r) of `trials` random draws: check(trial, envelope, exact)
// for each that has an envelope.
template <class Check>
void for_runs_of_one_design(unsigned seed, int trials, const Check& check) {
  const FiveBarOptions options = hapsyn::make_options<FiveBarOptions>(Json::object());
  const FiveBar fivebar(options);
  std::mt19937 rng(seed);
  for (int trial = 0; trial < trials; ++trial) {
    RandomRun run = random_run(rng);
    run.upper = run.lower;
    run.design.r = run.lower;
    const double design[4] = {run.design.l0, run.design.l1, run.design.l2, run.lower};
    SampleEnvelope envelope;
    if (!fivebar.sample_envelope(design, 3, run.lower, run.upper, run.pose, kAll, envelope)) continue;
    check(trial, envelope, solve(options, run.design, run.pose));
  }
}

TEST(FiveBarEnvelope, ARunOfOneDesignGivesItsOwnInverseConditionNumberAndNearlyItsMass) {
  // Width 0: the intervals shrink to the design's angles, so the GII bound is the design's own
  // sigma_min / sigma_max plus the margins, and the energy along the chosen direction is close
  // to sigma_max(M) (exact when the direction is M's top eigenvector); a wrong angle or sign in
  // either formula would show here.
  int compared = 0, mass_close = 0;
  for_runs_of_one_design(7, 20000, [&](int trial, const SampleEnvelope& envelope, const Exact& e) {
    if (envelope.all_fail || e.status != SampleStatus::kReachable) return;
    EXPECT_NEAR(envelope.jacobian_inverse_condition_max, e.inverse_condition, 1e-6 * (1.0 + e.inverse_condition))
        << "trial " << trial;
    EXPECT_LE(envelope.effective_mass_sigma_max_min, e.mass) << "trial " << trial;
    mass_close += envelope.effective_mass_sigma_max_min >= 0.95 * e.mass;
    ++compared;
  });
  EXPECT_GT(compared, 3000);
  EXPECT_GT(mass_close, compared * 9 / 10);
}

TEST(FiveBarEnvelope, ProvesFailureOnlyWhereEveryDesignFailsAndOftenWhereOneDesignFails) {
  // A run of one design whose sample fails is proved failing in most cases (the envelope's
  // failure tests follow the model's classification), and never one that reaches the sample.
  int failing = 0, proved = 0;
  for_runs_of_one_design(11, 20000, [&](int trial, const SampleEnvelope& envelope, const Exact& e) {
    if (e.status == SampleStatus::kReachable) {
      EXPECT_FALSE(envelope.all_fail) << "trial " << trial;
      return;
    }
    ++failing;
    proved += envelope.all_fail;
  });
  EXPECT_GT(failing, 3000);
  EXPECT_GT(proved, failing * 9 / 10);
}

TEST(FiveBarEnvelope, OnlyForRAndAboveTheJointsAxis) {
  const FiveBar fivebar(hapsyn::make_options<FiveBarOptions>(Json::object()));
  const double design[4] = {0.01, 0.2, 0.25, 0.3};
  const double pose[2] = {0.02, -0.05};
  SampleEnvelope envelope;
  for (int component : {0, 1, 2}) EXPECT_FALSE(fivebar.sample_envelope(design, component, 0.1, 0.2, pose, kAll, envelope));
  EXPECT_TRUE(fivebar.sample_envelope(design, 3, 0.1, 0.2, pose, kAll, envelope));
  EXPECT_FALSE(fivebar.sample_envelope(design, 3, 0.0, 0.2, pose, kAll, envelope));   // y + r = -0.05 at r = 0
  EXPECT_FALSE(fivebar.sample_envelope(design, 3, 0.05, 0.2, pose, kAll, envelope));  // y + r = 0: on the axis
  EXPECT_FALSE(fivebar.sample_envelope(design, 3, 0.2, 0.1, pose, kAll, envelope));   // an empty run
}

}  // namespace
