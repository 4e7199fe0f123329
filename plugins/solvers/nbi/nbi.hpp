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
///    solved by SLSQP (shared min-max SQP), warm-started from the nearest solved grid point
///    (L1 distance in beta; of equally near ones the first in the order shadows, then grid
///    order, among the grid points before it), and again from the best design (on this point's
///    merit t) of a seed pool: the shadow optima and `seed_designs` Halton designs evaluated
///    once. The better result is kept.
/// 4. Reverse sweep (`reverse_sweep`): every grid point solved again in reverse grid order, from
///    the nearest of the points after it (their better result) and the shadow optima (grid points
///    first on a tie); each point keeps the better of its two results. A chain of warm starts
///    from one shadow optimum can stay on a dominated branch of designs (README of the plugin).
/// 5. Every point is evaluated over the whole workspace; dominated points are dropped
///    (`filter_dominated`).
///
/// Degenerate payoff matrix: an objective whose payoff row has no spread (U_i - N_i <= 1e-9
/// max(|U_i|, |N_i|)) cannot be normalized. When that holds for some objectives only (a constant
/// objective, or one that does not conflict with the others at their optima), solve() returns
/// kFailed naming them: the front would be degenerate and silently so. When it holds for all
/// (one design is optimal in every objective), the front is that one point (kConverged, said
/// in the message).
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
#include <hapsyn/options.hpp>
#include <hapsyn/solver.hpp>

namespace hapsyn::plugins {

struct NbiOptions {
  int points{};
  double constraint_tolerance{};
  double xtol{};
  double ftol{};
  int max_evaluations{};
  int rounds{};
  int seed_designs{};
  bool reverse_sweep{};
  bool design_constraints{};
  bool filter_dominated{};
  SubSolver shadow_solver;

  static void declare(OptionDeclarations<NbiOptions>& d) {
    d.describe(
        "Normal Boundary Intersection (Das & Dennis 1998): shadow optima by a sub-solver, payoff matrix, a simplex "
        "grid of CHIM points, one SLSQP subproblem per point (epigraph form for worst-case metrics), warm-started "
        "from its neighbour; dominated points filtered. Continuous design variables only.");
    d.add(&NbiOptions::points, "points", 10,
          "Grid points per edge of the simplex, shadow points included (2 objectives: the number of front points)")
        .range(2, 1000);
    d.add(&NbiOptions::constraint_tolerance, "constraint_tolerance", 1e-8,
          "SLSQP constraint tolerance of each subproblem (normalized objectives, locals' units)")
        .greater_than(0);
    d.add(&NbiOptions::xtol, "xtol", 1e-7, "SLSQP relative tolerance on the design variables").greater_than(0);
    d.add(&NbiOptions::ftol, "ftol", 1e-10, "SLSQP absolute tolerance on t (normalized objective units)")
        .greater_than(0);
    d.add(&NbiOptions::max_evaluations, "max_evaluations", 200, "SLSQP evaluations per run of each subproblem stage")
        .minimum(1);
    d.add(&NbiOptions::rounds, "rounds", 6,
          "Active-set rounds per subproblem (each ends with a full workspace search)")
        .minimum(1);
    d.add(&NbiOptions::seed_designs, "seed_designs", 64,
          "Designs of a Halton sequence over the free box, evaluated once; each subproblem is also solved from the "
          "best of them (or of the shadow optima) for its grid point, and keeps the better result; 0: no second start")
        .range(0, 100000);
    d.add(&NbiOptions::reverse_sweep, "reverse_sweep", true,
          "Solve every grid point again in reverse grid order, warm-started from the points after it, and keep the "
          "better result: a chain of warm starts from one shadow optimum can stay on a dominated branch of designs");
    d.add(&NbiOptions::design_constraints, "design_constraints", false,
          "Hand the mechanism's design constraints g(p) <= 0 to SLSQP (finite-difference gradients); switch on when "
          "one binds the front, e.g. the five-bar's footprint");
    d.add(&NbiOptions::filter_dominated, "filter_dominated", true, "Drop dominated points from the front");
    d.add(&NbiOptions::shadow_solver, "shadow_solver", "culling",
          "Single-objective solver for the shadow (individual) optima: {\"plugin\", \"options\"}");
  }
};

class NbiSolver : public Solver {
 public:
  using Options = NbiOptions;
  explicit NbiSolver(const NbiOptions& options) : options_(options) {}
  /// Under MPI (and on several threads) the shadow optima are a task farm (each shadow solver
  /// runs whole on one rank, with its threads), then the subproblems run in waves: each wave is
  /// a farm of the subproblems whose warm start is settled (every earlier point that could be
  /// nearer is finished), one SLSQP run per thread. The starts, and so the front, are those of
  /// the one-by-one run in grid order, whatever the ranks and threads. With two objectives the
  /// starts form one chain (each point starts from the one before it), so only the first and
  /// the last subproblem run side by side; with three or more, the waves grow. The reverse
  /// sweep runs in waves the same way. The seed pool is evaluated on every rank (the same
  /// designs, deterministic), before the first wave.
  SolverSpecs specs() const override { return {true, true, false}; }
  /// \throws Error("nbi", ...) with fewer than two objectives, an integer free variable, no free
  ///         variable or a simplex grid too large; or when the shadow solver refuses one of the
  ///         single-objective problems ("<shadow_solver's path> (objective '<name>'): <its message>").
  void check(const Problem& problem) const override;
  /// The front (kConverged; one point, with a message saying so, when every shadow optimum has
  /// the same objective values: the objectives do not conflict); kInfeasible when a shadow
  /// optimum is not found (the first in objective order); kFailed without a shadow solver (options made without a registry) or
  /// when some but not all objectives have no spread in the payoff matrix (the message names
  /// them and what to do; the front would be degenerate); kStopped on a stop request (between
  /// shadow optima and subproblems, in the seed pool, in the reverse sweep, and inside the
  /// shadow solver), with the front of the points found so far.
  ///
  /// Checkpoint (context.checkpoint_file): written after every shadow optimum and every
  /// subproblem of either sweep (their records, designs, objective values and counts); on --resume the
  /// finished ones are skipped, after their designs are re-evaluated and found to give the
  /// claimed values, and the result is that of an uninterrupted run. The shadow solver runs
  /// without a checkpoint of its own (an interrupted shadow optimum is solved again). The
  /// finished ones need not be the first ones (each entry names its task).
  /// \throws Error("checkpoint", ...) on --resume with a checkpoint that fails the checks.
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;

 private:
  NbiOptions options_;
};

}  // namespace hapsyn::plugins
