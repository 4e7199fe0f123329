#pragma once
/// \file
/// Solver `culling`: exact worst-case optimization on the design grid (the modified culling
/// algorithm of Stocco, Salcudean & Sassani 1998 as used by Unal et al. 2008).
///
/// For a worst-case metric, the value over any subset of samples bounds the value over the
/// whole scene from above (GII(p) <= sigma_min(J(p,a)) / sigma_max(J(p,b))). One full workspace
/// search of a reference design yields critical samples; every other grid design is first
/// bounded at the critical samples collected so far and culled when the bound falls strictly
/// below the reference. Only designs that survive get a full workspace search; a better one
/// becomes the reference and adds its critical samples. The result is exactly the optimum an
/// exhaustive search of the same grid returns (ties: the first in grid order).
///
/// Unal's modification: the reference is seeded with a local SQP optimum (NLopt SLSQP, from the
/// best point of a coarse start grid, snapped to the design grid), and the final grid cell is
/// polished with SQP. Both can be switched off.
///
/// Stop and resume: a stop request is honoured between designs (during the seed, between its
/// evaluations and before its SQP): status stopped with the reference so far (the best fully
/// searched grid design, not polished). The checkpoint (after the seed, every
/// checkpoint_interval seconds, when stopped and at the end) holds the finished grid lines, the
/// reference (index and score), the critical samples, the counts and the seed's figures.
/// `--resume` re-evaluates the reference and refuses the checkpoint when its score differs, then
/// sweeps the unfinished lines: the grid optimum is bit for bit the uninterrupted run's.
///
/// Ranks and shards: the seed runs on rank 0, which broadcasts its reference; the sweep's lines
/// are the tasks of one task farm (hapsyn/cluster.hpp) on every thread of every rank, rank 0
/// collecting each line's counts, best design and critical samples, one record per task (and writing the
/// checkpoint). The ranks share their reference and critical samples as they find them. Under
/// `--shard i/N` the i-th contiguous slice of the lines is swept (after the seed, which every
/// shard runs alike) and merge_shards() joins the shares' states. The grid optimum does not
/// depend on the thread count, rank count or shard split; the polish runs on rank 0.
///
/// Monotonicity spot check (shared/bounds/worst_case_check.hpp): every design that survives its bound
/// at the critical samples and is then searched in full compares that bound with its full
/// value, and the grid optimum is checked on half of the samples; a bound below the full value
/// (a metric breaking the worst-case rule) gives status failed naming the metric.
#include <hapsyn/options.hpp>
#include <hapsyn/solver.hpp>

namespace hapsyn::plugins {

struct CullingOptions {
  bool seed{};
  bool polish{};
  int start_points{};
  double sqp_xtol{};
  double seed_xtol{};
  double sqp_ftol{};
  int sqp_max_evaluations{};
  bool line_bounds{};
  bool block_bounds{};
  double progress_interval{};
  double checkpoint_interval{};
  double max_designs{};

  static void declare(OptionDeclarations<CullingOptions>& d) {
    d.describe(
        "Exact culling (branch-and-bound) over the design grid for worst-case metrics and non-negative weighted "
        "sums of them (Stocco 1998, Unal 2008). Every free design variable needs a step.");
    d.add(&CullingOptions::seed, "seed", true,
          "Seed the reference design with an SQP (NLopt SLSQP) local optimum, snapped to the grid");
    d.add(&CullingOptions::polish, "polish", true,
          "Polish the grid optimum's cell (+- one step) with SQP; the grid optimum is kept in the statistics");
    d.add(&CullingOptions::start_points, "start_points", 5,
          "Points per free variable of the coarse grid the SQP seed starts from")
        .range(2, 50);
    d.add(&CullingOptions::sqp_xtol, "sqp_xtol", 1e-7, "SLSQP relative tolerance on the design variables (polish)")
        .greater_than(0);
    d.add(&CullingOptions::seed_xtol, "seed_xtol", 1e-5,
          "SLSQP relative tolerance on the design variables in the seed, which only needs a grid cell near the "
          "optimum (the paper's GII file: 245 full searches at 1e-5, 1,049 at 1e-7; docs/design.md "
          "section 3.9)")
        .greater_than(0);
    d.add(&CullingOptions::sqp_ftol, "sqp_ftol", 1e-10, "SLSQP absolute tolerance on the score").greater_than(0);
    d.add(&CullingOptions::sqp_max_evaluations, "sqp_max_evaluations", 400,
          "SLSQP objective evaluations per run (each one a full workspace search)")
        .minimum(1);
    d.add(&CullingOptions::line_bounds, "line_bounds", true,
          "Skip the designs of a grid line (the last variable varying) that the mechanism's constraint interval "
          "rules out, counting them as violating a constraint (exact: the same result and statistics; "
          "docs/design.md section 13.3)");
    d.add(&CullingOptions::block_bounds, "block_bounds", true,
          "Rule out runs of a grid line at once where the mechanism bounds a critical sample over the run "
          "(MechanismAcceleration::sample_envelope) and the metrics turn that into a score bound below the reference, and where a "
          "critical sample cannot be solved outside an interval of the line (MechanismAcceleration::reachable_interval); exact: the "
          "same optimum (docs/design.md sections 13.5 and 13.6). Ruled-out designs are counted in block_ruled_out, not "
          "culled");
    d.add(&CullingOptions::progress_interval, "progress_interval", 2.0, "Seconds between progress lines on stderr")
        .greater_than(0)
        .unit("s");
    d.add(&CullingOptions::checkpoint_interval, "checkpoint_interval", 30.0,
          "Seconds between checkpoints (and one after the seed, when stopped and at the end); hapsyn run --resume "
          "continues from it")
        .greater_than(0)
        .unit("s");
    d.add(&CullingOptions::max_designs, "max_designs", 1e12,
          "Most grid designs a search may have: a larger grid is refused at load (validate), not found out after days")
        .greater_than(0);
  }
};

class CullingSolver : public Solver {
 public:
  using Options = CullingOptions;
  explicit CullingSolver(const CullingOptions& options) : options_(options) {}
  /// \throws Error naming the metric when an objective is not worst-case, is minimized or has a
  ///         negative weight; or when a free design variable has no grid step.
  void check(const Problem& problem) const override;
  /// The grid optimum (polished) with kConverged, kInfeasible, kStopped (context.stop set: the
  /// reference so far, the checkpoint written) or kFailed (a metric breaks the worst-case rule).
  /// \throws Error("checkpoint", ...) with context.resume when the checkpoint is damaged, edited,
  ///         foreign or its reference does not re-evaluate to the score it claims.
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;
  /// The lines are one task farm over the ranks of an MPI job; the seed runs on rank 0.
  /// `--shard i/N` sweeps the i-th contiguous slice of the lines (status stopped, the shard's
  /// checkpoint written).
  SolverSpecs specs() const override { return {false, true, true}; }
  /// One state of the shards' checkpoint states (in shard order): the finished lines joined,
  /// the counts summed, the best reference (ties to the first grid index), the critical
  /// samples joined, the first shard's seed. Lines no shard finished stay unfinished.
  /// \throws Error("merge", "line 17 (grid designs ...) is finished in shard 1 and in shard 2
  ///         of 3: the shares overlap; ...") and Error("merge", "shard 2/3: state.counts.culled
  ///         is missing") for a state that does not hold together.
  Json merge_shards(const Problem& problem, const std::vector<Json>& states) const override;

 private:
  CullingOptions options_;
};

}  // namespace hapsyn::plugins
