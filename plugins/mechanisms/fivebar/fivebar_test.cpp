// Tests of the five-bar mechanism: Unal 2008 Table 2, kinematics and dynamics cross-checks,
// extremes (docs/design.md section 6), determinism, options and declarations.
#include "fivebar.hpp"

#include <gdi.hpp>
#include <gii.hpp>
#include <planar_square.hpp>

#include <hapsyn/error.hpp>
#include <hapsyn/options.hpp>
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/schema.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <thread>
#include <vector>

// ---- Heap allocation counter (glibc): every malloc of this process passes through here, so
// operator new and Eigen's aligned_malloc are both seen. Counting is per thread and only while
// enabled. Not used under AddressSanitizer (which owns malloc).
#if defined(__SANITIZE_ADDRESS__)
#define HAPSYN_COUNT_ALLOCATIONS 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define HAPSYN_COUNT_ALLOCATIONS 0
#endif
#endif
#if !defined(HAPSYN_COUNT_ALLOCATIONS) && defined(__GLIBC__)
#define HAPSYN_COUNT_ALLOCATIONS 1
#endif
#ifndef HAPSYN_COUNT_ALLOCATIONS
#define HAPSYN_COUNT_ALLOCATIONS 0
#endif

#if HAPSYN_COUNT_ALLOCATIONS
namespace {
thread_local bool t_counting = false;
thread_local long long t_allocations = 0;
}  // namespace

extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* pointer, std::size_t size);
void* malloc(std::size_t size) {
  if (t_counting) ++t_allocations;
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
  if (t_counting) ++t_allocations;
  return __libc_calloc(count, size);
}
void* realloc(void* pointer, std::size_t size) {
  if (t_counting) ++t_allocations;
  return __libc_realloc(pointer, size);
}
}
#endif

namespace {

using hapsyn::Json;
using hapsyn::MechanismScratch;
using hapsyn::SampleQuantities;
using hapsyn::SampleSet;
using hapsyn::SampleStatus;
using hapsyn::plugins::FiveBar;
using hapsyn::plugins::FiveBarDesign;
using hapsyn::plugins::FiveBarModel;
using hapsyn::plugins::FiveBarOptions;
using hapsyn::plugins::PlanarSquareOptions;
using hapsyn::plugins::Gdi;
using hapsyn::plugins::Gii;
using hapsyn::plugins::PlanarSquare;

constexpr double kPi = 3.14159265358979323846;
constexpr hapsyn::Needs kAll = hapsyn::kNeedJacobian | hapsyn::kNeedInertia | hapsyn::kNeedEffectiveMass;

// Table 2 designs [m].
constexpr FiveBarDesign kBestGii{0.0004, 0.2997, 0.3000, 0.4196};
constexpr FiveBarDesign kBestGdi{0.0001, 0.0899, 0.1152, 0.1236};

FiveBarOptions options_with(double k = 0.005, double tolerance = 1e-4) {
  return hapsyn::make_options<FiveBarOptions>(Json{{"k", k}, {"singularity_tolerance", tolerance}});
}

// The mechanism as the registry builds it from a problem file's options (validated, defaults filled).
FiveBar fivebar(const Json& options = Json::object()) {
  return FiveBar(hapsyn::make_options<FiveBarOptions>(options));
}

SampleSet square(double side, double step) {
  return PlanarSquare(hapsyn::make_options<PlanarSquareOptions>(Json{{"side", side}, {"step", step}})).build({});
}

struct Indices {
  double gii = 0.0, gdi = 0.0;
  int reachable = 0, unreachable = 0, singular = 0, invalid = 0;
  bool finite = true;  // every filled quantity finite
};

bool all_finite(const SampleQuantities& q, bool quantities) {
  if (!q.q.allFinite()) return false;
  if (!quantities) return true;
  return q.jacobian.allFinite() && q.inertia.allFinite() && q.effective_mass.allFinite();
}

// GII and GDI of a design over a scene, computed with the metric classes directly (the same
// reductions the framework's evaluator applies: min/max over samples, then combine).
Indices evaluate(const FiveBarModel& model, const SampleSet& scene) {
  const Gii gii;
  const Gdi gdi;
  MechanismScratch scratch;
  SampleQuantities q;
  double sigma_min = std::numeric_limits<double>::infinity(), sigma_max = 0.0, mass_max = 0.0;
  Indices out;
  for (int i = 0; i < scene.size(); ++i) {
    model.solve(scene.pose(i), kAll, scratch, q);
    switch (q.status) {
      case SampleStatus::kReachable: {
        ++out.reachable;
        double local[2];
        gii.local(q, local);
        sigma_min = std::min(sigma_min, local[0]);
        sigma_max = std::max(sigma_max, local[1]);
        gdi.local(q, local);
        mass_max = std::max(mass_max, local[0]);
        out.finite = out.finite && all_finite(q, true) && std::isfinite(local[0]);
        break;
      }
      case SampleStatus::kUnreachable: ++out.unreachable; out.finite = out.finite && all_finite(q, false); break;
      case SampleStatus::kSingular: ++out.singular; out.finite = out.finite && all_finite(q, false); break;
      case SampleStatus::kInvalid: ++out.invalid; out.finite = out.finite && all_finite(q, false); break;
    }
  }
  const double reduced[2] = {sigma_min, sigma_max};
  out.gii = gii.combine(reduced, scene.size());
  out.gdi = gdi.combine(&mass_max, scene.size());
  return out;
}

// ---- Independent kinematics for the cross-checks: forward kinematics from (q1, q4) by circle
// intersection (FiveBarModel::forward), then every bar's centre and angle.
struct Bars {
  Eigen::Vector2d centre[4];  // actuated left, free left, free right, actuated right
  double angle[4];
};

bool bars_at(const FiveBarModel& m, double q1, double q4, Bars& bars) {
  const FiveBarDesign& d = m.design();
  double xy[2];
  if (!m.forward(q1, q4, xy)) return false;
  const Eigen::Vector2d a1(-0.5 * d.l0, 0.0), a2(0.5 * d.l0, 0.0);
  const Eigen::Vector2d b1 = a1 + d.l1 * Eigen::Vector2d(std::cos(q1), std::sin(q1));
  const Eigen::Vector2d b2 = a2 + d.l1 * Eigen::Vector2d(std::cos(q4), std::sin(q4));
  const Eigen::Vector2d e(xy[0], xy[1] + d.r);
  bars.centre[0] = 0.5 * (a1 + b1);
  bars.centre[1] = 0.5 * (b1 + e);
  bars.centre[2] = 0.5 * (b2 + e);
  bars.centre[3] = 0.5 * (a2 + b2);
  bars.angle[0] = q1;
  bars.angle[1] = std::atan2(e.y() - b1.y(), e.x() - b1.x());
  bars.angle[2] = std::atan2(e.y() - b2.y(), e.x() - b2.x());
  bars.angle[3] = q4;
  return true;
}

// Kinetic energy of the four uniform bars (mass rho l, inertia about the centre
// m (l^2 + k^2) / 12) moving with actuator rates qdot, from the bars' velocities by central
// differences through FK along qdot (Richardson-extrapolated, error O(h^4)).
double bar_energy(const FiveBarModel& m, double q1, double q4, const Eigen::Vector2d& qdot) {
  const FiveBarDesign& d = m.design();
  const double rho = m.rho(), k = m.k();
  const double length[4] = {d.l1, d.l2, d.l2, d.l1};
  auto rates = [&](double h, Eigen::Vector2d (&v)[4], double (&w)[4]) {
    Bars plus, minus;
    EXPECT_TRUE(bars_at(m, q1 + h * qdot(0), q4 + h * qdot(1), plus));
    EXPECT_TRUE(bars_at(m, q1 - h * qdot(0), q4 - h * qdot(1), minus));
    for (int i = 0; i < 4; ++i) {
      v[i] = (plus.centre[i] - minus.centre[i]) / (2.0 * h);
      w[i] = std::remainder(plus.angle[i] - minus.angle[i], 2.0 * kPi) / (2.0 * h);
    }
  };
  const double h = 1e-6;
  Eigen::Vector2d v1[4], v2[4];
  double w1[4], w2[4];
  rates(h, v1, w1);
  rates(2 * h, v2, w2);
  double energy = 0.0;
  for (int i = 0; i < 4; ++i) {
    const double mass = rho * length[i];
    const double inertia = mass * (length[i] * length[i] + k * k) / 12.0;
    const Eigen::Vector2d v = (4.0 * v1[i] - v2[i]) / 3.0;
    const double w = (4.0 * w1[i] - w2[i]) / 3.0;
    energy += 0.5 * mass * v.squaredNorm() + 0.5 * inertia * w * w;
  }
  return energy;
}

// Smallest |sin| of the three transmission angles: finite differences through FK lose accuracy
// as it approaches 0 (the velocities blow up), so the energy checks use samples above 0.1.
double transmission(const SampleQuantities& q) {
  return std::min({std::abs(std::sin(q.q(0) - q.q(1))), std::abs(std::sin(q.q(2) - q.q(3))),
                   std::abs(std::sin(q.q(2) - q.q(1)))});
}

std::vector<FiveBarDesign> test_designs() {
  return {kBestGii, kBestGdi, FiveBarDesign{0.0, 0.3, 0.3, 0.42}, FiveBarDesign{0.1, 0.23, 0.3, 0.37},
          FiveBarDesign{0.05, 0.3, 0.12, 0.25}, FiveBarDesign{0.2, 0.12, 0.3, 0.2}};
}

// Reachable samples of a design, drawn uniformly from a box around the scene.
template <class Visit>
int for_random_reachable(const FiveBarModel& model, unsigned seed, int draws, Visit visit) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coordinate(-0.08, 0.08);
  MechanismScratch scratch;
  SampleQuantities q;
  int reachable = 0;
  for (int i = 0; i < draws; ++i) {
    const double pose[2] = {coordinate(rng), coordinate(rng)};
    model.solve(pose, kAll, scratch, q);
    if (q.status != SampleStatus::kReachable) continue;
    ++reachable;
    visit(pose, q);
  }
  return reachable;
}

