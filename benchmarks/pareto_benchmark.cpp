// Pareto studies of the five-bar (GII vs GDI, Unal 2008 Figures 3-5), in one run:
//   - NBI, 10 points (shadow optima by culling on the 10 mm grid + polish), against the
//     10-weight weighted sum solved by culling on the 5 mm design grid: the time ratio
//     (the paper reports NBI at about 1/3 of the weighted sum's time);
//   - NBI's time and front against its constraint tolerance (1e-7, 1e-8, 1e-9) and grid size.
// The studies are problems/fivebar-pareto-nbi.json and fivebar-pareto-weighted-sum.json
// (5 mm workspace), without their indicators section (no reference front needed here).
//
//   build/bin/pareto_benchmark
#include "common.hpp"

#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/internal/study.hpp>

#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>

namespace {

const hapsyn::Registry& registry() {
  static hapsyn::Registry r({HAPSYN_PLUGIN_DIR});
  return r;
}

hapsyn::Study& study(const std::string& name) {
  static std::map<std::string, std::unique_ptr<hapsyn::Study>> cache;
  auto& slot = cache[name];
  if (!slot) {
    hapsyn::Json doc = hapsyn::read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/problems/" + name + ".json");
    doc.erase("indicators");
    slot = std::make_unique<hapsyn::Study>(hapsyn::load_study(doc, registry()));
  }
  return *slot;
}

void run(benchmark::State& state, const hapsyn::Solver& solver, const hapsyn::Problem& problem) {
  hapsyn::SolverContext context;
  context.threads = 2;
  hapsyn::SolverResult result;
  for (auto _ : state) {
    result = solver.solve(problem, context);
    benchmark::DoNotOptimize(result);
  }
  state.counters["points"] = static_cast<double>(result.front.size());
  state.counters["sample_evals"] = static_cast<double>(result.sample_evaluations);
  if (!result.front.empty()) {
    state.counters["gii_max"] = result.front.front().objectives[0];
    state.counters["gdi_max"] = result.front.back().objectives[1];
  }
}

void BM_Nbi(benchmark::State& state) {
  hapsyn::Study& st = study("fivebar-pareto-nbi");
  run(state, *st.solver, *st.problem);
}
void BM_WeightedSum5mm(benchmark::State& state) {
  hapsyn::Study& st = study("fivebar-pareto-weighted-sum");
  run(state, *st.solver, *st.problem);
}
BENCHMARK(BM_Nbi)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_WeightedSum5mm)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// NBI against its constraint tolerance (1e-7, 1e-8, 1e-9: exponent as the argument) and points.
void BM_NbiTolerance(benchmark::State& state) {
  hapsyn::Json options = study("fivebar-pareto-nbi").resolved["solver"]["options"];
  options["constraint_tolerance"] = std::pow(10.0, -static_cast<double>(state.range(0)));
  options["points"] = state.range(1);
  const auto solver = registry().create_solver("nbi", options, "solver");
  run(state, *solver, *study("fivebar-pareto-nbi").problem);
}
BENCHMARK(BM_NbiTolerance)
    ->ArgNames({"tol_exp", "points"})
    ->Args({7, 10})->Args({8, 10})->Args({9, 10})->Args({8, 5})->Args({8, 20})->Args({8, 40})
    ->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

}  // namespace

int main(int argc, char** argv) {
  hapsyn::bench::record_context(study("fivebar-pareto-nbi").resolved, 1);
  hapsyn::bench::compare("BM_Nbi/iterations:1/real_time", "BM_WeightedSum5mm/iterations:1/real_time");
  hapsyn::bench::compare_counter("BM_Nbi/iterations:1/real_time", "BM_WeightedSum5mm/iterations:1/real_time",
                                 "sample_evals");
  return hapsyn::bench::run_main(argc, argv);
}
