// The five-bar's block kernel (fivebar_block.cpp) against the scalar model (FiveBarModel::solve),
// which classifies with the joint angles: the same status for every sample, and J, D, M bit for
// bit (the kernel does the scalar arithmetic without contraction), on the designs and samples where the classification is most fragile (design
// grids of round numbers, whose samples hit the limits of G exactly) and on random ones.
#include "fivebar.hpp"

#include <gdi.hpp>
#include <gii.hpp>

#include <hapsyn/options.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

namespace {

using hapsyn::Json;
using hapsyn::kBlockLanes;
using hapsyn::PoseBlock;
using hapsyn::QuantityBlock;
using hapsyn::SampleQuantities;
using hapsyn::SampleStatus;
using hapsyn::plugins::FiveBar;
using hapsyn::plugins::FiveBarDesign;
using hapsyn::plugins::FiveBarModel;
using hapsyn::plugins::FiveBarOptions;

constexpr hapsyn::Needs kAll = hapsyn::kNeedJacobian | hapsyn::kNeedInertia | hapsyn::kNeedEffectiveMass;

struct Tally {
  long long samples = 0, reachable = 0, singular = 0, invalid = 0, unreachable = 0;
  double worst_relative = 0.0;  // largest relative difference of J, D, M entries
};

double relative(double block, double scalar, double scale) {
  return std::abs(block - scalar) / std::max(scale, 1e-300);
}

// Compares the block kernel with solve() on the samples (x[i], y[i]) of one design.
void compare(const FiveBarModel& model, const std::vector<double>& x, const std::vector<double>& y,
             hapsyn::Needs needs, Tally& tally) {
  hapsyn::MechanismScratch scratch;
  SampleQuantities q;
  QuantityBlock block;
  std::array<double, kBlockLanes> bx{}, by{};
  for (std::size_t first = 0; first < x.size(); first += kBlockLanes) {
    const int count = static_cast<int>(std::min<std::size_t>(kBlockLanes, x.size() - first));
    for (int i = 0; i < kBlockLanes; ++i) {
      const std::size_t k = first + static_cast<std::size_t>(std::min(i, count - 1));
      bx[static_cast<std::size_t>(i)] = x[k];
      by[static_cast<std::size_t>(i)] = y[k];
    }
    PoseBlock poses;
    poses.coordinate[0] = bx.data();
    poses.coordinate[1] = by.data();
    poses.dimension = 2;
    poses.count = count;
    model.solve_block(poses, needs, scratch, block);
    for (int i = 0; i < count; ++i) {
      const double pose[2] = {bx[static_cast<std::size_t>(i)], by[static_cast<std::size_t>(i)]};
      model.solve(pose, needs, scratch, q);
      ++tally.samples;
      ASSERT_EQ(block.lane_status(i), q.status)
          << "design (" << model.design().l0 << ", " << model.design().l1 << ", " << model.design().l2 << ", "
          << model.design().r << "), sample (" << pose[0] << ", " << pose[1] << "), q = " << q.q.transpose();
      switch (q.status) {
        case SampleStatus::kReachable: ++tally.reachable; break;
        case SampleStatus::kSingular: ++tally.singular; break;
        case SampleStatus::kInvalid: ++tally.invalid; break;
        case SampleStatus::kUnreachable: ++tally.unreachable; break;
      }
      if (q.status != SampleStatus::kReachable) continue;
      const auto check = [&](const auto& scalar, const double (*entries)[kBlockLanes], int size) {
        ASSERT_EQ(scalar.rows(), size);
        const double scale = scalar.cwiseAbs().maxCoeff();
        for (int r = 0; r < size; ++r) {
          for (int c = 0; c < size; ++c) {
            tally.worst_relative = std::max(tally.worst_relative, relative(entries[r * size + c][i], scalar(r, c), scale));
          }
        }
      };
      if (needs & hapsyn::kNeedJacobian) check(q.jacobian, block.jacobian, block.jacobian_rows);
      if (needs & hapsyn::kNeedInertia) check(q.inertia, block.inertia, block.inertia_size);
      if (needs & hapsyn::kNeedEffectiveMass) check(q.effective_mass, block.effective_mass, block.effective_mass_size);
    }
  }
}

// The samples of a square of side `side` centred at (0, 0), on a grid of `step` [m].
void square(double side, double step, std::vector<double>& x, std::vector<double>& y) {
  const int n = static_cast<int>(std::lround(side / step));
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      x.push_back(-0.5 * side + i * step);
      y.push_back(-0.5 * side + j * step);
    }
  }
}

FiveBarOptions options() { return hapsyn::make_options<FiveBarOptions>(Json::object()); }

TEST(FiveBarBlock, EveryStatusAndQuantityMatchesSolveOnTheCoarseDesignGrid) {
  // The 10 mm design grid of problems/fivebar-gii-coarse.json thinned (every third l0, l1, l2,
  // every fifth r), against the 5 mm workspace: round numbers put samples exactly on the limits
  // of G (free link horizontal, links aligned), where the two classifications could part.
  std::vector<double> x, y;
  square(0.1, 0.005, x, y);
  Tally tally;
  for (int a = 0; a <= 30; a += 3) {
    for (int b = 1; b <= 30; b += 3) {
      for (int c = 1; c <= 30; c += 3) {
        for (int d = 0; d <= 60; d += 5) {
          const FiveBarModel model(FiveBarDesign{0.01 * a, 0.01 * b, 0.01 * c, 0.01 * d}, options());
          compare(model, x, y, kAll, tally);
          if (testing::Test::HasFatalFailure()) return;
        }
      }
    }
  }
  EXPECT_EQ(tally.worst_relative, 0.0);  // bit for bit
  // Every classification occurs, many times: the comparison covered each branch.
  EXPECT_GT(tally.reachable, 100000);
  EXPECT_GT(tally.singular, 1000);
  EXPECT_GT(tally.invalid, 100000);
  EXPECT_GT(tally.unreachable, 100000);
}