// ---------------------------------------------------------------------------------------------
// Unal 2008 Table 2 (scene: 0.1 m square, 0.001 m step; rho 1.08 kg/m).

TEST(FiveBarTable2, BestKinematicDesignReproducesGiiAndGdi) {
  const Indices r = evaluate(FiveBarModel(kBestGii, options_with()), square(0.1, 0.001));
  std::printf("best-GII design (0.4, 299.7, 300.0, 419.6) mm: GII %.6f GDI %.6f\n", r.gii, r.gdi);
  EXPECT_EQ(r.reachable, 101 * 101);
  EXPECT_NEAR(r.gii, 0.783, 0.0005);
  EXPECT_NEAR(r.gdi, 0.622, 0.0005);
}

TEST(FiveBarTable2, BestDynamicDesignReproducesGiiAndGdi) {
  const Indices r = evaluate(FiveBarModel(kBestGdi, options_with()), square(0.1, 0.001));
  std::printf("best-GDI design (0.1, 89.9, 115.2, 123.6) mm: GII %.6f GDI %.6f\n", r.gii, r.gdi);
  EXPECT_EQ(r.reachable, 101 * 101);
  EXPECT_NEAR(r.gii, 0.407, 0.0005);
  EXPECT_NEAR(r.gdi, 0.766, 0.0005);
}

TEST(FiveBarTable2, BarWidthsFromZeroTo12MillimetresReproduceBothGdiValues) {
  const SampleSet scene = square(0.1, 0.001);
  for (double k : {0.0, 0.005, 0.010, 0.012}) {
    const Indices g = evaluate(FiveBarModel(kBestGii, options_with(k)), scene);
    const Indices d = evaluate(FiveBarModel(kBestGdi, options_with(k)), scene);
    std::printf("k = %.3f m: GDI %.6f (0.622), %.6f (0.766)\n", k, g.gdi, d.gdi);
    EXPECT_NEAR(g.gdi, 0.622, 0.0005) << "k = " << k;
    EXPECT_NEAR(d.gdi, 0.766, 0.0005) << "k = " << k;
  }
  // A 20 mm bar no longer reproduces the best-GDI value: the width is not a free parameter.
  const Indices wide = evaluate(FiveBarModel(kBestGdi, options_with(0.02)), scene);
  EXPECT_GT(std::abs(wide.gdi - 0.766), 0.0005);
}

TEST(FiveBarTable2, NearOptimalRidgeDesignScoresAsDesignNotesSay) {
  const Indices r = evaluate(FiveBarModel(FiveBarDesign{0.1, 0.23, 0.3, 0.37}, options_with()), square(0.1, 0.001));
  EXPECT_NEAR(r.gii, 0.778, 0.0005);
}

TEST(FiveBarTable2, LiteralPaperWorkspaceOf200MillimetresDoesNotReproduce) {
  // docs/design.md section 3: with w = 200 mm the best-GII design scores 0.534 and the best-GDI
  // design cannot reach its workspace (its reach constraint fails).
  const SampleSet scene = square(0.2, 0.002);
  const Indices g = evaluate(FiveBarModel(kBestGii, options_with()), scene);
  EXPECT_NEAR(g.gii, 0.534, 0.0005);
  const FiveBar mechanism = fivebar();
  const double design[4] = {kBestGdi.l0, kBestGdi.l1, kBestGdi.l2, kBestGdi.r};
  double reach = 0.0;
  mechanism.evaluate_constraints(design, scene, &reach);
  EXPECT_GT(reach, 0.0);
  const Indices d = evaluate(FiveBarModel(kBestGdi, options_with()), scene);
  EXPECT_GT(d.unreachable, 0);
}

// ---------------------------------------------------------------------------------------------
// Kinematics and dynamics cross-checks.

TEST(FiveBarKinematics, SegmentsJoinTheActuatedJointsElbowsAndEndEffector) {
  const FiveBarModel model(kBestGdi, options_with());
  MechanismScratch scratch;
  SampleSet scene;
  scene.poses.resize(2, 2);
  scene.poses << 0.01, -0.02, 5.0, 5.0;  // a reachable sample, an unreachable one
  const std::vector<hapsyn::Segment> drawn = model.segments(scene, 0, scratch);
  ASSERT_EQ(drawn.size(), 2u);
  ASSERT_EQ(drawn[0].points.size(), 5u);
  const auto& p = drawn[0].points;  // A1, B1, E, B2, A2 in the scene frame (mechanism frame - (0, r))
  const double h = kBestGdi.l0 / 2, r = kBestGdi.r;
  EXPECT_LT((p[0] - Eigen::Vector3d(-h, -r, 0)).norm(), 1e-15);
  EXPECT_LT((p[4] - Eigen::Vector3d(h, -r, 0)).norm(), 1e-15);
  EXPECT_LT((p[2] - Eigen::Vector3d(0.01, -0.02, 0)).norm(), 1e-15);
  EXPECT_NEAR((p[1] - p[0]).norm(), kBestGdi.l1, 1e-12);
  EXPECT_NEAR((p[3] - p[4]).norm(), kBestGdi.l1, 1e-12);
  EXPECT_NEAR((p[2] - p[1]).norm(), kBestGdi.l2, 1e-12);
  EXPECT_NEAR((p[2] - p[3]).norm(), kBestGdi.l2, 1e-12);
  EXPECT_LT(p[1].x(), p[0].x());  // elbow out: the left elbow left of its joint
  EXPECT_GT(p[3].x(), p[4].x());
  EXPECT_EQ(drawn[1].name, "base");
  EXPECT_TRUE(model.segments(scene, 1, scratch).empty());
}

