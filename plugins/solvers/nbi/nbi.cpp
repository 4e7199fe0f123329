#include "nbi.hpp"

#include "../shared/minmax_sqp.hpp"
#include "../shared/sub_solver.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/pareto.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

namespace hapsyn::plugins {

namespace {
using Clock = std::chrono::steady_clock;
constexpr double kInf = std::numeric_limits<double>::infinity();
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
double sign_of(Sense s) { return s == Sense::kMaximize ? 1.0 : -1.0; }

// The normalized subproblem of one grid point: Ft_i(x) >= a_i + t d_i for every objective.
struct Subproblem {
  const Problem* problem = nullptr;
  std::vector<double> sign, nadir, scale;  // Ft_i = (sign_i f_i - nadir_i) / scale_i
  std::vector<double> a, d;
  mutable std::vector<double> f;  // scratch: objective values

  double normalized(std::size_t i, double value) const { return (sign[i] * value - nadir[i]) / scale[i]; }
  // Largest t the objective values allow (the merit of a fully evaluated design).
  double t_of(const double* values) const {
    double t = kInf;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const double slack = normalized(i, values[i]) - a[i];
      if (d[i] > 0) {
        t = std::min(t, slack / d[i]);
      } else if (slack < 0) {
        t = std::min(t, -1e3 + slack);  // a constraint without t that fails: far below any t
      }
    }
    return std::isfinite(t) ? t : 0.0;
  }
};

MinMaxGoal nbi_goal(const Subproblem& sub) {
  MinMaxGoal goal;
  goal.extra = 1;
  goal.constraints = static_cast<int>(sub.a.size());
  const Subproblem* s = &sub;
  goal.objective = [](const double*, const double* e) { return e[0]; };
  goal.constraint = [s](const double* z, const double* e, double* c) {
    s->f.resize(s->a.size());
    objectives_from_locals(*s->problem, z, s->f.data());
    for (std::size_t i = 0; i < s->a.size(); ++i) c[i] = s->a[i] + e[0] * s->d[i] - s->normalized(i, s->f[i]);
  };
  goal.initial_extra = [s](const double* z, double* e) {
    s->f.resize(s->a.size());
    objectives_from_locals(*s->problem, z, s->f.data());
    e[0] = s->t_of(s->f.data());
  };
  goal.merit = [s](const Evaluation& ev) { return s->t_of(ev.objectives.data()); };
  return goal;
}
}  // namespace

NbiSolver::NbiSolver(const Json& o) {
  options_.points = o.value("points", options_.points);
  options_.constraint_tolerance = o.value("constraint_tolerance", options_.constraint_tolerance);
  options_.xtol = o.value("xtol", options_.xtol);
  options_.ftol = o.value("ftol", options_.ftol);
  options_.max_evaluations = o.value("max_evaluations", options_.max_evaluations);
  options_.rounds = o.value("rounds", options_.rounds);
  options_.filter_dominated = o.value("filter_dominated", options_.filter_dominated);
  options_.design_constraints = o.value("design_constraints", options_.design_constraints);
  if (o.contains("shadow_solver")) options_.shadow_solver = o["shadow_solver"];
}

void NbiSolver::check(const Problem& problem) const {
  if (problem.objectives().size() < 2) {
    throw Error("nbi", "objectives: " + std::to_string(problem.objectives().size()) +
                           " objective(s); a Pareto front needs at least 2");
  }
  const DesignSpace& space = problem.design_space();
  for (int index : space.free_indices()) {
    const DesignComponent& c = space.components()[static_cast<std::size_t>(index)];
    if (c.integer) {
      throw Error("nbi", "design." + c.variable + " is integer-valued: NBI's subproblems are continuous (SLSQP); fix it or use nsga2");
    }
  }
  if (space.free_size() == 0) throw Error("nbi", "design: no free design variable; nothing to trade off");
  simplex_grid(static_cast<int>(problem.objectives().size()), options_.points - 1);  // throws when too large
}

void NbiSolver::prepare_sub_solvers(const Problem& problem, const Registry& registry) const {
  const auto solver = make_sub_solver(registry, options_.shadow_solver, "nbi", "solver.options.shadow_solver");
  for (std::size_t i = 0; i < problem.objectives().size(); ++i) {
    check_sub_solver(*solver, *single_objective_problem(problem, i), "nbi",
                     "solver.options.shadow_solver (objective '" + problem.objectives()[i].name + "')");
  }
}

