#include "nsga2.hpp"

#include "shared/pagmo_adapter.hpp"

#include <hapsyn/cluster.hpp>
#include <hapsyn/checkpoint.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/pareto.hpp>
#include <hapsyn/convergence.hpp>

#include <pagmo/algorithms/nsga2.hpp>
#include <pagmo/batch_evaluators/member_bfe.hpp>
#include <pagmo/bfe.hpp>
#include <pagmo/population.hpp>
#include <pagmo/utils/multi_objective.hpp>

#include <algorithm>
#include <optional>
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
  // pagmo's sorting wants two points or more; one feasible individual is the front alone.
  if (points.size() < 2) return feasible;
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

// The history entry of the population (statistics.history): design evaluations so far, the
// distinct designs of the first front, each objective's ideal (best natural value on that
// front; null without a feasible design) and, for two objectives with the study's reference
// point, the front's hypervolume (hapsyn::hypervolume, as indicators.hypervolume).
Json history_entry(const Problem& problem, const pagmo::population& population, pa::Evaluator& evaluator,
                   const SolverContext& context) {
  const std::vector<Objective>& objectives = problem.objectives();
  std::set<std::vector<double>> designs;
  std::vector<ObjectivePoint> points;
  for (std::size_t i : first_front(population)) {
    const pagmo::vector_double& x = population.get_x()[i];
    if (!designs.insert(evaluator.encoding().decode(x)).second) continue;
    points.push_back(evaluator.record(x).objectives);
  }
  Json ideal = Json::object();
  for (std::size_t k = 0; k < objectives.size(); ++k) {
    std::optional<double> best;
    const bool minimize = objectives[k].sense == Sense::kMinimize;
    for (const ObjectivePoint& p : points) {
      if (!best || (minimize ? p[k] < *best : p[k] > *best)) best = p[k];
    }
    ideal[objectives[k].name] = best ? Json(*best) : Json(nullptr);
  }
  Json entry = {{"evaluations", evaluator.design_evaluations()}, {"front_size", points.size()}, {"ideal", ideal}};
  if (objectives.size() == 2 && context.reference_point.size() == 2) {
    std::vector<Sense> senses;
    for (const Objective& o : objectives) senses.push_back(o.sense);
    entry["hypervolume"] = hypervolume(points, context.reference_point, senses);
  }
  return entry;
}

// The progress line after a generation.
// `done` generations (and `designs` evaluations) in `elapsed` seconds of this process.
std::string generation_line(const Nsga2Options& o, int generation, int done, const pagmo::population& population,
                            long long designs, double elapsed) {
  std::ostringstream line;
  line << "nsga2: gen " << generation << "/" << o.generations << " front " << first_front(population).size() << "/"
       << population.size() << " | " << static_cast<long long>(static_cast<double>(designs) / std::max(1e-9, elapsed))
       << " designs/s | elapsed " << pa::format_duration(elapsed) << ", left "
       << pa::format_duration(elapsed / std::max(1, done) * (o.generations - generation));
  return line.str();
}

