#pragma once
/// \file
/// Solver `nbi`: Normal Boundary Intersection (Das & Dennis 1998) for Pareto fronts of any
/// number of objectives, as Unal et al. (2008) apply it to GII and GDI.
///
/// 1. Shadow optima: each objective alone, solved by a configurable single-objective sub-solver
///    (`shadow_solver`, default `culling`: exact on the design grid, then SQP polish).
/// 2. Payoff matrix Phi_ij = F_i(x_j*) (sense-signed, larger is better), utopia U_i = max_j
///    Phi_ij, nadir estimate N_i = min_j Phi_ij; objectives are normalized, Ft = (F - N)/(U - N),
///    so that the CHIM (convex hull of individual minima) lies in [0, 1]^m.
/// 3. A simplex grid of beta (`points` per edge; C(points + m - 2, m - 1) points in all) and, for
///    each interior beta, the subproblem (in the normalized min form G = 1 - Ft, Phibar = 1 - Phit,
///    quasi-normal n = -Phibar e):
///        maximize t   s.t.   G(x) <= Phibar beta + t n     (componentwise), x within bounds
///    solved by SLSQP (shared min-max SQP), warm-started from the nearest solved grid point.
/// 4. Every point is evaluated over the whole workspace; dominated points are dropped
///    (`filter_dominated`).
///
/// Formulation and convergence. Das & Dennis pose the equality G(x) = Phibar beta + t n. GII and
/// GDI are min-max functions (not differentiable where the critical sample changes), and an
/// equality on them would have to hold on a kink. We use the inequality relaxation (the
/// Pascoletti-Serafini scalarization, "NBIm"), which on the front gives the same points where
/// the normal line meets the front, and write each worst-case objective in epigraph form: with
/// z_l <= local_l(p, s) (min-reduced) and local_l(p, s) <= z_l (max-reduced) for the active
/// samples s, F_i(z) = combine_i(z) is smooth and bounds F_i(p) from below, so the subproblem is
/// a smooth NLP in (p, z, t). The active set grows with the samples that become critical, until
/// a full workspace search agrees: the point is then a KKT point of the subproblem over all
/// samples. A local optimizer can stop on a dominated point (a non-convex front, a local
/// optimum); the final filter removes those, and the result records each subproblem's outcome.
#include <hapsyn/solver.hpp>

namespace hapsyn::plugins {

struct NbiOptions {
  int points = 10;                    ///< grid points per simplex edge (shadow points included)
  double constraint_tolerance = 1e-8; ///< SLSQP constraint tolerance (locals' and normalized units)
  double xtol = 1e-7;                 ///< SLSQP relative tolerance on the variables
  double ftol = 1e-10;                ///< SLSQP absolute tolerance on t
  int max_evaluations = 200;          ///< SLSQP evaluations per run (plain and epigraph stage each)
  int rounds = 6;                     ///< active-set rounds per subproblem
  bool filter_dominated = true;       ///< drop dominated points from the front
  bool design_constraints = false;    ///< hand the mechanism's design constraints to SLSQP
  Json shadow_solver = {{"plugin", "culling"}, {"options", Json::object()}};
};

class NbiSolver : public Solver {
 public:
  explicit NbiSolver(const Json& options);
  bool pareto() const override { return true; }
  /// \throws Error("nbi", ...) with fewer than two objectives, or an integer free variable.
  void check(const Problem& problem) const override;
  /// Creates the shadow solver and checks it on each single-objective problem.
  /// \throws Error naming solver.options.shadow_solver.
  void prepare_sub_solvers(const Problem& problem, const Registry& registry) const override;
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;

 private:
  NbiOptions options_;
};

}  // namespace hapsyn::plugins
