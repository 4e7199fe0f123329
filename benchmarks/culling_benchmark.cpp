// LIBRARIES: hapsyn_culling_model hapsyn_grid_model
// Culling against exhaustive search on the same grid, in one run, and the trade of the design
// grid step (10, 5, 2 mm; 1 mm with HAPSYN_BENCH_FINE=1) against the optimum and the time.
// Five-bar GII and GDI (Unal 2008), paper bounds, 1 mm workspace unless stated.
//
//   build/bin/culling_benchmark                          # comparison + trade at 10, 5, 2 mm
//   HAPSYN_BENCH_FINE=1 build/bin/culling_benchmark      # adds the 1 mm design grid (minutes)
#include "common.hpp"

#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/internal/study.hpp>
#include <solvers/culling/culling.hpp>
#include <solvers/grid/grid.hpp>

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <map>
#include <memory>

namespace {

const hapsyn::Registry& registry() {
  static hapsyn::Registry r({HAPSYN_PLUGIN_DIR});
  return r;
}

// The paper-resolution study with the given design step [mm] and workspace step [mm].
hapsyn::Study& study(const std::string& metric, int design_mm, int workspace_mm) {
  static std::map<std::string, std::unique_ptr<hapsyn::Study>> cache;
  const std::string key = metric + "/" + std::to_string(design_mm) + "/" + std::to_string(workspace_mm);
  auto& slot = cache[key];
  if (!slot) {
    hapsyn::Json doc = hapsyn::read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/problems/fivebar-" + metric +
                                                 "-culling-paper.json");
    for (const char* v : {"l0", "l1", "l2", "r"}) doc["design"][v]["step"] = design_mm / 1000.0;
    doc["scene"]["options"]["step"] = workspace_mm / 1000.0;
    slot = std::make_unique<hapsyn::Study>(hapsyn::load_study(doc, registry()));
  }
  return *slot;
}

void report(benchmark::State& state, const hapsyn::SolverResult& r) {
  state.counters["value"] = r.best ? r.best->objectives[0] : 0.0;
  state.counters["sample_evals"] = static_cast<double>(r.sample_evaluations);
  const auto& s = r.statistics;
  if (s.contains("full_workspace_searches")) {
    state.counters["full_searches"] = s["full_workspace_searches"].get<double>();
  } else if (s.contains("feasible")) {
    state.counters["full_searches"] = s["feasible"].get<double>();  // exhaustive: every feasible design
  }
  if (s.contains("grid_optimum")) state.counters["grid_value"] = s["grid_optimum"]["score"].get<double>();
  if (s.contains("grid_designs")) state.counters["grid_designs"] = s["grid_designs"].get<double>();
}

void run(benchmark::State& state, const hapsyn::Solver& solver, hapsyn::Study& st) {
  hapsyn::SolverContext context;
  context.threads = 2;
  hapsyn::SolverResult result;
  for (auto _ : state) {
    result = solver.solve(*st.problem, context);
    benchmark::DoNotOptimize(result);
  }
  report(state, result);
}

hapsyn::Json culling_options(bool polish) {
  return {{"seed", true}, {"polish", polish}, {"start_points", 5}, {"sqp_xtol", 1e-7}, {"sqp_ftol", 1e-10},
          {"sqp_max_evaluations", 400}, {"progress_interval", 1e9}};
}

// Same grid (10 mm design, 5 mm workspace): culling (no polish, so the value is the grid's),
// exhaustive search without pruning (every feasible design searched in full), and with pruning.
void BM_Compare_Culling(benchmark::State& state) {
  const hapsyn::plugins::CullingSolver solver(hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(false)));
  run(state, solver, study(state.range(0) ? "gdi" : "gii", 10, 5));
}
void BM_Compare_Exhaustive(benchmark::State& state) {
  const hapsyn::plugins::GridSolver solver(
      hapsyn::make_options<hapsyn::plugins::GridOptions>(hapsyn::Json{{"prune", false}, {"progress_interval", 1e9}}));
  run(state, solver, study(state.range(0) ? "gdi" : "gii", 10, 5));
}
void BM_Compare_ExhaustivePruned(benchmark::State& state) {
  const hapsyn::plugins::GridSolver solver(
      hapsyn::make_options<hapsyn::plugins::GridOptions>(hapsyn::Json{{"prune", true}, {"progress_interval", 1e9}}));
  run(state, solver, study(state.range(0) ? "gdi" : "gii", 10, 5));
}
BENCHMARK(BM_Compare_Culling)->ArgName("gdi")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_Compare_Exhaustive)->ArgName("gdi")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_Compare_ExhaustivePruned)->ArgName("gdi")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// The trade: design grid step [mm] against the optimum (grid and polished) and time, 1 mm workspace.
void BM_Trade_Culling(benchmark::State& state) {
  const hapsyn::plugins::CullingSolver solver(hapsyn::make_options<hapsyn::plugins::CullingOptions>(culling_options(true)));
  run(state, solver, study(state.range(1) ? "gdi" : "gii", static_cast<int>(state.range(0)), 1));
}
void trade_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"step_mm", "gdi"});
  std::vector<int> steps = {10, 5, 2};
  if (std::getenv("HAPSYN_BENCH_FINE")) steps.push_back(1);
  for (int gdi : {0, 1}) {
    for (int step : steps) b->Args({step, gdi});
  }
}
BENCHMARK(BM_Trade_Culling)->Apply(trade_args)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

}  // namespace

int main(int argc, char** argv) {
  hapsyn::bench::record_context(study("gii", 10, 5).resolved, 1);
  for (const char* m : {"0", "1"}) {
    const std::string culling = std::string("BM_Compare_Culling/gdi:") + m + "/iterations:1/real_time";
    hapsyn::bench::compare(culling, std::string("BM_Compare_Exhaustive/gdi:") + m + "/iterations:1/real_time");
    hapsyn::bench::compare(culling, std::string("BM_Compare_ExhaustivePruned/gdi:") + m + "/iterations:1/real_time");
    hapsyn::bench::compare_counter(culling, std::string("BM_Compare_Exhaustive/gdi:") + m + "/iterations:1/real_time",
                                   "sample_evals");
    hapsyn::bench::compare_counter(culling, std::string("BM_Compare_Exhaustive/gdi:") + m + "/iterations:1/real_time",
                                   "full_searches");
  }
  return hapsyn::bench::run_main(argc, argv);
}
