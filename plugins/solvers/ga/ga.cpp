#include "ga.hpp"

#include "ga_checkpoint.hpp"
#include "ga_summary.hpp"
#include "shared/pagmo_adapter.hpp"

#include <hapsyn/cluster.hpp>
#include <hapsyn/checkpoint.hpp>
#include <hapsyn/error.hpp>

#include <pagmo/algorithms/gaco.hpp>
#include <pagmo/algorithms/sga.hpp>
#include <pagmo/batch_evaluators/member_bfe.hpp>
#include <pagmo/bfe.hpp>
#include <pagmo/population.hpp>

#include <boost/filesystem.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace hapsyn::plugins {

namespace pa = pagmo_adapter;
using ga::with_digits;

namespace {

using Clock = std::chrono::steady_clock;

// The evaluator's fidelity levels (its cache keeps the values of each apart).
constexpr int kFullLevel = 0;
constexpr int kSubsetLevel = 1;
constexpr int kRefineLevel = 2;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

pagmo::algorithm make_algorithm(const GaOptions& o, std::uint64_t seed) {
  const unsigned s = static_cast<unsigned>(seed ^ (seed >> 32));
  if (o.algorithm == "gaco") {
    const GaGacoOptions& g = o.gaco;
    pagmo::gaco gaco(1u, static_cast<unsigned>(g.ker), g.q, g.oracle, g.acc, static_cast<unsigned>(g.threshold),
                     static_cast<unsigned>(g.n_gen_mark), 100000u, 100000u, g.focus, true, s);
    gaco.set_bfe(pagmo::bfe{pagmo::member_bfe{}});
    return pagmo::algorithm{gaco};
  }
  const GaSgaOptions& g = o.sga;
  return pagmo::algorithm{pagmo::sga(1u, g.crossover_probability, g.eta_c, g.mutation_probability, g.param_m,
                                     static_cast<unsigned>(g.param_s), g.crossover, g.mutation, g.selection, s)};
}

// A deterministic, stratified subset: m samples evenly spaced in sample index order (the scene's
// own order: lattice positions, then orientations for human_arm).
std::vector<int> stratified_subset(int samples, double fraction) {
  const long long m = std::max<long long>(1, static_cast<long long>(std::ceil(fraction * samples)));
  std::vector<int> subset;
  for (long long j = 0; j < m; ++j) subset.push_back(static_cast<int>(j * samples / m));
  return subset;
}

// The best feasible individual of a population (lowest fitness); -1 when none is feasible.
long long best_feasible(const pagmo::population& population) {
  const auto& f = population.get_f();
  long long best = -1;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (f[i][0] >= pa::kSampleFailedFitness) continue;
    if (best < 0 || f[i][0] < f[static_cast<std::size_t>(best)][0]) best = static_cast<long long>(i);
  }
  return best;
}

// Best and mean score of a population's feasible individuals at the current fidelity.
struct PopulationFigures {
  double best = -INFINITY;
  double mean = 0.0;
  int feasible = 0;
};

PopulationFigures population_figures(const pagmo::population& population) {
  PopulationFigures figures;
  double sum = 0.0;
  for (const auto& f : population.get_f()) {
    if (f[0] >= pa::kSampleFailedFitness) continue;
    figures.best = std::max(figures.best, -f[0]);
    sum += -f[0];
    ++figures.feasible;
  }
  if (figures.feasible > 0) figures.mean = sum / figures.feasible;
  return figures;
}

pa::EvaluationSettings evaluation_settings(const GaOptions& options, int threads) {
  pa::EvaluationSettings settings;
  settings.threads = threads;
  settings.over_individuals = options.parallel_over == "individuals";
  settings.sample_chunks = options.sample_chunks;
  return settings;
}

// One call of GaSolver::solve: the runs, with their checkpoints and progress lines, then the
// summary. Holds what the steps share; the multi-fidelity subset is a member the runs'
// evaluators point to, so a search is neither copied nor moved.
//
// Runs go one after another (each generation's batches a task farm over the ranks), or, under
// --shard or with at least as many runs as ranks, as one shardable task farm: one run per task,
// evaluated on its rank alone. Every run has its own evaluator and the evaluator's cache is
// exact (shared/pagmo_adapter.hpp), so a run's result depends only on the seed and its index.
class GaSearch {
 public:
  GaSearch(const GaOptions& options, const Problem& problem, const SolverContext& context);
  GaSearch(const GaSearch&) = delete;
  GaSearch& operator=(const GaSearch&) = delete;

  /// With SolverContext::resume: the finished runs, counters and the run in progress from the
  /// checkpoint file (or a log line that there is none). Collective (read_checkpoint).
  /// \throws Error for a bad checkpoint (on every rank alike)
  void resume_from_checkpoint();
  /// Runs the runs not finished yet, until the stop flag is set or the shard's share is done.
  void run_remaining();
  /// The result over the finished runs (ga_summary.hpp).
  SolverResult summary();