TEST(FiveBarKinematics, InverseThenForwardKinematicsReturnsTheTarget) {
  unsigned seed = 1;
  for (const FiveBarDesign& design : test_designs()) {
    const FiveBarModel model(design, options_with());
    const int reachable = for_random_reachable(model, seed++, 2000, [&](const double* pose, const SampleQuantities& q) {
      double xy[2];
      ASSERT_TRUE(model.forward(q.q(0), q.q(3), xy));
      EXPECT_NEAR(xy[0], pose[0], 1e-13);
      EXPECT_NEAR(xy[1], pose[1], 1e-13);
      // The free-link angles point from the elbows to the end effector.
      const double ex = pose[0], ey = pose[1] + design.r;
      const double b1x = -0.5 * design.l0 + design.l1 * std::cos(q.q(0)), b1y = design.l1 * std::sin(q.q(0));
      const double b2x = 0.5 * design.l0 + design.l1 * std::cos(q.q(3)), b2y = design.l1 * std::sin(q.q(3));
      EXPECT_NEAR(b1x + design.l2 * std::cos(q.q(1)), ex, 1e-13);
      EXPECT_NEAR(b1y + design.l2 * std::sin(q.q(1)), ey, 1e-13);
      EXPECT_NEAR(b2x + design.l2 * std::cos(q.q(2)), ex, 1e-13);
      EXPECT_NEAR(b2y + design.l2 * std::sin(q.q(2)), ey, 1e-13);
    });
    EXPECT_GT(reachable, 200) << "l1 = " << design.l1;
  }
}

TEST(FiveBarKinematics, ElbowsBendOutwardInTheValidPosture) {
  const FiveBarModel model(kBestGdi, options_with());
  MechanismScratch scratch;
  SampleQuantities q;
  const double centre[2] = {0.0, 0.0};
  model.solve(centre, kAll, scratch, q);
  ASSERT_EQ(q.status, SampleStatus::kReachable);
  // Left elbow left of A1, right elbow right of A2; the G inequalities hold.
  EXPECT_LT(-0.5 * kBestGdi.l0 + kBestGdi.l1 * std::cos(q.q(0)), -0.5 * kBestGdi.l0);
  EXPECT_GT(0.5 * kBestGdi.l0 + kBestGdi.l1 * std::cos(q.q(3)), 0.5 * kBestGdi.l0);
  EXPECT_GE(q.q(1), 0.0);
  EXPECT_LE(q.q(1), q.q(0));
  EXPECT_LE(q.q(2), kPi);
  EXPECT_GE(q.q(2), q.q(3));
  EXPECT_GT(q.q(2) - q.q(1), 0.0);
  EXPECT_LT(q.q(2) - q.q(1), kPi);
}

TEST(FiveBarKinematics, JacobianMatchesCentralDifferencesOfForwardKinematics) {
  unsigned seed = 100;
  for (const FiveBarDesign& design : test_designs()) {
    const FiveBarModel model(design, options_with());
    const double h = 1e-6;
    const int reachable = for_random_reachable(model, seed++, 300, [&](const double*, const SampleQuantities& q) {
      ASSERT_EQ(q.jacobian.rows(), 2);
      ASSERT_EQ(q.jacobian.cols(), 2);
      double p[2], m[2];
      Eigen::Matrix2d fd;
      ASSERT_TRUE(model.forward(q.q(0) + h, q.q(3), p));
      ASSERT_TRUE(model.forward(q.q(0) - h, q.q(3), m));
      fd.col(0) << (p[0] - m[0]) / (2 * h), (p[1] - m[1]) / (2 * h);
      ASSERT_TRUE(model.forward(q.q(0), q.q(3) + h, p));
      ASSERT_TRUE(model.forward(q.q(0), q.q(3) - h, m));
      fd.col(1) << (p[0] - m[0]) / (2 * h), (p[1] - m[1]) / (2 * h);
      const Eigen::Matrix2d jac = q.jacobian;
      EXPECT_LT((jac - fd).norm(), 1e-7 * (1.0 + jac.norm())) << "J =\n" << jac << "\nFD =\n" << fd;
    });
    EXPECT_GT(reachable, 30);
  }
}

TEST(FiveBarDynamics, InertiaMatchesKineticEnergyOfTheFourBars) {
  unsigned seed = 200;
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  for (const FiveBarDesign& design : test_designs()) {
    for (double k : {0.0, 0.005, 0.02}) {
      const FiveBarModel model(design, options_with(k));
      int checked = 0;
      for_random_reachable(model, seed++, 200, [&](const double*, const SampleQuantities& q) {
        if (transmission(q) < 0.1) return;
        ++checked;
        const Eigen::Vector2d qdot(normal(rng), normal(rng));
        const Eigen::Matrix2d d = q.inertia;
        const double expected = bar_energy(model, q.q(0), q.q(3), qdot);
        const double energy = 0.5 * qdot.dot(d * qdot);
        EXPECT_NEAR(energy, expected, 1e-7 * expected) << "design l1 " << design.l1 << " k " << k << " q " << q.q.transpose() << " sin " << transmission(q) << " qdot " << qdot.transpose();
        EXPECT_NEAR(d(0, 1), d(1, 0), 1e-15 * d.norm());
        EXPECT_GT(d.determinant(), 0.0);
      });
      EXPECT_GT(checked, 20);
    }
  }
}

TEST(FiveBarDynamics, EffectiveMassMatchesKineticEnergyInTaskCoordinates) {
  unsigned seed = 300;
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  for (const FiveBarDesign& design : test_designs()) {
    const FiveBarModel model(design, options_with());
    int checked = 0;
    for_random_reachable(model, seed++, 300, [&](const double*, const SampleQuantities& q) {
      if (transmission(q) < 0.1) return;
      ++checked;
      const Eigen::Vector2d v(normal(rng), normal(rng));  // end-effector velocity [m/s]
      const Eigen::Matrix2d jac = q.jacobian, mass = q.effective_mass;
      const Eigen::Vector2d qdot = jac.partialPivLu().solve(v);
      const double expected = bar_energy(model, q.q(0), q.q(3), qdot);
      EXPECT_NEAR(0.5 * v.dot(mass * v), expected, 1e-7 * expected);
      EXPECT_NEAR(mass(0, 1), mass(1, 0), 1e-12 * mass.norm());
    });
    EXPECT_GT(checked, 30);
  }
}

TEST(FiveBarDynamics, EffectiveMassEqualsInverseJacobianTransposeTimesInertia) {
  const FiveBarModel model(kBestGdi, options_with());
  const int reachable = for_random_reachable(model, 400, 100, [&](const double*, const SampleQuantities& q) {
    const Eigen::Matrix2d jinv = Eigen::Matrix2d(q.jacobian).inverse();
    const Eigen::Matrix2d expected = jinv.transpose() * Eigen::Matrix2d(q.inertia) * jinv;
    EXPECT_LT((Eigen::Matrix2d(q.effective_mass) - expected).norm(), 1e-12 * expected.norm());
  });
  EXPECT_GT(reachable, 10);
}

