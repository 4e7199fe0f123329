// LIBRARIES: hapsyn_grid_model
// The coarse exhaustive GII study (problems/fivebar-gii-coarse.json: 10 mm design grid, 5 mm
// workspace, 1.7 million grid designs) with the grid solver, against baselines measured in the
// same run: the same search without pruning, and on one thread.
#include "common.hpp"

#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/internal/study.hpp>
#include <solvers/grid/grid.hpp>

#include <benchmark/benchmark.h>

namespace {

hapsyn::Study& coarse_study() {
  static hapsyn::Registry registry({HAPSYN_PLUGIN_DIR});
  static hapsyn::Study study =
      hapsyn::load_study(hapsyn::read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/problems/fivebar-gii-coarse.json"),
                         registry);
  return study;
}

void BM_CoarseGridStudy(benchmark::State& state) {
  const hapsyn::Study& study = coarse_study();
  const bool prune = state.range(0) != 0;
  const bool block_bounds = state.range(2) != 0;
  hapsyn::plugins::GridSolver solver(hapsyn::make_options<hapsyn::plugins::GridOptions>(
      hapsyn::Json{{"prune", prune}, {"block_bounds", block_bounds}, {"progress_interval", 1e9}}));
  hapsyn::SolverContext context;
  context.threads = static_cast<int>(state.range(1));
  hapsyn::SolverResult result;
  for (auto _ : state) {
    result = solver.solve(*study.problem, context);
    benchmark::DoNotOptimize(result);
  }
  state.counters["designs"] = static_cast<double>(result.design_evaluations);
  state.counters["sample_solves"] = static_cast<double>(result.sample_evaluations);
  state.counters["best_gii"] = result.best ? result.best->objectives[0] : 0.0;
}
BENCHMARK(BM_CoarseGridStudy)->ArgNames({"prune", "threads", "block_bounds"})->Args({1, 2, 1})->Args({1, 1, 1})
    ->Args({1, 2, 0})->Args({1, 1, 0})->Args({0, 2, 0})->Args({0, 1, 0})
    ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

}  // namespace

int main(int argc, char** argv) {
  hapsyn::bench::record_context(coarse_study().resolved, 1);
  hapsyn::bench::compare("BM_CoarseGridStudy/prune:1/threads:2/block_bounds:1/min_time:2.000/real_time",
                         "BM_CoarseGridStudy/prune:0/threads:2/block_bounds:0/min_time:2.000/real_time");
  hapsyn::bench::compare("BM_CoarseGridStudy/prune:1/threads:2/block_bounds:1/min_time:2.000/real_time",
                         "BM_CoarseGridStudy/prune:1/threads:1/block_bounds:1/min_time:2.000/real_time");
  return hapsyn::bench::run_main(argc, argv);
}