 private:
  // A run in progress.
  struct Run {
    ga::RunState state;
    std::shared_ptr<pa::Evaluator> evaluator;
    pagmo::problem problem;
    pagmo::algorithm algorithm;
    pagmo::population population;
    Clock::time_point clock;
    std::string status = "budget_exhausted";
    const SolverContext* context = nullptr;  // what the run sees (SolverContext::in_task() in a farm)
    bool in_task = false;                    // a task of the runs farm: no progress lines, no checkpoints
  };
  // A finished run: its record (statistics.runs) and time.
  struct Finished {
    Json record;
    double seconds = 0.0;
  };

  std::unique_ptr<Run> make_run(int index, const SolverContext& context, int threads, Cluster* cluster,
                                bool in_task) const;
  void start_run(Run& run) const;
  void use_stage_samples(Run& run) const;
  bool evolve(Run& run);
  bool note_best(ga::RunState& state, const pagmo::population& population) const;
  void switch_fidelity(Run& run, bool to_full_scene);
  void finish_run(Run& run);
  void rank_on_full_scene(Run& run);
  void report_generation(const Run& run);
  void record_generation(Run& run, bool final_ranking) const;
  Json run_record(const Run& run) const;
  void add_finished(const Json& record, double seconds);
  void run_one_after_another(const std::vector<int>& todo);
  void run_as_farm(const std::vector<int>& todo);
  void write_checkpoint(const Run* run) const;
  void check_claimed_best(const pagmo::vector_double& x, double claimed, const std::string& what) const;

  const GaOptions& options_;
  const Problem& problem_;
  const SolverContext& context_;
  const Clock::time_point start_;
  const pa::Encoding encoding_;
  const bool multi_fidelity_;
  const std::vector<int> subset_;  // the multi-fidelity subset (empty without one)
  const std::vector<int> refine_subset_;  // the refine subset (empty: the switch goes to the full scene)
  pa::ProgressReporter reporter_;
  const std::string fingerprint_;

  std::map<int, Finished> finished_;  // by run index
  // Evaluations of every run so far (the checkpoint's before a resume, then the finished runs'
  // of this process); cache hits of this process.
  long long designs_ = 0, samples_ = 0, cache_hits_ = 0;
  double seconds_before_resume_ = 0.0;
  std::optional<Json> resumed_;  // the checkpoint's run in progress
  bool stopped_ = false;
  bool partial_ = false;  // a shard's share done
  int total_generations_done_ = 0;
  Clock::time_point solve_clock_;
};

GaSearch::GaSearch(const GaOptions& options, const Problem& problem, const SolverContext& context)
    : options_(options),
      problem_(problem),
      context_(context),
      start_(Clock::now()),
      encoding_(problem, options.sort_descending, options.sort_ascending, "ga"),
      multi_fidelity_(options.fidelity.generations > 0),
      subset_(multi_fidelity_ ? stratified_subset(problem.samples().size(), options.fidelity.subset_fraction)
                              : std::vector<int>{}),
      refine_subset_(multi_fidelity_ && options.fidelity.refine_fraction < 1.0
                         ? stratified_subset(problem.samples().size(), options.fidelity.refine_fraction)
                         : std::vector<int>{}),
      reporter_(context.progress, context.log, options.progress_interval),
      fingerprint_(study_fingerprint(problem, options_to_json(options))) {}

