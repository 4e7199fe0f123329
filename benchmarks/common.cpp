#include "common.hpp"

#include <hapsyn/plugin.hpp>
#include <hapsyn/study.hpp>

#include <benchmark/benchmark.h>

#include <iostream>
#include <map>

namespace hapsyn::bench {

namespace {
std::vector<std::pair<std::string, std::string>>& pairs() {
  static std::vector<std::pair<std::string, std::string>> p;
  return p;
}

// Console output as usual, plus the real time per iteration of every run for the ratios.
class RecordingReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.run_type == Run::RT_Iteration) times[r.benchmark_name()] = r.GetAdjustedRealTime();
    }
    ConsoleReporter::ReportRuns(runs);
  }
  std::map<std::string, double> times;
};
}  // namespace

void record_context(const Json& resolved_problem, unsigned long long seed) {
  benchmark::AddCustomContext("hapsyn_version", version());
  benchmark::AddCustomContext("plugin_api", std::to_string(HAPSYN_PLUGIN_API_VERSION));
  benchmark::AddCustomContext("machine", machine_info().dump());
  benchmark::AddCustomContext("seed", std::to_string(seed));
  if (!resolved_problem.is_null()) benchmark::AddCustomContext("problem", resolved_problem.dump());
}

void compare(const std::string& name, const std::string& baseline) { pairs().emplace_back(name, baseline); }

int run_main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  RecordingReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  for (const auto& [name, baseline] : pairs()) {
    const auto a = reporter.times.find(name);
    const auto b = reporter.times.find(baseline);
    if (a == reporter.times.end() || b == reporter.times.end()) continue;
    std::cout << "ratio " << baseline << " / " << name << " = " << b->second / a->second << "\n";
  }
  benchmark::Shutdown();
  return 0;
}

}  // namespace hapsyn::bench
