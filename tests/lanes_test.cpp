// hapsyn/accel/lanes.hpp's operations against the scalar expressions they stand for, lane by
// lane, with ties, signed zeros, infinities and NaN; each computed inside with_vector_lanes for
// every instruction set this machine runs (AVX-512, AVX2, SSE2: each its own lanes type and
// code), and the dispatch itself.
#include <hapsyn/accel/lanes.hpp>
#include <hapsyn/accel/vector_dispatch.hpp>
#include <hapsyn/error.hpp>

#include "vector_targets.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace {

using hapsyn::kBlockLanes;
using hapsyn::VectorTarget;
using hapsyn::testing::available_vector_targets;
using hapsyn::testing::ForcedVectorTarget;

constexpr double kInf = std::numeric_limits<double>::infinity();
const double kNaN = std::numeric_limits<double>::quiet_NaN();

// Arguments where a comparison is most fragile: ties, zeros of both signs, infinities, NaN.
const std::vector<double> kValues = {-kInf, -2.5, -1.0, -0.0, 0.0, 1e-300, 1.0, 2.5, kInf, kNaN};

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// The lanes of `a` and `b` set to every pair of kValues in turn, eight pairs per call.
template <typename Check>
void for_pairs(Check check) {
  std::vector<double> xs, ys;
  for (double x : kValues) {
    for (double y : kValues) {
      xs.push_back(x);
      ys.push_back(y);
    }
  }
  while (xs.size() % kBlockLanes != 0) {
    xs.push_back(0.0);
    ys.push_back(0.0);
  }
  for (std::size_t first = 0; first < xs.size(); first += kBlockLanes) {
    check(xs.data() + first, ys.data() + first);
  }
}

TEST(Lanes, EveryTargetTheCpuHasIsAvailableAndSse2Always) {
  const std::vector<VectorTarget> targets = available_vector_targets();
  ASSERT_FALSE(targets.empty());
  EXPECT_EQ(targets.front(), VectorTarget::kSse2);
  // The default is the widest available; forcing one and resetting works.
  EXPECT_EQ(hapsyn::vector_target(), targets.back());
  {
    ForcedVectorTarget forced(VectorTarget::kSse2);
    EXPECT_EQ(hapsyn::vector_target(), VectorTarget::kSse2);
  }
  EXPECT_EQ(hapsyn::vector_target(), targets.back());
  EXPECT_STREQ(hapsyn::vector_target_name(VectorTarget::kAvx512), "avx512");
}

TEST(Lanes, ForcingATargetTheCpuLacksIsRefusedNamingIt) {
  for (const VectorTarget t : {VectorTarget::kAvx2, VectorTarget::kAvx512}) {
    if (hapsyn::vector_target_available(t)) continue;
    try {
      hapsyn::force_vector_target(t);
      FAIL() << "forcing " << hapsyn::vector_target_name(t) << " was accepted";
    } catch (const hapsyn::Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("vector_dispatch"), std::string::npos) << what;
      EXPECT_NE(what.find(std::string("cannot run kernels for ") + hapsyn::vector_target_name(t)), std::string::npos) << what;
    }
  }
  SUCCEED();
}

TEST(Lanes, WithVectorLanesRunsTheForcedTargetsLanesType) {
  for (const VectorTarget t : available_vector_targets()) {
    ForcedVectorTarget forced(t);
    int part_bytes = 0;
    hapsyn::with_vector_lanes([&](auto tag) HAPSYN_KERNEL_BODY {
      using L = typename decltype(tag)::type;
      part_bytes = static_cast<int>(sizeof(L{}.part[0]));
    });
    EXPECT_EQ(part_bytes, t == VectorTarget::kAvx512 ? 64 : t == VectorTarget::kAvx2 ? 32 : 16) << hapsyn::vector_target_name(t);
  }
}

