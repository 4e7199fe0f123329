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
/// - Ranks and shards (hapsyn/cluster.hpp): under `--shard i/N`, or under MPI with at least as many runs as ranks or when the runs leave
///   fewer design evaluations per generation on the busiest thread than batches would
///   (ceil(runs/ranks) x ceil(population/threads) <= runs x ceil(population/(ranks x threads))), the runs are one shardable task farm (a run per task, on its rank's threads;
///   a shard runs its contiguous share of the run indices and checkpoints them, merge_shards
///   joins the shares); otherwise the runs follow one another and every batch of designs is a
///   task farm over the ranks (shared/pagmo_adapter.hpp). Each run has its own evaluator and
///   its result depends only on the seed and its index: the result is the same for any rank,
///   thread or shard count. Inside the runs farm a stop interrupts the runs in progress, which
///   start over on resume (a resumed run in progress stays in the checkpoint until it ends).
#include "ga_options.hpp"

#include <hapsyn/solver.hpp>

namespace hapsyn::plugins {

class GaSolver : public Solver {
 public:
  using Options = GaOptions;
  /// \throws Error("ga: options.<key> = value: rule") for option combinations the declarations
  ///         cannot express (gaco kernel larger than the population, a subset fraction without
  ///         fidelity generations, a param_m outside the range of its mutation, pagmo's refusals).
  explicit GaSolver(const GaOptions& options);
  /// \throws Error when there is no free design variable, or a repair/cluster variable is unknown.
  void check(const Problem& problem) const override;
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;
  SolverSpecs specs() const override { return {false, true, true}; }
  /// The shards' finished runs as one checkpoint state ("completed_runs" by run index, the
  /// evaluations summed, the longest elapsed time); --resume then re-checks every run's claimed
  /// optimum and summarises.
  /// \throws Error("merge", ...) when a state is damaged, holds a run in progress, a run outside
  ///         0..runs-1, a run another shard also holds, or when a run is in no shard.
  Json merge_shards(const Problem& problem, const std::vector<Json>& states) const override;

 private:
  GaOptions options_;
};

}  // namespace hapsyn::plugins