void GaSearch::resume_from_checkpoint() {
  if (!context_.resume) return;
  const std::optional<Json> state = read_checkpoint(context_, "ga", fingerprint_);
  if (!state) {
    reporter_.line("ga: no checkpoint to resume from; starting from the beginning", true);
    return;
  }
  ga::Checkpoint checkpoint = ga::checkpoint_from_state(context_, *state);
  // The claimed optima are re-evaluated: an edited score must never become the study's best.
  // Finished runs are listed by run index (all of them, or a shard's share, or a merge of shards).
  int previous = -1;
  for (std::size_t i = 0; i < checkpoint.completed_runs.size(); ++i) {
    const Json& run = checkpoint.completed_runs[i];
    const std::string path = "state.completed_runs[" + std::to_string(i) + "]";
    // The fields the summary reads, checked here: a damaged record is a checkpoint error, not a
    // raw JSON exception at the end of the solve.
    pagmo::vector_double x;
    double score = 0.0;
    std::vector<double> free;
    try {
      const int index = run.at("run").get<int>();
      if (index <= previous || index >= options_.runs) {
        throw std::invalid_argument("run " + std::to_string(index) + " is not after the previous record's (" +
                                    std::to_string(previous) + ") and below options.runs (" +
                                    std::to_string(options_.runs) + ")");
      }
      previous = index;
      if (run.at("seed").get<std::uint64_t>() != pa::derive_seed(context_.seed, static_cast<std::uint64_t>(index))) {
        throw std::invalid_argument("seed is not the one of run " + std::to_string(index) + " of the study seed");
      }
      if (run.contains("history")) (void)ConvergenceHistory::from_json(run.at("history"));
      if (run.at("status").get<std::string>() == "infeasible") continue;  // no optimum to check
      x = run.at("x").get<pagmo::vector_double>();
      score = run.at("score").get<double>();
      free = run.at("free").get<std::vector<double>>();
      for (const Objective& o : problem_.objectives()) (void)run.at("objectives").at(o.name).get<double>();
      if (!run.at("design").is_object()) throw std::invalid_argument("design is not an object");
    } catch (const std::exception& e) {
      throw bad_checkpoint(context_, path + ": " + e.what());
    }
    check_claimed_best(x, score, path);
    if (free != encoding_.decode(x)) throw bad_checkpoint(context_, path + ": free does not match the decoded x");
  }
  if (checkpoint.current) {
    const int index = checkpoint.current->at("run").get<int>();
    if (index < 0 || index >= options_.runs) {
      throw bad_checkpoint(context_, "state.current: run " + std::to_string(index) + " outside 0.." +
                                         std::to_string(options_.runs - 1));
    }
    for (const Json& run : checkpoint.completed_runs) {
      if (run.at("run").get<int>() == index) {
        throw bad_checkpoint(context_, "state.current: run " + std::to_string(index) + " is also a finished run");
      }
    }
  }
  if (checkpoint.current) {
    // Restored here once, so that a damaged run in progress is refused before any task farm,
    // alike on every rank (inside a farm an exception ends an MPI job).
    ga::RunState trial;
    pagmo::algorithm algorithm;
    pagmo::population population;
    const auto evaluator =
        std::make_shared<pa::Evaluator>(problem_, encoding_, evaluation_settings(options_, 1), false);
    ga::restore_run(context_, *checkpoint.current, pa::make_problem(evaluator), trial, algorithm, population);
  }
  if (checkpoint.current && checkpoint.current->contains("best_x")) {
    try {
      const pagmo::vector_double x = checkpoint.current->at("best_x").get<pagmo::vector_double>();
      if (!x.empty()) check_claimed_best(x, checkpoint.current->at("best_score").get<double>(), "state.current");
    } catch (const Json::exception& e) {
      throw bad_checkpoint(context_, std::string("state.current: ") + e.what());
    }
  }
  for (std::size_t i = 0; i < checkpoint.completed_runs.size(); ++i) {
    const Json& run = checkpoint.completed_runs[i];
    finished_[run.at("run").get<int>()] = Finished{run, checkpoint.run_seconds[i]};
  }
  designs_ = checkpoint.designs;
  samples_ = checkpoint.samples;
  seconds_before_resume_ = checkpoint.elapsed_seconds;
  resumed_ = std::move(checkpoint.current);
  reporter_.line("ga: resuming from " + context_.checkpoint_file + ": " + std::to_string(finished_.size()) +
                     " run(s) finished" +
                     (resumed_ ? ", run " + std::to_string(resumed_->at("run").get<int>() + 1) + " at generation " +
                                     std::to_string(resumed_->at("generation").get<int>())
                               : std::string()),
                 true);
}

// Re-evaluates a claimed optimum (pagmo vector) on the full scene, outside the runs' evaluators
// (their caches and counters stay those of an uninterrupted run), and refuses the checkpoint
// when the score differs. 1e-9 relative: over the individuals a run evaluates each design in
// sample order, this check splits it over sample chunks, and an averaging metric's sum may
// round differently (worst-case metrics agree exactly); an edit is far larger.
void GaSearch::check_claimed_best(const pagmo::vector_double& x, double claimed, const std::string& what) const {
  if (x.size() != encoding_.size()) {
    throw bad_checkpoint(context_, what + ": best has " + std::to_string(x.size()) + " components, the study " +
                                       std::to_string(encoding_.size()));
  }
  const std::vector<double> free = encoding_.decode(x);
  Problem::ParallelOptions options;
  options.chunks = options_.sample_chunks;
  const Evaluation e = problem_.evaluate_parallel(free.data(), context_.threads, options);
  if (e.status != EvalStatus::kFeasible || !(std::abs(e.score - claimed) <= 1e-9 * std::max(1.0, std::abs(claimed)))) {
    std::ostringstream m;
    m.precision(17);
    m << what << ": its best design scores " << e.score << " (" << to_string(e.status)
      << ") on re-evaluation, the checkpoint claims " << claimed;
    throw bad_checkpoint(context_, m.str());
  }
}

