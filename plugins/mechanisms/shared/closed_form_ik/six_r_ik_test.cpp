// Tests of the 6R closed-form IK (six_r_ik.hpp): for each family, random joint configurations
// -> forward kinematics -> IK; every returned solution must reproduce the pose to 1e-9 and the
// generating configuration must be among them. Configurations near a singularity (smallest
// singular value of the 6 x 6 Jacobian below kSingular) are skipped and counted; the counts are
// printed and recorded as test properties. Also: joint limits, reversed chains, option errors.
#include "shared/closed_form_ik/six_r_ik.hpp"
#include "shared/closed_form_ik/test_arms.hpp"

#include <hapsyn/error.hpp>

#include <gtest/gtest.h>

#include "test_support.hpp"

#include <Eigen/SVD>

#include <cstdio>
#include <functional>
#include <random>
#include <string>

namespace {

using namespace hapsyn::plugins::closed_form_ik;
using namespace hapsyn::plugins::closed_form_ik::test_arms;

constexpr double kSingular = 1e-3;  // smallest singular value of J [rad or m per rad]
constexpr double kPose = 1e-9;

Vector6d random_q(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-M_PI, M_PI);
  Vector6d q;
  for (int i = 0; i < 6; ++i) q(i) = u(rng);
  return q;
}

double pose_error(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  const Eigen::AngleAxisd r(a.linear() * b.linear().transpose());
  return std::max(std::abs(r.angle()), (a.translation() - b.translation()).norm());
}

double q_distance(const Vector6d& a, const Vector6d& b) {
  double worst = 0.0;
  for (int i = 0; i < 6; ++i) worst = std::max(worst, std::abs(std::remainder(a(i) - b(i), 2 * M_PI)));
  return worst;
}

double smallest_singular_value(const PoeChain& c, const Vector6d& q) {
  Eigen::Isometry3d pose;
  Eigen::Matrix<double, 6, kMaxJoints> j;
  c.forward_jacobian(q.data(), pose, j);
  const Eigen::Matrix<double, 6, 6> j6 = j.leftCols<6>();
  return Eigen::JacobiSVD<Eigen::Matrix<double, 6, 6>>(j6).singularValues()(5);
}

constexpr double kWellConditioned = 3e-2;  // the 1-D search's misses are counted apart above it

struct RoundTrip {
  int tried = 0, skipped = 0, missed = 0, solutions = 0;
  int well = 0, well_missed = 0;  // configurations with smallest singular value >= kWellConditioned
};

// FK -> IK on `trials` random configurations; every solution is checked, the generating one sought.
RoundTrip round_trip(const ClosedFormIk6R& ik, int trials, unsigned seed) {
  std::mt19937 rng(seed);
  IkScratch scratch;
  IkSolutions out;
  RoundTrip r;
  for (int t = 0; t < trials; ++t) {
    const Vector6d q = random_q(rng);
    ++r.tried;
    const double sigma = smallest_singular_value(ik.chain(), q);
    if (sigma < kSingular) {
      ++r.skipped;
      continue;
    }
    const bool well = sigma >= kWellConditioned;
    r.well += well;
    const Eigen::Isometry3d target = ik.chain().forward(q.data());
    ik.solve(target, scratch, out);
    bool found = false;
    for (int i = 0; i < out.count; ++i) {
      const Vector6d& s = out.q[static_cast<std::size_t>(i)];
      EXPECT_LT(pose_error(ik.chain().forward(s.data()), target), kPose) << "trial " << t << " solution " << i;
      found = found || q_distance(s, q) < 1e-6;
    }
    r.solutions += out.count;
    if (!found) ++r.missed, r.well_missed += well;
  }
  std::printf("[ stats    ] %s: %d configurations, %d skipped as singular (sigma_min < %g), %d generating "
              "configurations missed (%d of the %d with sigma_min >= %g), %.2f solutions per pose\n",
              ik.geometry().describe().c_str(), r.tried, r.skipped, kSingular, r.missed, r.well_missed, r.well,
              kWellConditioned, static_cast<double>(r.solutions) / std::max(1, r.tried - r.skipped));
  ::testing::Test::RecordProperty("skipped", r.skipped);
  ::testing::Test::RecordProperty("missed", r.missed);
  return r;
}

TEST(ClosedFormIk6R, Ur5FindsTheGeneratingConfiguration) {
  const ClosedFormIk6R ik(ur5().poe());
  EXPECT_EQ(ik.geometry().family, IkFamily::kThreeParallel);
  const RoundTrip r = round_trip(ik, 5000, 11);
  EXPECT_EQ(r.missed, 0);
  EXPECT_LT(r.skipped, r.tried / 10);
}

TEST(ClosedFormIk6R, PumaFindsTheGeneratingConfiguration) {
  const ClosedFormIk6R ik(puma().poe());
  EXPECT_EQ(ik.geometry().family, IkFamily::kSphericalWrist);
  const RoundTrip r = round_trip(ik, 5000, 12);
  EXPECT_EQ(r.missed, 0);
  EXPECT_LT(r.skipped, r.tried / 10);
}

TEST(ClosedFormIk6R, ReversedArmsAreSolvedOnTheirReverse) {
  const ClosedFormIk6R puma_reversed(puma().poe().reversed());
  EXPECT_TRUE(puma_reversed.geometry().reversed);
  EXPECT_EQ(round_trip(puma_reversed, 1000, 13).missed, 0);
  const ClosedFormIk6R ur5_reversed(ur5().poe().reversed());
  EXPECT_TRUE(ur5_reversed.geometry().reversed);
  EXPECT_EQ(round_trip(ur5_reversed, 1000, 14).missed, 0);
}

