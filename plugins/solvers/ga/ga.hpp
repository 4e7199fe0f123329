#pragma once
/// \file
/// Solver `ga`: pagmo 2.18's mixed-integer evolutionary algorithms (sga, gaco) on the study's
/// score (a metric or a weighted sum, maximised), as Fennel et al. (2022) size the haptic 6R
/// with a mixed-integer GA. Through the shared pagmo adapter (shared/pagmo_adapter.hpp): integer
/// components last, constraint repair by sorting, penalties, parallel evaluation, a cache.
///
/// - Runs: `runs` independent runs (seeds derived from the study seed); the best over the runs
///   is the result; every run's optimum is in statistics.runs and, with 3 or more runs, their
///   k-means clusters (k by average silhouette) over the real design components, with intra-
///   and inter-cluster deviations and each cluster's mean objectives (Fennel, section VII).
/// - Stopping: a run converges when its best score has not improved by more than `ftol` for
///   `stall_generations` generations at full fidelity; it ends with budget_exhausted at
///   `generations`. The stop flag ends the study with status stopped.
/// - Checkpoints: every `checkpoint_every` generations (and after each run) the state (the
///   pagmo algorithm with its random engine, the population, counters, finished runs) is written
///   atomically to SolverContext::checkpoint_file; with SolverContext::resume the study
///   continues from it and gives exactly the result of an uninterrupted run.
/// - Multi-fidelity: the first `fidelity.generations` generations of each run evaluate a
///   deterministic stratified subset of the scene (`fidelity.subset_fraction` of the samples,
///   every k-th in sample index order); then the population is re-evaluated on the full scene
///   and the run continues there, so the final ranking is on the full scene.
/// - Progress (generation, best, mean, evaluations per second, time left) on
///   SolverContext::progress and every generation in SolverContext::log.
#include <hapsyn/solver.hpp>

#include <string>
#include <vector>

namespace hapsyn::plugins {

/// Options of the `ga` solver (schema.json has the same names, defaults and units).
struct GaOptions {
  std::string algorithm = "sga";     ///< "sga" or "gaco"
  int population = 50;               ///< individuals per generation
  int generations = 100;             ///< generation limit per run
  int stall_generations = 20;        ///< convergence: generations without improvement
  double ftol = 1e-6;                ///< improvement that counts [score units]
  int runs = 1;                      ///< independent runs
  int checkpoint_every = 0;          ///< generations between checkpoints (0 = none)
  std::string parallel_over = "individuals";  ///< batches: "individuals" or "samples"
  int sample_chunks = 16;            ///< chunks of one design's samples
  std::vector<std::string> sort_descending;   ///< repair: variables sorted descending
  std::vector<std::string> sort_ascending;    ///< repair: variables sorted ascending
  double subset_fraction = 1.0;      ///< multi-fidelity: fraction of the samples early on
  int fidelity_generations = 0;      ///< multi-fidelity: generations on the subset
  int max_clusters = 6;              ///< cluster analysis: largest k tried
  std::vector<std::string> cluster_variables;  ///< variables clustered (default: all real ones)
  double progress_interval = 2.0;    ///< seconds between progress lines on stderr
  // sga
  double crossover_probability = 0.9;
  std::string crossover = "sbx";
  double eta_c = 10.0;
  double mutation_probability = 0.1;
  std::string mutation = "polynomial";
  double param_m = 10.0;
  std::string selection = "tournament";
  int param_s = 2;
  // gaco
  int ker = 20;
  double q = 1.0;
  double oracle = 0.0;
  double acc = 0.01;
  int threshold = 1;
  int n_gen_mark = 7;
  double focus = 0.0;
};

class GaSolver : public Solver {
 public:
  /// \throws Error("ga: options.<key> = value: rule") for inconsistent options (gaco kernel
  ///         larger than the population, a subset fraction without fidelity generations, ...).
  explicit GaSolver(const Json& options);
  /// \throws Error when there is no free design variable, or a repair/cluster variable is unknown.
  void check(const Problem& problem) const override;
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;
  const GaOptions& options() const { return options_; }

 private:
  GaOptions options_;
  Json raw_options_;
};

}  // namespace hapsyn::plugins
