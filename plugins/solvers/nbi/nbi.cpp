#include "nbi.hpp"

#include "shared/minmax_sqp.hpp"
#include "shared/sub_solver.hpp"

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

// ---------------------------------------------------------------------------------------------
// 1. Shadow optima: each objective alone, by the shadow solver.

struct ShadowOptima {
  std::vector<Eigen::VectorXd> designs;     // full designs
  std::vector<std::vector<double>> values;  // natural units, all objectives
};

// Fills `shadows` and stats["shadows"] (and "shadow_seconds"). Returns false, with the result's
// status and message set, when one of them is not found.
bool find_shadow_optima(const Problem& problem, const Solver& shadow_solver, const SolverContext& context,
                        ShadowOptima& shadows, SolverResult& result, Json& stats) {
  const std::size_t m = problem.objectives().size();
  Json records = Json::array();
  const auto t_shadow = Clock::now();
  for (std::size_t i = 0; i < m; ++i) {
    const auto t0 = Clock::now();
    const SolverResult r = run_sub_solver(shadow_solver, *single_objective_problem(problem, i), context);
    result.design_evaluations += r.design_evaluations;
    result.sample_evaluations += r.sample_evaluations;
    std::vector<double> values;
    if (!r.best || !evaluate_full_design(problem, r.best->design, context.threads, values, result.sample_evaluations)) {
      result.status = r.status == SolverStatus::kStopped ? SolverStatus::kStopped : SolverStatus::kInfeasible;
      result.message = "shadow optimum of objective '" + problem.objectives()[i].name + "' not found: " + r.message;
      stats["shadows"] = records;
      return false;
    }
    shadows.designs.push_back(r.best->design);
    shadows.values.push_back(values);
    records.push_back({{"objective", problem.objectives()[i].name}, {"design", problem.design_to_json(r.best->design)},
                       {"objectives", values}, {"status", to_string(r.status)}, {"seconds", seconds_since(t0)},
                       {"design_evaluations", r.design_evaluations}, {"sample_evaluations", r.sample_evaluations}});
  }
  stats["shadows"] = records;
  stats["shadow_seconds"] = seconds_since(t_shadow);
  return true;
}

// ---------------------------------------------------------------------------------------------
// 2. Payoff matrix, utopia, nadir: the normalization and the CHIM.

struct Chim {
  std::vector<std::vector<double>> phibar;  // Phibar_ij = 1 - Ft_i(x_j*): the CHIM's corners
  std::vector<double> normal;               // d = -n = Phibar e
  bool degenerate = false;                  // the shadow optima coincide: no direction to go
};

// Sets the normalization of `sub` (sign, nadir, scale) from the shadow optima and returns the
// CHIM; records stats["payoff"] and stats["quasi_normal"].
Chim normalize(const Problem& problem, const ShadowOptima& shadows, Subproblem& sub, Json& stats) {
  const std::size_t m = problem.objectives().size();
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
      const double v = sub.sign[i] * shadows.values[j][i];
      utopia[i] = std::max(utopia[i], v);
      sub.nadir[i] = std::min(sub.nadir[i], v);
      row.push_back(shadows.values[j][i]);
    }
    payoff.push_back(row);
    sub.scale[i] = utopia[i] - sub.nadir[i] > 0 ? utopia[i] - sub.nadir[i] : 1.0;
  }
  stats["payoff"] = payoff;  // payoff[i][j] = objective i at shadow optimum j (natural units)
  // Phibar_ij = 1 - Ft_i(x_j*): 0 on the diagonal (when the shadow is exact), the CHIM's corners.
  Chim chim;
  chim.phibar.assign(m, std::vector<double>(m));
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = 0; j < m; ++j) chim.phibar[i][j] = 1.0 - sub.normalized(i, shadows.values[j][i]);
  }
  chim.normal.assign(m, 0.0);
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = 0; j < m; ++j) chim.normal[i] += chim.phibar[i][j];
  }
  stats["quasi_normal"] = chim.normal;
  chim.degenerate = std::all_of(chim.normal.begin(), chim.normal.end(), [](double v) { return v <= 0.0; });
  return chim;
}