void GaSearch::run_remaining() {
  solve_clock_ = Clock::now();
  std::vector<int> todo;
  for (int r = 0; r < options_.runs; ++r) {
    if (!finished_.count(r)) todo.push_back(r);
  }
  if (todo.empty()) return;
  const Cluster& cluster = context_.cluster();
  // Runs over ranks when there are at least as many as ranks (no generation waits for another
  // rank), and also with fewer runs when that leaves fewer design evaluations per generation on
  // the busiest thread than spreading each run's batches: 31 runs on 64 ranks of 32 threads:
  // ceil(31/64) * ceil(200/32) = 7 against 31 * ceil(200/2048) = 31, so the runs. Both give the
  // same result; the choice is the same on every rank (the finished runs come from the same
  // checkpoint).
  const auto ceil_div = [](long long a, long long b) { return (a + b - 1) / b; };
  const long long ranks = cluster.size(), threads = std::max(1, context_.threads), population = options_.population;
  const long long runs = static_cast<long long>(todo.size());
  const bool runs_cheaper = ceil_div(runs, ranks) * ceil_div(population, threads) <= runs * ceil_div(population, ranks * threads);
  const bool farm = cluster.shard().second > 1 || (ranks > 1 && (runs >= ranks || runs_cheaper));
  if (farm) {
    run_as_farm(todo);
  } else {
    run_one_after_another(todo);
  }
}

// A run's evaluation: its own evaluator (and cache) on `threads` threads, its batches farmed
// over `cluster` (null: this process).
std::unique_ptr<GaSearch::Run> GaSearch::make_run(int index, const SolverContext& context, int threads,
                                                  Cluster* cluster, bool in_task) const {
  auto run = std::make_unique<Run>();
  pa::EvaluationSettings settings = evaluation_settings(options_, threads);
  settings.cluster = cluster;
  run->evaluator = std::make_shared<pa::Evaluator>(problem_, encoding_, settings, false);
  run->problem = pa::make_problem(run->evaluator);
  run->state.run = index;
  run->clock = Clock::now();
  run->context = &context;
  run->in_task = in_task;
  return run;
}

void GaSearch::run_one_after_another(const std::vector<int>& todo) {
  for (int r : todo) {
    if (context_.stop_requested()) {
      // Before a run starts: the checkpoint on disk (between runs, or the resumed one) stands.
      stopped_ = true;
      break;
    }
    const std::unique_ptr<Run> run = make_run(r, context_, context_.threads, &context_.cluster(), false);
    start_run(*run);
    if (!evolve(*run)) stopped_ = true;  // the checkpoint is written
    finish_run(*run);  // the final ranking on the full scene
    if (stopped_ && run->state.best_x.empty()) break;
    // A stopped run's best so far is in the result; the checkpoint keeps the run in progress.
    designs_ += run->evaluator->design_evaluations();
    samples_ += run->evaluator->sample_evaluations();
    cache_hits_ += run->evaluator->cache_hits();
    add_finished(run_record(*run), run->state.seconds_before + seconds_since(run->clock));
    if (stopped_) break;
    write_checkpoint(nullptr);
  }
}

// The runs as one shardable task farm over the run indices (a shard runs its contiguous share):
// each task a whole run on its rank (SolverContext::in_task()), its record collected on rank 0
// and checkpointed there, then broadcast so every rank returns the same result. A run a stop
// interrupts is not done: it starts over on resume (the checkpoint keeps the finished runs, and
// a resumed run in progress until it finishes).
void GaSearch::run_as_farm(const std::vector<int>& todo) {
  Cluster& cluster = context_.cluster();
  if (context_.stop_requested()) {
    stopped_ = true;
    return;
  }
  // Several runs per rank: one per thread; fewer: each run splits its batches over the threads.
  const long long ranks = static_cast<long long>(cluster.size()) * cluster.shard().second;
  const long long per_rank = (static_cast<long long>(todo.size()) + ranks - 1) / ranks;
  const int farm_threads = static_cast<int>(std::max(1LL, std::min<long long>(context_.threads, per_rank)));
  const int run_threads = std::max(1, context_.threads / farm_threads);
  reporter_.line("ga: " + std::to_string(todo.size()) + " run(s) as tasks over " + std::to_string(cluster.size()) +
                     " rank(s), " + std::to_string(farm_threads) + " run(s) at a time per rank, " +
                     std::to_string(run_threads) + " thread(s) each",
                 true);
  std::mutex mutex;  // collect and on_abort
  TaskFarm farm;
  farm.count = options_.runs;
  farm.shardable = true;
  // Done before the farm (collect adds to finished_ while tasks run).
  std::vector<char> done(static_cast<std::size_t>(options_.runs), 1);
  for (int r : todo) done[static_cast<std::size_t>(r)] = 0;
  farm.done = [&done](long long index) { return done[static_cast<std::size_t>(index)] != 0; };
  farm.run = [this, run_threads](long long index, int) -> std::optional<std::string> {
    const SolverContext task = context_.in_task();
    const std::unique_ptr<Run> run = make_run(static_cast<int>(index), task, run_threads, nullptr, true);
    start_run(*run);
    if (!evolve(*run)) return std::nullopt;
    finish_run(*run);
    Json result;
    result["record"] = run_record(*run);
    result["seconds"] = run->state.seconds_before + seconds_since(run->clock);
    result["designs"] = run->evaluator->design_evaluations();
    result["samples"] = run->evaluator->sample_evaluations();
    result["cache_hits"] = run->evaluator->cache_hits();
    return result.dump();
  };
  farm.collect = [this, &mutex](long long, std::string&& bytes) {
    const Json result = Json::parse(bytes);
    std::lock_guard<std::mutex> lock(mutex);
    designs_ += result.at("designs").get<long long>();
    samples_ += result.at("samples").get<long long>();
    cache_hits_ += result.at("cache_hits").get<long long>();
    add_finished(result.at("record"), result.at("seconds").get<double>());
    write_checkpoint(nullptr);
  };
  farm.on_abort = [this, &mutex] {
    std::lock_guard<std::mutex> lock(mutex);
    write_checkpoint(nullptr);
  };
  const FarmOutcome outcome = cluster.run_tasks(farm, farm_threads);
  stopped_ = outcome.stopped;
  partial_ = outcome.partial;
  if (cluster.size() > 1) {
    // What rank 0 collected, on every rank (the same result everywhere).
    std::string bytes;
    if (cluster.root()) {
      Json all = Json::array();
      for (const auto& [index, f] : finished_) all.push_back({{"record", f.record}, {"seconds", f.seconds}});
      bytes = Json{{"finished", all}, {"designs", designs_}, {"samples", samples_}, {"cache_hits", cache_hits_}}.dump();
    }
    cluster.broadcast(bytes);
    if (!cluster.root()) {
      const Json all = Json::parse(bytes);
      finished_.clear();
      for (const Json& f : all.at("finished")) {
        finished_[f.at("record").at("run").get<int>()] = Finished{f.at("record"), f.at("seconds").get<double>()};
      }
      designs_ = all.at("designs").get<long long>();
      samples_ = all.at("samples").get<long long>();
      cache_hits_ = all.at("cache_hits").get<long long>();
    }
  }
  write_checkpoint(nullptr);
}

