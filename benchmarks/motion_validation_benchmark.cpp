// LIBRARIES: hapsyn_motion_model
// The validation of one haptic6r design on the shipped (synthetic) motion data set
// (problems/haptic6r-motion-validation.json, Fennel 2022 section VII-B):
//   BM_MotionSceneBuild  -- reading the 24 CSV recordings, resampling, filtering and
//                           differentiating them (the scene build), per stride.
//   BM_MotionValidation  -- evaluating the design on every sample: IK, joint rates, the full
//                           inverse dynamics, the three shares; per stride (every k-th sample)
//                           and thread count, to show how the cost grows with the samples, and
//                           with the reachable share alone (what the rates and dynamics cost).
// Counters: samples, s_per_sample, and the three shares. Ratios against stride 1 / 2 threads of the same run.
#include "common.hpp"

#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/solver.hpp>
#include <hapsyn/internal/study.hpp>

#include <motion_scene.hpp>

#include <benchmark/benchmark.h>

#include <map>

namespace {

const std::string kProblem = std::string(HAPSYN_SOURCE_DIR) + "/problems/haptic6r-motion-validation.json";

hapsyn::Registry& registry() {
  static hapsyn::Registry r({HAPSYN_PLUGIN_DIR});
  return r;
}

// The study with the scene at a stride, loaded once per (stride, shares) (the scene build is not
// timed here); `all_shares` false keeps the reachable share only (IK, no rates or dynamics).
hapsyn::Study& study(int stride, bool all_shares = true) {
  static std::map<std::pair<int, bool>, hapsyn::Study> studies;
  auto it = studies.find({stride, all_shares});
  if (it == studies.end()) {
    hapsyn::Json doc = hapsyn::read_problem_file(kProblem);
    doc["scene"]["options"]["stride"] = stride;
    if (!all_shares) doc["objectives"] = hapsyn::Json::array({doc["objectives"][0]});
    it = studies.emplace(std::make_pair(stride, all_shares), hapsyn::load_study(doc, registry())).first;
  }
  return it->second;
}

void BM_MotionSceneBuild(benchmark::State& state) {
  hapsyn::Json doc = hapsyn::read_problem_file(kProblem);
  hapsyn::Json options = doc["scene"]["options"];
  options["stride"] = state.range(0);
  const hapsyn::plugins::MotionScene scene(hapsyn::make_options<hapsyn::plugins::MotionOptions>(options));
  hapsyn::SampleSet set;
  for (auto _ : state) {
    set = scene.build({});
    benchmark::DoNotOptimize(set.poses.data());
  }
  state.counters["samples"] = set.size();
}
BENCHMARK(BM_MotionSceneBuild)->ArgName("stride")->Arg(1)->Arg(8)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_MotionValidation(benchmark::State& state) {
  hapsyn::Study& s = study(static_cast<int>(state.range(0)), state.range(2) != 0);
  hapsyn::SolverContext context;
  context.threads = static_cast<int>(state.range(1));
  hapsyn::SolverResult result;
  for (auto _ : state) {
    result = s.solver->solve(*s.problem, context);
    benchmark::DoNotOptimize(result);
  }
  const double samples = s.problem->samples().size();
  state.counters["samples"] = samples;
  // Seconds per sample (printed with an SI prefix: 780n = 780 ns).
  state.counters["s_per_sample"] = benchmark::Counter(samples * static_cast<double>(state.iterations()),
                                                      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  if (result.best) {
    const std::vector<double>& shares = result.best->objectives;
    state.counters["reachable"] = shares[0];
    if (shares.size() == 3) state.counters["velocity"] = shares[1], state.counters["acceleration"] = shares[2];
  }
}
BENCHMARK(BM_MotionValidation)
    ->ArgNames({"stride", "threads", "all_shares"})
    ->Args({1, 2, 1})
    ->Args({1, 1, 1})
    ->Args({1, 2, 0})
    ->Args({2, 2, 1})
    ->Args({4, 2, 1})
    ->Args({8, 2, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(1.0);

}  // namespace

int main(int argc, char** argv) {
  hapsyn::bench::record_context(study(1).resolved, 0);
  const std::string base = "BM_MotionValidation/stride:1/threads:2/all_shares:1/min_time:1.000/real_time";
  hapsyn::bench::compare(base, "BM_MotionValidation/stride:1/threads:1/all_shares:1/min_time:1.000/real_time");
  hapsyn::bench::compare("BM_MotionValidation/stride:1/threads:2/all_shares:0/min_time:1.000/real_time", base);
  for (const char* stride : {"2", "4", "8"}) {
    hapsyn::bench::compare(std::string("BM_MotionValidation/stride:") + stride + "/threads:2/all_shares:1/min_time:1.000/real_time", base);
  }
  return hapsyn::bench::run_main(argc, argv);
}
