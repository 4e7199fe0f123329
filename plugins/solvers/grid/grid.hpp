#pragma once
/// \file
/// Solver `grid`: exhaustive search of the design grid (every free design variable needs a
/// step). Exact on the grid: it returns the best grid design (ties: the first in grid order),
/// whatever the thread count. It is the oracle later solvers are tested against.
///
/// With `prune` (default on, worst-case studies only) a design's evaluation stops as soon as its
/// upper bound from the samples seen so far falls strictly below the best score found; no
/// design that could tie or beat the optimum is ever cut, so the result is the same. With
/// `block_bounds` as well (default on; single objective or weighted sum) runs of a grid line are
/// ruled out at once where the mechanism's envelope of a sample bounds the run below the best
/// score found, or shows that every design of the run fails there (shared/bounds/run_bounds.hpp); the
/// counts then differ from a run without them (ruled-out designs count as pruned or failed),
/// the best design does not.
///
/// With `pareto` (two or more objectives) it returns the exact Pareto front of the grid instead:
/// every grid design is visited; with `prune` (worst-case studies, maximized objectives) a
/// design's workspace search stops as soon as the upper bounds of its objectives are dominated
/// by a point of the front found so far, which cannot cut a design of the final front. The
/// front's objective vectors do not depend on the thread count; of designs with identical
/// objective vectors the first in grid order is kept. This is the reference front for nbi.
///
/// Stop and resume: the grid is visited in chunks of 64 consecutive designs (grids of 2^20
/// designs and more: of whole lines of the last variable, the smallest multiple of a line with at
/// least 64 designs). A stop request is
/// honoured between pieces of a chunk (status stopped, the best or front of the designs searched so far);
/// the checkpoint (every checkpoint_interval seconds, at a stop and at the end) holds the
/// finished chunks, the best (index and score) or the front (indices and objective values) and
/// the counts. `--resume` re-evaluates the claimed best (every front point) and refuses the
/// checkpoint when a value differs, then visits the unfinished chunks: the result is bit for
/// bit the one of an uninterrupted run.
///
/// Ranks and shards: the chunks are the tasks of one task farm (hapsyn/cluster.hpp), handed out
/// to every thread of every rank of an MPI job; rank 0 collects each chunk's counts and best
/// (front points), reports progress and writes the checkpoint. The ranks share their best score
/// (their front) as they find it, so each prunes against what all found. Under `--shard i/N`
/// the i-th contiguous slice of the chunks runs and merge_shards() joins the shares' states;
/// the resumed merged state gives the single run's result. Best and front do not depend on the
/// thread count, rank count or shard split.
///
/// With pruning, designs that improve a thread's best (enter the front) and the winner are
/// spot-checked for the worst-case monotonicity rule (shared/bounds/worst_case_check.hpp): a breach
/// gives status failed naming the metric.
#include <hapsyn/options.hpp>
#include <hapsyn/solver.hpp>

namespace hapsyn::plugins {

struct GridOptions {
  bool prune{};
  bool pareto{};
  bool line_bounds{};
  bool block_bounds{};
  double progress_interval{};
  double checkpoint_interval{};
  double max_designs{};

  static void declare(OptionDeclarations<GridOptions>& d) {
    d.describe(
        "Exhaustive search over the grid lower + i*step of every free design variable. Single objective or "
        "weighted sum, or (pareto) the exact Pareto front of the grid.");
    d.add(&GridOptions::prune, "prune", true,
          "Worst-case studies: stop a design's workspace search once its bound falls below the best found (exact)");
    d.add(&GridOptions::pareto, "pareto", false,
          "Return the exact Pareto front of the grid (two or more objectives) instead of the best weighted sum; "
          "with prune, a design is abandoned once its objective bounds are dominated by the front so far (exact)");
    d.add(&GridOptions::line_bounds, "line_bounds", true,
          "Skip the designs of a grid line (the last variable varying) that the mechanism's constraint interval "
          "rules out, counting them as violating a constraint (exact: the same result and statistics; "
          "docs/design.md section 13.3)");
    d.add(&GridOptions::block_bounds, "block_bounds", true,
          "With prune, single objective or weighted sum: rule out runs of a grid line at once where the mechanism "
          "bounds a sample over the run (MechanismAcceleration::sample_envelope) and the metrics turn that into a score bound "
          "below the best found, or every design of the run fails there, and where a sample cannot be solved outside an "
          "interval of the line (MechanismAcceleration::reachable_interval); exact: the same optimum (docs/design.md sections 13.5 "
          "and 13.6). Ruled-out designs are counted as pruned (or failing at a sample) and in block_ruled_out");
    d.add(&GridOptions::progress_interval, "progress_interval", 2.0, "Seconds between progress lines on stderr")
        .greater_than(0)
        .unit("s");
    d.add(&GridOptions::checkpoint_interval, "checkpoint_interval", 30.0,
          "Seconds between checkpoints (and one when stopped or done); hapsyn run --resume continues from it")
        .greater_than(0)
        .unit("s");
    d.add(&GridOptions::max_designs, "max_designs", 1e12,
          "Most grid designs a search may have: a larger grid is refused at load (validate), not found out after days")
        .greater_than(0);
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
  /// when no grid design is feasible, kStopped when context.stop was set (best so far, the
  /// checkpoint written), kFailed when a metric breaks the worst-case monotonicity rule.
  /// \throws Error("checkpoint", ...) with context.resume when the checkpoint is damaged, edited,
  ///         foreign or its best (front) does not re-evaluate to the values it claims.
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;
  /// The chunks are one task farm over the ranks of an MPI job (pruning knowledge shared).
  /// `--shard i/N` runs the i-th contiguous slice of the chunks (status stopped, the shard's
  /// checkpoint written).
  SolverSpecs specs() const override { return {options_.pareto, true, true}; }
  /// One state of the shards' checkpoint states (in shard order): the finished chunks joined,
  /// the counts summed, the best by score (ties to the first grid index) or the fronts joined.
  /// Chunks no shard finished stay unfinished (a resumed run visits them).
  /// \throws Error("merge", "chunk 17 (grid designs 1088..1151) is finished in shard 1 and in
  ///         shard 2 of 3: the shares overlap; ...") and Error("merge", "shard 2/3: state.mode
  ///         is missing") for a state that does not hold together or is of the other mode.
  Json merge_shards(const Problem& problem, const std::vector<Json>& states) const override;

 private:
  SolverResult solve_best(const Problem& problem, const SolverContext& context) const;
  SolverResult solve_front(const Problem& problem, const SolverContext& context) const;
  GridOptions options_;
};

}  // namespace hapsyn::plugins