// ---------------------------------------------------------------------------------------------
// 3. One subproblem per interior point of the simplex grid.

SqpSettings sqp_settings(const NbiOptions& options, const Problem& problem) {
  SqpSettings settings;
  settings.xtol = options.xtol;
  settings.ftol = options.ftol;
  settings.max_evaluations = options.max_evaluations;
  settings.constraint_tolerance = options.constraint_tolerance;
  settings.rounds = options.rounds;
  settings.design_constraints = options.design_constraints;
  // The epigraph bounds maximized worst-case objectives from below only.
  settings.epigraph = std::all_of(problem.objectives().begin(), problem.objectives().end(),
                                  [](const Objective& o) { return o.sense == Sense::kMaximize; });
  return settings;
}

// The free components of a full design.
std::vector<double> free_design(const DesignSpace& space, const Eigen::VectorXd& full) {
  std::vector<double> x(space.free_size());
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = full[space.free_indices()[k]];
  return x;
}

// A grid point whose subproblem gave a feasible design: where the next ones start from.
struct Solved {
  std::vector<double> beta;
  std::vector<double> x;  // free design
};

// The solved point nearest to beta (L1; of equally near ones the first solved).
const Solved& nearest_solved(const std::vector<Solved>& solved, const std::vector<double>& beta) {
  const Solved* start = &solved.front();
  double nearest = kInf;
  for (const Solved& s : solved) {
    double dist = 0.0;
    for (std::size_t i = 0; i < beta.size(); ++i) dist += std::abs(s.beta[i] - beta[i]);
    if (dist < nearest - 1e-12) {
      nearest = dist;
      start = &s;
    }
  }
  return *start;
}

// What the subproblems gave: every candidate front point (the shadow optima first) and a
// record per subproblem.
struct SubproblemSweep {
  std::vector<SolutionPoint> candidates;
  Json records = Json::array();
  bool stopped = false;
};

// Runs every interior grid point's subproblem, each warm-started from the nearest solved point.
SubproblemSweep solve_subproblems(const Problem& problem, const NbiOptions& options, const ShadowOptima& shadows,
                                  const Chim& chim, Subproblem& sub, const std::vector<std::vector<double>>& grid,
                                  const SolverContext& context, SolverResult& result) {
  const std::size_t m = problem.objectives().size();
  const DesignSpace& space = problem.design_space();
  std::vector<double> lower(space.free_size()), upper(space.free_size());
  for (std::size_t k = 0; k < lower.size(); ++k) {
    const DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
    lower[k] = c.lower;
    upper[k] = c.upper;
  }
  const SqpSettings settings = sqp_settings(options, problem);
  std::vector<Solved> solved;
  SubproblemSweep sweep;
  for (std::size_t j = 0; j < m; ++j) {
    std::vector<double> beta(m, 0.0);
    beta[j] = 1.0;
    solved.push_back({beta, free_design(space, shadows.designs[j])});
    sweep.candidates.push_back({shadows.designs[j], shadows.values[j], problem.score(shadows.values[j])});
  }
  for (const std::vector<double>& beta : grid) {
    if (std::count_if(beta.begin(), beta.end(), [](double b) { return b > 0; }) <= 1) continue;  // a shadow point
    if (context.stop && context.stop->load()) {
      sweep.stopped = true;
      break;
    }
    if (chim.degenerate) break;
    const auto t0 = Clock::now();
    // a = 1 - Phibar beta; d = Phibar e.
    sub.a.assign(m, 1.0);
    for (std::size_t i = 0; i < m; ++i) {
      for (std::size_t k = 0; k < m; ++k) sub.a[i] -= chim.phibar[i][k] * beta[k];
    }
    sub.d = chim.normal;
    const std::vector<double> x0 = nearest_solved(solved, beta).x;
    const SqpOutcome sqp = run_minmax_sqp(problem, x0, lower, upper, settings, nbi_goal(sub));
    result.design_evaluations += sqp.evaluations;
    result.sample_evaluations += sqp.samples;
    Json record = {{"beta", beta}, {"status", sqp.status}, {"t", sqp.x.empty() ? Json(nullptr) : Json(sqp.merit)},
                   {"design_evaluations", sqp.evaluations}, {"rounds", sqp.rounds}, {"seconds", seconds_since(t0)}};
    if (!sqp.x.empty()) {
      std::vector<double> values;
      const Eigen::VectorXd full = problem.full_design(sqp.x.data());
      if (evaluate_full_design(problem, full, 1, values, result.sample_evaluations)) {
        sweep.candidates.push_back({full, values, problem.score(values)});
        record["objectives"] = values;
        solved.push_back({beta, sqp.x});
      }
    }
    sweep.records.push_back(record);
  }
  return sweep;
}

