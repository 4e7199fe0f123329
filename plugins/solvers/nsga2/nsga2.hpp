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
/// population (duplicates removed), sorted by the first objective. Runs the given number of
/// generations (status budget_exhausted; stopped on request). No checkpoints.
#include <hapsyn/solver.hpp>

#include <string>
#include <vector>

namespace hapsyn::plugins {

/// Options of `nsga2` (schema.json: the same names, defaults, ranges).
struct Nsga2Options {
  int population = 40;          ///< multiple of 4, >= 8 (pagmo's rule)
  int generations = 50;
  double cr = 0.95;             ///< crossover probability
  double eta_c = 10.0;          ///< sbx distribution index
  double m = 0.01;              ///< mutation probability per component
  double eta_m = 50.0;          ///< polynomial mutation distribution index
  std::string parallel_over = "individuals";
  int sample_chunks = 16;
  std::vector<std::string> sort_descending, sort_ascending;
  double progress_interval = 2.0;
};

class Nsga2Solver : public Solver {
 public:
  /// \throws Error("nsga2: options.population = 10: must be a multiple of 4 ...") and pagmo's refusals.
  explicit Nsga2Solver(const Json& options);
  bool pareto() const override { return true; }
  /// \throws Error with fewer than two objectives or no free design variable, or an unknown
  ///         repair variable.
  void check(const Problem& problem) const override;
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;

 private:
  Nsga2Options options_;
};

}  // namespace hapsyn::plugins