// Points the run's evaluator at the samples of its stage: the subset before the switch, the
// refine subset while refining, else the full scene (each at its own cache level). A study
// without a subset is on the full scene whatever a checkpoint says.
void GaSearch::use_stage_samples(Run& run) const {
  const ga::RunState& state = run.state;
  if (multi_fidelity_ && !state.switched) {
    run.evaluator->set_subset(&subset_, kSubsetLevel);
  } else if (state.refining) {
    run.evaluator->set_subset(&refine_subset_, kRefineLevel);
  } else {
    run.evaluator->set_subset(nullptr, kFullLevel);
  }
}

// A fresh run (random population from the run's seed), or the checkpoint's run in progress.
void GaSearch::start_run(Run& run) const {
  ga::RunState& state = run.state;
  pa::Evaluator& evaluator = *run.evaluator;
  if (resumed_ && resumed_->at("run").get<int>() == state.run) {
    ga::restore_run(context_, *resumed_, run.problem, state, run.algorithm, run.population);
    use_stage_samples(run);
  } else {
    const std::uint64_t seed = pa::derive_seed(context_.seed, static_cast<std::uint64_t>(state.run));
    state.switched = !multi_fidelity_;
    use_stage_samples(run);
    run.algorithm = make_algorithm(options_, seed);
    run.population =
        pa::random_population(run.problem, evaluator, static_cast<std::size_t>(options_.population), seed);
    record_generation(run, false);
  }
  if (state.switched && state.generation == 0) note_best(state, run.population);
}

// Generations until the limit, convergence or the stop flag (false: stopped; outside a farm the
// checkpoint is written); checkpoints on the way. Under MPI the flag changes inside task farms
// only, on every rank alike, so every rank leaves the loop at the same generation.
bool GaSearch::evolve(Run& run) {
  ga::RunState& state = run.state;
  while (state.generation < options_.generations) {
    if (run.context->stop_requested()) {
      run.status = "stopped";
      if (!run.in_task) write_checkpoint(&run);  // between generations: a resumed run continues exactly from here
      return false;
    }
    if (!state.switched && state.generation >= options_.fidelity.generations) switch_fidelity(run, false);
    // sga asks for its offspring one at a time: evaluated first as one batch (over the ranks).
    if (options_.algorithm == "sga") run.evaluator->prefetch(run.algorithm, run.population);
    run.population = run.algorithm.evolve(run.population);
    ++state.generation;
    if (state.switched) {
      state.stall = note_best(state, run.population) ? 0 : state.stall + 1;
    }
    record_generation(run, false);
    if (!run.in_task) {
      ++total_generations_done_;
      report_generation(run);
    }
    if (state.switched && state.stall >= options_.stall_generations) {
      run.status = "converged";
      return true;
    }
    if (!run.in_task && options_.checkpoint_every > 0 && state.generation % options_.checkpoint_every == 0 &&
        state.generation < options_.generations) {
      write_checkpoint(&run);
    }
  }
  return true;
}

