#include "ga.hpp"

#include "pagmo_adapter.hpp"

#include <hapsyn/cluster.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/output_files.hpp>

#include <pagmo/algorithms/gaco.hpp>
#include <pagmo/algorithms/sga.hpp>
#include <pagmo/batch_evaluators/member_bfe.hpp>
#include <pagmo/bfe.hpp>
#include <pagmo/population.hpp>

#include <boost/filesystem.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace hapsyn::plugins {

namespace pa = pagmo_adapter;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::string fixed(double v, int digits = 6) {
  std::ostringstream s;
  s << std::setprecision(digits) << v;
  return s.str();
}

pagmo::algorithm make_algorithm(const GaOptions& o, std::uint64_t seed) {
  const unsigned s = static_cast<unsigned>(seed ^ (seed >> 32));
  if (o.algorithm == "gaco") {
    pagmo::gaco gaco(1u, static_cast<unsigned>(o.ker), o.q, o.oracle, o.acc, static_cast<unsigned>(o.threshold),
                     static_cast<unsigned>(o.n_gen_mark), 100000u, 100000u, o.focus, true, s);
    gaco.set_bfe(pagmo::bfe{pagmo::member_bfe{}});
    return pagmo::algorithm{gaco};
  }
  return pagmo::algorithm{pagmo::sga(1u, o.crossover_probability, o.eta_c, o.mutation_probability, o.param_m,
                                     static_cast<unsigned>(o.param_s), o.crossover, o.mutation, o.selection, s)};
}

// FNV-1a: a stable fingerprint of the study a checkpoint belongs to.
std::string fingerprint(const std::string& text) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  std::ostringstream s;
  s << std::hex << h;
  return s.str();
}

std::string study_fingerprint(const Problem& problem, const Json& options) {
  std::ostringstream s;
  s.precision(17);
  s << options.dump() << "|" << problem.samples().size() << "|";
  for (int k : problem.design_space().free_indices()) {
    const DesignComponent& c = problem.design_space().components()[static_cast<std::size_t>(k)];
    s << c.name << ":" << c.lower << ":" << c.upper << ":" << c.integer << ";";
  }
  for (const Objective& o : problem.objectives()) s << o.name << ":" << o.weight << ":" << (o.sense == Sense::kMaximize) << ";";
  return fingerprint(s.str());
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

struct RunState {
  int run = 0;
  int generation = 0;
  int stall = 0;
  bool switched = false;         // on the full scene (or never on a subset)
  double best_score = -std::numeric_limits<double>::infinity();
  pagmo::vector_double best_x;   // best full-fidelity individual seen in this run
  long long designs_before = 0;  // study evaluations when the run started
  double seconds_before = 0.0;   // run time before a resume
};

}  // namespace

