#pragma once
/// \file
/// Solver `weighted_sum`: Pareto points from weighted sums (Unal's aggregated performance index,
/// API = lambda GII + (1 - lambda) GDI). Each weight vector is one single-objective study of
/// sum_i w_i s_i f_i solved by a sub-solver (default `culling`, exact on the design grid); the
/// designs found are evaluated on every objective and the non-dominated ones form the front.
/// Weighted sums cannot reach the non-convex parts of a front, and equally spaced weights give
/// unequally spaced points (they clump): the statistics keep every weight's design to show it.
#include <hapsyn/solver.hpp>

namespace hapsyn::plugins {

class WeightedSumSolver : public Solver {
 public:
  explicit WeightedSumSolver(const Json& options);
  bool pareto() const override { return true; }
  /// \throws Error("weighted_sum", ...) with fewer than two objectives, or when a weight vector
  ///         has the wrong length, a negative or non-finite entry, or sums to zero.
  void check(const Problem& problem) const override;
  /// \throws Error naming solver.options.sub_solver (unknown plugin, bad options, refused problem).
  void prepare_sub_solvers(const Problem& problem, const Registry& registry) const override;
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;
  /// The weight vectors the options give for `objectives` objectives: `weights` when given,
  /// else the simplex grid with `count` points per edge.
  std::vector<std::vector<double>> weight_vectors(std::size_t objectives) const;

 private:
  Json weights_;   // array of arrays, or empty
  int count_ = 10;
  Json sub_solver_;
};

}  // namespace hapsyn::plugins
