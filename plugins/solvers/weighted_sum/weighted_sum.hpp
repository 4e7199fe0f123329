#pragma once
/// \file
/// Solver `weighted_sum`: Pareto points from weighted sums (Unal's aggregated performance index,
/// API = lambda GII + (1 - lambda) GDI). Each weight vector is one single-objective study of
/// sum_i w_i s_i f_i solved by a sub-solver (default `culling`, exact on the design grid); the
/// designs found are evaluated on every objective and the non-dominated ones form the front.
/// Weighted sums cannot reach the non-convex parts of a front, and equally spaced weights give
/// unequally spaced points (they clump): the statistics keep every weight's design to show it.
#include <hapsyn/options.hpp>
#include <hapsyn/solver.hpp>

#include <vector>

namespace hapsyn::plugins {

struct WeightedSumOptions {
  int count{};
  std::vector<std::vector<double>> weights;
  SubSolver sub_solver;

  static void declare(OptionDeclarations<WeightedSumOptions>& d) {
    d.describe(
        "Weighted-sum (aggregated index) Pareto study: one single-objective sub-solver run per weight vector; the "
        "non-dominated designs form the front (Unal 2008, Figure 3).");
    d.add(&WeightedSumOptions::count, "count", 10,
          "Weight vectors per edge of the simplex when `weights` is empty (2 objectives: lambda = 0, 1/(count-1), "
          "..., 1)")
        .range(2, 1000);
    d.add(&WeightedSumOptions::weights, "weights", {},
          "Explicit weight vectors, one weight per objective each (overrides count)");
    d.add(&WeightedSumOptions::sub_solver, "sub_solver", "culling",
          "Single-objective solver of each weighted sum: {\"plugin\", \"options\"}");
  }
};

class WeightedSumSolver : public Solver {
 public:
  using Options = WeightedSumOptions;
  explicit WeightedSumSolver(const WeightedSumOptions& options) : options_(options) {}
  /// Under MPI the weight vectors are a task farm: each one's sub-solver runs whole on one
  /// rank (its threads, no progress lines of its own), and the front is the same whatever the
  /// number of ranks (the weight vectors are independent).
  SolverSpecs specs() const override { return {true, true, false}; }
  /// \throws Error("weighted_sum", ...) with fewer than two objectives, or when a weight vector
  ///         has the wrong length, a negative or non-finite entry, or sums to zero; or when the
  ///         sub-solver refuses a reweighted problem ("<sub_solver's path>: <its message>").
  void check(const Problem& problem) const override;
  /// The front (kConverged); kInfeasible when no weight found a feasible design; kFailed
  /// without a sub-solver (options made without a registry); kStopped on a stop request
  /// (between weight vectors, and inside the sub-solver), with the front of the finished weight
  /// vectors (an interrupted sub-solver's best is not used).
  ///
  /// Checkpoint (context.checkpoint_file): written after every weight vector (its record,
  /// design, objective values and counts); on --resume the finished ones are skipped, after
  /// their designs are re-evaluated and found to give the claimed values, and the result is
  /// that of an uninterrupted run. The sub-solver runs without a checkpoint of its own. Under
  /// MPI the finished ones need not be the first ones (each entry names its task).
  /// \throws Error("checkpoint", ...) on --resume with a checkpoint that fails the checks.
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;
  /// The weight vectors the options give for `objectives` objectives: `weights` when given,
  /// else the simplex grid with `count` points per edge.
  std::vector<std::vector<double>> weight_vectors(std::size_t objectives) const;

 private:
  WeightedSumOptions options_;
};

}  // namespace hapsyn::plugins