TEST(ClosedFormIk6R, OffsetWristSearchFindsTheGeneratingConfiguration) {
  const ClosedFormIk6R ik(offset_wrist().poe());
  EXPECT_EQ(ik.geometry().family, IkFamily::kSearch1d);
  const RoundTrip r = round_trip(ik, 2000, 15);
  // The search may miss roots (six_r_ik.hpp), nearly only close to singular configurations.
  EXPECT_LE(r.missed, 3 * (r.tried - r.skipped) / 100);
  EXPECT_LE(r.well_missed, r.well / 200);
  EXPECT_LT(r.skipped, r.tried / 10);
}

TEST(ClosedFormIk6R, HapticSixRFindsTheGeneratingConfiguration) {
  const ClosedFormIk6R ik(haptic6r().poe());
  EXPECT_EQ(ik.geometry().family, IkFamily::kScaraPair);
  const RoundTrip r = round_trip(ik, 5000, 16);
  EXPECT_EQ(r.missed, 0);
  EXPECT_LT(r.skipped, r.tried / 10);
  const ClosedFormIk6R reversed(haptic6r().poe().reversed());
  EXPECT_TRUE(reversed.geometry().reversed);
  EXPECT_EQ(round_trip(reversed, 1000, 18).missed, 0);
}

TEST(ClosedFormIk6R, JointLimitsKeepOnlySolutionsInside) {
  IkOptions options;
  options.use_limits = true;
  options.lower = {-M_PI, -M_PI, -M_PI, -M_PI, -M_PI, -M_PI};
  options.upper = {M_PI, 0.0, M_PI, M_PI, M_PI, M_PI};  // q2 <= 0 only
  options.lower[0] = 0.0, options.upper[0] = 2 * M_PI;      // q1 wrapped into [0, 2 pi]
  const ClosedFormIk6R limited(puma().poe(), options), free(puma().poe());
  std::mt19937 rng(17);
  IkScratch scratch;
  IkSolutions a, b;
  int kept = 0, all = 0;
  for (int t = 0; t < 500; ++t) {
    const Vector6d q = random_q(rng);
    const Eigen::Isometry3d target = free.chain().forward(q.data());
    limited.solve(target, scratch, a);
    free.solve(target, scratch, b);
    int inside = 0;
    for (int i = 0; i < b.count; ++i) inside += b.q[static_cast<std::size_t>(i)](1) <= 0.0;
    EXPECT_EQ(a.count, inside) << "trial " << t;
    for (int i = 0; i < a.count; ++i) {
      const Vector6d& s = a.q[static_cast<std::size_t>(i)];
      EXPECT_GE(s(0), 0.0);
      EXPECT_LE(s(0), 2 * M_PI);
      EXPECT_LE(s(1), 0.0);
      EXPECT_LT(pose_error(free.chain().forward(s.data()), target), kPose);
    }
    kept += a.count, all += b.count;
  }
  EXPECT_GT(kept, 0);
  EXPECT_LT(kept, all);
}

TEST(ClosedFormIk6R, UnreachablePoseHasNoSolution) {
  const ClosedFormIk6R ik(ur5().poe());
  IkScratch scratch;
  IkSolutions out;
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() = Eigen::Vector3d(3.0, 0.0, 0.0);
  ik.solve(far, scratch, out);
  EXPECT_EQ(out.count, 0);
  const ClosedFormIk6R search(offset_wrist().poe());
  search.solve(far, scratch, out);
  EXPECT_EQ(out.count, 0);
}

using hapsyn::test::error_of;  // tests/test_support.hpp

TEST(ClosedFormIk6R, RefusesWhatItCannotSolve) {
  const LocalFrames general = from_dh({{{0.32, 0.05, 1.4}}, {{0.11, 0.41, 0.25}}, {{-0.06, 0.03, -1.2}},
                                       {{0.37, 0.07, 1.0}}, {{0.09, 0.04, -1.3}}, {{0.08, 0.02, 0.3}}});
  EXPECT_EQ(error_of([&] { ClosedFormIk6R ik(general.poe()); }),
            "closed_form_ik: no closed-form decomposition for this chain (6R: no parallel or intersecting consecutive "
            "axes; family: none (general 6R: needs a 2-D search, not implemented))");
  LocalFrames five = puma();
  five.origins.pop_back(), five.axes.pop_back();
  EXPECT_EQ(error_of([&] { ClosedFormIk6R ik(five.poe()); }),
            "closed_form_ik: chain has 5 joints: the closed-form solvers are for 6R");
  IkOptions few;
  few.search_samples = 4;
  EXPECT_EQ(error_of([&] { ClosedFormIk6R ik(puma().poe(), few); }), "closed_form_ik: search_samples = 4: must be >= 8");
  IkOptions tol;
  tol.accept_tolerance = 0.0;
  EXPECT_EQ(error_of([&] { ClosedFormIk6R ik(puma().poe(), tol); }),
            "closed_form_ik: newton_steps = 4, accept_tolerance = 0.000000: must be >= 0 and > 0");
  IkOptions radius;
  radius.polish_radius = 1e-12;
  EXPECT_EQ(error_of([&] { ClosedFormIk6R ik(puma().poe(), radius); }),
            "closed_form_ik: polish_radius = 1e-12: must be >= accept_tolerance (1e-10)");
  IkOptions limits;
  limits.use_limits = true;
  limits.lower[2] = 1.0;
  EXPECT_EQ(error_of([&] { ClosedFormIk6R ik(puma().poe(), limits); }),
            "closed_form_ik: joint 3 limits [1.000000, 0.000000]: need lower <= upper");
}

}  // namespace