TEST(FiveBarDynamics, KineticEnergyMatchesThePapersCoEnergyWithCorrectedTypos) {
  // Unal 2008 eq. 9 (its "3 m1 l1^2" should read 3 m4 l1^2, harmless here since m1 = m4), with
  // q2dot, q3dot from the loop closure (computed here from Edot = J qdot).
  const FiveBarModel model(kBestGii, options_with(0.005));
  const double l1 = kBestGii.l1, l2 = kBestGii.l2, k = 0.005;
  const double m1 = model.actuated_mass(), m2 = model.free_mass();
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  const int reachable = for_random_reachable(model, 500, 100, [&](const double*, const SampleQuantities& q) {
    const double q1 = q.q(0), q2 = q.q(1), q3 = q.q(2), q4 = q.q(3);
    const Eigen::Vector2d qdot(normal(rng), normal(rng));
    const Eigen::Vector2d edot = Eigen::Matrix2d(q.jacobian) * qdot;
    // Free-link rates: (E - B)^perp . (Edot - Bdot) / l2^2.
    const Eigen::Vector2d w1(std::cos(q2), std::sin(q2)), w2(std::cos(q3), std::sin(q3));
    const Eigen::Vector2d b1dot = l1 * qdot(0) * Eigen::Vector2d(-std::sin(q1), std::cos(q1));
    const Eigen::Vector2d b2dot = l1 * qdot(1) * Eigen::Vector2d(-std::sin(q4), std::cos(q4));
    const double q2dot = Eigen::Vector2d(-w1.y(), w1.x()).dot(edot - b1dot) / l2;
    const double q3dot = Eigen::Vector2d(-w2.y(), w2.x()).dot(edot - b2dot) / l2;
    const double q1dot = qdot(0), q4dot = qdot(1);
    const double paper =
        m1 * (k * k + 4 * l1 * l1) * q1dot * q1dot / 24 + (3 * m1 * l1 * l1 + m1 * (k * k + l1 * l1)) * q4dot * q4dot / 24 +
        m2 * (k * k * q2dot * q2dot + 4 * l2 * l2 * q2dot * q2dot + 12 * l1 * l1 * q1dot * q1dot +
              12 * l1 * l2 * std::cos(q1 - q2) * q1dot * q2dot) / 24 +
        m2 * (k * k * q3dot * q3dot + 4 * l2 * l2 * q3dot * q3dot + 12 * l1 * l1 * q4dot * q4dot +
              12 * l1 * l2 * std::cos(q3 - q4) * q3dot * q4dot) / 24;
    EXPECT_NEAR(0.5 * qdot.dot(Eigen::Matrix2d(q.inertia) * qdot), paper, 1e-12 * paper);
  });
  EXPECT_GT(reachable, 10);
}

TEST(FiveBarKinematics, MirroredSampleGivesTheMirroredConfigurationBitForBit) {
  const FiveBarModel model(FiveBarDesign{0.05, 0.2, 0.25, 0.2}, options_with());
  MechanismScratch scratch;
  SampleQuantities a, b;
  const SampleSet scene = square(0.1, 0.005);
  for (int i = 0; i < scene.size(); ++i) {
    const double* p = scene.pose(i);
    const double mirrored[2] = {-p[0], p[1]};
    model.solve(p, kAll, scratch, a);
    model.solve(mirrored, kAll, scratch, b);
    ASSERT_EQ(a.status, b.status);
    ASSERT_EQ(b.q(3), kPi - a.q(0));
    ASSERT_EQ(b.q(2), kPi - a.q(1));
    ASSERT_EQ(a.q(3), kPi - b.q(0));
  }
}

// ---------------------------------------------------------------------------------------------
// Extremes (docs/design.md section 6).

TEST(FiveBarExtremes, ZeroBaseLengthIsFiniteAndReachesTheSquare) {
  const FiveBarModel model(FiveBarDesign{0.0, 0.3, 0.3, 0.42}, options_with());
  const Indices r = evaluate(model, square(0.1, 0.005));
  EXPECT_EQ(r.reachable, 441);
  EXPECT_TRUE(r.finite);
  EXPECT_GT(r.gii, 0.7);
  EXPECT_LT(r.gii, 1.0);
  EXPECT_GT(r.gdi, 0.5);
}

TEST(FiveBarExtremes, SampleExactlyOnTheOuterReachBoundaryIsSingular) {
  // Dyadic lengths: E - A1 = (0.375, 0.5) exactly, |E - A1| = 0.625 = l1 + l2, so c1 = 1
  // exactly and the left leg is stretched; the right leg reaches E comfortably.
  const FiveBarModel model(FiveBarDesign{0.25, 0.25, 0.375, 0.5}, options_with());
  MechanismScratch scratch;
  SampleQuantities q;
  const double on[2] = {0.25, 0.0};  // E = (0.25, 0.5) = A1 + (0.375, 0.5)
  model.solve(on, kAll, scratch, q);
  EXPECT_EQ(q.status, SampleStatus::kSingular);
  EXPECT_TRUE(q.q.allFinite());
  EXPECT_NEAR(q.q(0), std::atan2(0.5, 0.375), 1e-15);  // link along E - A1
  EXPECT_NEAR(q.q(1), std::atan2(0.5, 0.375), 1e-15);
  const double beyond[2] = {0.25, 1e-12};
  model.solve(beyond, kAll, scratch, q);
  EXPECT_EQ(q.status, SampleStatus::kUnreachable);
  EXPECT_TRUE(q.q.allFinite());
  const double inside[2] = {0.25, -1e-3};
  model.solve(inside, kAll, scratch, q);
  EXPECT_EQ(q.status, SampleStatus::kReachable);
}

TEST(FiveBarExtremes, SamplesWithinRoundingOfTheReachBoundaryAreClassifiedNeverNan) {
  // Non-dyadic lengths (l1 + l2 = 0.30000000000000004): |E - A| = l1 + l2 holds only up to
  // rounding. l0 = 0, so both legs see the same E - A; walk |E - A| over 17 consecutive doubles
  // around 0.3 and then clearly past the boundary.
  const FiveBarModel model(FiveBarDesign{0.0, 0.1, 0.2, 0.3}, options_with());
  MechanismScratch scratch;
  SampleQuantities q;
  const double ulp = std::nextafter(0.3, 1.0) - 0.3;
  int singular = 0;
  for (int i = -8; i <= 8; ++i) {
    const double pose[2] = {0.0, i * ulp};
    model.solve(pose, kAll, scratch, q);
    EXPECT_TRUE(q.status == SampleStatus::kSingular || q.status == SampleStatus::kUnreachable)
        << "i = " << i << " status " << hapsyn::to_string(q.status);
    EXPECT_TRUE(q.q.allFinite());
    singular += q.status == SampleStatus::kSingular;
  }
  EXPECT_GT(singular, 0);
  const double past[2] = {0.0, 1e-9};
  model.solve(past, kAll, scratch, q);
  EXPECT_EQ(q.status, SampleStatus::kUnreachable);
}

TEST(FiveBarExtremes, SamplesAtTheRoundedReachOfRandomLegsAreSingularNotUnreachable) {
  // |E - A| = fl(l1 + l2) or fl(|l1 - l2|) is the reach boundary up to one rounding; c may
  // compute a few ulps beyond +-1 there. Such samples are clamped and classified singular.
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> length(0.01, 0.3);
  MechanismScratch scratch;
  SampleQuantities q;
  for (int i = 0; i < 2000; ++i) {
    const double l1 = length(rng), l2 = length(rng);
    const FiveBarModel model(FiveBarDesign{0.0, l1, l2, 0.0}, options_with());
    for (double distance : {l1 + l2, std::abs(l1 - l2)}) {
      const double pose[2] = {0.0, distance};
      model.solve(pose, kAll, scratch, q);
      ASSERT_EQ(q.status, SampleStatus::kSingular) << "l1 = " << l1 << ", l2 = " << l2 << ", |E - A| = " << distance;
      ASSERT_TRUE(q.q.allFinite());
    }
  }
}

TEST(FiveBarExtremes, SampleExactlyOnTheInnerReachBoundaryIsSingular) {
  // |E - A1| = l2 - l1 = 0.125: the left leg folds back (q1 - q2 = pi).
  const FiveBarModel model(FiveBarDesign{0.125, 0.125, 0.25, 0.25}, options_with());
  MechanismScratch scratch;
  SampleQuantities q;
  const double inner[2] = {-0.0625, -0.125};  // E = A1 + (0, 0.125)
  model.solve(inner, kAll, scratch, q);
  EXPECT_EQ(q.status, SampleStatus::kSingular);
  EXPECT_TRUE(q.q.allFinite());
  const double inside[2] = {-0.0625, -0.125 - 1e-12};  // closer than |l1 - l2|
  model.solve(inside, kAll, scratch, q);
  EXPECT_EQ(q.status, SampleStatus::kUnreachable);
  // l1 > l2: |E - A1| = l1 - l2 folds the free link back onto the actuated one.
  const FiveBarModel longer(FiveBarDesign{0.125, 0.25, 0.125, 0.25}, options_with());
  longer.solve(inner, kAll, scratch, q);
  EXPECT_EQ(q.status, SampleStatus::kSingular);
  EXPECT_TRUE(q.q.allFinite());
}

