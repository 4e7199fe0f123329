#pragma once
/// \file
/// Solver `nsga2`: pagmo 2.18's NSGA-II (mixed integer through pagmo's integer part) for Pareto
/// studies: every objective of the study is one objective of the front (maximised or minimised
/// by its sense). Through the pagmo adapter it shares with `ga` (shared/pagmo_adapter.hpp):
/// integer components last, the sort repair, penalties for infeasible designs (dominated by
/// every feasible one), batches evaluated over the threads (one design per thread, or each
/// design split over the samples), a cache of evaluated designs.
///
/// The result's front is the non-dominated set of the feasible designs of the final
/// population (duplicates removed), sorted by the objectives (one point when one design is
/// feasible). Runs the given number of generations (status budget_exhausted).
///
/// Stop and resume: a stop request is honoured between generations (status stopped, the front
/// of the current population). The checkpoint (every checkpoint_every generations and at a
/// stop) holds the generation, the algorithm with its random engine, the population's decision
/// and fitness vectors and the counts; `--resume` re-evaluates the population, refuses the
/// checkpoint when a fitness vector differs, and continues: the front is exactly the one of an
/// uninterrupted run with the seed.
///
/// Under MPI (distributed()): every rank runs the same NSGA-II; each generation's batch is a task
/// farm over the ranks whose fitness values rank 0 broadcasts (shared/pagmo_adapter.hpp), and
/// the stop check between generations sees the agreed flag, so the front does not depend on the
/// rank count. Not shardable: the generations follow one another.
#include "shared/batch_options.hpp"

#include <hapsyn/options.hpp>
#include <hapsyn/solver.hpp>

#include <string>
#include <vector>

namespace hapsyn::plugins {

/// Options of `nsga2`.
struct Nsga2Options {
  int population{};  ///< a multiple of 4 (pagmo's rule; a declared rule)
  int generations{};
  double cr{};     ///< crossover probability
  double eta_c{};  ///< sbx distribution index
  double m{};      ///< mutation probability per component
  double eta_m{};  ///< polynomial mutation distribution index
  std::string parallel_over;  ///< "individuals" or "samples"
  int sample_chunks{};
  std::vector<std::string> sort_descending;
  std::vector<std::string> sort_ascending;
  double progress_interval{};  ///< [s]
  int checkpoint_every{};      ///< generations between checkpoints (0 = only at a stop)

  static void declare(OptionDeclarations<Nsga2Options>& d) {
    d.describe(
        "Pareto front of the study's objectives with pagmo 2.18's NSGA-II (mixed integer through pagmo's integer "
        "part; sort repair and penalties as in ga; batches over the threads). Runs the given generations; the front "
        "is the non-dominated feasible designs of the final population.");
    d.add(&Nsga2Options::population, "population", 40, "Individuals per generation (a multiple of 4)")
        .range(8, 100000);
    d.add(&Nsga2Options::generations, "generations", 50, "Generations (status budget_exhausted when done)")
        .range(1, 1000000);
    d.add(&Nsga2Options::cr, "cr", 0.95, "Crossover probability (sbx)").minimum(0).less_than(1);
    d.add(&Nsga2Options::eta_c, "eta_c", 10.0, "Distribution index of the sbx crossover").range(1, 100);
    d.add(&Nsga2Options::m, "m", 0.01, "Mutation probability per component").range(0, 1);
    d.add(&Nsga2Options::eta_m, "eta_m", 50.0, "Distribution index of the polynomial mutation").range(1, 100);
    declare_batch_options(d);
    d.add(&Nsga2Options::progress_interval, "progress_interval", 2.0,
          "Seconds between progress lines on stderr (run.log gets every generation)")
        .greater_than(0)
        .unit("s");
    d.add(&Nsga2Options::checkpoint_every, "checkpoint_every", 10,
          "Generations between checkpoints (output directory's checkpoint.json, for hapsyn run --resume; one is "
          "also written at a stop); 0 = only at a stop")
        .range(0, 1000000);
    d.rule({"population"}, "population is a multiple of 4", [](const Nsga2Options& o) {
      return o.population % 4 != 0 ? std::string("must be a multiple of 4 (pagmo's NSGA-II pairs parents in fours)")
                                   : std::string();
    });
  }
};

class Nsga2Solver : public Solver {
 public:
  using Options = Nsga2Options;
  /// \throws Error for pagmo's refusals (the declared rules are checked before this runs).
  explicit Nsga2Solver(const Nsga2Options& options);
  SolverSpecs specs() const override { return {true, true, false}; }
  /// \throws Error with fewer than two objectives or no free design variable, or an unknown
  ///         repair variable.
  void check(const Problem& problem) const override;
  /// The final population's front with kBudgetExhausted, kInfeasible, or kStopped (context.stop
  /// set: the current front, the checkpoint written).
  /// \throws Error("checkpoint", ...) with context.resume when the checkpoint is damaged, edited,
  ///         foreign, or its population does not re-evaluate to the fitness it claims.
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;

 private:
  Nsga2Options options_;
};

}  // namespace hapsyn::plugins