TEST(FiveBarBlock, EveryStatusAndQuantityMatchesSolveOnRandomDesignsAndSamples) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> length(0.0, 0.3), placement(-0.2, 0.6), coordinate(-0.3, 0.3);
  Tally tally;
  for (int design = 0; design < 3000; ++design) {
    const FiveBarModel model(FiveBarDesign{length(rng), 0.01 + length(rng), 0.01 + length(rng), placement(rng)},
                             options());
    std::vector<double> x, y;
    for (int s = 0; s < 64; ++s) {
      x.push_back(coordinate(rng));
      y.push_back(coordinate(rng));
    }
    compare(model, x, y, kAll, tally);
    if (testing::Test::HasFatalFailure()) return;
  }
  EXPECT_EQ(tally.worst_relative, 0.0);  // bit for bit
  EXPECT_GT(tally.reachable, 1000);
  EXPECT_GT(tally.invalid, 1000);
}

TEST(FiveBarBlock, DegenerateSamplesAreClassifiedAsSolveDoes) {
  // End effector on an actuated joint (folded leg when l1 = l2), on the inner and outer reach
  // boundary, on the horizon of the joints (y + r = 0, also -0), and a zero base length.
  Tally tally;
  const std::vector<FiveBarDesign> designs = {{0.1, 0.1, 0.1, 0.0}, {0.1, 0.1, 0.15, 0.0}, {0.0, 0.1, 0.1, 0.05},
                                              {0.2, 0.1, 0.3, 0.0}, {0.06, 0.05, 0.05, 0.0}};
  for (const FiveBarDesign& d : designs) {
    const FiveBarModel model(d, options());
    const double h = 0.5 * d.l0;
    std::vector<double> x = {-h, h, -h + d.l1 + d.l2, h - d.l1 - d.l2, -h + std::abs(d.l1 - d.l2), 0.0, 0.0, 0.05, -0.05};
    std::vector<double> y(x.size(), -d.r);
    y[5] = -0.0 - d.r;
    y[6] = d.l1 + d.l2 - d.r;
    for (double& v : y) v = v == 0.0 ? -0.0 : v;
    compare(model, x, y, kAll, tally);
    if (testing::Test::HasFatalFailure()) return;
  }
  EXPECT_GT(tally.singular + tally.unreachable, 10);
  EXPECT_EQ(tally.worst_relative, 0.0);  // bit for bit
}

TEST(FiveBarBlock, OnlyTheRequestedQuantitiesAreFilled) {
  const FiveBarModel model(FiveBarDesign{0.1, 0.2, 0.2, 0.2}, options());
  std::array<double, kBlockLanes> x{}, y{};
  PoseBlock poses;
  poses.coordinate[0] = x.data();
  poses.coordinate[1] = y.data();
  poses.dimension = 2;
  poses.count = kBlockLanes;
  hapsyn::MechanismScratch scratch;
  QuantityBlock block;
  block.inertia[0][0] = 123.0;
  model.solve_block(poses, hapsyn::kNeedJacobian, scratch, block);
  EXPECT_EQ(block.lane_status(0), SampleStatus::kReachable);
  EXPECT_EQ(block.jacobian_rows, 2);
  EXPECT_EQ(block.inertia_size, 0);
  EXPECT_EQ(block.inertia[0][0], 123.0);  // untouched
  model.solve_block(poses, hapsyn::kNeedPose, scratch, block);
  EXPECT_EQ(block.jacobian_rows, 0);
  const FiveBar mechanism(options());
  EXPECT_TRUE(mechanism.solves_blocks(kAll));
  EXPECT_FALSE(mechanism.solves_blocks(hapsyn::kNeedGravity));
}

TEST(FiveBarBlock, GiiAndGdiBlockLocalsMatchTheirLocals) {
  const FiveBarModel model(FiveBarDesign{0.05, 0.2, 0.25, 0.25}, options());
  std::vector<double> x, y;
  square(0.1, 0.0125, x, y);
  x.resize(kBlockLanes * (x.size() / kBlockLanes));
  hapsyn::MechanismScratch scratch;
  const hapsyn::plugins::Gii gii;
  const hapsyn::plugins::Gdi gdi;
  ASSERT_TRUE(gii.has_local_block());
  ASSERT_TRUE(gdi.has_local_block());
  int compared = 0;
  for (std::size_t first = 0; first < x.size(); first += kBlockLanes) {
    PoseBlock poses;
    poses.coordinate[0] = x.data() + first;
    poses.coordinate[1] = y.data() + first;
    poses.dimension = 2;
    poses.count = kBlockLanes;
    QuantityBlock block;
    model.solve_block(poses, kAll, scratch, block);
    double gii_block[2 * kBlockLanes], gdi_block[kBlockLanes];
    gii.local_block(block, gii_block);
    gdi.local_block(block, gdi_block);
    for (int i = 0; i < kBlockLanes; ++i) {
      if (block.lane_status(i) != SampleStatus::kReachable) continue;
      SampleQuantities q;
      const double pose[2] = {x[first + static_cast<std::size_t>(i)], y[first + static_cast<std::size_t>(i)]};
      model.solve(pose, kAll, scratch, q);
      double expected[2];
      gii.local(q, expected);
      EXPECT_EQ(gii_block[i], expected[0]);
      EXPECT_EQ(gii_block[kBlockLanes + i], expected[1]);
      gdi.local(q, expected);
      EXPECT_EQ(gdi_block[i], expected[0]);
      ++compared;
    }
  }
  EXPECT_GT(compared, 50);
}

}  // namespace