TEST(FiveBarExtremes, EndEffectorOnAnActuatedJointIsClassified) {
  MechanismScratch scratch;
  SampleQuantities q;
  const double on_a1[2] = {-0.05, -0.2};  // E = A1 = (-0.05, 0)
  const FiveBarModel equal(FiveBarDesign{0.1, 0.2, 0.2, 0.2}, options_with());
  equal.solve(on_a1, kAll, scratch, q);
  EXPECT_EQ(q.status, SampleStatus::kSingular);
  EXPECT_TRUE(q.q.allFinite());
  const FiveBarModel unequal(FiveBarDesign{0.1, 0.2, 0.3, 0.2}, options_with());
  unequal.solve(on_a1, kAll, scratch, q);
  EXPECT_EQ(q.status, SampleStatus::kUnreachable);
  EXPECT_TRUE(q.q.allFinite());
}

TEST(FiveBarExtremes, FreeLinksInLineAreSingular) {
  // l0 = 0.2, l1 = 0.15, l2 = 0.1: at E = (0, 0.15) both free links are horizontal,
  // q3 - q2 = pi.
  const FiveBarModel model(FiveBarDesign{0.2, 0.15, 0.1, 0.15}, options_with());
  MechanismScratch scratch;
  SampleQuantities q;
  const double pose[2] = {0.0, 0.0};
  model.solve(pose, kAll, scratch, q);
  EXPECT_EQ(q.status, SampleStatus::kSingular);
  EXPECT_TRUE(q.q.allFinite());
  EXPECT_NEAR(q.q(2) - q.q(1), kPi, 1e-7);
}

TEST(FiveBarExtremes, SingularityToleranceOptionMovesTheSingularBoundary) {
  const FiveBarDesign design{0.2, 0.15, 0.1, 0.15};
  MechanismScratch scratch;
  SampleQuantities q;
  const double pose[2] = {0.0, 0.01};  // near the in-line configuration above
  FiveBarModel(design, options_with(0.005, 1e-4)).solve(pose, kAll, scratch, q);
  ASSERT_EQ(q.status, SampleStatus::kReachable);
  const double s = std::abs(std::sin(q.q(2) - q.q(1)));
  EXPECT_LT(s, 0.5);
  FiveBarModel(design, options_with(0.005, 0.9 * s)).solve(pose, kAll, scratch, q);
  EXPECT_EQ(q.status, SampleStatus::kReachable);
  FiveBarModel(design, options_with(0.005, 1.1 * s)).solve(pose, kAll, scratch, q);
  EXPECT_EQ(q.status, SampleStatus::kSingular);
}

TEST(FiveBarExtremes, EndEffectorBelowTheElbowsIsInvalid) {
  // E below the actuated joints: the free links would point down (q2 > pi): not the paper's G.
  const FiveBarModel model(FiveBarDesign{0.1, 0.2, 0.2, 0.0}, options_with());
  MechanismScratch scratch;
  SampleQuantities q;
  const double pose[2] = {0.0, -0.05};
  model.solve(pose, kAll, scratch, q);
  EXPECT_EQ(q.status, SampleStatus::kInvalid);
  EXPECT_TRUE(q.q.allFinite());
  EXPECT_GT(q.q(1), kPi);
}

TEST(FiveBarExtremes, DesignThatCannotReachPartOfTheSquareIsClassifiedAndViolatesReach) {
  const FiveBarDesign design{0.0, 0.05, 0.05, 0.1};
  const SampleSet scene = square(0.1, 0.005);
  const Indices r = evaluate(FiveBarModel(design, options_with()), scene);
  EXPECT_GT(r.unreachable, 0);
  EXPECT_GT(r.reachable, 0);
  EXPECT_TRUE(r.finite);
  const FiveBar mechanism = fivebar();
  const double vector[4] = {design.l0, design.l1, design.l2, design.r};
  double g = 0.0;
  mechanism.evaluate_constraints(vector, scene, &g);
  EXPECT_GT(g, 0.0);
}

// Every corner of the default design box and of the hard limits: every sample is classified,
// every quantity finite, the constraint finite, and the indices finite.
void check_corners(const std::array<double, 2> (&bounds)[4]) {
  const FiveBar mechanism = fivebar();
  const SampleSet scene = square(0.1, 0.005);
  for (int corner = 0; corner < 16; ++corner) {
    double design[4];
    for (int v = 0; v < 4; ++v) design[v] = bounds[v][(corner >> v) & 1];
    const auto model = mechanism.build(design);
    const Indices r = evaluate(static_cast<const FiveBarModel&>(*model), scene);
    EXPECT_EQ(r.reachable + r.unreachable + r.singular + r.invalid, scene.size());
    EXPECT_TRUE(r.finite) << "corner " << corner;
    EXPECT_TRUE(std::isfinite(r.gii) && std::isfinite(r.gdi)) << "corner " << corner;
    double g = 0.0;
    mechanism.evaluate_constraints(design, scene, &g);
    EXPECT_TRUE(std::isfinite(g));
  }
}

TEST(FiveBarExtremes, EveryCornerOfTheDefaultDesignBoxIsFiniteOrClassified) {
  const std::array<double, 2> bounds[4] = {{0.0, 0.3}, {0.01, 0.3}, {0.01, 0.3}, {0.0, 0.6}};
  check_corners(bounds);
  // Spot-check the classifications: the shortest links cannot reach a square 0.6 m away.
  const FiveBarModel far(FiveBarDesign{0.0, 0.01, 0.01, 0.6}, options_with());
  EXPECT_EQ(evaluate(far, square(0.1, 0.005)).unreachable, 441);
}

TEST(FiveBarExtremes, EveryCornerOfTheHardLimitsIsFiniteOrClassified) {
  const std::array<double, 2> bounds[4] = {{0.0, 10.0}, {1e-4, 10.0}, {1e-4, 10.0}, {-10.0, 10.0}};
  check_corners(bounds);
}

TEST(FiveBarExtremes, DesignVariablesMatchTheirDeclaredBounds) {
  const auto variables = fivebar().variables();
  ASSERT_EQ(variables.size(), 4u);
  const char* names[4] = {"l0", "l1", "l2", "r"};
  const double lower[4] = {0.0, 0.01, 0.01, 0.0}, upper[4] = {0.3, 0.3, 0.3, 0.6};
  const double hard_lower[4] = {0.0, 1e-4, 1e-4, -10.0}, hard_upper[4] = {10.0, 10.0, 10.0, 10.0};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(variables[i].name, names[i]);
    EXPECT_EQ(variables[i].unit, "m");
    EXPECT_EQ(variables[i].size, 1);
    EXPECT_FALSE(variables[i].integer);
    EXPECT_FALSE(variables[i].description.empty());
    EXPECT_EQ(variables[i].default_lower, std::vector<double>{lower[i]});
    EXPECT_EQ(variables[i].default_upper, std::vector<double>{upper[i]});
    EXPECT_EQ(variables[i].hard_lower, std::vector<double>{hard_lower[i]});
    EXPECT_EQ(variables[i].hard_upper, std::vector<double>{hard_upper[i]});
  }
}

