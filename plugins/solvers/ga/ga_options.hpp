#pragma once
/// \file
/// Options of the `ga` solver, declared once (hapsyn/options.hpp): names, defaults, ranges,
/// choices and descriptions live only here. `hapsyn describe ga` prints them.
/// The checkpoint's study fingerprint takes the values through hapsyn::options_to_json, from the
/// same declarations, so no option is listed a second time.
#include "shared/batch_options.hpp"

#include <hapsyn/options.hpp>

#include <string>
#include <vector>

namespace hapsyn::plugins {

/// options.fidelity: the multi-fidelity schedule of each run.
struct GaFidelityOptions {
  double subset_fraction{};  ///< share of the samples evaluated early, in (0, 1]
  int generations{};         ///< generations of each run on the subset (0 = none)
  double refine_fraction{};  ///< share of the samples evaluated after them, until the stall, in (0, 1]
  int final_candidates{};    ///< with refine_fraction < 1: the best ranked on the full scene at the end

  static void declare(OptionDeclarations<GaFidelityOptions>& d) {
    d.add(&GaFidelityOptions::subset_fraction, "subset_fraction", 1.0,
          "Share of the samples evaluated early (every k-th in sample index order)")
        .greater_than(0)
        .maximum(1);
    d.add(&GaFidelityOptions::generations, "generations", 0, "Generations of each run on the subset (0 = none)")
        .minimum(0);
    d.add(&GaFidelityOptions::refine_fraction, "refine_fraction", 1.0,
          "Share of the samples the generations after the subset ones evaluate, until the run stalls (every k-th in "
          "sample index order; 1 = the full scene). Below 1, each run ends by evaluating its final_candidates best "
          "on the full scene, and its best is the best of them")
        .greater_than(0)
        .maximum(1);
    d.add(&GaFidelityOptions::final_candidates, "final_candidates", 20,
          "With refine_fraction < 1: how many of a run's last population (best first, at the refine fidelity) are "
          "evaluated on the full scene when the run ends")
        .range(1, 1000000);
    using F = GaFidelityOptions;
    d.rule({"subset_fraction", "generations"}, "subset_fraction < 1 needs generations >= 1", [](const F& f) {
      return f.subset_fraction < 1.0 && f.generations == 0
                 ? "needs options.fidelity.generations >= 1 (the generations evaluated on the subset)"
                 : std::string();
    });
    d.rule({"generations", "subset_fraction"}, "generations >= 1 needs subset_fraction < 1", [](const F& f) {
      return f.generations > 0 && f.subset_fraction >= 1.0
                 ? "needs options.fidelity.subset_fraction < 1 (the share of the samples evaluated early)"
                 : std::string();
    });
    d.rule({"refine_fraction", "generations"}, "refine_fraction < 1 needs generations >= 1", [](const F& f) {
      return f.refine_fraction < 1.0 && f.generations == 0
                 ? "needs options.fidelity.generations >= 1 (the refine subset follows the subset generations)"
                 : std::string();
    });
    d.rule({"refine_fraction", "subset_fraction"}, "refine_fraction > subset_fraction or refine_fraction = 1",
           [](const F& f) {
             return f.refine_fraction < 1.0 && !(f.refine_fraction > f.subset_fraction)
                        ? "must be greater than options.fidelity.subset_fraction (" + render_value(Json(f.subset_fraction)) +
                              ") or 1 (the full scene)"
                        : std::string();
           });
  }
};

/// options.sga: the parameters of pagmo::sga.
struct GaSgaOptions {
  double crossover_probability{};
  std::string crossover;  ///< "exponential", "binomial", "single" or "sbx"
  double eta_c{};
  double mutation_probability{};
  std::string mutation;  ///< "gaussian", "polynomial" or "uniform"
  /// Polynomial: distribution index in [1, 100]; gaussian/uniform: width in [0, 1] (a declared
  /// rule checks the range that goes with `mutation`).
  double param_m{};
  std::string selection;  ///< "tournament" or "truncated"
  int param_s{};

  static void declare(OptionDeclarations<GaSgaOptions>& d) {
    d.add(&GaSgaOptions::crossover_probability, "crossover_probability", 0.9, "Crossover probability").range(0, 1);
    d.add(&GaSgaOptions::crossover, "crossover", "sbx", "Crossover operator")
        .one_of({"exponential", "binomial", "single", "sbx"});
    d.add(&GaSgaOptions::eta_c, "eta_c", 10.0, "Distribution index of sbx crossover").range(1, 100);
    d.add(&GaSgaOptions::mutation_probability, "mutation_probability", 0.1, "Mutation probability per component")
        .range(0, 1);
    d.add(&GaSgaOptions::mutation, "mutation", "polynomial", "Mutation operator")
        .one_of({"gaussian", "polynomial", "uniform"});
    d.add(&GaSgaOptions::param_m, "param_m", 10.0,
          "Distribution index (polynomial, in [1, 100]) or width (gaussian, in [0, 1]) of the mutation")
        .minimum(0);
    d.add(&GaSgaOptions::selection, "selection", "tournament", "Selection").one_of({"tournament", "truncated"});
    d.add(&GaSgaOptions::param_s, "param_s", 2, "Tournament size, or the number of best individuals kept (truncated)")
        .minimum(1);
    d.rule({"param_m", "mutation"}, "param_m in [1, 100] (polynomial) or [0, 1] (gaussian, uniform)",
           [](const GaSgaOptions& o) -> std::string {
             if (o.mutation == "polynomial") {
               return o.param_m < 1.0 || o.param_m > 100.0
                          ? "must lie in [1, 100] (distribution index of polynomial mutation)"
                          : "";
             }
             return o.param_m < 0.0 || o.param_m > 1.0 ? "must lie in [0, 1] (width of " + o.mutation + " mutation)" : "";
           });
  }
};

/// options.gaco: the parameters of pagmo::gaco (run with memory on).
struct GaGacoOptions {
  int ker{};  ///< solution archive size; at most the population (a rule of GaOptions)
  double q{};
  double oracle{};
  double acc{};
  int threshold{};
  int n_gen_mark{};
  double focus{};

