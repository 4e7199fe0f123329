#include "nsga2.hpp"

#include "shared/pagmo_adapter.hpp"

#include <hapsyn/error.hpp>

#include <pagmo/algorithms/nsga2.hpp>
#include <pagmo/batch_evaluators/member_bfe.hpp>
#include <pagmo/bfe.hpp>
#include <pagmo/population.hpp>
#include <pagmo/utils/multi_objective.hpp>

#include <algorithm>
#include <chrono>
#include <set>
#include <sstream>
#include <stdexcept>

namespace hapsyn::plugins {

namespace pa = pagmo_adapter;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

pagmo::algorithm make_algorithm(const Nsga2Options& o, std::uint64_t seed) {
  pagmo::nsga2 nsga2(1u, o.cr, o.eta_c, o.m, o.eta_m, static_cast<unsigned>(seed ^ (seed >> 32)));
  nsga2.set_bfe(pagmo::bfe{pagmo::member_bfe{}});
  return pagmo::algorithm{nsga2};
}

// Indices of the population's feasible individuals on the first non-dominated front.
std::vector<std::size_t> first_front(const pagmo::population& population) {
  std::vector<std::size_t> feasible;
  std::vector<pagmo::vector_double> points;
  for (std::size_t i = 0; i < population.size(); ++i) {
    if (population.get_f()[i][0] >= pa::kSampleFailedFitness) continue;
    feasible.push_back(i);
    points.push_back(population.get_f()[i]);
  }
  std::vector<std::size_t> front;
  if (points.empty()) return front;
  const auto sorting = pagmo::fast_non_dominated_sorting(points);
  for (const auto k : std::get<0>(sorting)[0]) front.push_back(feasible[k]);
  return front;
}

// The final front: distinct designs of the first front, sorted by their objectives.
std::vector<SolutionPoint> final_front(const Problem& problem, const pagmo::population& population,
                                       pa::Evaluator& evaluator) {
  std::set<std::vector<double>> seen;
  std::vector<SolutionPoint> front;
  for (std::size_t i : first_front(population)) {
    const pagmo::vector_double& x = population.get_x()[i];
    const std::vector<double> free = evaluator.encoding().decode(x);
    if (!seen.insert(free).second) continue;
    const pa::DesignRecord& record = evaluator.record(x);
    front.push_back(SolutionPoint{problem.full_design(free.data()), record.objectives, record.score});
  }
  std::sort(front.begin(), front.end(), [](const SolutionPoint& a, const SolutionPoint& b) {
    return a.objectives < b.objectives;
  });
  return front;
}

// The progress line after a generation.
std::string generation_line(const Nsga2Options& o, int generation, const pagmo::population& population,
                            const pa::Evaluator& evaluator, double elapsed) {
  std::ostringstream line;
  line << "nsga2: gen " << generation << "/" << o.generations << " front " << first_front(population).size() << "/"
       << population.size() << " | " << static_cast<long long>(evaluator.design_evaluations() / std::max(1e-9, elapsed))
       << " designs/s | elapsed " << pa::format_duration(elapsed) << ", left "
       << pa::format_duration(elapsed / generation * (o.generations - generation));
  return line.str();
}

// Status and message from how the generations ended.
void set_status_and_message(const Nsga2Options& o, int generation, bool stopped, SolverResult& result) {
  std::ostringstream message;
  if (stopped) {
    result.status = SolverStatus::kStopped;
    message << "stopped on request after " << generation << " generations";
  } else if (result.front.empty()) {
    result.status = SolverStatus::kInfeasible;
    message << "no feasible design in the final population of " << o.population;
  } else {
    result.status = SolverStatus::kBudgetExhausted;
    message << generation << " generations of NSGA-II, population " << o.population << ": " << result.front.size()
            << " non-dominated designs";
  }
  result.message = message.str();
}

}  // namespace

Nsga2Solver::Nsga2Solver(const Nsga2Options& options) : options_(options) {
  const Nsga2Options& o = options_;
  if (o.population % 4 != 0) {
    throw Error("nsga2", "options.population = " + std::to_string(o.population) +
                             ": must be a multiple of 4 (pagmo's NSGA-II pairs parents in fours)");
  }
  try {
    (void)make_algorithm(o, 1);
  } catch (const std::invalid_argument& e) {
    throw Error("nsga2", std::string("options: pagmo refuses the parameters: ") + e.what());
  }
}

void Nsga2Solver::check(const Problem& problem) const {
  if (problem.objectives().size() < 2) {
    throw Error("nsga2", "objectives: " + std::to_string(problem.objectives().size()) +
                             " objective(s): a Pareto front needs at least two (use ga for one)");
  }
  if (problem.dimension() == 0) {
    throw Error("nsga2", "no free design variable: give at least one variable bounds instead of a \"value\"");
  }
  (void)pa::Encoding(problem, options_.sort_descending, options_.sort_ascending, "nsga2");
}

SolverResult Nsga2Solver::solve(const Problem& problem, const SolverContext& context) const {
  const Nsga2Options& o = options_;
  const auto start = Clock::now();
  pa::EvaluationSettings settings;
  settings.threads = context.threads;
  settings.over_individuals = o.parallel_over == "individuals";
  settings.sample_chunks = o.sample_chunks;
  auto evaluator = std::make_shared<pa::Evaluator>(
      problem, pa::Encoding(problem, o.sort_descending, o.sort_ascending, "nsga2"), settings, true);
  const pagmo::problem prob = pa::make_problem(evaluator);
  pa::ProgressReporter reporter(context.progress, context.log, o.progress_interval);
  const std::uint64_t seed = pa::derive_seed(context.seed, 0);
  pagmo::algorithm algorithm = make_algorithm(o, seed);
  pagmo::population population = pa::random_population(prob, *evaluator, static_cast<std::size_t>(o.population), seed);

  int generation = 0;
  bool stopped = false;
  while (generation < o.generations) {
    if (context.stop && context.stop->load()) {
      stopped = true;
      break;
    }
    population = algorithm.evolve(population);
    ++generation;
    reporter.line(generation_line(o, generation, population, *evaluator, seconds_since(start)));
  }

  SolverResult result;
  result.front = final_front(problem, population, *evaluator);
  result.design_evaluations = evaluator->design_evaluations();
  result.sample_evaluations = evaluator->sample_evaluations();
  result.statistics = {{"generations", generation},
                       {"front_size", result.front.size()},
                       {"cache_hits", evaluator->cache_hits()},
                       {"repair", evaluator->encoding().describe_repair(problem)},
                       {"evaluation", {{"parallel_over", o.parallel_over}, {"sample_chunks", o.sample_chunks}}},
                       {"solve_seconds", seconds_since(start)}};
  set_status_and_message(o, generation, stopped, result);
  return result;
}

}  // namespace hapsyn::plugins
