// LIBRARIES: hapsyn_pagmo_adapter
// The per-design overhead of the pagmo adapter (plugins/solvers/shared/pagmo_adapter.hpp), which
// `ga` and `nsga2` evaluate through: the same designs of the five-bar GII/GDI front study
// (problems/fivebar-pareto-nsga2.json) evaluated with Problem::evaluate directly (the baseline)
// and through Evaluator::batch_fitness (decode, cache look-up, task farm, record, fitness), on
// one thread, in the same run. Most random designs of that box fail at an early sample, so the
// evaluation itself is short and the adapter's share shows; a second set holds designs that
// survive their first samples. The difference per design is the adapter's overhead.
#include "common.hpp"

#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/study.hpp>
#include <shared/pagmo_adapter.hpp>

#include <benchmark/benchmark.h>

#include <memory>
#include <random>
#include <vector>

namespace {

namespace adapter = hapsyn::plugins::pagmo_adapter;

hapsyn::Study& front_study() {
  static hapsyn::Registry registry({HAPSYN_PLUGIN_DIR});
  static hapsyn::Study study = hapsyn::load_study(
      hapsyn::read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/problems/fivebar-pareto-nsga2.json"), registry);
  return study;
}

constexpr std::size_t kDesigns = 4096;

// kDesigns pagmo vectors uniform in the study's box (seed 1); with `feasible`, only designs
// whose full evaluation is feasible (drawn until there are kDesigns of them).
const std::vector<pagmo::vector_double>& designs(bool feasible) {
  static std::vector<pagmo::vector_double> sets[2];
  std::vector<pagmo::vector_double>& out = sets[feasible ? 1 : 0];
  if (!out.empty()) return out;
  const hapsyn::Problem& problem = *front_study().problem;
  const adapter::Encoding encoding(problem, {}, {}, "benchmark");
  auto scratch = problem.make_eval_scratch();
  std::mt19937_64 rng(1);
  while (out.size() < kDesigns) {
    pagmo::vector_double x(encoding.size());
    for (std::size_t k = 0; k < x.size(); ++k) {
      x[k] = std::uniform_real_distribution<double>(encoding.lower()[k], encoding.upper()[k])(rng);
    }
    if (feasible) {
      const std::vector<double> free = encoding.decode(x);
      if (problem.evaluate(free.data(), *scratch).status != hapsyn::EvalStatus::kFeasible) continue;
    }
    out.push_back(x);
  }
  return out;
}

// The baseline: the decoded designs evaluated directly, one thread.
void BM_DirectEvaluate(benchmark::State& state) {
  const hapsyn::Problem& problem = *front_study().problem;
  const adapter::Encoding encoding(problem, {}, {}, "benchmark");
  std::vector<std::vector<double>> free;
  for (const auto& x : designs(state.range(0) != 0)) free.push_back(encoding.decode(x));
  auto scratch = problem.make_eval_scratch();
  double sum = 0.0;
  for (auto _ : state) {
    for (const auto& f : free) sum += problem.evaluate(f.data(), *scratch).score;
  }
  benchmark::DoNotOptimize(sum);
  state.counters["designs"] = static_cast<double>(free.size());
}
BENCHMARK(BM_DirectEvaluate)->ArgName("feasible")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// The same designs through the adapter, one batch, a fresh cache every iteration.
void BM_AdapterBatchFitness(benchmark::State& state) {
  const hapsyn::Problem& problem = *front_study().problem;
  pagmo::vector_double all;
  for (const auto& x : designs(state.range(0) != 0)) all.insert(all.end(), x.begin(), x.end());
  adapter::EvaluationSettings settings;
  settings.threads = 1;
  std::unique_ptr<adapter::Evaluator> evaluator;
  double sum = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    evaluator = std::make_unique<adapter::Evaluator>(problem, adapter::Encoding(problem, {}, {}, "benchmark"),
                                                     settings, true);
    state.ResumeTiming();
    sum += evaluator->batch_fitness(all)[0];
  }
  benchmark::DoNotOptimize(sum);
}
BENCHMARK(BM_AdapterBatchFitness)->ArgName("feasible")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// The same batch again on a warm cache: what a repeated design costs.
void BM_AdapterCacheHits(benchmark::State& state) {
  const hapsyn::Problem& problem = *front_study().problem;
  pagmo::vector_double all;
  for (const auto& x : designs(false)) all.insert(all.end(), x.begin(), x.end());
  adapter::EvaluationSettings settings;
  settings.threads = 1;
  adapter::Evaluator evaluator(problem, adapter::Encoding(problem, {}, {}, "benchmark"), settings, true);
  double sum = evaluator.batch_fitness(all)[0];
  for (auto _ : state) sum += evaluator.batch_fitness(all)[0];
  benchmark::DoNotOptimize(sum);
}
BENCHMARK(BM_AdapterCacheHits)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  hapsyn::bench::record_context(front_study().resolved, 1);
  hapsyn::bench::compare("BM_DirectEvaluate/feasible:0/real_time", "BM_AdapterBatchFitness/feasible:0/real_time");
  hapsyn::bench::compare("BM_DirectEvaluate/feasible:1/real_time", "BM_AdapterBatchFitness/feasible:1/real_time");
  return hapsyn::bench::run_main(argc, argv);
}
