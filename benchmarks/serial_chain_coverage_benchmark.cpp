// Coverage per design of a UR-class arm read from a URDF (share/serial_chain/ur5_like.urdf, the
// mechanism options of problems/ur5like-coverage-ga.json at the file's design) on the paper's
// human-arm workspace (0.1 m lattice, 505 orientations, 17 joint-3 steps: 34,548 poses; the scene
// is cached on disk after the first build), the four-term objective J through the framework's
// evaluator on 2 threads, with serial_chain's closed-form IK (ik.solver closed_form) and its
// numerical IK (ik.solver numerical, 8 restarts, closest to home), against the haptic6r
// mechanism's own closed form on the same workspace (problems/haptic6r-evaluate.json's design),
// all in the same run. Read the ratios printed at the end, not bare times.
#include "common.hpp"

#include <hapsyn/problem.hpp>
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/study.hpp>

#include <benchmark/benchmark.h>

#include <map>
#include <string>

namespace {

using hapsyn::Json;

constexpr int kThreads = 2;

hapsyn::Registry& registry() {
  static hapsyn::Registry r({HAPSYN_PLUGIN_DIR});
  return r;
}

const char* kScene = R"("scene": {"plugin": "human_arm", "options": {"lattice_step": 0.1, "orientations": 505, "joint3_steps": 17}},
    "objectives": [{"metric": "coverage"}], "solver": {"plugin": "evaluate"})";

const hapsyn::Problem& ur_study(const std::string& solver) {
  static std::map<std::string, hapsyn::Study> studies;
  auto it = studies.find(solver);
  if (it == studies.end()) {
    Json doc = Json::parse(std::string(R"({"name": "bench-ur", "mechanism": {"plugin": "serial_chain", "options": {
      "urdf": "serial_chain/ur5_like.urdf", "base_link": "base_link", "tip_link": "tool0",
      "base_xyz": [0.2, -0.1, -0.1], "base_rpy": [180, 0, 0], "home": [0, -90, 90, -90, -90, 0]}},)") + kScene + "}");
    doc["mechanism"]["options"]["ik"]["solver"] = solver;
    it = studies.emplace(solver, hapsyn::load_study(doc, registry())).first;
  }
  return *it->second.problem;
}

const hapsyn::Problem& haptic6r_study() {
  static hapsyn::Study study = hapsyn::load_study(
      Json::parse(std::string(R"({"name": "bench-haptic6r", "mechanism": {"plugin": "haptic6r", "options": {"selection": "closest_to_home"}},
    "design": {"l": {"value": [0.45, 0.45, 0.65, 0.55, 0.15]}, "s": {"value": [3, 3, 2, 2, 1, 1]}, "r": {"value": [2, 2, 3, 2, 3, 3]}},)") +
                  kScene + "}"),
      registry());
  return *study.problem;
}

void run(benchmark::State& state, const hapsyn::Problem& problem) {
  double j = 0.0;
  for (auto _ : state) j = problem.evaluate_parallel(nullptr, kThreads).objectives[0];
  state.counters["J"] = j;
  state.counters["poses"] = problem.samples().size();
}

void BM_Haptic6RCoveragePerDesign(benchmark::State& state) { run(state, haptic6r_study()); }
void BM_UrUrdfClosedFormCoveragePerDesign(benchmark::State& state) { run(state, ur_study("closed_form")); }
void BM_UrUrdfNumericalCoveragePerDesign(benchmark::State& state) { run(state, ur_study("numerical")); }

}  // namespace

BENCHMARK(BM_Haptic6RCoveragePerDesign)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_UrUrdfClosedFormCoveragePerDesign)->Unit(benchmark::kMillisecond)->UseRealTime();
// About 5 s per design: one evaluation.
BENCHMARK(BM_UrUrdfNumericalCoveragePerDesign)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

int main(int argc, char** argv) {
  hapsyn::bench::record_context(Json{{"mechanism", "serial_chain ur5_like.urdf / haptic6r"}, {"metric", "coverage (J)"},
                                     {"scene", "human_arm 0.1 m, 505 orientations, 17 joint-3 steps"},
                                     {"threads", kThreads}});
  hapsyn::bench::compare("BM_UrUrdfClosedFormCoveragePerDesign/real_time", "BM_UrUrdfNumericalCoveragePerDesign/iterations:1/real_time");
  hapsyn::bench::compare("BM_Haptic6RCoveragePerDesign/real_time", "BM_UrUrdfClosedFormCoveragePerDesign/real_time");
  return hapsyn::bench::run_main(argc, argv);
}
