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
#include <hapsyn/solver.hpp>

namespace hapsyn::plugins {

struct CullingOptions {
  bool seed = true;                 ///< seed the reference with an SQP local optimum
  bool polish = true;               ///< polish the grid optimum's cell with SQP
  int start_points = 5;             ///< points per free variable of the coarse start grid
  double sqp_xtol = 1e-7;           ///< SLSQP relative tolerance on the design
  double sqp_ftol = 1e-10;          ///< SLSQP absolute tolerance on the score
  int sqp_max_evaluations = 400;    ///< SLSQP objective evaluations (each a workspace search)
  double progress_interval = 2.0;   ///< seconds between progress lines
};

class CullingSolver : public Solver {
 public:
  explicit CullingSolver(const Json& options);
  /// \throws Error naming the metric when an objective is not worst-case, is minimized or has a
  ///         negative weight; or when a free design variable has no grid step.
  void check(const Problem& problem) const override;
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;

 private:
  CullingOptions options_;
};

}  // namespace hapsyn::plugins