TEST(FiveBarExtremes, BuildRefusesNonPhysicalDesigns) {
  const FiveBar mechanism = fivebar();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double bad[][4] = {{-0.1, 0.2, 0.2, 0.2}, {0.1, 0.0, 0.2, 0.2}, {0.1, 0.2, -0.2, 0.2}, {0.1, 0.2, 0.2, nan}};
  for (const auto& design : bad) EXPECT_THROW(mechanism.build(design), hapsyn::Error);
  try {
    const double zero_l1[4] = {0.1, 0.0, 0.2, 0.2};
    mechanism.build(zero_l1);
    FAIL() << "no error";
  } catch (const hapsyn::Error& e) {
    EXPECT_STREQ(e.what(), "fivebar: design l1 = 0.0: must be finite and > 0");
  }
}

// ---------------------------------------------------------------------------------------------
// The reach constraint.

TEST(FiveBarReach, ConstraintMatchesThePapersFormulaForTheSquare) {
  const FiveBar mechanism = fivebar();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> l0(0.0, 0.3), l(0.01, 0.3), r(0.0, 0.6);
  for (double side : {0.1, 0.2}) {
    const SampleSet scene = square(side, side / 20);
    for (int i = 0; i < 50; ++i) {
      const double design[4] = {l0(rng), l(rng), l(rng), r(rng)};
      double g = 0.0;
      mechanism.evaluate_constraints(design, scene, &g);
      const double paper = std::pow(design[0] / 2 + side / 2, 2) + std::pow(design[3] + side / 2, 2) -
                           std::pow(design[1] + design[2], 2);
      EXPECT_NEAR(g, paper, 1e-15);
    }
  }
}

TEST(FiveBarReach, ConstraintUsesTheScenesBoundingBox) {
  // An off-centre, non-square scene: compare with the corners from SampleSet::lower_corner /
  // upper_corner and a brute-force maximum over the corners and both joints.
  SampleSet scene;
  scene.coordinates = {"x", "y"};
  scene.poses.resize(3, 2);
  scene.poses << 0.02, -0.01, -0.07, 0.03, 0.05, 0.08;
  const Eigen::VectorXd lo = scene.lower_corner(), hi = scene.upper_corner();
  const FiveBar mechanism = fivebar();
  const double design[4] = {0.12, 0.1, 0.15, 0.05};
  double g = 0.0;
  mechanism.evaluate_constraints(design, scene, &g);
  double farthest = 0.0;
  for (double ax : {-0.06, 0.06}) {
    for (double x : {lo(0), hi(0)}) {
      for (double y : {lo(1), hi(1)}) farthest = std::max(farthest, std::pow(x - ax, 2) + std::pow(y + 0.05, 2));
    }
  }
  EXPECT_NEAR(g, farthest - 0.25 * 0.25, 1e-15);
}

TEST(FiveBarReach, SatisfiedConstraintMeansTheFarCornersAreReachable) {
  // On the paper's square, g < 0 puts the two far corners strictly inside both legs' reach;
  // g > 0 leaves a far corner out of reach of one leg.
  const SampleSet scene = square(0.1, 0.1);  // the four corners
  MechanismScratch scratch;
  SampleQuantities q;
  for (double total : {0.24, 0.26}) {
    const FiveBarDesign design{0.1, total / 2, total / 2, 0.1};
    const double g = FiveBar::reach_constraint(design, -0.05, 0.05, -0.05, 0.05);
    const FiveBarModel model(design, options_with());
    const double far_corner[2] = {0.05, 0.05};
    model.solve(far_corner, kAll, scratch, q);
    if (g < 0) {
      EXPECT_NE(q.status, SampleStatus::kUnreachable) << "l1 + l2 = " << total;
    } else {
      EXPECT_EQ(q.status, SampleStatus::kUnreachable) << "l1 + l2 = " << total;
    }
  }
}

TEST(FiveBarReach, IntervalOfRHoldsExactlyThePlacementsTheConstraintAccepts) {
  // Random designs and boxes (also off-centre), r on a fine grid and at the interval's ends.
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int inside = 0, outside = 0, empty = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    FiveBarDesign d{0.3 * u(rng), 0.01 + 0.3 * u(rng), 0.01 + 0.3 * u(rng), 0.0};
    const double xmin = -0.1 * u(rng), xmax = 0.1 * u(rng), ymin = -0.1 * u(rng), ymax = 0.1 * u(rng);
    double lower = 0.0, upper = 0.0;
    FiveBar::reach_interval(d, xmin, xmax, ymin, ymax, lower, upper);
    if (lower > upper) {
      ++empty;
      for (double r = -1.0; r <= 1.0; r += 0.01) {
        d.r = r;
        ASSERT_GT(FiveBar::reach_constraint(d, xmin, xmax, ymin, ymax), 0.0);
      }
      continue;
    }
    const double margin = 1e-9 * (1.0 + std::abs(lower) + std::abs(upper));
    for (double r = lower - 0.2; r <= upper + 0.2; r += 0.005) {
      d.r = r;
      const double g = FiveBar::reach_constraint(d, xmin, xmax, ymin, ymax);
      if (r < lower - margin || r > upper + margin) {
        ASSERT_GT(g, 0.0) << "r = " << r << " outside [" << lower << ", " << upper << "]";
        ++outside;
      } else if (r > lower + margin && r < upper - margin) {
        ASSERT_LE(g, 0.0) << "r = " << r << " inside [" << lower << ", " << upper << "]";
        ++inside;
      }
    }
    // At the ends the constraint is zero to rounding.
    d.r = lower;
    EXPECT_NEAR(FiveBar::reach_constraint(d, xmin, xmax, ymin, ymax), 0.0, 1e-12);
    d.r = upper;
    EXPECT_NEAR(FiveBar::reach_constraint(d, xmin, xmax, ymin, ymax), 0.0, 1e-12);
  }
  EXPECT_GT(inside, 10000);
  EXPECT_GT(outside, 10000);
  EXPECT_GT(empty, 100);
}

TEST(FiveBarReach, ConstraintHoldsOnOneRunOfRAsComputed) {
  // The promise of constraints_quasiconvex(3), in floating point: along r, the values where the
  // computed constraint is <= 0 form one run. Checked on random designs and boxes at r on a
  // grid and on every double within 300 ulps of the interval's ends, in increasing order.
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int runs = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    FiveBarDesign d{0.3 * u(rng), 0.01 + 0.3 * u(rng), 0.01 + 0.3 * u(rng), 0.0};
    const double xmin = -0.1 * u(rng), xmax = 0.1 * u(rng), ymin = -0.1 * u(rng), ymax = 0.1 * u(rng);
    double lower = 0.0, upper = 0.0;
    FiveBar::reach_interval(d, xmin, xmax, ymin, ymax, lower, upper);
    std::vector<double> rs;
    for (double r = -1.0; r <= 1.0; r += 0.0037) rs.push_back(r);
    for (const double end : {lower, upper, -0.5 * (ymin + ymax)}) {
      if (!std::isfinite(end)) continue;
      double below = end, above = end;
      for (int k = 0; k < 300; ++k) {
        rs.push_back(below = std::nextafter(below, -2.0));
        rs.push_back(above = std::nextafter(above, 2.0));
      }
      rs.push_back(end);
    }
    std::sort(rs.begin(), rs.end());
    int changes = 0;
    bool previous = false;
    for (std::size_t i = 0; i < rs.size(); ++i) {
      d.r = rs[i];
      const bool holds = FiveBar::reach_constraint(d, xmin, xmax, ymin, ymax) <= 0.0;
      if (i > 0 && holds != previous) ++changes;
      previous = holds;
    }
    d.r = rs.front();
    ASSERT_GT(FiveBar::reach_constraint(d, xmin, xmax, ymin, ymax), 0.0);  // starts and ends outside
    ASSERT_TRUE(changes == 0 || changes == 2) << "trial " << trial << ": " << changes << " changes along r";
    runs += changes == 2;
  }
  EXPECT_GT(runs, 1000);
}

TEST(FiveBarReach, PromisesOneRunOnlyAlongRAndWithoutAFootprint) {
  const FiveBar plain = fivebar();
  for (int k = 0; k < 3; ++k) EXPECT_FALSE(plain.constraints_quasiconvex(k)) << k;
  EXPECT_TRUE(plain.constraints_quasiconvex(3));
  const FiveBar footprint = fivebar(Json{{"footprint_width", 0.2}});
  EXPECT_FALSE(footprint.constraints_quasiconvex(3));
}

