// LIBRARIES: hapsyn_human_arm_model
//
// The human_arm scene (Fennel 2022, section V):
//   BM_HumanArmBuild    -- a full build without the cache, for the paper resolution (0.1 m
//                          lattice over +-0.7 m, 505 orientations, 17 joint-3 steps) on 2 and 1
//                          threads, with and without M_v/M_a, and the speed-vs-accuracy sweeps of
//                          joint-3 steps, orientation count and lattice step. Counters: n_reach
//                          (n_reach^h), reach_fraction = n_reach / poses tried (comparable
//                          across lattice steps and orientation counts).
//   BM_HumanArmCacheLoad -- the paper-resolution scene loaded from its cache file.
// Read the rows as ratios against the paper-resolution row of the same run (printed at the end).
#include "common.hpp"

#include <human_arm.hpp>

#include <benchmark/benchmark.h>

#include <filesystem>
#include <unistd.h>

namespace {

using hapsyn::Json;
using hapsyn::SampleSet;
using hapsyn::plugins::HumanArmScene;

Json options(const benchmark::State& state) {
  return Json{{"lattice_step", state.range(0) / 1000.0},
              {"lattice_extent", 0.7},
              {"orientations", state.range(1)},
              {"joint3_steps", state.range(2)},
              {"threads", state.range(3)},
              {"cache", false}};
}

void report(benchmark::State& state, const SampleSet& set) {
  state.counters["n_reach"] = set.info["n_reach"].get<double>();
  state.counters["reach_fraction"] = set.info["n_reach"].get<double>() / set.info["poses_tried"].get<double>();
  state.counters["lattice_points"] = set.info["lattice_points"].get<double>();
}

void BM_HumanArmBuild(benchmark::State& state) {
  const HumanArmScene scene(hapsyn::make_options<hapsyn::plugins::HumanArmOptions>(options(state)));
  hapsyn::SceneRequest request;
  if (state.range(4)) request.attributes = {"M_v", "M_a"};
  SampleSet set;
  for (auto _ : state) {
    set = scene.build(request);
    benchmark::DoNotOptimize(set.poses.data());
  }
  report(state, set);
}

void BM_HumanArmCacheLoad(benchmark::State& state) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("hapsyn-human-arm-bench-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  Json o = options(state);
  o["cache"] = true;
  o["cache_directory"] = dir.string();
  const HumanArmScene scene(hapsyn::make_options<hapsyn::plugins::HumanArmOptions>(o));
  hapsyn::SceneRequest request;
  if (state.range(4)) request.attributes = {"M_v", "M_a"};
  SampleSet set = scene.build(request);  // writes the cache
  for (auto _ : state) {
    set = scene.build(request);
    if (!set.info["from_cache"].get<bool>()) state.SkipWithError("not loaded from the cache");
    benchmark::DoNotOptimize(set.poses.data());
  }
  report(state, set);
  state.counters["cache_bytes"] = static_cast<double>(std::filesystem::file_size(set.info["cache_file"].get<std::string>()));
  std::filesystem::remove_all(dir);
}

// {lattice step [mm], orientations, joint-3 steps, threads, ellipsoids}
void build_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"step_mm", "orientations", "j3", "threads", "ellipsoids"});
  b->Args({100, 505, 17, 2, 0});  // the paper's resolution
  b->Args({100, 505, 17, 1, 0});
  b->Args({100, 505, 17, 2, 1});
  for (int j3 : {5, 9, 33, 65}) b->Args({100, 505, j3, 2, 0});
  for (int n : {101, 2020}) b->Args({100, n, 17, 2, 0});
  for (int step : {200, 50}) b->Args({step, 505, 17, 2, 0});
}

BENCHMARK(BM_HumanArmBuild)->Apply(build_args)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_HumanArmCacheLoad)
    ->ArgNames({"step_mm", "orientations", "j3", "threads", "ellipsoids"})
    ->Args({100, 505, 17, 2, 0})
    ->Args({100, 505, 17, 2, 1})
    ->Iterations(5)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  hapsyn::bench::record_context(Json{{"scene", "human_arm"}, {"arm_file", "human_arm/fennel2022_right_arm.json"}});
  const std::string paper = "BM_HumanArmBuild/step_mm:100/orientations:505/j3:17/threads:2/ellipsoids:0/iterations:1/real_time";
  hapsyn::bench::compare("BM_HumanArmCacheLoad/step_mm:100/orientations:505/j3:17/threads:2/ellipsoids:0/iterations:5/real_time",
                         paper);
  hapsyn::bench::compare(paper, "BM_HumanArmBuild/step_mm:100/orientations:505/j3:17/threads:1/ellipsoids:0/iterations:1/real_time");
  hapsyn::bench::compare(paper, "BM_HumanArmBuild/step_mm:100/orientations:505/j3:17/threads:2/ellipsoids:1/iterations:1/real_time");
  for (const char* other : {"step_mm:100/orientations:505/j3:5", "step_mm:100/orientations:505/j3:9",
                            "step_mm:100/orientations:505/j3:33", "step_mm:100/orientations:505/j3:65",
                            "step_mm:100/orientations:101/j3:17", "step_mm:100/orientations:2020/j3:17",
                            "step_mm:200/orientations:505/j3:17", "step_mm:50/orientations:505/j3:17"}) {
    hapsyn::bench::compare(std::string("BM_HumanArmBuild/") + other + "/threads:2/ellipsoids:0/iterations:1/real_time", paper);
  }
  return hapsyn::bench::run_main(argc, argv);
}