TEST(Lanes, SelectionsAndArithmeticEqualTheScalarExpressionsOnEveryTarget) {
  for (const VectorTarget t : available_vector_targets()) {
    ForcedVectorTarget forced(t);
    for_pairs([&](const double* x, const double* y) {
      double a[kBlockLanes], b[kBlockLanes];
      for (int i = 0; i < kBlockLanes; ++i) {
        a[i] = 10.0 + i;
        b[i] = -10.0 - i;
      }
      double lt[kBlockLanes], gt[kBlockLanes], eq[kBlockLanes], le[kBlockLanes], ge[kBlockLanes], sign[kBlockLanes],
          sum[kBlockLanes], quotient[kBlockLanes], negated[kBlockLanes], absolute[kBlockLanes], maximum[kBlockLanes],
          splat[kBlockLanes];
      hapsyn::with_vector_lanes([&](auto tag) HAPSYN_KERNEL_BODY {
        using L = typename decltype(tag)::type;
        const L lx = L::load(x), ly = L::load(y), la = L::load(a), lb = L::load(b);
        hapsyn::where_less(lx, ly, la, lb).store(lt);
        hapsyn::where_greater(lx, ly, la, lb).store(gt);
        hapsyn::where_equal(lx, ly, la, lb).store(eq);
        hapsyn::where_less_equal(lx, ly, la, lb).store(le);
        hapsyn::where_greater_equal(lx, ly, la, lb).store(ge);
        hapsyn::where_sign_bit(lx, la, lb).store(sign);
        (lx * 2.0 + ly - 1.0).store(sum);
        (lx / ly).store(quotient);
        (-lx).store(negated);
        hapsyn::abs(lx).store(absolute);
        hapsyn::max(lx, ly).store(maximum);
        L::splat(y[0]).store(splat);
      });
      for (int i = 0; i < kBlockLanes; ++i) {
        const std::string at = std::string(hapsyn::vector_target_name(t)) + ": x = " + std::to_string(x[i]) +
                               ", y = " + std::to_string(y[i]);
        EXPECT_TRUE(same_bits(lt[i], x[i] < y[i] ? a[i] : b[i])) << at;
        EXPECT_TRUE(same_bits(gt[i], x[i] > y[i] ? a[i] : b[i])) << at;
        EXPECT_TRUE(same_bits(eq[i], x[i] == y[i] ? a[i] : b[i])) << at;
        EXPECT_TRUE(same_bits(le[i], x[i] <= y[i] ? a[i] : b[i])) << at;
        EXPECT_TRUE(same_bits(ge[i], x[i] >= y[i] ? a[i] : b[i])) << at;
        EXPECT_TRUE(same_bits(sign[i], std::signbit(x[i]) ? a[i] : b[i])) << at;
        EXPECT_TRUE(same_bits(sum[i], x[i] * 2.0 + y[i] - 1.0) || (std::isnan(sum[i]) && std::isnan(x[i] * 2.0 + y[i] - 1.0))) << at;
        EXPECT_TRUE(same_bits(quotient[i], x[i] / y[i]) || (std::isnan(quotient[i]) && std::isnan(x[i] / y[i]))) << at;
        EXPECT_TRUE(same_bits(negated[i], -x[i]) || std::isnan(x[i])) << at;
        EXPECT_TRUE(same_bits(absolute[i], std::fabs(x[i])) || std::isnan(x[i])) << at;
        EXPECT_TRUE(same_bits(maximum[i], x[i] > y[i] ? x[i] : y[i]) || std::isnan(maximum[i])) << at;
        EXPECT_TRUE(same_bits(splat[i], y[0]) || std::isnan(y[0])) << at;
      }
    });
  }
}

TEST(Lanes, AllGreaterAndAllLessHoldOnlyWhenEveryLaneDoesOnEveryTarget) {
  for (const VectorTarget t : available_vector_targets()) {
    ForcedVectorTarget forced(t);
    for (double bound : kValues) {
      for (double value : kValues) {
        for (int odd = 0; odd < kBlockLanes; ++odd) {
          // Seven lanes strictly on the tested side of `bound` (when it is finite), one lane `value`.
          double x[kBlockLanes], y[kBlockLanes];
          for (int i = 0; i < kBlockLanes; ++i) {
            x[i] = std::isfinite(bound) ? bound + 1.0 + i : value;
            y[i] = std::isfinite(bound) ? bound - 1.0 - i : value;
          }
          x[odd] = value;
          y[odd] = value;
          bool greater = true, less = true, any_zero = false, any_nonzero = false;
          for (int i = 0; i < kBlockLanes; ++i) {
            greater = greater && x[i] > bound;
            less = less && y[i] < bound;
            any_zero = any_zero || x[i] == 0.0;
            any_nonzero = any_nonzero || x[i] != 0.0;
          }
          bool got_greater = false, got_less = false, got_zero = false, got_nonzero = false;
          hapsyn::with_vector_lanes([&](auto tag) HAPSYN_KERNEL_BODY {
            using L = typename decltype(tag)::type;
            got_greater = hapsyn::all_greater(L::load(x), bound);
            got_less = hapsyn::all_less(L::load(y), bound);
            got_zero = hapsyn::any_zero(L::load(x));
            got_nonzero = hapsyn::any_nonzero(L::load(x));
          });
          const std::string at = std::string(hapsyn::vector_target_name(t)) + ": " + std::to_string(value) + " vs " +
                                 std::to_string(bound) + " in lane " + std::to_string(odd);
          EXPECT_EQ(got_greater, greater) << at;
          EXPECT_EQ(got_less, less) << at;
          EXPECT_EQ(got_zero, any_zero) << at;
          EXPECT_EQ(got_nonzero, any_nonzero) << at;
        }
      }
    }
  }
}