  static void declare(OptionDeclarations<GaGacoOptions>& d) {
    d.add(&GaGacoOptions::ker, "ker", 20, "Solution archive (kernel) size; at most the population").minimum(1);
    d.add(&GaGacoOptions::q, "q", 1.0, "Convergence speed parameter").minimum(0);
    d.add(&GaGacoOptions::oracle, "oracle", 0.0, "Oracle parameter of the penalty method");
    d.add(&GaGacoOptions::acc, "acc", 0.01, "Accuracy parameter of the constraint handling").minimum(0);
    d.add(&GaGacoOptions::threshold, "threshold", 1, "Generation from which q is reduced").minimum(1);
    d.add(&GaGacoOptions::n_gen_mark, "n_gen_mark", 7, "Convergence speed of the standard deviations").minimum(1);
    d.add(&GaGacoOptions::focus, "focus", 0.0, "Focus on the best solutions").minimum(0);
  }
};

/// Options of the `ga` solver.
struct GaOptions {
  std::string algorithm;  ///< "sga" or "gaco"
  int population{};
  int generations{};        ///< generation limit of a run
  int stall_generations{};  ///< a run converges after this many generations without improvement
  double ftol{};            ///< improvement of the best score that resets the stall count [score units]
  int runs{};
  int checkpoint_every{};      ///< generations between checkpoints (0 = none)
  std::string parallel_over;   ///< "individuals" or "samples"
  int sample_chunks{};
  std::vector<std::string> sort_descending;  ///< repair: variables sorted descending
  std::vector<std::string> sort_ascending;   ///< repair: variables sorted ascending
  GaFidelityOptions fidelity;
  int max_clusters{};
  std::vector<std::string> cluster_variables;  ///< empty: every real free component
  double progress_interval{};                  ///< [s]
  GaSgaOptions sga;
  GaGacoOptions gaco;

  static void declare(OptionDeclarations<GaOptions>& d) {
    d.describe(
        "Mixed-integer evolutionary search with pagmo 2.18 (sga or gaco) maximizing the study's score (one metric or a "
        "weighted sum). Integer design variables are pagmo's integer part; constraints by a sort repair "
        "(sort_descending / sort_ascending) and penalties. Several independent runs with k-means/silhouette "
        "clustering of their optima, checkpoints for hapsyn run --resume, multi-fidelity on a scene subset.");
    d.add(&GaOptions::algorithm, "algorithm", "sga",
          "pagmo algorithm: sga (simple genetic algorithm) or gaco (extended ant colony); either evaluates each "
          "generation as one batch of designs")
        .one_of({"sga", "gaco"});
    d.add(&GaOptions::population, "population", 50, "Individuals per generation").range(2, 100000);
    d.add(&GaOptions::generations, "generations", 100,
          "Generation limit of a run (status budget_exhausted when reached)")
        .range(1, 1000000);
    d.add(&GaOptions::stall_generations, "stall_generations", 20,
          "A run converges after this many generations without an improvement of the best score larger than ftol "
          "(on the full scene)")
        .minimum(1);
    d.add(&GaOptions::ftol, "ftol", 1e-6, "Improvement of the best score that resets the stall count [score units]")
        .minimum(0);
    d.add(&GaOptions::runs, "runs", 1,
          "Independent runs (seeds derived from the study seed); with 3 or more, their optima are clustered")
        .range(1, 1000);
    d.add(&GaOptions::checkpoint_every, "checkpoint_every", 0,
          "Generations between checkpoints (output directory's checkpoint.json, for hapsyn run --resume); 0 = none")
        .minimum(0);
    declare_batch_options(d);
    d.add(&GaOptions::fidelity, "fidelity",
          "Multi-fidelity: the first generations on a deterministic stratified subset of the scene, then the "
          "population re-evaluated and the run continued on the full scene");
    d.add(&GaOptions::max_clusters, "max_clusters", 6,
          "Largest k of the k-means cluster analysis of the runs' optima (k = 2..max chosen by average silhouette)")
        .range(2, 50);
    d.add(&GaOptions::cluster_variables, "cluster_variables", {},
          "Design variables whose free components are clustered (default: every real-valued free component; "
          "haptic6r: the link lengths l)");
    d.add(&GaOptions::progress_interval, "progress_interval", 2.0,
          "Seconds between progress lines on stderr (run.log gets every generation)")
        .greater_than(0)
        .unit("s");
    d.add(&GaOptions::sga, "sga", "pagmo::sga parameters");
    d.add(&GaOptions::gaco, "gaco", "pagmo::gaco parameters (memory on: one generation per call)");
    d.rule({"gaco.ker", "population", "algorithm"}, "gaco.ker <= population (algorithm gaco)",
           [](const GaOptions& o) {
             return o.algorithm == "gaco" && o.gaco.ker > o.population
                        ? "must not exceed options.population (" + std::to_string(o.population) +
                              "): gaco fills its solution archive from the population"
                        : std::string();
           });
    d.rule({"sga.param_s", "population", "algorithm", "sga.selection"},
           "sga.param_s <= population (algorithm sga, tournament selection)", [](const GaOptions& o) {
             return o.algorithm == "sga" && o.sga.selection == "tournament" && o.sga.param_s > o.population
                        ? "the tournament size must not exceed options.population (" + std::to_string(o.population) +
                              ")"
                        : std::string();
           });
  }
};

}  // namespace hapsyn::plugins
