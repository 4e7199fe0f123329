#include "ga.hpp"

#include "ga_checkpoint.hpp"
#include "ga_summary.hpp"
#include "shared/pagmo_adapter.hpp"

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
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace hapsyn::plugins {

namespace pa = pagmo_adapter;
using ga::with_digits;

namespace {

using Clock = std::chrono::steady_clock;

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

// One call of GaSolver::solve: the runs one after the other, with their checkpoints and
// progress lines, then the summary. Holds what the steps share. The evaluator keeps a pointer
// to subset_, so a search is neither copied nor moved.
class GaSearch {
 public:
  GaSearch(const GaOptions& options, const Problem& problem, const SolverContext& context);
  GaSearch(const GaSearch&) = delete;
  GaSearch& operator=(const GaSearch&) = delete;

  /// With SolverContext::resume: the finished runs, counters and the run in progress from the
  /// checkpoint file (or a log line that there is none). \throws Error for a bad checkpoint
  void resume_from_checkpoint();
  /// Runs the runs not finished yet, until the stop flag is set.
  void run_remaining();
  /// The result over the finished runs (ga_summary.hpp).
  SolverResult summary();

 private:
  // A run in progress.
  struct Run {
    ga::RunState state;
    pagmo::algorithm algorithm;
    pagmo::population population;
    Clock::time_point clock;
    std::string status = "budget_exhausted";
  };

  void start_run(Run& run, std::uint64_t seed);
  void evolve(Run& run);
  bool note_best(ga::RunState& state, const pagmo::population& population) const;
  void switch_to_full(Run& run);
  void report_generation(const Run& run);
  void finish_run(const Run& run, std::uint64_t seed);
  void write_checkpoint(const Run* run) const;
  void check_claimed_best(const pagmo::vector_double& x, double claimed, const std::string& what) const;

  const GaOptions& options_;
  const Problem& problem_;
  const SolverContext& context_;
  const Clock::time_point start_;
  std::shared_ptr<pa::Evaluator> evaluator_;
  pagmo::problem pagmo_problem_;
  const bool multi_fidelity_;
  const std::vector<int> subset_;  // the multi-fidelity subset (empty without one)
  pa::ProgressReporter reporter_;
  const std::string fingerprint_;

  Json runs_ = Json::array();  // records of the finished runs
  std::vector<double> run_seconds_;
  long long designs_before_resume_ = 0, samples_before_resume_ = 0;
  double seconds_before_resume_ = 0.0;
  std::optional<Json> resumed_;  // the checkpoint's run in progress, until it is restored
  bool stopped_ = false;
  int total_generations_done_ = 0;
  Clock::time_point solve_clock_;
};

pa::EvaluationSettings evaluation_settings(const GaOptions& options, int threads) {
  pa::EvaluationSettings settings;
  settings.threads = threads;
  settings.over_individuals = options.parallel_over == "individuals";
  settings.sample_chunks = options.sample_chunks;
  return settings;
}

GaSearch::GaSearch(const GaOptions& options, const Problem& problem, const SolverContext& context)
    : options_(options),
      problem_(problem),
      context_(context),
      start_(Clock::now()),
      evaluator_(std::make_shared<pa::Evaluator>(
          problem, pa::Encoding(problem, options.sort_descending, options.sort_ascending, "ga"),
          evaluation_settings(options, context.threads), false)),
      pagmo_problem_(pa::make_problem(evaluator_)),
      multi_fidelity_(options.fidelity.generations > 0),
      subset_(multi_fidelity_ ? stratified_subset(problem.samples().size(), options.fidelity.subset_fraction)
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
  for (std::size_t i = 0; i < checkpoint.completed_runs.size(); ++i) {
    const Json& run = checkpoint.completed_runs[i];
    const std::string path = "state.completed_runs[" + std::to_string(i) + "]";
    // The fields the summary reads, checked here: a damaged record is a checkpoint error, not a
    // raw JSON exception at the end of the solve.
    pagmo::vector_double x;
    double score = 0.0;
    std::vector<double> free;
    try {
      if (run.at("run").get<int>() != static_cast<int>(i)) throw std::invalid_argument("run is not " + std::to_string(i));
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
    if (free != evaluator_->encoding().decode(x)) {
      throw bad_checkpoint(context_, path + ": free does not match the decoded x");
    }
  }
  if (checkpoint.current && checkpoint.current->contains("best_x")) {
    try {
      const pagmo::vector_double x = checkpoint.current->at("best_x").get<pagmo::vector_double>();
      if (!x.empty()) check_claimed_best(x, checkpoint.current->at("best_score").get<double>(), "state.current");
    } catch (const Json::exception& e) {
      throw bad_checkpoint(context_, std::string("state.current: ") + e.what());
    }
  }
  runs_ = std::move(checkpoint.completed_runs);
  run_seconds_ = std::move(checkpoint.run_seconds);
  designs_before_resume_ = checkpoint.designs;
  samples_before_resume_ = checkpoint.samples;
  seconds_before_resume_ = checkpoint.elapsed_seconds;
  evaluator_->add_counts(designs_before_resume_, samples_before_resume_);
  resumed_ = std::move(checkpoint.current);
  reporter_.line("ga: resuming from " + context_.checkpoint_file + ": " + std::to_string(runs_.size()) + " run(s) finished" +
                     (resumed_ ? ", run " + std::to_string(resumed_->at("run").get<int>() + 1) + " at generation " +
                                     std::to_string(resumed_->at("generation").get<int>())
                               : std::string()),
                 true);
}

// Re-evaluates a claimed optimum (pagmo vector) on the full scene, outside the evaluator (its
// cache and counters stay those of an uninterrupted run), and refuses the checkpoint when the
// score differs. 1e-9 relative: the evaluator's paths (one design per thread, or split over
// sample chunks) may round an averaging metric's sum differently; an edit is far larger.
void GaSearch::check_claimed_best(const pagmo::vector_double& x, double claimed, const std::string& what) const {
  if (x.size() != evaluator_->encoding().size()) {
    throw bad_checkpoint(context_, what + ": best has " + std::to_string(x.size()) + " components, the study " +
                                       std::to_string(evaluator_->encoding().size()));
  }
  const std::vector<double> free = evaluator_->encoding().decode(x);
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
  for (int r = static_cast<int>(runs_.size()); r < options_.runs && !stopped_; ++r) {
    if (context_.stop_requested()) {
      // Before a run starts: the checkpoint on disk (between runs, or the resumed one) stands.
      stopped_ = true;
      break;
    }
    const std::uint64_t run_seed = pa::derive_seed(context_.seed, static_cast<std::uint64_t>(r));
    Run run;
    run.state.run = r;
    run.clock = Clock::now();
    start_run(run, run_seed);
    evolve(run);
    if (!run.state.switched) switch_to_full(run);  // the final ranking on the full scene
    if (stopped_ && run.state.best_x.empty()) break;
    finish_run(run, run_seed);
  }
}

// A fresh run (random population from the run's seed), or the checkpoint's run in progress.
void GaSearch::start_run(Run& run, std::uint64_t seed) {
  ga::RunState& state = run.state;
  if (resumed_ && resumed_->at("run").get<int>() == state.run) {
    ga::restore_run(context_, *resumed_, pagmo_problem_, state, run.algorithm, run.population);
    const bool on_subset = multi_fidelity_ && !state.switched;
    evaluator_->set_subset(on_subset ? &subset_ : nullptr, on_subset ? 1 : 0);
    resumed_.reset();
  } else {
    state.switched = !multi_fidelity_;
    state.designs_before = evaluator_->design_evaluations();
    evaluator_->set_subset(multi_fidelity_ ? &subset_ : nullptr, multi_fidelity_ ? 1 : 0);
    run.algorithm = make_algorithm(options_, seed);
    run.population =
        pa::random_population(pagmo_problem_, *evaluator_, static_cast<std::size_t>(options_.population), seed);
  }
  if (state.switched && state.generation == 0) note_best(state, run.population);
}

// Generations until the limit, convergence or the stop flag; checkpoints on the way.
void GaSearch::evolve(Run& run) {
  ga::RunState& state = run.state;
  while (state.generation < options_.generations) {
    if (context_.stop_requested()) {
      stopped_ = true;
      run.status = "stopped";
      write_checkpoint(&run);  // between generations: a resumed run continues exactly from here
      return;
    }
    if (!state.switched && state.generation >= options_.fidelity.generations) switch_to_full(run);
    run.population = run.algorithm.evolve(run.population);
    ++state.generation;
    ++total_generations_done_;
    if (state.switched) {
      state.stall = note_best(state, run.population) ? 0 : state.stall + 1;
    }
    report_generation(run);
    if (state.switched && state.stall >= options_.stall_generations) {
      run.status = "converged";
      return;
    }
    if (options_.checkpoint_every > 0 && state.generation % options_.checkpoint_every == 0 &&
        state.generation < options_.generations) {
      write_checkpoint(&run);
    }
  }
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

// The multi-fidelity switch: the population re-evaluated on the full scene.
void GaSearch::switch_to_full(Run& run) {
  ga::RunState& state = run.state;
  const long long b = best_feasible(run.population);
  const double subset_best = b >= 0 ? -run.population.get_f()[static_cast<std::size_t>(b)][0] : -INFINITY;
  evaluator_->set_subset(nullptr, 0);
  pa::reevaluate(run.population, *evaluator_);
  state.switched = true;
  state.stall = 0;
  note_best(state, run.population);
  reporter_.line("ga: run " + std::to_string(state.run + 1) + " generation " + std::to_string(state.generation) +
                     ": fidelity switch, population re-evaluated on the full scene (best " + with_digits(subset_best) +
                     " on the subset, " + with_digits(state.best_score) + " on the full scene)",
                 true);
}

// The progress line of a generation: best and mean of the feasible individuals at the current
// fidelity, speed, stall count, time.
void GaSearch::report_generation(const Run& run) {
  const ga::RunState& state = run.state;
  double best = -INFINITY, mean = 0.0;
  int feasible = 0;
  for (const auto& f : run.population.get_f()) {
    if (f[0] >= pa::kSampleFailedFitness) continue;
    best = std::max(best, -f[0]);
    mean += -f[0];
    ++feasible;
  }
  const int generations = options_.generations;
  const double elapsed = seconds_since(solve_clock_);
  const double per_generation = elapsed / std::max(1, total_generations_done_);
  const double left =
      per_generation * ((generations - state.generation) + static_cast<double>(options_.runs - state.run - 1) * generations);
  const double designs_per_second =
      (evaluator_->design_evaluations() - designs_before_resume_) / std::max(1e-9, seconds_since(start_));
  std::ostringstream line;
  line << "ga: run " << (state.run + 1) << "/" << options_.runs << " gen " << state.generation << "/" << generations
       << (state.switched ? "" : " (subset)") << " best " << with_digits(best) << " mean "
       << (feasible ? with_digits(mean / feasible) : std::string("-")) << " feasible " << feasible << "/"
       << run.population.size() << " | " << with_digits(designs_per_second, 4) << " designs/s | stall " << state.stall
       << "/" << options_.stall_generations << " | elapsed "
       << pa::format_duration(seconds_before_resume_ + seconds_since(start_)) << ", left <= " << pa::format_duration(left);
  reporter_.line(line.str());
}

// The run's record (statistics.runs), its time, its log line, and a checkpoint between runs.
void GaSearch::finish_run(const Run& run, std::uint64_t seed) {
  const ga::RunState& state = run.state;
  Json record;
  record["run"] = state.run;
  record["seed"] = seed;
  record["generations"] = state.generation;
  record["designs"] = evaluator_->design_evaluations() - state.designs_before;
  if (state.best_x.empty()) {
    record["status"] = "infeasible";
  } else {
    const pa::DesignRecord& best = evaluator_->record(state.best_x);
    const std::vector<double> free = evaluator_->encoding().decode(state.best_x);
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
  runs_.push_back(record);
  run_seconds_.push_back(state.seconds_before + seconds_since(run.clock));
  reporter_.line("ga: run " + std::to_string(state.run + 1) + "/" + std::to_string(options_.runs) + " " +
                     record["status"].get<std::string>() + " after " + std::to_string(state.generation) +
                     " generations, " + std::to_string(record["designs"].get<long long>()) + " designs, " +
                     pa::format_duration(run_seconds_.back()) +
                     (record.contains("score") ? ": score " + with_digits(record["score"].get<double>(), 8) : std::string()),
                 true);
  if (!stopped_) write_checkpoint(nullptr);
}

// The checkpoint file: the finished runs and counters, and `run` when one is in progress.
void GaSearch::write_checkpoint(const Run* run) const {
  if (context_.checkpoint_file.empty()) return;
  ga::Checkpoint checkpoint;
  checkpoint.completed_runs = runs_;
  checkpoint.run_seconds = run_seconds_;
  checkpoint.designs = evaluator_->design_evaluations();
  checkpoint.samples = evaluator_->sample_evaluations();
  checkpoint.elapsed_seconds = seconds_before_resume_ + seconds_since(start_);
  if (run) {
    ga::RunState saved = run->state;
    saved.seconds_before += seconds_since(run->clock);
    checkpoint.current = ga::run_to_json(saved, run->algorithm, run->population);
  }
  hapsyn::write_checkpoint(context_, "ga", fingerprint_, ga::checkpoint_to_state(checkpoint));
}

SolverResult GaSearch::summary() {
  ga::SolveFigures figures;
  figures.stopped = stopped_;
  figures.solve_seconds = seconds_before_resume_ + seconds_since(start_);
  figures.design_evaluations = evaluator_->design_evaluations();
  figures.sample_evaluations = evaluator_->sample_evaluations();
  figures.cache_hits = evaluator_->cache_hits();
  figures.repair = evaluator_->encoding().describe_repair(problem_);
  figures.subset_samples = subset_.size();
  SolverResult result = ga::summarise_runs(problem_, options_, runs_, run_seconds_, figures, context_.seed, reporter_);
  if (stopped_) {
    result.message += context_.checkpoint_file.empty()
                          ? "; best so far; no checkpoint file, a new run starts over"
                          : "; best so far; checkpoint " + context_.checkpoint_file + " written, resume with --resume";
  }
  return result;
}

}  // namespace

GaSolver::GaSolver(const GaOptions& options) : options_(options) {
  const GaOptions& o = options_;
  if (o.algorithm == "gaco" && o.gaco.ker > o.population) {
    throw Error("ga", "options.gaco.ker = " + std::to_string(o.gaco.ker) + ": must not exceed options.population (" +
                          std::to_string(o.population) + "): gaco fills its solution archive from the population");
  }
  if (o.algorithm == "sga" && o.sga.selection == "tournament" && o.sga.param_s > o.population) {
    throw Error("ga", "options.sga.param_s = " + std::to_string(o.sga.param_s) +
                          ": the tournament size must not exceed options.population (" + std::to_string(o.population) +
                          ")");
  }
  const std::string& mutation = o.sga.mutation;
  const double param_m = o.sga.param_m;
  if (mutation == "polynomial" ? (param_m < 1.0 || param_m > 100.0) : (param_m < 0.0 || param_m > 1.0)) {
    throw Error("ga", "options.sga.param_m = " + with_digits(param_m) + ": must lie in " +
                          (mutation == "polynomial" ? "[1, 100] (distribution index of polynomial mutation)"
                                                    : "[0, 1] (width of " + mutation + " mutation)"));
  }
  if (o.fidelity.subset_fraction < 1.0 && o.fidelity.generations == 0) {
    throw Error("ga", "options.fidelity.subset_fraction = " + with_digits(o.fidelity.subset_fraction) +
                          ": needs options.fidelity.generations >= 1 (the generations evaluated on the subset)");
  }
  if (o.fidelity.generations > 0 && o.fidelity.subset_fraction >= 1.0) {
    throw Error("ga", "options.fidelity.generations = " + std::to_string(o.fidelity.generations) +
                          ": needs options.fidelity.subset_fraction < 1 (the share of the samples evaluated early)");
  }
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

SolverResult GaSolver::solve(const Problem& problem, const SolverContext& context) const {
  GaSearch search(options_, problem, context);
  search.resume_from_checkpoint();
  search.run_remaining();
  return search.summary();
}

}  // namespace hapsyn::plugins
