// The min-max SQP on analytic max-min problems with known optima: three samples whose worst
// case is optimal at the centre of the circle through them (a kink where all three meet), the
// same with a bound that cuts the centre off, and the flat locals the epigraph stage works on.
#include "shared/minmax_sqp.hpp"

#include "analytic_problems.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace {

using hapsyn::plugins::run_minmax_sqp;
using hapsyn::plugins::score_goal;
using hapsyn::plugins::SqpSettings;

// f(x) = min_s 1 - |x - c_s|^2 over three samples s (pose = the sample's index) with centres
// (0, 0), (1, 0), (0.5, 0.8): the largest worst case is at the centre of the circle through
// them (the triangle is acute), x* = (0.5, 0.24375), f* = 1 - (0.25 + 0.24375^2).
constexpr double kCentres[3][2] = {{0.0, 0.0}, {1.0, 0.0}, {0.5, 0.8}};
constexpr double kOptimumY = 0.24375;
constexpr double kOptimum = 1.0 - (0.25 + kOptimumY * kOptimumY);

std::shared_ptr<hapsyn::Problem> circle_problem(double lower_y = 0.0) {
  auto problem = hapsyn::test::analytic_problem({{0.0, 1.0}, {lower_y, 1.0}}, 0.05, {0.0, 1.0, 2.0},
                                                {[](const double* x, const double* pose) {
                                                  const double* c = kCentres[static_cast<int>(pose[0])];
                                                  return 1.0 - (x[0] - c[0]) * (x[0] - c[0]) -
                                                         (x[1] - c[1]) * (x[1] - c[1]);
                                                }});
  return problem;
}

double score_at(const hapsyn::Problem& problem, const std::vector<double>& x) {
  auto ws = problem.make_eval_scratch();
  const hapsyn::Evaluation& e = problem.evaluate(x.data(), *ws);
  EXPECT_EQ(e.status, hapsyn::EvalStatus::kFeasible);
  return e.score;
}

}  // namespace

TEST(MinMaxSqp, FindsTheMaxMinOptimumAtTheKinkWhereThreeSamplesMeet) {
  const auto problem = circle_problem();
  const std::vector<double> start = {0.2, 0.7};
  const auto out = run_minmax_sqp(*problem, start, {0.0, 0.0}, {1.0, 1.0}, SqpSettings{}, score_goal(*problem));
  ASSERT_EQ(out.x.size(), 2u) << out.status;
  EXPECT_NEAR(out.x[0], 0.5, 1e-6) << out.status;
  EXPECT_NEAR(out.x[1], kOptimumY, 1e-6) << out.status;
  // The plain stage alone stalls at the kink about 2e-7 below f*: this tolerance needs the
  // epigraph stage (which lands on the optimum to round-off).
  EXPECT_NEAR(out.merit, kOptimum, 1e-8) << out.status;
  // The merit is the returned point's score over the whole workspace, and no point scores more.
  EXPECT_EQ(out.merit, score_at(*problem, out.x));
  EXPECT_LE(out.merit, kOptimum + 1e-12);
  // All three samples are critical at the optimum, so all three are in the active set.
  EXPECT_EQ(out.active_samples, 3u);
  EXPECT_NE(out.status.find("epigraph: "), std::string::npos) << out.status;
  EXPECT_GE(out.evaluations, 2);
  EXPECT_GT(out.samples, out.evaluations);
}

TEST(MinMaxSqp, KeepsToTheBoundsWhenTheyCutTheOptimumOff) {
  // With x1 >= 0.5 the worst samples are the two base centres: x* = (0.5, 0.5), f* = 0.5.
  const auto problem = circle_problem(0.5);
  const auto out =
      run_minmax_sqp(*problem, {0.9, 0.9}, {0.0, 0.5}, {1.0, 1.0}, SqpSettings{}, score_goal(*problem));
  ASSERT_EQ(out.x.size(), 2u) << out.status;
  EXPECT_GE(out.x[1], 0.5);
  EXPECT_NEAR(out.x[0], 0.5, 1e-6) << out.status;
  EXPECT_NEAR(out.x[1], 0.5, 1e-6) << out.status;
  EXPECT_NEAR(out.merit, 0.5, 1e-8) << out.status;
}

TEST(MinMaxSqp, NeverReturnsLessThanThePlainStageOrTheStart) {
  const auto problem = circle_problem();
  const std::vector<double> start = {0.9, 0.9};
  SqpSettings plain_only;
  plain_only.epigraph = false;
  const auto plain = run_minmax_sqp(*problem, start, {0.0, 0.0}, {1.0, 1.0}, plain_only, score_goal(*problem));
  EXPECT_NE(plain.status.find("epigraph: off"), std::string::npos) << plain.status;
  EXPECT_EQ(plain.rounds, 1);
  const auto both = run_minmax_sqp(*problem, start, {0.0, 0.0}, {1.0, 1.0}, SqpSettings{}, score_goal(*problem));
  EXPECT_GE(plain.merit, score_at(*problem, start));
  EXPECT_GE(both.merit, plain.merit);
  EXPECT_GT(both.rounds, plain.rounds);
}

TEST(MinMaxSqp, MapsTheFlatLocalsToObjectives) {
  // Two metrics with one min-reduced local each: z = (z_f1, z_f2), combine is the identity.
  const auto problem = hapsyn::test::two_objective_problem();
  EXPECT_EQ(hapsyn::plugins::local_count(*problem), 2u);
  const double z[2] = {0.25, -0.5};
  double f[2] = {0.0, 0.0};
  hapsyn::plugins::objectives_from_locals(*problem, z, f);
  EXPECT_EQ(f[0], 0.25);
  EXPECT_EQ(f[1], -0.5);
  // The score goal weighs them as the study does (both maximized, weight 1).
  const auto goal = score_goal(*problem);
  EXPECT_EQ(goal.objective(z, nullptr), 0.25 - 0.5);
}