// The population's best at full fidelity becomes the run's best when better; true when it
// improved by more than ftol (a smaller improvement is kept but counts as stalling).
bool GaSearch::note_best(ga::RunState& state, const pagmo::population& population) const {
  const long long b = best_feasible(population);
  if (b < 0) return false;
  const double score = -population.get_f()[static_cast<std::size_t>(b)][0];
  if (state.best_x.empty() || score > state.best_score + options_.ftol) {
    state.best_score = score;
    state.best_x = population.get_x()[static_cast<std::size_t>(b)];
    return true;
  }
  if (score > state.best_score) {
    state.best_score = score;
    state.best_x = population.get_x()[static_cast<std::size_t>(b)];
  }
  return false;
}

// The multi-fidelity switch after the subset generations: the population re-evaluated on the
// refine subset (fidelity.refine_fraction < 1, unless `to_full_scene`) or on the full scene;
// stalling is counted from here.
void GaSearch::switch_fidelity(Run& run, bool to_full_scene) {
  ga::RunState& state = run.state;
  const long long b = best_feasible(run.population);
  const double subset_best = b >= 0 ? -run.population.get_f()[static_cast<std::size_t>(b)][0] : -INFINITY;
  state.refining = !to_full_scene && !refine_subset_.empty();
  state.switched = true;
  use_stage_samples(run);
  pa::reevaluate(run.population, *run.evaluator);
  state.stall = 0;
  note_best(state, run.population);
  if (run.in_task) return;
  const std::string where = state.refining ? "the refine subset (" + std::to_string(refine_subset_.size()) + " samples)"
                                           : std::string("the full scene");
  reporter_.line("ga: run " + std::to_string(state.run + 1) + " generation " + std::to_string(state.generation) +
                     ": fidelity switch, population re-evaluated on " + where + " (best " + with_digits(subset_best) +
                     " on the subset, " + with_digits(state.best_score) + " on " + where + ")",
                 true);
}

// A run that ended (converged, budget spent or stopped) gets its best from the full scene: the
// whole population re-evaluated when it never left the subset, its best candidates when it
// ended on the refine subset.
void GaSearch::finish_run(Run& run) {
  const long long before = run.evaluator->design_evaluations();
  if (!run.state.switched) {
    switch_fidelity(run, true);
  } else if (run.state.refining) {
    rank_on_full_scene(run);
  }
  if (run.evaluator->design_evaluations() > before) record_generation(run, true);
}

// The refine stage's end: the final_candidates best of the population (at the refine fidelity,
// best first; feasible before infeasible, as pagmo ranks) evaluated on the full scene, and the
// run's best chosen among them. The population itself is left as the run ended.
void GaSearch::rank_on_full_scene(Run& run) {
  ga::RunState& state = run.state;
  const auto& f = run.population.get_f();
  const auto& x = run.population.get_x();
  std::vector<std::size_t> order(f.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&f](std::size_t a, std::size_t b) { return f[a][0] < f[b][0]; });
  const std::size_t count = std::min(order.size(), static_cast<std::size_t>(options_.fidelity.final_candidates));
  const double refine_best = state.best_score;
  pagmo::population candidates(run.problem, 0u, 0u);
  for (std::size_t k = 0; k < count; ++k) candidates.push_back(x[order[k]], f[order[k]]);
  state.refining = false;
  use_stage_samples(run);
  pa::reevaluate(candidates, *run.evaluator);
  state.best_x.clear();
  state.best_score = -INFINITY;
  note_best(state, candidates);
  if (run.in_task) return;
  reporter_.line("ga: run " + std::to_string(state.run + 1) + ": its " + std::to_string(count) +
                     " best ranked on the full scene (best " + with_digits(refine_best) + " on the refine subset, " +
                     with_digits(state.best_score) + " on the full scene)",
                 true);
}

// The progress line of a generation: best and mean of the feasible individuals at the current
// fidelity, speed, stall count, time.
void GaSearch::report_generation(const Run& run) {
  const ga::RunState& state = run.state;
  const PopulationFigures figures = population_figures(run.population);
  const int generations = options_.generations;
  const double elapsed = seconds_since(solve_clock_);
  const double per_generation = elapsed / std::max(1, total_generations_done_);
  const double left =
      per_generation * ((generations - state.generation) + static_cast<double>(options_.runs - state.run - 1) * generations);
  const double designs_per_second = run.evaluator->design_evaluations() / std::max(1e-9, seconds_since(run.clock));
  std::ostringstream line;
  line << "ga: run " << (state.run + 1) << "/" << options_.runs << " gen " << state.generation << "/" << generations
       << (state.switched ? (state.refining ? " (refine)" : "") : " (subset)") << " best " << with_digits(figures.best)
       << " mean " << (figures.feasible ? with_digits(figures.mean) : std::string("-")) << " feasible " << figures.feasible << "/"
       << run.population.size() << " | " << with_digits(designs_per_second, 4) << " designs/s | stall " << state.stall
       << "/" << options_.stall_generations << " | elapsed "
       << pa::format_duration(seconds_before_resume_ + seconds_since(start_)) << ", left <= " << pa::format_duration(left);
  reporter_.line(line.str());
}

