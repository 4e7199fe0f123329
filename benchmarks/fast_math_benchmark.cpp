// hapsyn/accel/fast_math.hpp against libm on the same 1200 arguments in [-4, 4] (the range of joint
// angles and IK vectors): atan2 and sin+cos per call. Read the ratios printed at the end.
#include "common.hpp"

#include <hapsyn/accel/fast_math.hpp>

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

namespace {

struct Arguments {
  std::vector<double> x, y;
  Arguments() {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> uniform(-4.0, 4.0);
    for (int i = 0; i < 1200; ++i) {
      x.push_back(uniform(rng));
      y.push_back(uniform(rng));
    }
  }
};
const Arguments& arguments() {
  static const Arguments a;
  return a;
}

void per_call(benchmark::State& state) {
  state.counters["per_call"] =
      benchmark::Counter(static_cast<double>(arguments().x.size()) * static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_LibmAtan2(benchmark::State& state) {
  const Arguments& a = arguments();
  double sum = 0.0;
  for (auto _ : state) {
    for (std::size_t i = 0; i < a.x.size(); ++i) sum += std::atan2(a.y[i], a.x[i]);
  }
  benchmark::DoNotOptimize(sum);
  per_call(state);
}

void BM_FastAtan2(benchmark::State& state) {
  const Arguments& a = arguments();
  double sum = 0.0;
  for (auto _ : state) {
    for (std::size_t i = 0; i < a.x.size(); ++i) sum += hapsyn::fast::atan2(a.y[i], a.x[i]);
  }
  benchmark::DoNotOptimize(sum);
  per_call(state);
}

void BM_LibmSinCos(benchmark::State& state) {
  const Arguments& a = arguments();
  double sum = 0.0;
  for (auto _ : state) {
    for (const double x : a.x) sum += std::sin(x) * std::cos(x);  // GCC merges these into one sincos call
  }
  benchmark::DoNotOptimize(sum);
  per_call(state);
}

void BM_FastSinCos(benchmark::State& state) {
  const Arguments& a = arguments();
  double sum = 0.0;
  for (auto _ : state) {
    for (const double x : a.x) {
      double s = 0.0, c = 0.0;
      hapsyn::fast::sin_cos(x, s, c);
      sum += s * c;
    }
  }
  benchmark::DoNotOptimize(sum);
  per_call(state);
}

}  // namespace

BENCHMARK(BM_LibmAtan2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FastAtan2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_LibmSinCos)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FastSinCos)->Unit(benchmark::kMicrosecond);

int main(int argc, char** argv) {
  hapsyn::bench::record_context(hapsyn::Json{{"arguments", "1200 uniform in [-4, 4], seed 3"}}, 3);
  hapsyn::bench::compare("BM_FastAtan2", "BM_LibmAtan2");
  hapsyn::bench::compare("BM_FastSinCos", "BM_LibmSinCos");
  return hapsyn::bench::run_main(argc, argv);
}