SolverResult NbiSolver::solve(const Problem& problem, const SolverContext& context) const {
  const auto t_start = Clock::now();
  SolverResult result;
  Json stats = Json::object();
  const std::size_t m = problem.objectives().size();
  const DesignSpace& space = problem.design_space();
  const std::size_t n = space.free_size();
  const auto shadow_solver = sub_solver_for_solve(context, options_.shadow_solver, "nbi", "solver.options.shadow_solver",
                                                   "shadow solver", result);
  if (!shadow_solver) return result;

  // 1. Shadow optima.
  std::vector<Eigen::VectorXd> shadow_designs;
  std::vector<std::vector<double>> shadow_values;  // natural units, all objectives
  Json shadows = Json::array();
  const auto t_shadow = Clock::now();
  for (std::size_t i = 0; i < m; ++i) {
    const auto t0 = Clock::now();
    const SolverResult r = run_sub_solver(*shadow_solver, *single_objective_problem(problem, i), context);
    result.design_evaluations += r.design_evaluations;
    result.sample_evaluations += r.sample_evaluations;
    std::vector<double> values;
    if (!r.best || !evaluate_full_design(problem, r.best->design, context.threads, values, result.sample_evaluations)) {
      result.status = r.status == SolverStatus::kStopped ? SolverStatus::kStopped : SolverStatus::kInfeasible;
      result.message = "shadow optimum of objective '" + problem.objectives()[i].name + "' not found: " + r.message;
      stats["shadows"] = shadows;
      result.statistics = stats;
      return result;
    }
    shadow_designs.push_back(r.best->design);
    shadow_values.push_back(values);
    shadows.push_back({{"objective", problem.objectives()[i].name}, {"design", problem.design_to_json(r.best->design)},
                       {"objectives", values}, {"status", to_string(r.status)}, {"seconds", seconds_since(t0)},
                       {"design_evaluations", r.design_evaluations}, {"sample_evaluations", r.sample_evaluations}});
  }
  stats["shadows"] = shadows;
  stats["shadow_seconds"] = seconds_since(t_shadow);

  // 2. Payoff matrix (sense-signed), utopia, nadir, normalization.
  Subproblem sub;
  sub.problem = &problem;
  sub.sign.resize(m);
  sub.nadir.assign(m, kInf);
  sub.scale.resize(m);
  std::vector<double> utopia(m, -kInf);
  Json payoff = Json::array();
  for (std::size_t i = 0; i < m; ++i) {
    sub.sign[i] = sign_of(problem.objectives()[i].sense);
    Json row = Json::array();
    for (std::size_t j = 0; j < m; ++j) {
      const double v = sub.sign[i] * shadow_values[j][i];
      utopia[i] = std::max(utopia[i], v);
      sub.nadir[i] = std::min(sub.nadir[i], v);
      row.push_back(shadow_values[j][i]);
    }
    payoff.push_back(row);
    sub.scale[i] = utopia[i] - sub.nadir[i] > 0 ? utopia[i] - sub.nadir[i] : 1.0;
  }
  stats["payoff"] = payoff;  // payoff[i][j] = objective i at shadow optimum j (natural units)
  // Phibar_ij = 1 - Ft_i(x_j*): 0 on the diagonal (when the shadow is exact), the CHIM's corners.
  std::vector<std::vector<double>> phibar(m, std::vector<double>(m));
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = 0; j < m; ++j) phibar[i][j] = 1.0 - sub.normalized(i, shadow_values[j][i]);
  }
  std::vector<double> normal(m, 0.0);  // d = -n = Phibar e
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = 0; j < m; ++j) normal[i] += phibar[i][j];
  }
  stats["quasi_normal"] = normal;
  const bool degenerate = std::all_of(normal.begin(), normal.end(), [](double v) { return v <= 0.0; });

  // 3. Subproblems over the simplex grid, warm-started from the nearest solved point.
  const std::vector<std::vector<double>> grid = simplex_grid(static_cast<int>(m), options_.points - 1);
  std::vector<double> lower(n), upper(n);
  for (std::size_t k = 0; k < n; ++k) {
    const DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
    lower[k] = c.lower;
    upper[k] = c.upper;
  }
  SqpSettings settings;
  settings.xtol = options_.xtol;
  settings.ftol = options_.ftol;
  settings.max_evaluations = options_.max_evaluations;
  settings.constraint_tolerance = options_.constraint_tolerance;
  settings.rounds = options_.rounds;
  settings.design_constraints = options_.design_constraints;
  // The epigraph bounds maximized worst-case objectives from below only.
  settings.epigraph = std::all_of(problem.objectives().begin(), problem.objectives().end(),
                                  [](const Objective& o) { return o.sense == Sense::kMaximize; });

  struct Solved {
    std::vector<double> beta;
    std::vector<double> x;  // free design
  };
  std::vector<Solved> solved;
  auto free_of = [&](const Eigen::VectorXd& full) {
    std::vector<double> x(n);
    for (std::size_t k = 0; k < n; ++k) x[k] = full[space.free_indices()[k]];
    return x;
  };
  for (std::size_t j = 0; j < m; ++j) {
    std::vector<double> beta(m, 0.0);
    beta[j] = 1.0;
    solved.push_back({beta, free_of(shadow_designs[j])});
  }

  std::vector<SolutionPoint> candidates;
  Json subproblems = Json::array();
  for (std::size_t j = 0; j < m; ++j) {
    candidates.push_back({shadow_designs[j], shadow_values[j], problem.score(shadow_values[j])});
  }
  const auto t_sub = Clock::now();
  bool stopped = false;
  for (const std::vector<double>& beta : grid) {
    if (std::count_if(beta.begin(), beta.end(), [](double b) { return b > 0; }) <= 1) continue;  // a shadow point
    if (context.stop && context.stop->load()) {
      stopped = true;
      break;
    }
    if (degenerate) break;
    const auto t0 = Clock::now();
    // a = 1 - Phibar beta; d = Phibar e.
    sub.a.assign(m, 1.0);
    for (std::size_t i = 0; i < m; ++i) {
      for (std::size_t k = 0; k < m; ++k) sub.a[i] -= phibar[i][k] * beta[k];
    }
    sub.d = normal;
    const Solved* start = &solved.front();
    double nearest = kInf;
    for (const Solved& s : solved) {
      double dist = 0.0;
      for (std::size_t i = 0; i < m; ++i) dist += std::abs(s.beta[i] - beta[i]);
      if (dist < nearest - 1e-12) {
        nearest = dist;
        start = &s;
      }
    }
    const std::vector<double> x0 = start->x;
    const MinMaxGoal goal = nbi_goal(sub);
    const SqpOutcome sqp = run_minmax_sqp(problem, x0, lower, upper, settings, goal);
    result.design_evaluations += sqp.evaluations;
    result.sample_evaluations += sqp.samples;
    Json record = {{"beta", beta}, {"status", sqp.status}, {"t", sqp.x.empty() ? Json(nullptr) : Json(sqp.merit)},
                   {"design_evaluations", sqp.evaluations}, {"rounds", sqp.rounds}, {"seconds", seconds_since(t0)}};
    if (!sqp.x.empty()) {
      std::vector<double> values;
      const Eigen::VectorXd full = problem.full_design(sqp.x.data());
      if (evaluate_full_design(problem, full, 1, values, result.sample_evaluations)) {
        candidates.push_back({full, values, problem.score(values)});
        record["objectives"] = values;
        solved.push_back({beta, sqp.x});
      }
    }
    subproblems.push_back(record);
  }
  stats["subproblems"] = subproblems;
  stats["subproblem_seconds"] = seconds_since(t_sub);
  stats["grid_points"] = grid.size();

  // 4. Filter dominated points (and duplicates).
  std::vector<Sense> senses;
  for (const Objective& o : problem.objectives()) senses.push_back(o.sense);
  std::vector<ObjectivePoint> values;
  for (const SolutionPoint& p : candidates) values.push_back(p.objectives);
  std::vector<std::size_t> keep;
  if (options_.filter_dominated) {
    keep = non_dominated(values, senses);
  } else {
    for (std::size_t i = 0; i < candidates.size(); ++i) keep.push_back(i);
  }
  for (std::size_t i : keep) result.front.push_back(candidates[i]);
  // Order along the first objective (for m = 2: from one shadow optimum to the other).
  std::stable_sort(result.front.begin(), result.front.end(), [&](const SolutionPoint& a, const SolutionPoint& b) {
    return sign_of(senses[0]) * a.objectives[0] > sign_of(senses[0]) * b.objectives[0];
  });
  stats["candidates"] = candidates.size();
  stats["filtered_out"] = candidates.size() - keep.size();
  stats["seconds"] = seconds_since(t_start);
  result.statistics = stats;
  std::ostringstream message;
  message << "NBI: " << result.front.size() << " non-dominated points of " << candidates.size() << " ("
          << m << " shadow optima, " << subproblems.size() << " subproblems)";
  if (degenerate) message << "; the shadow optima coincide, the front is one point";
  result.message = message.str();
  result.status = stopped ? SolverStatus::kStopped : SolverStatus::kConverged;
  return result;
}

}  // namespace hapsyn::plugins