// The run's history entry after a generation (or generation 0, the initial population): the
// population's best and mean score at its fidelity. The final ranking of a multi-fidelity run
// on the full scene adds an entry of the same generation with the run's best (its reported
// score) and no mean (the ranked candidates are not the population).
void GaSearch::record_generation(Run& run, bool final_ranking) const {
  ga::RunState& state = run.state;
  const PopulationFigures figures = population_figures(run.population);
  const auto number = [](bool has, double v) { return has ? Json(v) : Json(nullptr); };
  Json entry;
  entry["evaluations"] = state.designs + run.evaluator->design_evaluations();
  entry["best"] = final_ranking ? number(!state.best_x.empty(), state.best_score) : number(figures.feasible > 0, figures.best);
  entry["mean"] = final_ranking ? Json(nullptr) : number(figures.feasible > 0, figures.mean);
  if (multi_fidelity_) entry["fidelity"] = !state.switched ? "subset" : state.refining ? "refine" : "full";
  state.history.add(state.generation, entry);
}

// The run's record (statistics.runs).
Json GaSearch::run_record(const Run& run) const {
  const ga::RunState& state = run.state;
  Json record;
  record["run"] = state.run;
  record["seed"] = pa::derive_seed(context_.seed, static_cast<std::uint64_t>(state.run));
  record["generations"] = state.generation;
  record["designs"] = state.designs + run.evaluator->design_evaluations();
  record["history"] = state.history.json();
  if (state.best_x.empty()) {
    record["status"] = "infeasible";
  } else {
    const pa::DesignRecord& best = run.evaluator->record(state.best_x);
    const std::vector<double> free = encoding_.decode(state.best_x);
    const Eigen::VectorXd full = problem_.full_design(free.data());
    record["status"] = run.status;
    record["x"] = state.best_x;
    record["free"] = free;
    record["design"] = problem_.design_to_json(full);
    record["score"] = best.score;
    Json objectives = Json::object();
    for (std::size_t i = 0; i < problem_.objectives().size(); ++i) objectives[problem_.objectives()[i].name] = best.objectives[i];
    record["objectives"] = objectives;
  }
  return record;
}

// A finished run: kept by index, with its log line.
void GaSearch::add_finished(const Json& record, double seconds) {
  const int index = record.at("run").get<int>();
  finished_[index] = Finished{record, seconds};
  reporter_.line("ga: run " + std::to_string(index + 1) + "/" + std::to_string(options_.runs) + " " +
                     record.at("status").get<std::string>() + " after " +
                     std::to_string(record.at("generations").get<int>()) + " generations, " +
                     std::to_string(record.at("designs").get<long long>()) + " designs, " +
                     pa::format_duration(seconds) +
                     (record.contains("score") ? ": score " + with_digits(record.at("score").get<double>(), 8)
                                               : std::string()) +
                     " (" + std::to_string(finished_.size()) + " of " + std::to_string(options_.runs) + " done)",
                 true);
}

// The checkpoint file: the finished runs and counters, and the run in progress: `run`, or the
// resumed one while it is not finished.
void GaSearch::write_checkpoint(const Run* run) const {
  if (context_.checkpoint_file.empty()) return;
  ga::Checkpoint checkpoint;
  for (const auto& [index, f] : finished_) {
    checkpoint.completed_runs.push_back(f.record);
    checkpoint.run_seconds.push_back(f.seconds);
  }
  checkpoint.designs = designs_;
  checkpoint.samples = samples_;
  checkpoint.elapsed_seconds = seconds_before_resume_ + seconds_since(start_);
  if (run) {
    ga::RunState saved = run->state;
    saved.seconds_before += seconds_since(run->clock);
    saved.designs += run->evaluator->design_evaluations();
    checkpoint.designs += run->evaluator->design_evaluations();
    checkpoint.samples += run->evaluator->sample_evaluations();
    checkpoint.current = ga::run_to_json(saved, run->algorithm, run->population);
  } else if (resumed_ && !finished_.count(resumed_->at("run").get<int>())) {
    checkpoint.current = *resumed_;
  }
  hapsyn::write_checkpoint(context_, "ga", fingerprint_, ga::checkpoint_to_state(checkpoint));
}

