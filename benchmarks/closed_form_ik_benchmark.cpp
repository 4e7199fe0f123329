// LIBRARIES: hapsyn_closed_form_ik
// PLUGINS: none
//
// Time per call of the closed-form 6R IK (plugins/mechanisms/shared/closed_form_ik, all
// solutions per pose), per family, on 1,000 reachable poses each (FK of seeded random q in
// [-pi, pi]^6, seed 7), cycled: the UR5 (three parallel axes), a Puma 560 (spherical wrist),
// the haptic 6R of share/serial_chain (axes 1 || 2 || 3 and 4 || 5) and an offset-wrist 6R
// (1-D search, at 72 and 144 samples of q1). Counters: solutions per pose, and how often the generating configuration is
// among them (found). Single thread. For scale: the serial_chain numerical IK takes 144-235 us
// per pose on 6R arms (serial_chain_ik_benchmark).
#include "common.hpp"

#include "shared/closed_form_ik/six_r_ik.hpp"
#include "shared/closed_form_ik/test_arms.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

namespace {

using namespace hapsyn::plugins::closed_form_ik;

constexpr int kPoses = 1000;

struct Poses {
  std::vector<Vector6d> q;
  std::vector<Eigen::Isometry3d> target;
};

Poses poses(const PoeChain& chain) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-M_PI, M_PI);
  Poses p;
  for (int i = 0; i < kPoses; ++i) {
    Vector6d q;
    for (int j = 0; j < 6; ++j) q(j) = u(rng);
    p.q.push_back(q);
    p.target.push_back(chain.forward(q.data()));
  }
  return p;
}

void run(benchmark::State& state, const PoeChain& chain, int samples) {
  IkOptions options;
  options.search_samples = samples;
  const ClosedFormIk6R ik(chain, options);
  const Poses p = poses(chain);
  IkScratch scratch;
  IkSolutions out;
  std::size_t i = 0;
  double solutions = 0, found = 0, calls = 0;
  for (auto _ : state) {
    ik.solve(p.target[i], scratch, out);
    benchmark::DoNotOptimize(out.count);
    solutions += out.count;
    for (int k = 0; k < out.count; ++k) {
      double worst = 0.0;
      for (int j = 0; j < 6; ++j) worst = std::max(worst, std::abs(std::remainder(out.q[static_cast<std::size_t>(k)](j) - p.q[i](j), 2 * M_PI)));
      if (worst < 1e-6) {
        found += 1;
        break;
      }
    }
    calls += 1;
    i = (i + 1) % p.q.size();
  }
  state.counters["solutions"] = solutions / calls;
  state.counters["found"] = found / calls;
  state.SetLabel(ik.geometry().describe());
}

void BM_Ur5ThreeParallel(benchmark::State& state) { run(state, test_arms::ur5().poe(), 72); }
void BM_PumaSphericalWrist(benchmark::State& state) { run(state, test_arms::puma().poe(), 72); }
void BM_OffsetWristSearch(benchmark::State& state) {
  run(state, test_arms::offset_wrist().poe(), static_cast<int>(state.range(0)));
}
void BM_Haptic6rScaraPair(benchmark::State& state) { run(state, test_arms::haptic6r().poe(), 72); }

}  // namespace

BENCHMARK(BM_Ur5ThreeParallel)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PumaSphericalWrist)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_OffsetWristSearch)->Arg(72)->Arg(144)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Haptic6rScaraPair)->Unit(benchmark::kMicrosecond);

int main(int argc, char** argv) {
  hapsyn::bench::record_context(hapsyn::Json{{"arguments", "1000 poses per arm, FK of uniform q in [-pi, pi]^6, seed 7"}}, 7);
  return hapsyn::bench::run_main(argc, argv);
}
