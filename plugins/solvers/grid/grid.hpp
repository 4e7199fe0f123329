#pragma once
/// \file
/// Solver `grid`: exhaustive search of the design grid (every free design variable needs a
/// step). Exact on the grid: it returns the best grid design (ties: the first in grid order),
/// whatever the thread count. It is the oracle later solvers are tested against.
///
/// With `prune` (default on, worst-case studies only) a design's evaluation stops as soon as its
/// upper bound from the samples seen so far falls strictly below the best score found; no
/// design that could tie or beat the optimum is ever cut, so the result is the same.
///
/// With `pareto` (two or more objectives) it returns the exact Pareto front of the grid instead:
/// every grid design is visited; with `prune` (worst-case studies, maximized objectives) a
/// design's workspace search stops as soon as the upper bounds of its objectives are dominated
/// by a point of the front found so far, which cannot cut a design of the final front. The
/// front's objective vectors do not depend on the thread count; of designs with identical
/// objective vectors the first in grid order is kept. This is the reference front for nbi.
#include <hapsyn/solver.hpp>

namespace hapsyn::plugins {

class GridSolver : public Solver {
 public:
  explicit GridSolver(const Json& options);
  /// \throws Error when a free design variable has no step, or the grid is too large to index;
  ///         in pareto mode, with fewer than two objectives.
  void check(const Problem& problem) const override;
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;
  bool pareto() const override { return pareto_; }

 private:
  SolverResult solve_front(const Problem& problem, const SolverContext& context) const;
  bool prune_ = true;
  bool pareto_ = false;
  double progress_interval_ = 2.0;  // seconds
};

}  // namespace hapsyn::plugins
