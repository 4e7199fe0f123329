// LIBRARIES: hapsyn_fivebar_model hapsyn_gii_model hapsyn_gdi_model hapsyn_planar_square_model
//
// Per-sample cost of the five-bar study (Unal 2008) on the 441 samples of a 0.1 m square at a
// 0.005 m step, for the best-GII design of Table 2 (0.4, 299.7, 300.0, 419.6) mm:
//   pose only (IK + classification)      -- what a coverage-only metric needs
//   IK + J                                -- what GII needs
//   IK + J + D + M                        -- what GDI needs
//   IK + J + D + M and both metrics' local() -- one full GII + GDI design evaluation
//   gii.local() and gdi.local() alone     -- the metrics' closed-form singular values
//   the reach constraint                  -- once per design, O(samples)
//   the same on the block path (hapsyn/accel/sample_block.hpp): the Highway kernel, 8 samples per call,
//   and the metrics' local_block() -- "Block" rows; the ratio Block / per-sample is the speed-up
//   of the vectorised, trigonometry-free kernel on this CPU (its instruction set is recorded as
//   "block_target").
// Compare the rows with each other (ratios), not as bare times: "per_sample" is the time per
// sample (inverted rate), so IK+J+D+M / IK+J is the price of the dynamic index; the ratios
// are printed at the end of the run.
#include "common.hpp"

#include <fivebar.hpp>
#include <gdi.hpp>
#include <gii.hpp>
#include <planar_square.hpp>

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

