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
#include <hapsyn/options.hpp>
#include <hapsyn/solver.hpp>

namespace hapsyn::plugins {

struct GridOptions {
  bool prune{};
  bool pareto{};
  double progress_interval{};

  static void declare(OptionDeclarations<GridOptions>& d) {
    d.describe(
        "Exhaustive search over the grid lower + i*step of every free design variable. Single objective or "
        "weighted sum, or (pareto) the exact Pareto front of the grid.");
    d.add(&GridOptions::prune, "prune", true,
          "Worst-case studies: stop a design's workspace search once its bound falls below the best found (exact)");
    d.add(&GridOptions::pareto, "pareto", false,
          "Return the exact Pareto front of the grid (two or more objectives) instead of the best weighted sum; "
          "with prune, a design is abandoned once its objective bounds are dominated by the front so far (exact)");
    d.add(&GridOptions::progress_interval, "progress_interval", 2.0, "Seconds between progress lines on stderr")
        .greater_than(0)
        .unit("s");
  }
};

class GridSolver : public Solver {
 public:
  using Options = GridOptions;
  explicit GridSolver(const GridOptions& options) : options_(options) {}
  /// \throws Error when a free design variable has no step, or the grid is too large to index;
  ///         in pareto mode, with fewer than two objectives.
  void check(const Problem& problem) const override;
  /// The best grid design (kConverged), or in pareto mode the grid's exact front; kInfeasible
  /// when no grid design is feasible, kStopped when context.stop was set (best so far).
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;
  bool pareto() const override { return options_.pareto; }

 private:
  SolverResult solve_best(const Problem& problem, const SolverContext& context) const;
  SolverResult solve_front(const Problem& problem, const SolverContext& context) const;
  GridOptions options_;
};

}  // namespace hapsyn::plugins