GaSolver::GaSolver(const Json& options) : raw_options_(options) {
  GaOptions& o = options_;
  o.algorithm = options.at("algorithm");
  o.population = options.at("population");
  o.generations = options.at("generations");
  o.stall_generations = options.at("stall_generations");
  o.ftol = options.at("ftol");
  o.runs = options.at("runs");
  o.checkpoint_every = options.at("checkpoint_every");
  o.parallel_over = options.at("parallel_over");
  o.sample_chunks = options.at("sample_chunks");
  o.sort_descending = options.at("sort_descending").get<std::vector<std::string>>();
  o.sort_ascending = options.at("sort_ascending").get<std::vector<std::string>>();
  o.subset_fraction = options.at("fidelity").at("subset_fraction");
  o.fidelity_generations = options.at("fidelity").at("generations");
  o.max_clusters = options.at("max_clusters");
  o.cluster_variables = options.at("cluster_variables").get<std::vector<std::string>>();
  o.progress_interval = options.at("progress_interval");
  const Json& sga = options.at("sga");
  o.crossover_probability = sga.at("crossover_probability");
  o.crossover = sga.at("crossover");
  o.eta_c = sga.at("eta_c");
  o.mutation_probability = sga.at("mutation_probability");
  o.mutation = sga.at("mutation");
  o.param_m = sga.at("param_m");
  o.selection = sga.at("selection");
  o.param_s = sga.at("param_s");
  const Json& gaco = options.at("gaco");
  o.ker = gaco.at("ker");
  o.q = gaco.at("q");
  o.oracle = gaco.at("oracle");
  o.acc = gaco.at("acc");
  o.threshold = gaco.at("threshold");
  o.n_gen_mark = gaco.at("n_gen_mark");
  o.focus = gaco.at("focus");

  if (o.algorithm == "gaco" && o.ker > o.population) {
    throw Error("ga", "options.gaco.ker = " + std::to_string(o.ker) + ": must not exceed options.population (" +
                          std::to_string(o.population) + "): gaco fills its solution archive from the population");
  }
  if (o.algorithm == "sga" && o.selection == "tournament" && o.param_s > o.population) {
    throw Error("ga", "options.sga.param_s = " + std::to_string(o.param_s) + ": the tournament size must not exceed options.population (" +
                          std::to_string(o.population) + ")");
  }
  if (o.mutation == "polynomial" ? (o.param_m < 1.0 || o.param_m > 100.0) : (o.param_m < 0.0 || o.param_m > 1.0)) {
    throw Error("ga", "options.sga.param_m = " + fixed(o.param_m) + ": must lie in " +
                          (o.mutation == "polynomial" ? "[1, 100] (distribution index of polynomial mutation)"
                                                      : "[0, 1] (width of " + o.mutation + " mutation)"));
  }
  if (o.subset_fraction < 1.0 && o.fidelity_generations == 0) {
    throw Error("ga", "options.fidelity.subset_fraction = " + fixed(o.subset_fraction) +
                          ": needs options.fidelity.generations >= 1 (the generations evaluated on the subset)");
  }
  if (o.fidelity_generations > 0 && o.subset_fraction >= 1.0) {
    throw Error("ga", "options.fidelity.generations = " + std::to_string(o.fidelity_generations) +
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
  const GaOptions& o = options_;
  const auto start = Clock::now();
  SolverResult result;
  pa::EvaluationSettings settings;
  settings.threads = context.threads;
  settings.over_individuals = o.parallel_over == "individuals";
  settings.sample_chunks = o.sample_chunks;
  auto evaluator = std::make_shared<pa::Evaluator>(
      problem, pa::Encoding(problem, o.sort_descending, o.sort_ascending, "ga"), settings, false);
  const pagmo::problem prob = pa::make_problem(evaluator);
  const bool multi_fidelity = o.fidelity_generations > 0;
  const std::vector<int> subset = multi_fidelity ? stratified_subset(problem.samples().size(), o.subset_fraction)
                                                 : std::vector<int>{};
  pa::ProgressReporter reporter(context.progress, context.log, o.progress_interval);
  const std::string fp = study_fingerprint(problem, raw_options_);

  // Finished runs (JSON records), and the state of a run in progress from a checkpoint.
  Json runs = Json::array();
  std::vector<double> run_seconds;
  long long designs_before_resume = 0, samples_before_resume = 0;
  double seconds_before_resume = 0.0;
  std::optional<Json> resumed;
  if (context.resume && !context.checkpoint_file.empty() && boost::filesystem::exists(context.checkpoint_file)) {
    std::ifstream in(context.checkpoint_file);
    Json checkpoint;
    try {
      checkpoint = Json::parse(in);
    } catch (const std::exception& e) {
      throw Error("ga", context.checkpoint_file + ": cannot be read as a checkpoint (" + e.what() + ")");
    }
    if (checkpoint.value("solver", "") != "ga" || checkpoint.value("fingerprint", "") != fp) {
      throw Error("ga", context.checkpoint_file + ": written for another study (solver '" + checkpoint.value("solver", "?") +
                            "', fingerprint " + checkpoint.value("fingerprint", "?") + ", this study " + fp +
                            "); delete it or run without --resume");
    }
    runs = checkpoint.at("completed_runs");
    run_seconds = checkpoint.at("run_seconds").get<std::vector<double>>();
    designs_before_resume = checkpoint.at("evaluations").at("designs");
    samples_before_resume = checkpoint.at("evaluations").at("samples");
    seconds_before_resume = checkpoint.at("elapsed_seconds");
    evaluator->add_counts(designs_before_resume, samples_before_resume);
    if (checkpoint.contains("current")) resumed = checkpoint.at("current");
    reporter.line("ga: resuming from " + context.checkpoint_file + ": " + std::to_string(runs.size()) + " run(s) finished" +
                      (resumed ? ", run " + std::to_string(resumed->at("run").get<int>() + 1) + " at generation " +
                                     std::to_string(resumed->at("generation").get<int>())
                               : std::string()),
                  true);
  } else if (context.resume) {
    reporter.line("ga: no checkpoint to resume from; starting from the beginning", true);
  }

  auto write_checkpoint = [&](const RunState* state, const pagmo::algorithm* algorithm, const pagmo::population* population) {
    if (context.checkpoint_file.empty()) return;
    Json c;
    c["seed"] = context.seed;
    c["solver"] = "ga";
    c["fingerprint"] = fp;
    c["completed_runs"] = runs;
    c["run_seconds"] = run_seconds;
    c["evaluations"] = {{"designs", evaluator->design_evaluations()}, {"samples", evaluator->sample_evaluations()}};
    c["elapsed_seconds"] = seconds_before_resume + seconds_since(start);
    if (state) {
      Json cur;
      cur["run"] = state->run;
      cur["generation"] = state->generation;
      cur["stall"] = state->stall;
      cur["switched"] = state->switched;
      cur["best_score"] = state->best_x.empty() ? Json(nullptr) : Json(state->best_score);
      cur["best_x"] = state->best_x;
      cur["designs_before"] = state->designs_before;
      cur["run_seconds"] = state->seconds_before;
      cur["algorithm"] = pa::save_algorithm(*algorithm);
      cur["population_seed"] = population->get_seed();
      cur["x"] = pa::matrix_to_json(population->get_x());
      cur["f"] = pa::matrix_to_json(population->get_f());
      c["current"] = cur;
    }
    write_file_atomically(context.checkpoint_file, c.dump() + "\n");
  };

  bool stopped = false;
  int total_generations_done = 0;
  const auto solve_clock = Clock::now();
  for (int r = static_cast<int>(runs.size()); r < o.runs && !stopped; ++r) {
    const std::uint64_t run_seed = pa::derive_seed(context.seed, static_cast<std::uint64_t>(r));
    RunState state;
    state.run = r;
    pagmo::algorithm algorithm;
    pagmo::population population;
    const auto run_clock = Clock::now();
    if (resumed && resumed->at("run").get<int>() == r) {
      const Json& cur = *resumed;
      state.generation = cur.at("generation");
      state.stall = cur.at("stall");
      state.switched = cur.at("switched");
      state.best_x = cur.at("best_x").get<pagmo::vector_double>();
      if (!state.best_x.empty()) state.best_score = cur.at("best_score");
      state.designs_before = cur.at("designs_before");
      state.seconds_before = cur.at("run_seconds");
      algorithm = pa::load_algorithm(cur.at("algorithm").get<std::string>());
      evaluator->set_subset(multi_fidelity && !state.switched ? &subset : nullptr, multi_fidelity && !state.switched ? 1 : 0);
      pagmo::population restored(prob, 0u, cur.at("population_seed").get<unsigned>());
      const auto xs = pa::matrix_from_json(cur.at("x"));
      const auto fs = pa::matrix_from_json(cur.at("f"));
      for (std::size_t i = 0; i < xs.size(); ++i) restored.push_back(xs[i], fs[i]);
      population = restored;
      resumed.reset();
    } else {
      state.switched = !multi_fidelity;
      state.designs_before = evaluator->design_evaluations();
      evaluator->set_subset(multi_fidelity ? &subset : nullptr, multi_fidelity ? 1 : 0);
      algorithm = make_algorithm(o, run_seed);
      population = pa::random_population(prob, *evaluator, static_cast<std::size_t>(o.population), run_seed);
    }

    // Best of the population at full fidelity: the run's best so far.
    auto note_best = [&](const pagmo::population& pop) {
      const long long b = best_feasible(pop);
      if (b < 0) return false;
      const double score = -pop.get_f()[static_cast<std::size_t>(b)][0];
      if (state.best_x.empty() || score > state.best_score + o.ftol) {
        state.best_score = score;
        state.best_x = pop.get_x()[static_cast<std::size_t>(b)];
        return true;
      }
      if (score > state.best_score) {  // a smaller improvement: kept, but counts as stalling
        state.best_score = score;
        state.best_x = pop.get_x()[static_cast<std::size_t>(b)];
      }
      return false;
    };
    auto switch_to_full = [&](pagmo::population& pop) {
      const long long b = best_feasible(pop);
      const double subset_best = b >= 0 ? -pop.get_f()[static_cast<std::size_t>(b)][0] : -INFINITY;
      evaluator->set_subset(nullptr, 0);
      pa::reevaluate(pop, *evaluator);
      state.switched = true;
      state.stall = 0;
      note_best(pop);
      reporter.line("ga: run " + std::to_string(r + 1) + " generation " + std::to_string(state.generation) +
                        ": fidelity switch, population re-evaluated on the full scene (best " + fixed(subset_best) +
                        " on the subset, " + fixed(state.best_score) + " on the full scene)",
                    true);
    };
    if (state.switched && state.generation == 0) note_best(population);

    std::string run_status = "budget_exhausted";
    while (state.generation < o.generations) {
      if (context.stop && context.stop->load()) {
        stopped = true;
        run_status = "stopped";
        break;
      }
      if (!state.switched && state.generation >= o.fidelity_generations) switch_to_full(population);
      population = algorithm.evolve(population);
      ++state.generation;
      ++total_generations_done;
      if (state.switched) {
        state.stall = note_best(population) ? 0 : state.stall + 1;
      }
      // Progress: best and mean of the feasible individuals at the current fidelity.
      double best = -INFINITY, mean = 0.0;
      int feasible = 0;
      for (const auto& f : population.get_f()) {
        if (f[0] >= pa::kSampleFailedFitness) continue;
        best = std::max(best, -f[0]);
        mean += -f[0];
        ++feasible;
      }
      const double elapsed = seconds_since(solve_clock);
      const double per_generation = elapsed / std::max(1, total_generations_done);
      const double left = per_generation * ((o.generations - state.generation) +
                                            static_cast<double>(o.runs - r - 1) * o.generations);
      std::ostringstream line;
      line << "ga: run " << (r + 1) << "/" << o.runs << " gen " << state.generation << "/" << o.generations
           << (state.switched ? "" : " (subset)") << " best " << fixed(best) << " mean "
           << (feasible ? fixed(mean / feasible) : std::string("-")) << " feasible " << feasible << "/"
           << population.size() << " | " << fixed((evaluator->design_evaluations() - designs_before_resume) / std::max(1e-9, seconds_since(start)), 4)
           << " designs/s | stall " << state.stall << "/" << o.stall_generations << " | elapsed "
           << pa::format_duration(seconds_before_resume + seconds_since(start)) << ", left <= " << pa::format_duration(left);
      reporter.line(line.str());
      if (state.switched && state.stall >= o.stall_generations) {
        run_status = "converged";
        break;
      }
      if (o.checkpoint_every > 0 && state.generation % o.checkpoint_every == 0 && state.generation < o.generations) {
        RunState saved = state;
        saved.seconds_before += seconds_since(run_clock);
        write_checkpoint(&saved, &algorithm, &population);
      }
    }
    if (!state.switched) switch_to_full(population);  // the final ranking on the full scene
    if (stopped && state.best_x.empty()) break;

    Json record;
    record["run"] = r;
    record["seed"] = run_seed;
    record["generations"] = state.generation;
    record["designs"] = evaluator->design_evaluations() - state.designs_before;
    if (state.best_x.empty()) {
      record["status"] = "infeasible";
    } else {
      const pa::DesignRecord& best = evaluator->record(state.best_x);
      const std::vector<double> free = evaluator->encoding().decode(state.best_x);
      const Eigen::VectorXd full = problem.full_design(free.data());
      record["status"] = run_status;
      record["x"] = state.best_x;
      record["free"] = free;
      record["design"] = problem.design_to_json(full);
      record["score"] = best.score;
      Json objectives = Json::object();
      for (std::size_t i = 0; i < problem.objectives().size(); ++i) objectives[problem.objectives()[i].name] = best.objectives[i];
      record["objectives"] = objectives;
    }
    runs.push_back(record);
    run_seconds.push_back(state.seconds_before + seconds_since(run_clock));
    reporter.line("ga: run " + std::to_string(r + 1) + "/" + std::to_string(o.runs) + " " + record["status"].get<std::string>() +
                      " after " + std::to_string(state.generation) + " generations, " + std::to_string(record["designs"].get<long long>()) +
                      " designs, " + pa::format_duration(run_seconds.back()) +
                      (record.contains("score") ? ": score " + fixed(record["score"].get<double>(), 8) : std::string()),
                  true);
    if (!stopped) write_checkpoint(nullptr, nullptr, nullptr);
  }

  // The best run, and the summary over the runs.
  result.design_evaluations = evaluator->design_evaluations();
  result.sample_evaluations = evaluator->sample_evaluations();
  int best_run = -1, converged = 0, budget = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const std::string s = runs[i]["status"];
    converged += s == "converged";
    budget += s == "budget_exhausted";
    if (!runs[i].contains("score")) continue;
    if (best_run < 0 || runs[i]["score"].get<double>() > runs[static_cast<std::size_t>(best_run)]["score"].get<double>()) {
      best_run = static_cast<int>(i);
    }
  }
  Json statistics;
  statistics["algorithm"] = o.algorithm;
  statistics["runs"] = runs;
  statistics["run_seconds"] = run_seconds;
  statistics["solve_seconds"] = seconds_before_resume + seconds_since(start);
  statistics["cache_hits"] = evaluator->cache_hits();
  statistics["repair"] = evaluator->encoding().describe_repair(problem);
  statistics["evaluation"] = {{"parallel_over", o.parallel_over}, {"sample_chunks", o.sample_chunks}};
  if (multi_fidelity) {
    statistics["fidelity"] = {{"subset_fraction", o.subset_fraction},
                              {"subset_samples", subset.size()},
                              {"generations", o.fidelity_generations}};
  }
  std::vector<std::string> report;
  if (best_run >= 0) {
    const Json& b = runs[static_cast<std::size_t>(best_run)];
    const std::vector<double> free = b["free"].get<std::vector<double>>();
    std::vector<double> objectives;
    for (const Objective& obj : problem.objectives()) objectives.push_back(b["objectives"][obj.name]);
    result.best = SolutionPoint{problem.full_design(free.data()), objectives, b["score"].get<double>()};
    statistics["best_run"] = best_run;
    // Score spread over the runs.
    double lo = INFINITY, hi = -INFINITY;
    for (const Json& run : runs) {
      if (!run.contains("score")) continue;
      lo = std::min(lo, run["score"].get<double>());
      hi = std::max(hi, run["score"].get<double>());
    }
    statistics["score_range"] = {lo, hi};
  }

  // Cluster analysis of the runs' optima (Fennel 2022, section VII, Table III).
  std::vector<std::size_t> feasible_runs;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (runs[i].contains("score")) feasible_runs.push_back(i);
  }
  if (feasible_runs.size() >= 3) {
    std::vector<int> columns;  // free indices clustered
    std::vector<std::string> names;
    const DesignSpace& space = problem.design_space();
    for (std::size_t k = 0; k < space.free_size(); ++k) {
      const DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
      const bool chosen = o.cluster_variables.empty()
                              ? !c.integer
                              : std::find(o.cluster_variables.begin(), o.cluster_variables.end(), c.variable) != o.cluster_variables.end();
      if (chosen) {
        columns.push_back(static_cast<int>(k));
        names.push_back(c.name);
      }
    }
    if (!columns.empty()) {
      Eigen::MatrixXd points(static_cast<Eigen::Index>(feasible_runs.size()), static_cast<Eigen::Index>(columns.size()));
      for (std::size_t i = 0; i < feasible_runs.size(); ++i) {
        const auto free = runs[feasible_runs[i]]["free"].get<std::vector<double>>();
        for (std::size_t j = 0; j < columns.size(); ++j) {
          points(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = free[static_cast<std::size_t>(columns[j])];
        }
      }
      const ClusterAnalysis a = cluster_by_silhouette(points, o.max_clusters, context.seed);
      Json clusters;
      clusters["variables"] = names;
      clusters["k"] = a.best.k;
      clusters["silhouette"] = a.silhouette;
      Json silhouettes = Json::object();
      for (std::size_t i = 0; i < a.silhouettes.size(); ++i) silhouettes[std::to_string(i + 2)] = a.silhouettes[i];
      clusters["silhouettes"] = silhouettes;
      clusters["intra_deviation"] = a.intra_deviation;
      clusters["inter_deviation"] = a.inter_deviation;
      Json table = Json::array();
      std::ostringstream head;
      head << "cluster  runs  score(mean)  score(best)  intra";
      for (const std::string& n : names) head << "  " << std::setw(8) << n;
      for (const Objective& obj : problem.objectives()) head << "  " << std::setw(8) << obj.name;
      report.push_back("clusters of the " + std::to_string(feasible_runs.size()) + " run optima over (" +
                       [&] { std::string s; for (const auto& n : names) s += (s.empty() ? "" : ", ") + n; return s; }() +
                       "): k = " + std::to_string(a.best.k) + " by average silhouette " + fixed(a.silhouette, 3) +
                       "; intra-cluster deviation " + fixed(a.intra_deviation, 4) + ", inter-cluster deviation " +
                       fixed(a.inter_deviation, 4) + " (design units)");
      report.push_back(head.str());
      for (int c = 0; c < a.best.k; ++c) {
        Json entry;
        Json members = Json::array();
        double score_sum = 0.0, score_best = -INFINITY;
        int best_member = -1;
        std::vector<double> objective_sum(problem.objectives().size(), 0.0);
        for (std::size_t i = 0; i < feasible_runs.size(); ++i) {
          if (a.best.labels[i] != c) continue;
          const Json& run = runs[feasible_runs[i]];
          members.push_back(run["run"]);
          const double s = run["score"];
          score_sum += s;
          if (s > score_best) {
            score_best = s;
            best_member = run["run"];
          }
          for (std::size_t q = 0; q < problem.objectives().size(); ++q) {
            objective_sum[q] += run["objectives"][problem.objectives()[q].name].get<double>();
          }
        }
        const int size = a.sizes[static_cast<std::size_t>(c)];
        Json centroid = Json::object();
        for (std::size_t j = 0; j < names.size(); ++j) centroid[names[j]] = a.best.centroids(c, static_cast<Eigen::Index>(j));
        Json mean_objectives = Json::object();
        for (std::size_t q = 0; q < problem.objectives().size(); ++q) mean_objectives[problem.objectives()[q].name] = objective_sum[q] / size;
        entry["size"] = size;
        entry["runs"] = members;
        entry["centroid"] = centroid;
        entry["intra_distance"] = a.cluster_intra_distance[static_cast<std::size_t>(c)];
        entry["mean_objectives"] = mean_objectives;
        entry["mean_score"] = score_sum / size;
        entry["best_score"] = score_best;
        entry["best_run"] = best_member;
        entry["best_design"] = runs[static_cast<std::size_t>(best_member)]["design"];
        table.push_back(entry);
        std::ostringstream row;
        row << std::setw(7) << (c + 1) << "  " << std::setw(4) << size << "  " << std::setw(11) << fixed(score_sum / size, 6)
            << "  " << std::setw(11) << fixed(score_best, 6) << "  " << std::setw(5) << fixed(a.cluster_intra_distance[static_cast<std::size_t>(c)], 3);
        for (std::size_t j = 0; j < names.size(); ++j) row << "  " << std::setw(8) << fixed(a.best.centroids(c, static_cast<Eigen::Index>(j)), 4);
        for (std::size_t q = 0; q < problem.objectives().size(); ++q) row << "  " << std::setw(8) << fixed(objective_sum[q] / size, 4);
        report.push_back(row.str());
      }
      clusters["clusters"] = table;
      statistics["clusters"] = clusters;
    }
  }
  statistics["report"] = report;
  for (const std::string& line : report) reporter.line(line, true);

  std::ostringstream message;
  message << runs.size() << " run(s) of " << o.algorithm << ", population " << o.population;
  if (stopped) {
    result.status = SolverStatus::kStopped;
    message << ": stopped on request";
  } else if (best_run < 0) {
    result.status = SolverStatus::kInfeasible;
    message << ": no feasible design found";
  } else if (budget > 0) {
    result.status = SolverStatus::kBudgetExhausted;
    message << ": " << budget << " run(s) reached the generation limit (" << o.generations << ") before stalling for "
            << o.stall_generations << " generations, " << converged << " converged";
  } else {
    result.status = SolverStatus::kConverged;
    message << ": every run converged (no improvement > " << o.ftol << " for " << o.stall_generations << " generations)";
  }
  if (best_run >= 0) message << "; best score " << fixed(runs[static_cast<std::size_t>(best_run)]["score"].get<double>(), 8) << " (run " << best_run + 1 << ")";
  result.message = message.str();
  result.statistics = statistics;
  return result;
}

}  // namespace hapsyn::plugins
