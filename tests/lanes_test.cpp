// hapsyn/accel/lanes.hpp's selections and whole-block tests against the scalar expressions they
// stand for, lane by lane, with ties, signed zeros, infinities and NaN.
#include <hapsyn/accel/lanes.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

namespace {

using hapsyn::kBlockLanes;
using hapsyn::Lanes;

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

TEST(Lanes, WhereLessEqualAndGreaterEqualSelectAsTheScalarComparison) {
  for_pairs([](const double* x, const double* y) {
    double a[kBlockLanes], b[kBlockLanes];
    for (int i = 0; i < kBlockLanes; ++i) {
      a[i] = 10.0 + i;
      b[i] = -10.0 - i;
    }
    const Lanes lx = Lanes::load(x), ly = Lanes::load(y), la = Lanes::load(a), lb = Lanes::load(b);
    const Lanes le = hapsyn::where_less_equal(lx, ly, la, lb), ge = hapsyn::where_greater_equal(lx, ly, la, lb);
    for (int i = 0; i < kBlockLanes; ++i) {
      EXPECT_TRUE(same_bits(le.v[i], x[i] <= y[i] ? a[i] : b[i])) << x[i] << " <= " << y[i];
      EXPECT_TRUE(same_bits(ge.v[i], x[i] >= y[i] ? a[i] : b[i])) << x[i] << " >= " << y[i];
    }
  });
}

TEST(Lanes, AllGreaterAndAllLessHoldOnlyWhenEveryLaneDoes) {
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
        bool greater = true, less = true;
        for (int i = 0; i < kBlockLanes; ++i) {
          greater = greater && x[i] > bound;
          less = less && y[i] < bound;
        }
        EXPECT_EQ(hapsyn::all_greater(Lanes::load(x), bound), greater) << value << " > " << bound << " in lane " << odd;
        EXPECT_EQ(hapsyn::all_less(Lanes::load(y), bound), less) << value << " < " << bound << " in lane " << odd;
      }
    }
  }
}

// The evaluator's test of whether a block of local values may move a worst-case reduction
// (Problem::block_moves): y = x + (x - x) is x where x is finite and NaN elsewhere, and a NaN
// lane is never strictly worse than the current value.
TEST(Lanes, FiniteLanesStrictlyWorseThanABoundAsTheEvaluatorTestsThem) {
  for (double current : {-1.0, 0.0, 2.5}) {
    for (double value : kValues) {
      for (int odd = 0; odd < kBlockLanes; ++odd) {
        double v[kBlockLanes];
        for (int i = 0; i < kBlockLanes; ++i) v[i] = current + 1.0 + i;
        v[odd] = value;
        const Lanes x = Lanes::load(v);
        const Lanes y = x + (x - x);
        bool worse = true;
        for (int i = 0; i < kBlockLanes; ++i) worse = worse && std::isfinite(v[i]) && v[i] > current;
        EXPECT_EQ(hapsyn::all_greater(y, current), worse) << value << " in lane " << odd;
      }
    }
  }
}

}  // namespace
