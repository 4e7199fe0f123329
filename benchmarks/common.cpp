#include "common.hpp"

#include <hapsyn/output_files.hpp>
#include <hapsyn/plugin.hpp>

#include <benchmark/benchmark.h>

#include <iostream>
#include <map>
#include <set>

namespace hapsyn::bench {

namespace {
struct Comparison {
  std::string name, baseline, counter;  // counter empty: real time
};
std::vector<Comparison>& pairs() {
  static std::vector<Comparison> p;
  return p;
}

// Console output as usual, plus the real time per iteration of every run for the ratios. With
// --benchmark_repetitions the median of the repetitions is used (also with
// --benchmark_report_aggregates_only, which reports no single repetition).
class RecordingReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      const bool median = r.run_type == Run::RT_Aggregate && r.aggregate_name == "median";
      if (r.run_type != Run::RT_Iteration && !median) continue;
      const std::string name = median ? r.run_name.str() : r.benchmark_name();
      if (!median && medians.count(name)) continue;
      if (median) medians.insert(name);
      times[name] = r.GetAdjustedRealTime();
      cpu_times[name] = r.GetAdjustedCPUTime();
      for (const auto& [key, counter] : r.counters) counters[name + "#" + key] = counter.value;
    }
    ConsoleReporter::ReportRuns(runs);
  }
  std::map<std::string, double> times;
  std::map<std::string, double> cpu_times;  // differs from real time on a loaded machine
  std::map<std::string, double> counters;
  std::set<std::string> medians;  // names whose median is recorded (it wins over repetitions)
};
}  // namespace

void record_context(const Json& resolved_problem, unsigned long long seed) {
  benchmark::AddCustomContext("hapsyn_version", version());
  benchmark::AddCustomContext("plugin_api", std::to_string(HAPSYN_PLUGIN_API_VERSION));
  benchmark::AddCustomContext("machine", machine_info().dump());
  benchmark::AddCustomContext("seed", std::to_string(seed));
  if (!resolved_problem.is_null()) benchmark::AddCustomContext("problem", resolved_problem.dump());
}

void compare(const std::string& name, const std::string& baseline) { pairs().push_back({name, baseline, ""}); }

void compare_counter(const std::string& name, const std::string& baseline, const std::string& counter) {
  pairs().push_back({name, baseline, counter});
}

int run_main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  RecordingReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  for (const Comparison& c : pairs()) {
    const auto& table = c.counter.empty() ? reporter.times : reporter.counters;
    const std::string suffix = c.counter.empty() ? "" : "#" + c.counter;
    const auto a = table.find(c.name + suffix);
    const auto b = table.find(c.baseline + suffix);
    if (a == table.end() || b == table.end()) continue;
    std::cout << "ratio " << (c.counter.empty() ? "real time" : c.counter) << ": " << c.baseline << " / " << c.name
              << " = " << b->second / a->second;
    if (c.counter.empty()) {
      // Single-threaded pairs: the CPU-time ratio is the one to read when other jobs share the machine.
      std::cout << " (cpu time: " << reporter.cpu_times.at(c.baseline) / reporter.cpu_times.at(c.name) << ")";
    }
    std::cout << "\n";
  }
  benchmark::Shutdown();
  return 0;
}

}  // namespace hapsyn::bench
