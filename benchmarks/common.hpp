#pragma once
// Shared by the benchmarks: the run context every benchmark log records (hapsyn version,
// machine, seed, resolved problem), and a main() that prints ratios against a baseline
// measured in the same run.
#include <hapsyn/json.hpp>

#include <string>
#include <utility>
#include <vector>

namespace hapsyn::bench {

/// Adds version, machine and (optionally) the resolved problem to the benchmark context.
void record_context(const Json& resolved_problem = Json(), unsigned long long seed = 0);

/// Pairs (benchmark, baseline) whose real-time ratio baseline/benchmark is printed at the end.
void compare(const std::string& name, const std::string& baseline);

/// Also prints baseline/benchmark for a user counter of both runs (e.g. "sample_evals").
void compare_counter(const std::string& name, const std::string& baseline, const std::string& counter);

/// Runs the registered benchmarks, then prints "speed-up" lines for every compare() pair.
int run_main(int argc, char** argv);

}  // namespace hapsyn::bench