// ---------------------------------------------------------------------------------------------
// 4. The front: the candidates without dominated points and duplicates (when filtering),
// ordered along the first objective (for m = 2: from one shadow optimum to the other).

std::vector<SolutionPoint> front_of(const Problem& problem, const std::vector<SolutionPoint>& candidates,
                                    bool filter_dominated) {
  std::vector<Sense> senses;
  for (const Objective& o : problem.objectives()) senses.push_back(o.sense);
  std::vector<ObjectivePoint> values;
  for (const SolutionPoint& p : candidates) values.push_back(p.objectives);
  std::vector<std::size_t> keep;
  if (filter_dominated) {
    keep = non_dominated(values, senses);
  } else {
    for (std::size_t i = 0; i < candidates.size(); ++i) keep.push_back(i);
  }
  std::vector<SolutionPoint> front;
  for (std::size_t i : keep) front.push_back(candidates[i]);
  std::stable_sort(front.begin(), front.end(), [&](const SolutionPoint& a, const SolutionPoint& b) {
    return sign_of(senses[0]) * a.objectives[0] > sign_of(senses[0]) * b.objectives[0];
  });
  return front;
}

}  // namespace

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
  for (std::size_t i = 0; i < problem.objectives().size(); ++i) {
    check_sub_solver(options_.shadow_solver, *single_objective_problem(problem, i), "nbi",
                     options_.shadow_solver.json_path + " (objective '" + problem.objectives()[i].name + "')");
  }
}

SolverResult NbiSolver::solve(const Problem& problem, const SolverContext& context) const {
  const auto t_start = Clock::now();
  SolverResult result;
  Json stats = Json::object();
  const Solver* shadow_solver = sub_solver_for_solve(options_.shadow_solver, "nbi", "shadow solver", result);
  if (!shadow_solver) return result;

  ShadowOptima shadows;
  if (!find_shadow_optima(problem, *shadow_solver, context, shadows, result, stats)) {
    result.statistics = stats;
    return result;
  }
  Subproblem sub;
  const Chim chim = normalize(problem, shadows, sub, stats);
  const std::size_t m = problem.objectives().size();
  const std::vector<std::vector<double>> grid = simplex_grid(static_cast<int>(m), options_.points - 1);
  const auto t_sub = Clock::now();
  const SubproblemSweep sweep = solve_subproblems(problem, options_, shadows, chim, sub, grid, context, result);
  stats["subproblems"] = sweep.records;
  stats["subproblem_seconds"] = seconds_since(t_sub);
  stats["grid_points"] = grid.size();

  result.front = front_of(problem, sweep.candidates, options_.filter_dominated);
  stats["candidates"] = sweep.candidates.size();
  stats["filtered_out"] = sweep.candidates.size() - result.front.size();
  stats["seconds"] = seconds_since(t_start);
  result.statistics = stats;
  std::ostringstream message;
  message << "NBI: " << result.front.size() << " non-dominated points of " << sweep.candidates.size() << " ("
          << m << " shadow optima, " << sweep.records.size() << " subproblems)";
  if (chim.degenerate) message << "; the shadow optima coincide, the front is one point";
  result.message = message.str();
  result.status = sweep.stopped ? SolverStatus::kStopped : SolverStatus::kConverged;
  return result;
}

}  // namespace hapsyn::plugins
