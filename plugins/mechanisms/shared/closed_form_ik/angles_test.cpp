// Tests of remainder_two_pi (angles.hpp): the same bits as std::remainder(x, 2 pi) everywhere.
#include "shared/closed_form_ik/angles.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace {

using hapsyn::plugins::closed_form_ik::remainder_two_pi;

std::uint64_t bits(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

void expect_same_bits(double x) {
  const double expected = std::remainder(x, 2.0 * M_PI);
  const double got = remainder_two_pi(x);
  if (std::isnan(expected)) {
    EXPECT_TRUE(std::isnan(got)) << "x = " << x;
  } else {
    EXPECT_EQ(bits(got), bits(expected)) << "x = " << x << ": " << got << " against " << expected;
  }
}

TEST(ClosedFormIkAngles, RemainderTwoPiEqualsStdRemainderBitForBit) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> xs = {0.0, -0.0, inf, -inf, std::numeric_limits<double>::quiet_NaN(), 1e300, -1e300, 1e-300,
                            std::numeric_limits<double>::denorm_min()};
  // The boundaries: odd multiples of pi (ties and their neighbours), even multiples, k pi +- ulps.
  for (int k = -9; k <= 9; ++k) {
    const double c = k * M_PI;
    double lo = c, hi = c;
    for (int u = 0; u < 4; ++u) {
      xs.push_back(lo);
      xs.push_back(hi);
      lo = std::nextafter(lo, -inf);
      hi = std::nextafter(hi, inf);
    }
  }
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> wide(-40.0, 40.0), narrow(-10.0, 10.0);
  for (int i = 0; i < 200000; ++i) xs.push_back(i % 2 ? wide(rng) : narrow(rng));
  for (double x : xs) expect_same_bits(x);
}

}  // namespace