TEST(Lanes, SmallIntegersBecomeBitsAndInt32OnEveryTarget) {
  for (const VectorTarget t : available_vector_targets()) {
    ForcedVectorTarget forced(t);
    const double values[kBlockLanes] = {0.0, 5.0, 5.0, 63.0, 2.0, 31.0, 0.0, 7.0};
    std::uint64_t bits = 0;
    std::int32_t ints[kBlockLanes] = {};
    const double negative[kBlockLanes] = {-1.9, -0.5, 2.9, 3.0, -7.0, 1e9, -1e9, 0.0};
    std::int32_t truncated[kBlockLanes] = {};
    hapsyn::with_vector_lanes([&](auto tag) HAPSYN_KERNEL_BODY {
      using L = typename decltype(tag)::type;
      bits = hapsyn::bits_of_small_integers(L::load(values));
      hapsyn::to_int32(L::load(values), ints);
      hapsyn::to_int32(L::load(negative), truncated);
    });
    std::uint64_t expected = 0;
    for (int i = 0; i < kBlockLanes; ++i) {
      expected |= std::uint64_t{1} << static_cast<int>(values[i]);
      EXPECT_EQ(ints[i], static_cast<std::int32_t>(values[i])) << hapsyn::vector_target_name(t);
      EXPECT_EQ(truncated[i], static_cast<std::int32_t>(negative[i])) << hapsyn::vector_target_name(t);
    }
    EXPECT_EQ(bits, expected) << hapsyn::vector_target_name(t);
  }
}

TEST(Lanes, ChunksOfOneRegisterCoverTheBlockInOrder) {
  for (const VectorTarget t : available_vector_targets()) {
    ForcedVectorTarget forced(t);
    double in[kBlockLanes], out[kBlockLanes] = {};
    for (int i = 0; i < kBlockLanes; ++i) in[i] = 1.5 * i - 3.0;
    int chunk_lanes = 0;
    hapsyn::with_vector_lanes([&](auto tag) HAPSYN_KERNEL_BODY {
      using Tag = decltype(tag);
      using C = typename Tag::chunk;
      chunk_lanes = C::kLanes;
      for (int c = 0; c < Tag::kChunks; ++c) (C::load(in + c * C::kLanes) * 2.0).store(out + c * C::kLanes);
    });
    EXPECT_EQ(chunk_lanes, t == VectorTarget::kAvx512 ? 8 : t == VectorTarget::kAvx2 ? 4 : 2);
    for (int i = 0; i < kBlockLanes; ++i) EXPECT_EQ(out[i], 2.0 * in[i]) << hapsyn::vector_target_name(t) << " lane " << i;
  }
}

// The evaluator's test of whether a block of local values may move a worst-case reduction
// (Evaluator::block_moves, baseline code with LanesSse2): y = x + (x - x) is x where x is finite
// and NaN elsewhere, and a NaN lane is never strictly worse than the current value.
TEST(Lanes, FiniteLanesStrictlyWorseThanABoundAsTheEvaluatorTestsThem) {
  for (double current : {-1.0, 0.0, 2.5}) {
    for (double value : kValues) {
      for (int odd = 0; odd < kBlockLanes; ++odd) {
        double v[kBlockLanes];
        for (int i = 0; i < kBlockLanes; ++i) v[i] = current + 1.0 + i;
        v[odd] = value;
        const hapsyn::LanesSse2 x = hapsyn::LanesSse2::load(v);
        const hapsyn::LanesSse2 y = x + (x - x);
        bool worse = true;
        for (int i = 0; i < kBlockLanes; ++i) worse = worse && std::isfinite(v[i]) && v[i] > current;
        EXPECT_EQ(hapsyn::all_greater(y, current), worse) << value << " in lane " << odd;
      }
    }
  }
}

}  // namespace