TEST(FiveBarReach, ConstraintIntervalIsTheReachIntervalWidenedAndOnlyForR) {
  const FiveBar mechanism = fivebar();
  const SampleSet scene = square(0.1, 0.01);
  const double design[4] = {0.1, 0.2, 0.15, 0.3};
  double lower = 0.0, upper = 0.0, exact_lower = 0.0, exact_upper = 0.0;
  ASSERT_TRUE(mechanism.constraint_interval(design, 3, scene, lower, upper));
  FiveBar::reach_interval(FiveBar::design_from(design), -0.05, 0.05, -0.05, 0.05, exact_lower, exact_upper);
  EXPECT_LT(lower, exact_lower);
  EXPECT_GT(upper, exact_upper);
  EXPECT_NEAR(lower, exact_lower, 1e-8);
  EXPECT_NEAR(upper, exact_upper, 1e-8);
  for (int component = 0; component < 3; ++component) {
    EXPECT_FALSE(mechanism.constraint_interval(design, component, scene, lower, upper)) << component;
  }
}

TEST(FiveBarReach, DeclaresOneConstraintNamedReach) {
  const auto constraints = fivebar().constraints();
  ASSERT_EQ(constraints.size(), 1u);
  EXPECT_EQ(constraints[0].name, "reach");
  EXPECT_FALSE(constraints[0].description.empty());
}

// ---------------------------------------------------------------------------------------------
// Conformance: determinism, thread safety, allocation, needs, options, scene check.

