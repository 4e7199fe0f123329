#pragma once
/// \file
/// Solver `grid`: exhaustive search of the design grid (every free design variable needs a
/// step). Exact on the grid: it returns the best grid design (ties: the first in grid order),
/// whatever the thread count. It is the oracle later solvers are tested against.
///
/// With `prune` (default on, worst-case studies only) a design's evaluation stops as soon as its
/// upper bound from the samples seen so far falls strictly below the best score found; no
/// design that could tie or beat the optimum is ever cut, so the result is the same.
#include <hapsyn/solver.hpp>

namespace hapsyn::plugins {

class GridSolver : public Solver {
 public:
  explicit GridSolver(const Json& options);
  /// \throws Error when a free design variable has no step, or the grid is too large to index.
  void check(const Problem& problem) const override;
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;

 private:
  bool prune_ = true;
  double progress_interval_ = 2.0;  // seconds
};

}  // namespace hapsyn::plugins
