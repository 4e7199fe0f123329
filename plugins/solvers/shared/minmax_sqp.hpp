#pragma once
/// \file
/// SQP (NLopt SLSQP) for goals over worst-case metrics, shared by the solvers `culling` (seed
/// and polish), `nbi` (one subproblem per simplex grid point) and whoever else needs a local
/// optimizer of min-max functions. A static library, not a plugin.
///
/// A worst-case metric is a min-max function of the design, not smooth where the critical
/// sample changes. The run therefore has two stages:
///
/// 1. **Plain**: SLSQP on the merit of the design itself (finite-difference gradients). Blind
///    to the kinks, but it handles the cliff where a sample stops being reachable (an
///    infeasible design scores below every feasible one), which binds e.g. the GDI optimum.
/// 2. **Epigraph** (worst-case problems only): SLSQP over (p, z, e), smooth:
///      maximize  goal.objective(z, e)
///      s.t.      z_l <= local_l(p, s)   for every min-reduced local l and active sample s
///                local_l(p, s) <= z_l   for every max-reduced local l and active sample s
///                goal.constraint(z, e) <= 0
///    z holds one value per local value of every metric (flat, metric by metric), e the goal's
///    extra variables (NBI's t). The active set starts with the near-critical samples of the
///    start point; after each SLSQP run the design is searched over the whole workspace, samples
///    that became critical join the active set, and SLSQP runs again (at most `rounds` times).
///    It stops when the whole workspace agrees with the active set: the point is then a KKT
///    point of the epigraph problem over *all* samples, i.e. a local optimum of the goal.
///
/// With `design_constraints`, both stages also pass the mechanism's design constraints
/// g(p) <= 0 (Problem::constraints) to SLSQP, with finite-difference gradients. Off by default:
/// an infeasible design is judged infeasible by the evaluation anyway, and on the five-bar the
/// reach constraint in SLSQP held one NBI point 0.003 below the front; on with a binding
/// constraint such as the five-bar's footprint, whose cliff the plain stage cannot follow.
///
/// Every candidate is evaluated over the whole workspace and judged by goal.merit; the best
/// fully evaluated feasible point is returned (never worse than the start when it is feasible).
#include <hapsyn/problem.hpp>

#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace hapsyn::plugins {

struct SqpSettings {
  double xtol = 1e-7;                   ///< SLSQP relative tolerance on the variables
  double ftol = 1e-10;                  ///< SLSQP absolute tolerance on the objective
  int max_evaluations = 400;            ///< SLSQP objective evaluations per run
  double constraint_tolerance = 1e-8;   ///< epigraph and goal constraint tolerance (locals' units)
  int rounds = 6;                       ///< active-set rounds of the epigraph stage
  bool plain = true;                    ///< run the plain stage first
  bool epigraph = true;                 ///< run the epigraph stage (worst-case problems only)
  bool design_constraints = false;      ///< pass the mechanism's design constraints to SLSQP
  /// Optional progress: called at most every `report_interval` seconds with a line such as
  /// "plain stage: 120 evaluations, best score 0.781 (12.3 s)" (an SQP over a large workspace
  /// may run for minutes).
  std::function<void(const std::string&)> report;
  double report_interval = 2.0;         ///< seconds between report lines
};

/// What the run maximizes. `objective`/`constraint` see the epigraph variables; `merit` judges a
/// fully evaluated feasible design and must agree with `objective` at z = the design's reduced
/// local values and the best feasible e.
struct MinMaxGoal {
  int extra = 0;        ///< extra variables after z
  int constraints = 0;  ///< goal constraints c(z, e) <= 0
  std::function<double(const double* z, const double* extra)> objective;
  std::function<void(const double* z, const double* extra, double* c)> constraint;  ///< may be empty if constraints == 0
  std::function<void(const double* z, double* extra)> initial_extra;               ///< may be empty if extra == 0
  std::function<double(const Evaluation& e)> merit;
};

/// The goal of a single-objective solver: maximize the study's score sum_o w_o s_o f_o.
MinMaxGoal score_goal(const Problem& problem);

/// Objective values f_o (natural units, per objective) from the flat epigraph locals z.
void objectives_from_locals(const Problem& problem, const double* z, double* f);
/// Number of local values over all metrics (the size of z).
std::size_t local_count(const Problem& problem);

struct SqpOutcome {
  std::vector<double> x;  ///< best fully evaluated feasible point (empty if none)
  double merit = -std::numeric_limits<double>::infinity();
  std::string status;     ///< "plain: <nlopt result>; epigraph: <nlopt result>"
  long long evaluations = 0, samples = 0;
  int rounds = 0;
  std::size_t active_samples = 0;
  double seconds = 0.0;
};

/// Runs the plain then the epigraph stage from x within [lower, upper].
/// \pre x, lower, upper have problem.dimension() entries; the goal's functions are set.
SqpOutcome run_minmax_sqp(const Problem& problem, const std::vector<double>& x, const std::vector<double>& lower,
                          const std::vector<double>& upper, const SqpSettings& settings, const MinMaxGoal& goal);

}  // namespace hapsyn::plugins