TEST(FiveBarConformance, TwoEvaluationsOfTheSameDesignAreBitIdentical) {
  const FiveBar mechanism = fivebar();
  const SampleSet scene = square(0.1, 0.005);
  const double design[4] = {kBestGdi.l0, kBestGdi.l1, kBestGdi.l2, kBestGdi.r};
  const auto first = mechanism.build(design);
  const auto second = mechanism.build(design);
  MechanismScratch scratch;
  SampleQuantities a, b;
  for (int i = 0; i < scene.size(); ++i) {
    first->solve(scene.pose(i), kAll, scratch, a);
    second->solve(scene.pose(i), kAll, scratch, b);
    ASSERT_EQ(a.status, b.status);
    ASSERT_EQ(std::memcmp(a.q.data(), b.q.data(), 4 * sizeof(double)), 0);
    ASSERT_EQ(std::memcmp(a.jacobian.data(), b.jacobian.data(), 4 * sizeof(double)), 0);
    ASSERT_EQ(std::memcmp(a.inertia.data(), b.inertia.data(), 4 * sizeof(double)), 0);
    ASSERT_EQ(std::memcmp(a.effective_mass.data(), b.effective_mass.data(), 4 * sizeof(double)), 0);
  }
  const Indices x = evaluate(static_cast<const FiveBarModel&>(*first), scene);
  const Indices y = evaluate(static_cast<const FiveBarModel&>(*second), scene);
  EXPECT_EQ(std::memcmp(&x.gii, &y.gii, sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(&x.gdi, &y.gdi, sizeof(double)), 0);
}

TEST(FiveBarConformance, ConcurrentSolvesOfOneModelAgreeWithSequentialOnes) {
  const FiveBarModel model(kBestGii, options_with());
  const SampleSet scene = square(0.1, 0.002);
  std::vector<double> sequential(scene.size()), parallel(scene.size());
  auto run = [&](std::vector<double>& out, int begin, int stride) {
    MechanismScratch scratch;
    SampleQuantities q;
    for (int i = begin; i < scene.size(); i += stride) {
      model.solve(scene.pose(i), kAll, scratch, q);
      out[i] = q.effective_mass(0, 0) + q.jacobian(1, 0);
    }
  };
  run(sequential, 0, 1);
  std::thread t1(run, std::ref(parallel), 0, 2), t2(run, std::ref(parallel), 1, 2);
  t1.join();
  t2.join();
  EXPECT_EQ(std::memcmp(sequential.data(), parallel.data(), sequential.size() * sizeof(double)), 0);
}

TEST(FiveBarConformance, SolveAndMetricLocalsDoNotAllocate) {
#if !HAPSYN_COUNT_ALLOCATIONS
  GTEST_SKIP() << "allocation counting needs glibc without sanitizers";
#else
  const FiveBarModel model(kBestGii, options_with());
  const SampleSet scene = square(0.1, 0.005);
  const Gii gii;
  const Gdi gdi;
  MechanismScratch scratch;
  SampleQuantities q;
  SampleQuantities wide;  // a 3 x 3 Jacobian / mass exercises the metrics' SVD fallback
  wide.jacobian = hapsyn::TaskJointMatrix::Identity(3, 3);
  wide.effective_mass = hapsyn::TaskMatrix::Identity(3, 3);
  double local[2];
  t_allocations = 0;
  t_counting = true;
  for (int i = 0; i < scene.size(); ++i) {
    model.solve(scene.pose(i), kAll, scratch, q);
    gii.local(q, local);
    gdi.local(q, local);
  }
  gii.local(wide, local);
  gdi.local(wide, local);
  t_counting = false;
  EXPECT_EQ(t_allocations, 0);
  // The counter works: a vector allocates.
  t_counting = true;
  std::vector<double> sink(100);
  t_counting = false;
  EXPECT_GT(t_allocations, 0);
  EXPECT_EQ(sink.size(), 100u);
#endif
}

TEST(FiveBarConformance, OnlyRequestedQuantitiesAreComputed) {
  const FiveBarModel model(kBestGii, options_with());
  MechanismScratch scratch;
  SampleQuantities q;
  const double pose[2] = {0.01, 0.02};
  model.solve(pose, hapsyn::kNeedPose, scratch, q);
  EXPECT_EQ(q.status, SampleStatus::kReachable);
  EXPECT_EQ(q.q.size(), 4);
  EXPECT_EQ(q.jacobian.size(), 0);
  EXPECT_EQ(q.inertia.size(), 0);
  EXPECT_EQ(q.effective_mass.size(), 0);
  model.solve(pose, hapsyn::kNeedJacobian, scratch, q);
  EXPECT_EQ(q.jacobian.rows(), 2);
  EXPECT_EQ(q.inertia.size(), 0);
  model.solve(pose, hapsyn::kNeedEffectiveMass, scratch, q);
  EXPECT_EQ(q.inertia.rows(), 2);
  EXPECT_EQ(q.effective_mass.rows(), 2);
  EXPECT_EQ(fivebar().provides(),
            hapsyn::kNeedJacobian | hapsyn::kNeedInertia | hapsyn::kNeedEffectiveMass);
}

TEST(FiveBarConformance, SchemaIsDerivedFromTheDeclarationsWithThePapersDefaults) {
  const Json schema = hapsyn::options_schema<FiveBarOptions>();
  EXPECT_NO_THROW(hapsyn::check_schema(schema, "fivebar"));
  for (const auto& item : schema.at("properties").items()) {
    EXPECT_TRUE(item.value().contains("description")) << item.key();
    EXPECT_TRUE(item.value().contains("default")) << item.key();
  }
  // The declared defaults, as the registry fills them: Unal 2008's rho and a width inside the
  // range that reproduces Table 2, no footprint limit.
  const FiveBarOptions defaults = hapsyn::default_options<FiveBarOptions>();
  EXPECT_EQ(defaults.elbow, "out");
  EXPECT_EQ(defaults.rho, 1.08);
  EXPECT_EQ(defaults.k, 0.005);
  EXPECT_EQ(defaults.singularity_tolerance, 1e-4);
  EXPECT_EQ(defaults.footprint_width, 0.0);
  EXPECT_EQ(defaults.footprint_height, 0.0);
  EXPECT_EQ(fivebar().options().k, defaults.k);
}

TEST(FiveBarConformance, BadOptionsAreRefusedWithTheirPathAndRule) {
  auto message = [](const Json& options) {
    try {
      fivebar(options);
    } catch (const hapsyn::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message(Json{{"rho", -1.0}}), "problem: options.rho = -1.0: must be > 0");
  EXPECT_EQ(message(Json{{"k", -0.001}}), "problem: options.k = -0.001: must be >= 0");
  EXPECT_EQ(message(Json{{"singularity_tolerance", 0.0}}),
            "problem: options.singularity_tolerance = 0.0: must be > 0");
  EXPECT_EQ(message(Json{{"singularity_tolerance", 1.5}}),
            "problem: options.singularity_tolerance = 1.5: must be <= 1");
  EXPECT_EQ(message(Json{{"elbow", "in"}}), "problem: options.elbow = \"in\": must be one of \"out\"");
  EXPECT_EQ(message(Json{{"rho", "heavy"}}), "problem: options.rho = \"heavy\": must be a number");
  EXPECT_EQ(message(Json{{"width", 0.01}}),
            "problem: options.width: unknown key; known keys: elbow, footprint_height, footprint_width, k, rho, "
            "singularity_tolerance");
}

TEST(FiveBarConformance, CheckSceneRefusesNonPlanarScenes) {
  const FiveBar mechanism = fivebar();
  EXPECT_NO_THROW(mechanism.check_scene(square(0.1, 0.005)));
  SampleSet spatial;
  spatial.coordinates = {"x", "y", "z"};
  spatial.poses = SampleSet::RowMatrix::Zero(4, 3);
  try {
    mechanism.check_scene(spatial);
    FAIL() << "no error";
  } catch (const hapsyn::Error& e) {
    EXPECT_STREQ(e.what(), "fivebar: scene samples have 3 coordinates: the five-bar serves planar scenes of (x, y) [m] samples");
  }
  SampleSet empty;
  empty.poses.resize(0, 2);
  EXPECT_THROW(mechanism.check_scene(empty), hapsyn::Error);
  double g = 0.0;
  const double design[4] = {0.1, 0.2, 0.2, 0.2};
  EXPECT_THROW(mechanism.evaluate_constraints(design, spatial, &g), hapsyn::Error);
}

// ---------------------------------------------------------------------------------------------
// The plugin files: loaded by name through the registry, with the schemas derived from their
// declarations.

TEST(FiveBarPlugin, LoadedPluginsReproduceTable2) {
  const hapsyn::Registry registry({HAPSYN_PLUGIN_DIR});
  const hapsyn::PluginRecord& record = registry.find("fivebar");
  EXPECT_EQ(record.kind, "mechanism");
  EXPECT_EQ(record.version, "1.0.0");
  EXPECT_EQ(record.schema.at("properties").at("rho").at("default").get<double>(), 1.08);
  const auto mechanism = registry.create_mechanism("fivebar", Json::object(), "mechanism.options");
  const auto scene = registry.create_scene("planar_square", Json{{"step", 0.001}}, "scene.options");
  const auto gii = registry.create_metric("gii", Json::object(), "metrics[0].options");
  const auto gdi = registry.create_metric("gdi", Json::object(), "metrics[1].options");
  const SampleSet samples = scene->build({});
  mechanism->check_scene(samples);
  ASSERT_EQ(samples.size(), 101 * 101);
  const double design[4] = {kBestGii.l0, kBestGii.l1, kBestGii.l2, kBestGii.r};
  double g = 0.0;
  mechanism->evaluate_constraints(design, samples, &g);
  EXPECT_LT(g, 0.0);
  const auto model = mechanism->build(design);
  const auto scratch = mechanism->make_scratch();
  SampleQuantities q;
  double reduced_gii[2] = {std::numeric_limits<double>::infinity(), 0.0}, reduced_gdi = 0.0;
  for (int i = 0; i < samples.size(); ++i) {
    model->solve(samples.pose(i), gii->specs().needs | gdi->specs().needs, *scratch, q);
    ASSERT_EQ(q.status, SampleStatus::kReachable);
    double local[2];
    gii->local(q, local);
    reduced_gii[0] = std::min(reduced_gii[0], local[0]);
    reduced_gii[1] = std::max(reduced_gii[1], local[1]);
    gdi->local(q, local);
    reduced_gdi = std::max(reduced_gdi, local[0]);
  }
  EXPECT_NEAR(gii->combine(reduced_gii, samples.size()), 0.783, 0.0005);
  EXPECT_NEAR(gdi->combine(&reduced_gdi, samples.size()), 0.622, 0.0005);
  // Options are validated against the schema derived from the declarations.
  EXPECT_THROW(registry.create_mechanism("fivebar", Json{{"rho", 0.0}}, "mechanism.options"), hapsyn::Error);
  EXPECT_THROW(registry.create_scene("planar_square", Json{{"step", 0.03}}, "scene.options"), hapsyn::Error);
}

}  // namespace

TEST(FiveBar, FootprintConstraintBoundsTheMechanismInEveryPosture) {
  // Box around the actuated joints' l1 circles and the scene: for the best-GDI design of Table 2
  // (l0 0.1 mm, l1 89.9 mm, r 123.6 mm) and a 100 mm square: width 2*0.0899 + 0.0001 = 0.1799 m,
  // height from -0.0899 to r + 0.05 = 0.1736: 0.2635 m.
  const hapsyn::plugins::FiveBarDesign d{0.0001, 0.0899, 0.1152, 0.1236};
  EXPECT_NEAR(FiveBar::footprint_constraint(d, -0.05, 0.05, -0.05, 0.05, 0.3, 0.3), 0.2635 - 0.3, 1e-12);
  EXPECT_NEAR(FiveBar::footprint_constraint(d, -0.05, 0.05, -0.05, 0.05, 0.15, 0.0), 0.1799 - 0.15, 1e-12);
  // Every elbow and the end effector of every reachable sample lie inside the box.
  const FiveBarModel model(d, options_with());
  const SampleSet scene = square(0.1, 0.01);
  const double box_w = 0.1799, box_lo = -0.0899, box_hi = 0.1736;
  hapsyn::MechanismScratch scratch;
  hapsyn::SampleQuantities q;
  for (int i = 0; i < scene.size(); ++i) {
    model.solve(scene.pose(i), hapsyn::kNeedPose, scratch, q);
    if (q.status != hapsyn::SampleStatus::kReachable) continue;
    const double ex1 = -d.l0 / 2 + d.l1 * std::cos(q.q[0]), ey1 = d.l1 * std::sin(q.q[0]);
    EXPECT_LE(std::abs(ex1), box_w / 2 + 1e-12);
    EXPECT_GE(ey1, box_lo - 1e-12);
    EXPECT_LE(ey1, box_hi + 1e-12);
  }
}

TEST(FiveBar, FootprintOptionDeclaresASecondConstraintAndRefusesNegativeLimits) {
  const FiveBar plain = fivebar();
  EXPECT_EQ(plain.constraints().size(), 1u);
  const FiveBar limited = fivebar(Json{{"footprint_width", 0.3}, {"footprint_height", 0.3}});
  ASSERT_EQ(limited.constraints().size(), 2u);
  EXPECT_EQ(limited.constraints()[1].name, "footprint");
  const SampleSet scene = square(0.1, 0.05);
  double g[2];
  const double gii_best[4] = {0.0004, 0.2997, 0.3, 0.4196};
  limited.evaluate_constraints(gii_best, scene, g);
  EXPECT_GT(g[1], 0.0);  // l1 = 0.3 m: 0.6 m wide
  try {
    fivebar(Json{{"footprint_width", -0.1}});
    ADD_FAILURE() << "expected an error";
  } catch (const hapsyn::Error& e) {
    EXPECT_NE(std::string(e.what()).find("options.footprint_width = -0.1: must be >= 0"), std::string::npos) << e.what();
  }
}