SolverResult GaSearch::summary() {
  ga::SolveFigures figures;
  figures.stopped = stopped_ || partial_;
  figures.solve_seconds = seconds_before_resume_ + seconds_since(start_);
  figures.design_evaluations = designs_;
  figures.sample_evaluations = samples_;
  figures.cache_hits = cache_hits_;
  figures.repair = encoding_.describe_repair(problem_);
  figures.subset_samples = subset_.size();
  figures.refine_samples = refine_subset_.size();
  Json runs = Json::array();
  std::vector<double> run_seconds;
  for (const auto& [index, f] : finished_) {
    runs.push_back(f.record);
    run_seconds.push_back(f.seconds);
  }
  SolverResult result = ga::summarise_runs(problem_, options_, runs, run_seconds, figures, context_.seed, reporter_);
  if (partial_ && !stopped_) {
    result.message = context_.cluster().shard_message();
  } else if (stopped_) {
    result.message += context_.checkpoint_file.empty()
                          ? "; best so far; no checkpoint file, a new run starts over"
                          : "; best so far; checkpoint " + context_.checkpoint_file + " written, resume with --resume";
  }
  return result;
}

}  // namespace

GaSolver::GaSolver(const GaOptions& options) : options_(options) {
  // The relations between the options are declared rules (ga_options.hpp), checked before this runs.
  const GaOptions& o = options_;
  try {
    (void)make_algorithm(o, 1);
  } catch (const std::invalid_argument& e) {
    throw Error("ga", std::string("options.") + o.algorithm + ": pagmo refuses the parameters: " + e.what());
  }
}

void GaSolver::check(const Problem& problem) const {
  if (problem.dimension() == 0) {
    throw Error("ga", "no free design variable: the GA needs at least one variable with bounds instead of a \"value\"");
  }
  (void)pa::Encoding(problem, options_.sort_descending, options_.sort_ascending, "ga");
  for (std::size_t i = 0; i < options_.cluster_variables.size(); ++i) {
    bool found = false;
    for (const DesignComponent& c : problem.design_space().components()) found = found || c.variable == options_.cluster_variables[i];
    if (!found) {
      throw Error("ga", "options.cluster_variables[" + std::to_string(i) + "] = \"" + options_.cluster_variables[i] +
                            "\": no such design variable");
    }
  }
}

Json GaSolver::merge_shards(const Problem& problem, const std::vector<Json>& states) const {
  (void)problem;
  ga::Checkpoint merged;
  std::map<int, std::pair<Json, double>> runs;
  std::map<int, std::size_t> owner;  // run -> shard
  for (std::size_t s = 0; s < states.size(); ++s) {
    const std::string shard = "shard " + std::to_string(s + 1) + " of " + std::to_string(states.size());
    const Json& state = states[s];
    try {
      const Json& completed = state.at("completed_runs");
      const auto seconds = state.at("run_seconds").get<std::vector<double>>();
      if (!completed.is_array() || seconds.size() != completed.size()) {
        throw std::invalid_argument("completed_runs and run_seconds do not match");
      }
      if (state.contains("current")) {
        throw Error("merge", shard + " has run " + std::to_string(state.at("current").at("run").get<int>() + 1) +
                                 " in progress: finish the shard (hapsyn run --shard i/N --resume) before merging");
      }
      for (std::size_t i = 0; i < completed.size(); ++i) {
        const int r = completed[i].at("run").get<int>();
        if (r < 0 || r >= options_.runs) {
          throw Error("merge", shard + ": run " + std::to_string(r + 1) + " outside 1.." +
                                   std::to_string(options_.runs) + " (options.runs)");
        }
        if (owner.count(r)) {
          throw Error("merge", "shards " + std::to_string(owner[r] + 1) + " and " + std::to_string(s + 1) +
                                   " both hold run " + std::to_string(r + 1) +
                                   ": the shares overlap (give each shard of one job array once)");
        }
        owner[r] = s;
        runs[r] = {completed[i], seconds[i]};
      }
      merged.designs += state.at("evaluations").at("designs").get<long long>();
      merged.samples += state.at("evaluations").at("samples").get<long long>();
      merged.elapsed_seconds = std::max(merged.elapsed_seconds, state.at("elapsed_seconds").get<double>());
    } catch (const Error&) {
      throw;
    } catch (const std::exception& e) {
      throw Error("merge", shard + ": damaged ga state: " + e.what());
    }
  }
  for (int r = 0; r < options_.runs; ++r) {
    if (!runs.count(r)) {
      throw Error("merge", "run " + std::to_string(r + 1) + " of " + std::to_string(options_.runs) +
                               " is in no shard: every shard must finish (hapsyn run --shard i/N --resume) "
                               "before merging");
    }
    merged.completed_runs.push_back(runs[r].first);
    merged.run_seconds.push_back(runs[r].second);
  }
  return ga::checkpoint_to_state(merged);
}

SolverResult GaSolver::solve(const Problem& problem, const SolverContext& context) const {
  GaSearch search(options_, problem, context);
  search.resume_from_checkpoint();
  search.run_remaining();
  return search.summary();
}

}  // namespace hapsyn::plugins