namespace {

using hapsyn::Json;
using hapsyn::SampleQuantities;
using hapsyn::SampleSet;
using namespace hapsyn::plugins;

const SampleSet& scene() {
  static const SampleSet set = PlanarSquare(hapsyn::make_options<PlanarSquareOptions>(Json{{"side", 0.1}, {"step", 0.005}})).build({});
  return set;
}

const FiveBarModel& model() {
  static const FiveBarModel m(FiveBarDesign{0.0004, 0.2997, 0.3000, 0.4196},
                              hapsyn::default_options<FiveBarOptions>());
  return m;
}

void per_sample(benchmark::State& state) {
  const double samples = static_cast<double>(state.iterations()) * scene().size();
  state.SetItemsProcessed(static_cast<int64_t>(samples));
  state.counters["per_sample"] = benchmark::Counter(samples, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void solve_all(benchmark::State& state, hapsyn::Needs needs) {
  const SampleSet& set = scene();
  const FiveBarModel& m = model();
  hapsyn::MechanismScratch scratch;
  SampleQuantities q;
  for (auto _ : state) {
    for (int i = 0; i < set.size(); ++i) {
      m.solve(set.pose(i), needs, scratch, q);
      benchmark::DoNotOptimize(q);
    }
    benchmark::ClobberMemory();
  }
  per_sample(state);
}

void BM_FiveBarPoseOnly(benchmark::State& state) { solve_all(state, hapsyn::kNeedPose); }
void BM_FiveBarIkJacobian(benchmark::State& state) { solve_all(state, hapsyn::kNeedJacobian); }
void BM_FiveBarIkJacobianInertiaMass(benchmark::State& state) { solve_all(state, hapsyn::kNeedEffectiveMass); }

void BM_FiveBarGiiAndGdiFullEvaluation(benchmark::State& state) {
  const SampleSet& set = scene();
  const FiveBarModel& m = model();
  const Gii gii;
  const Gdi gdi;
  hapsyn::MechanismScratch scratch;
  SampleQuantities q;
  for (auto _ : state) {
    double sigma_min = 1e300, sigma_max = 0.0, mass = 0.0;
    for (int i = 0; i < set.size(); ++i) {
      m.solve(set.pose(i), hapsyn::kNeedJacobian | hapsyn::kNeedEffectiveMass, scratch, q);
      double local[2];
      gii.local(q, local);
      sigma_min = std::min(sigma_min, local[0]);
      sigma_max = std::max(sigma_max, local[1]);
      gdi.local(q, local);
      mass = std::max(mass, local[0]);
    }
    const double reduced[2] = {sigma_min, sigma_max};
    benchmark::DoNotOptimize(gii.combine(reduced, set.size()));
    benchmark::DoNotOptimize(gdi.combine(&mass, set.size()));
  }
  per_sample(state);
}

// The scene's samples, structure of arrays, padded to whole blocks with the last sample (as the
// evaluator lays them out).
struct Lanes {
  std::vector<double> x, y;
  Lanes() {
    const SampleSet& set = scene();
    const int padded = (set.size() + hapsyn::kBlockLanes - 1) / hapsyn::kBlockLanes * hapsyn::kBlockLanes;
    for (int i = 0; i < padded; ++i) {
      x.push_back(set.pose(std::min(i, set.size() - 1))[0]);
      y.push_back(set.pose(std::min(i, set.size() - 1))[1]);
    }
  }
};

void solve_blocks(benchmark::State& state, hapsyn::Needs needs) {
  static const Lanes lanes;
  const FiveBarModel& m = model();
  hapsyn::MechanismScratch scratch;
  hapsyn::QuantityBlock block;
  hapsyn::PoseBlock poses;
  poses.dimension = 2;
  poses.count = hapsyn::kBlockLanes;
  for (auto _ : state) {
    for (std::size_t first = 0; first < lanes.x.size(); first += hapsyn::kBlockLanes) {
      poses.coordinate[0] = lanes.x.data() + first;
      poses.coordinate[1] = lanes.y.data() + first;
      m.solve_block(poses, needs, scratch, block);
      benchmark::DoNotOptimize(block);
    }
    benchmark::ClobberMemory();
  }
  per_sample(state);
}

void BM_FiveBarBlockPoseOnly(benchmark::State& state) { solve_blocks(state, hapsyn::kNeedPose); }
void BM_FiveBarBlockIkJacobian(benchmark::State& state) { solve_blocks(state, hapsyn::kNeedJacobian); }
void BM_FiveBarBlockIkJacobianInertiaMass(benchmark::State& state) { solve_blocks(state, hapsyn::kNeedEffectiveMass); }

void BM_FiveBarBlockGiiAndGdiFullEvaluation(benchmark::State& state) {
  static const Lanes lanes;
  const FiveBarModel& m = model();
  const Gii gii;
  const Gdi gdi;
  hapsyn::MechanismScratch scratch;
  hapsyn::QuantityBlock block;
  hapsyn::PoseBlock poses;
  poses.dimension = 2;
  double gii_locals[2 * hapsyn::kBlockLanes], gdi_locals[hapsyn::kBlockLanes];
  const int n = scene().size();
  for (auto _ : state) {
    double sigma_min = 1e300, sigma_max = 0.0, mass = 0.0;
    for (int first = 0; first < n; first += hapsyn::kBlockLanes) {
      poses.coordinate[0] = lanes.x.data() + first;
      poses.coordinate[1] = lanes.y.data() + first;
      poses.count = std::min(hapsyn::kBlockLanes, n - first);
      m.solve_block(poses, hapsyn::kNeedJacobian | hapsyn::kNeedEffectiveMass, scratch, block);
      gii.local_block(block, gii_locals);
      gdi.local_block(block, gdi_locals);
      for (int i = 0; i < poses.count; ++i) {
        sigma_min = std::min(sigma_min, gii_locals[i]);
        sigma_max = std::max(sigma_max, gii_locals[hapsyn::kBlockLanes + i]);
        mass = std::max(mass, gdi_locals[i]);
      }
    }
    const double reduced[2] = {sigma_min, sigma_max};
    benchmark::DoNotOptimize(gii.combine(reduced, n));
    benchmark::DoNotOptimize(gdi.combine(&mass, n));
  }
  per_sample(state);
}

std::vector<SampleQuantities> solved_samples() {
  std::vector<SampleQuantities> out(scene().size());
  hapsyn::MechanismScratch scratch;
  for (int i = 0; i < scene().size(); ++i) {
    model().solve(scene().pose(i), hapsyn::kNeedJacobian | hapsyn::kNeedEffectiveMass, scratch, out[i]);
  }
  return out;
}

void BM_GiiLocal(benchmark::State& state) {
  const std::vector<SampleQuantities> samples = solved_samples();
  const Gii gii;
  for (auto _ : state) {
    for (const SampleQuantities& q : samples) {
      double local[2];
      gii.local(q, local);
      benchmark::DoNotOptimize(local);
    }
  }
  per_sample(state);
}

void BM_GdiLocal(benchmark::State& state) {
  const std::vector<SampleQuantities> samples = solved_samples();
  const Gdi gdi;
  for (auto _ : state) {
    for (const SampleQuantities& q : samples) {
      double local = 0.0;
      gdi.local(q, &local);
      benchmark::DoNotOptimize(local);
    }
  }
  per_sample(state);
}

void BM_FiveBarReachConstraint(benchmark::State& state) {
  const FiveBar mechanism(hapsyn::default_options<FiveBarOptions>());
  const double design[4] = {0.0004, 0.2997, 0.3000, 0.4196};
  double g = 0.0;
  for (auto _ : state) {
    mechanism.evaluate_constraints(design, scene(), &g);
    benchmark::DoNotOptimize(g);
  }
  per_sample(state);
}

// The block bound of one sample over a run of r (FiveBar::sample_envelope,
// plugins/mechanisms/fivebar/KERNELS.md section 13.5), as culling and the pruned grid call it: 4,096 runs of 8 to 64 designs at a 2 mm
// step (seed 1) of designs and samples of the paper's kind, each tried above the joints' axis.
// Argument: 0 the GII envelope (no mass bound), 1 GDI's (with the bound of sigma_max(M)).
void BM_FiveBarSampleEnvelope(benchmark::State& state) {
  const FiveBar fivebar(hapsyn::default_options<FiveBarOptions>());
  const hapsyn::Needs needs = state.range(0) != 0 ? hapsyn::kNeedJacobian | hapsyn::kNeedInertia | hapsyn::kNeedEffectiveMass
                                                  : hapsyn::kNeedJacobian;
  struct Run {
    double design[4], lower, upper, pose[2];
  };
  std::vector<Run> runs;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  while (runs.size() < 4096) {
    Run run{};
    run.design[0] = 0.002 * std::floor(150 * u(rng));
    run.design[1] = 0.01 + 0.002 * std::floor(145 * u(rng));
    run.design[2] = 0.01 + 0.002 * std::floor(145 * u(rng));
    run.lower = 0.002 * std::floor(300 * u(rng));
    run.upper = run.lower + 0.002 * (7 + std::floor(57 * u(rng)));
    run.design[3] = run.lower;
    run.pose[0] = -0.05 + 0.001 * std::floor(101 * u(rng));
    run.pose[1] = -0.05 + 0.001 * std::floor(101 * u(rng));
    if (run.pose[1] + run.lower > 0.0) runs.push_back(run);
  }
  double sum = 0.0;
  for (auto _ : state) {
    for (const Run& run : runs) {
      hapsyn::SampleEnvelope out;
      fivebar.sample_envelope(run.design, 3, run.lower, run.upper, run.pose, needs, out);
      sum += out.jacobian_inverse_condition_max + out.effective_mass_sigma_max_min;
    }
  }
  benchmark::DoNotOptimize(sum);
  state.counters["per_run"] = benchmark::Counter(static_cast<double>(runs.size()),
                                                 benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_FiveBarSampleEnvelope)->ArgName("mass")->Arg(0)->Arg(1);

BENCHMARK(BM_FiveBarPoseOnly);
BENCHMARK(BM_FiveBarIkJacobian);
BENCHMARK(BM_FiveBarIkJacobianInertiaMass);
BENCHMARK(BM_FiveBarGiiAndGdiFullEvaluation);
BENCHMARK(BM_GiiLocal);
BENCHMARK(BM_GdiLocal);
BENCHMARK(BM_FiveBarReachConstraint);
BENCHMARK(BM_FiveBarBlockPoseOnly);
BENCHMARK(BM_FiveBarBlockIkJacobian);
BENCHMARK(BM_FiveBarBlockIkJacobianInertiaMass);
BENCHMARK(BM_FiveBarBlockGiiAndGdiFullEvaluation);

}  // namespace

int main(int argc, char** argv) {
  hapsyn::bench::record_context(Json{{"mechanism", "fivebar"},
                                     {"design", {0.0004, 0.2997, 0.3000, 0.4196}},
                                     {"scene", {{"plugin", "planar_square"}, {"side", 0.1}, {"step", 0.005}}},
                                     {"block_target", fivebar_block_target()}});
  // Printed as "ratio <second> / <first>": the cost of each step relative to the cheaper one.
  hapsyn::bench::compare("BM_FiveBarPoseOnly", "BM_FiveBarIkJacobian");
  hapsyn::bench::compare("BM_FiveBarIkJacobian", "BM_FiveBarIkJacobianInertiaMass");
  hapsyn::bench::compare("BM_FiveBarIkJacobian", "BM_FiveBarGiiAndGdiFullEvaluation");
  hapsyn::bench::compare("BM_GdiLocal", "BM_GiiLocal");
  // The block path against the per-sample path: below 1 is a speed-up.
  hapsyn::bench::compare("BM_FiveBarPoseOnly", "BM_FiveBarBlockPoseOnly");
  hapsyn::bench::compare("BM_FiveBarIkJacobian", "BM_FiveBarBlockIkJacobian");
  hapsyn::bench::compare("BM_FiveBarIkJacobianInertiaMass", "BM_FiveBarBlockIkJacobianInertiaMass");
  hapsyn::bench::compare("BM_FiveBarGiiAndGdiFullEvaluation", "BM_FiveBarBlockGiiAndGdiFullEvaluation");
  return hapsyn::bench::run_main(argc, argv);
}