// Status and message from how the generations ended.
void set_status_and_message(const Nsga2Options& o, int generation, bool stopped, const SolverContext& context,
                            SolverResult& result) {
  std::ostringstream message;
  if (stopped) {
    result.status = SolverStatus::kStopped;
    message << "stopped on request after " << generation << " of " << o.generations << " generations; front so far: "
            << result.front.size() << " non-dominated designs; "
            << (context.checkpoint_file.empty() ? std::string("no checkpoint file, a new run starts over")
                                                : "checkpoint " + context.checkpoint_file + " written, resume with --resume");
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

// The checkpoint's fingerprint: the study and the options that change the front (not the
// progress interval or the checkpoint period, which a resumed run may change).
std::string fingerprint_of(const Problem& problem, const Nsga2Options& options) {
  Json o = options_to_json(options);
  o.erase("progress_interval");
  o.erase("checkpoint_every");
  return study_fingerprint(problem, o);
}

// The run between generations, as the checkpoint's state holds it.
struct RunState {
  int generation = 0;
  pagmo::algorithm algorithm;
  pagmo::population population;
  long long designs = 0, samples = 0;  // evaluations before this process
  double seconds = 0.0;                // solve time before this process [s]
  ConvergenceHistory history;          // per generation (statistics.history)
};

Json state_to_json(const RunState& run, const pa::Evaluator& evaluator, double seconds) {
  return {{"generation", run.generation},
          {"algorithm", pa::save_algorithm(run.algorithm)},
          {"population_seed", run.population.get_seed()},
          {"x", pa::matrix_to_json(run.population.get_x())},
          {"f", pa::matrix_to_json(run.population.get_f())},
          {"evaluations", {{"designs", evaluator.design_evaluations()}, {"samples", evaluator.sample_evaluations()}}},
          {"elapsed_seconds", seconds},
          {"history", run.history.json()}};
}

// The run from a checkpoint's state. Every individual is re-evaluated (through the evaluator,
// the path the run used, so the values repeat bit for bit) and the checkpoint refused when a
// fitness vector differs from the claimed one: an edited value must never steer the search or
// reach the front. What nlohmann, boost or pagmo throw for a damaged state becomes a bad
// checkpoint naming the file.
RunState restore_state(const SolverContext& context, const Nsga2Options& o, const Json& state,
                       const pagmo::problem& problem, pa::Evaluator& evaluator) {
  RunState run;
  std::vector<pagmo::vector_double> xs, fs;
  try {
    run.generation = state.at("generation").get<int>();
    run.algorithm = pa::load_algorithm(state.at("algorithm").get<std::string>());
    run.population = pagmo::population(problem, 0u, state.at("population_seed").get<unsigned>());
    xs = pa::matrix_from_json(state.at("x"));
    fs = pa::matrix_from_json(state.at("f"));
    run.designs = state.at("evaluations").at("designs").get<long long>();
    run.samples = state.at("evaluations").at("samples").get<long long>();
    run.seconds = state.at("elapsed_seconds").get<double>();
    // Absent in checkpoints of earlier versions: the history starts at the resume.
    if (state.contains("history")) run.history = ConvergenceHistory::from_json(state.at("history"));
    if (xs.size() != fs.size() || xs.size() != static_cast<std::size_t>(o.population)) {
      throw std::invalid_argument(std::to_string(xs.size()) + " decision and " + std::to_string(fs.size()) +
                                  " fitness vectors for a population of " + std::to_string(o.population));
    }
    if (run.generation < 0 || run.generation > o.generations) {
      throw std::invalid_argument("generation " + std::to_string(run.generation) + " outside [0, " +
                                  std::to_string(o.generations) + "]");
    }
    // push_back checks each vector's size against the problem.
    for (std::size_t i = 0; i < xs.size(); ++i) run.population.push_back(xs[i], fs[i]);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw bad_checkpoint(context, std::string("state: ") + e.what());
  }
  pagmo::vector_double all;
  for (const auto& x : xs) all.insert(all.end(), x.begin(), x.end());
  const pagmo::vector_double f = evaluator.batch_fitness(all);
  const std::size_t nf = evaluator.objective_count();
  for (std::size_t i = 0; i < xs.size(); ++i) {
    const pagmo::vector_double again(f.begin() + static_cast<std::ptrdiff_t>(i * nf),
                                     f.begin() + static_cast<std::ptrdiff_t>((i + 1) * nf));
    if (again != fs[i]) {
      std::ostringstream m;
      m.precision(17);
      m << "state.f[" << i << "]: individual " << i << " has fitness " << Json(again).dump()
        << " on re-evaluation, the checkpoint claims " << Json(fs[i]).dump();
      throw bad_checkpoint(context, m.str());
    }
  }
  evaluator.add_counts(run.designs, run.samples);
  return run;
}

}  // namespace

Nsga2Solver::Nsga2Solver(const Nsga2Options& options) : options_(options) {
  const Nsga2Options& o = options_;
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
  settings.cluster = &context.cluster();  // every batch a task farm over the ranks
  auto evaluator = std::make_shared<pa::Evaluator>(
      problem, pa::Encoding(problem, o.sort_descending, o.sort_ascending, "nsga2"), settings, true);
  const pagmo::problem prob = pa::make_problem(evaluator);
  pa::ProgressReporter reporter(context.progress, context.log, o.progress_interval);
  const std::string fingerprint = fingerprint_of(problem, o);

  RunState run;
  if (const std::optional<Json> state = read_checkpoint(context, "nsga2", fingerprint)) {
    run = restore_state(context, o, *state, prob, *evaluator);
    reporter.line("nsga2: resuming from " + context.checkpoint_file + " at generation " + std::to_string(run.generation),
                  true);
  } else {
    if (context.resume) reporter.line("nsga2: no checkpoint to resume from; starting from the beginning", true);
    const std::uint64_t seed = pa::derive_seed(context.seed, 0);
    run.algorithm = make_algorithm(o, seed);
    run.population = pa::random_population(prob, *evaluator, static_cast<std::size_t>(o.population), seed);
    run.history.add(0, history_entry(problem, run.population, *evaluator, context));
  }
  const int first_generation = run.generation;
  const long long designs_before = evaluator->design_evaluations();
  auto save = [&] {
    write_checkpoint(context, "nsga2", fingerprint, state_to_json(run, *evaluator, run.seconds + seconds_since(start)));
  };

  bool stopped = false;
  while (run.generation < o.generations) {
    if (context.stop_requested()) {
      stopped = true;
      save();  // between generations: a resumed run continues exactly from here
      break;
    }
    run.population = run.algorithm.evolve(run.population);
    ++run.generation;
    run.history.add(run.generation, history_entry(problem, run.population, *evaluator, context));
    reporter.line(generation_line(o, run.generation, run.generation - first_generation, run.population,
                                  evaluator->design_evaluations() - designs_before, seconds_since(start)));
    if (o.checkpoint_every > 0 && run.generation % o.checkpoint_every == 0 && run.generation < o.generations) save();
  }

  SolverResult result;
  result.front = final_front(problem, run.population, *evaluator);
  result.design_evaluations = evaluator->design_evaluations();
  result.sample_evaluations = evaluator->sample_evaluations();
  result.statistics = {{"generations", run.generation},
                       {"front_size", result.front.size()},
                       {"cache_hits", evaluator->cache_hits()},
                       {"repair", evaluator->encoding().describe_repair(problem)},
                       {"evaluation", {{"parallel_over", o.parallel_over}, {"sample_chunks", o.sample_chunks}}},
                       {"solve_seconds", run.seconds + seconds_since(start)},
                       {"history", run.history.json()}};
  set_status_and_message(o, run.generation, stopped, context, result);
  return result;
}

}  // namespace hapsyn::plugins
