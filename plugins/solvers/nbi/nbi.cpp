#include "nbi.hpp"

#include "shared/minmax_sqp.hpp"
#include "shared/sub_solver.hpp"

#include <hapsyn/checkpoint.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/pareto.hpp>

#include <pagmo/utils/discrepancy.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <string>

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

// \pre every slot holds a shadow optimum with its point.
ShadowOptima shadow_optima(const SubproblemSlots& shadows) {
  ShadowOptima s;
  for (const std::optional<FinishedSubproblem>& f : shadows) {
    s.designs.push_back(f->point->design);
    s.values.push_back(f->point->objectives);
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
// 2. Payoff matrix, utopia, nadir: the normalization and the CHIM.

struct Chim {
  std::vector<std::vector<double>> phibar;  // Phibar_ij = 1 - Ft_i(x_j*): the CHIM's corners
  std::vector<double> normal;               // d = -n = Phibar e
  // Objectives whose payoff row has no spread (U_i - N_i ~ 0 relative to |U_i|, |N_i|): the
  // same value at every shadow optimum, so Ft_i is undefined.
  std::vector<std::size_t> degenerate_objectives;
};

// No spread relative to the magnitude (exactly 0 when both are 0): below double rounding of
// the objective's own values, far below any trade-off.
constexpr double kDegenerateSpread = 1e-9;

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
  Chim chim;
  for (std::size_t i = 0; i < m; ++i) {
    const double magnitude = std::max(std::abs(utopia[i]), std::abs(sub.nadir[i]));
    if (!(utopia[i] - sub.nadir[i] > kDegenerateSpread * magnitude)) chim.degenerate_objectives.push_back(i);
  }
  stats["payoff"] = payoff;  // payoff[i][j] = objective i at shadow optimum j (natural units)
  // Phibar_ij = 1 - Ft_i(x_j*): 0 on the diagonal (when the shadow is exact), the CHIM's corners.
  chim.phibar.assign(m, std::vector<double>(m));
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = 0; j < m; ++j) chim.phibar[i][j] = 1.0 - sub.normalized(i, shadows.values[j][i]);
  }
  chim.normal.assign(m, 0.0);
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = 0; j < m; ++j) chim.normal[i] += chim.phibar[i][j];
  }
  stats["quasi_normal"] = chim.normal;
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
  std::string name;       // "shadows[j]", "subproblems[j]", "reverse[j]" or "seeds[i]": where it comes from
};

double l1_distance(const std::vector<double>& a, const std::vector<double>& b) {
  double dist = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) dist += std::abs(a[i] - b[i]);
  return dist;
}

// Two L1 distances between points of the simplex grid are equal (up to rounding, ~1e-15) or
// differ by at least 2/divisions >= 2e-3: sum_i |k_i - k'_i| is even, as sum_i k_i is the same
// for every point. 1e-9 separates the two cases with room to spare.
constexpr double kSameDistance = 1e-9;

// Where subproblem k starts: the nearest (L1) of the shadow optima and of the feasible
// subproblems before k, ties to the first in the order shadows, then grid order (the first
// sweep), or grid order, then shadows (`grid_first`: the reverse sweep, which passes the grid
// reversed, so that it starts from a grid point where one is as near as the shadow optimum the
// first sweep started from); this is the start the one-by-one run in that order gives it.
// nullopt while a subproblem before k that is not finished could change it: one nearer, or as
// near and earlier in that order than the one chosen so far.
std::optional<Solved> start_of(std::size_t k, const std::vector<Solved>& shadow_starts,
                               const std::vector<std::vector<double>>& interior, const SubproblemSlots& subproblems,
                               const DesignSpace& space, const std::function<std::string(std::size_t)>& name_of,
                               bool grid_first = false) {
  const std::size_t m = shadow_starts.size(), n = interior.size();
  const auto grid_order = [&](std::size_t j) { return grid_first ? j : m + j; };
  std::vector<Solved> solved;
  std::vector<std::size_t> order;  // position of each solved point in the tie order
  for (std::size_t j = 0; j < k; ++j) {
    if (subproblems[j] && subproblems[j]->point) {
      solved.push_back({interior[j], free_design(space, subproblems[j]->point->design), name_of(j)});
      order.push_back(grid_order(j));
    }
  }
  for (std::size_t j = 0; j < m; ++j) {
    solved.push_back(shadow_starts[j]);
    order.push_back(grid_first ? n + j : j);
  }
  std::size_t chosen = 0;
  double nearest = kInf;
  for (std::size_t i = 0; i < solved.size(); ++i) {
    const double dist = l1_distance(solved[i].beta, interior[k]);
    if (dist < nearest - kSameDistance || (dist <= nearest + kSameDistance && order[i] < order[chosen])) {
      nearest = std::min(nearest, dist);
      chosen = i;
    }
  }
  for (std::size_t j = 0; j < k; ++j) {
    if (subproblems[j]) continue;
    const double dist = l1_distance(interior[j], interior[k]);
    if (dist < nearest - kSameDistance) return std::nullopt;
    if (dist <= nearest + kSameDistance && grid_order(j) < order[chosen]) return std::nullopt;
  }
  return solved[chosen];
}

// The interior points of the simplex grid (the others are the shadow optima), in grid order:
// one subproblem each.
std::vector<std::vector<double>> interior_points(const std::vector<std::vector<double>>& grid) {
  std::vector<std::vector<double>> interior;
  for (const std::vector<double>& beta : grid) {
    if (std::count_if(beta.begin(), beta.end(), [](double b) { return b > 0; }) > 1) interior.push_back(beta);
  }
  return interior;
}

// Points `sub` at grid point beta: a = 1 - Phibar beta; d = Phibar e.
void aim(Subproblem& sub, const Chim& chim, const std::vector<double>& beta) {
  const std::size_t m = beta.size();
  sub.a.assign(m, 1.0);
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t k = 0; k < m; ++k) sub.a[i] -= chim.phibar[i][k] * beta[k];
  }
  sub.d = chim.normal;
}

// Designs spread over the free box (a Halton sequence, the same for every run), fully evaluated
// once: the second start of every subproblem is the feasible one of them (or the shadow optimum)
// with the best merit t for that subproblem. The neighbour's design alone is a local start: on
// a non-convex front it can hold a subproblem in the basin of the neighbour's part of the front
// (seen on the five-bar: a start at the GII optimum, links at their upper bounds, ended on a
// point 0.09 below the front in GII).
struct SeedPool {
  std::vector<Solved> seeds;                // the shadow optima, then the feasible Halton designs; beta unused
  std::vector<std::vector<double>> values;  // objective values of each seed
  long long designs = 0, samples = 0;       // what evaluating the Halton designs cost
  long long feasible = 0;                   // Halton designs that are feasible
};

// Empty (no second start) for count 0. Stops early, incomplete, on a stop request: the caller
// then stops before any subproblem uses it. The same pool for any number of threads.
SeedPool seed_pool(const Problem& problem, int count, const SolverContext& context, const ShadowOptima& shadows) {
  SeedPool pool;
  if (count == 0) return pool;
  const DesignSpace& space = problem.design_space();
  for (std::size_t j = 0; j < shadows.designs.size(); ++j) {
    pool.seeds.push_back({{}, free_design(space, shadows.designs[j]), "shadows[" + std::to_string(j) + "]"});
    pool.values.push_back(shadows.values[j]);
  }
  pagmo::halton sequence(static_cast<unsigned>(space.free_size()), 1);
  for (int i = 0; i < count && !context.stop_requested(); ++i) {
    const std::vector<double> u = sequence();
    std::vector<double> x(space.free_size());
    for (std::size_t k = 0; k < x.size(); ++k) {
      const DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
      x[k] = c.lower + u[k] * (c.upper - c.lower);
    }
    std::vector<double> values;
    ++pool.designs;
    if (evaluate_full_design(problem, problem.full_design(x.data()), context.threads, values, pool.samples)) {
      pool.seeds.push_back({{}, x, "seeds[" + std::to_string(i) + "]"});
      pool.values.push_back(std::move(values));
      ++pool.feasible;
    }
  }
  return pool;
}

// One subproblem: the SQP from its start (start_of) and, with a pool, from the pool's best design
// for it when that is another design (the better result is kept), then the full evaluation of
// its design. The reverse sweep passes no pool: its point's best seed was tried in the first.
// `sub` is this subproblem's own copy (its scratch is written): subproblems run concurrently.
FinishedSubproblem solve_subproblem(const Problem& problem, const NbiOptions& options, const Chim& chim, Subproblem sub,
                                    const std::vector<double>& beta, const Solved& start, const SeedPool* pool) {
  const DesignSpace& space = problem.design_space();
  std::vector<double> lower(space.free_size()), upper(space.free_size());
  for (std::size_t k = 0; k < lower.size(); ++k) {
    const DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
    lower[k] = c.lower;
    upper[k] = c.upper;
  }
  const auto t0 = Clock::now();
  aim(sub, chim, beta);
  const SqpSettings settings = sqp_settings(options, problem);
  SqpOutcome sqp = run_minmax_sqp(problem, start.x, lower, upper, settings, nbi_goal(sub));
  FinishedSubproblem f;
  f.design_evaluations = sqp.evaluations;
  f.sample_evaluations = sqp.samples;
  f.record = {{"beta", beta}, {"start", start.name}, {"status", sqp.status}, {"t", sqp.x.empty() ? Json(nullptr) : Json(sqp.merit)},
              {"design_evaluations", sqp.evaluations}, {"rounds", sqp.rounds}};
  // The second start: the pool's best design for this subproblem, when it is not the first start.
  const Solved* seed = nullptr;
  double seed_t = -kInf;
  for (std::size_t j = 0; pool && j < pool->seeds.size(); ++j) {
    const double t = sub.t_of(pool->values[j].data());
    if (t > seed_t) {
      seed_t = t;
      seed = &pool->seeds[j];
    }
  }
  if (seed && seed->x != start.x) {
    SqpOutcome second = run_minmax_sqp(problem, seed->x, lower, upper, settings, nbi_goal(sub));
    f.design_evaluations += second.evaluations;
    f.sample_evaluations += second.samples;
    const bool better = !second.x.empty() && (sqp.x.empty() || second.merit > sqp.merit);
    f.record["second_start"] = {{"start", seed->name}, {"start_t", seed_t}, {"status", second.status},
                                {"t", second.x.empty() ? Json(nullptr) : Json(second.merit)},
                                {"design_evaluations", second.evaluations}, {"kept", better}};
    if (better) {
      sqp = std::move(second);
      f.record["t"] = sqp.merit;
    }
  }
  if (!sqp.x.empty()) {
    std::vector<double> values;
    const Eigen::VectorXd full = problem.full_design(sqp.x.data());
    if (evaluate_full_design(problem, full, 1, values, f.sample_evaluations)) {
      f.point = SolutionPoint{full, values, problem.score(values)};
      f.record["objectives"] = values;
    }
  }
  f.record["seconds"] = seconds_since(t0);
  return f;
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

namespace {

// What one solve() call has done: the finished shadow optima and subproblems by index (what
// the checkpoint keeps), and the cost of subproblems interrupted by a stop request.
struct NbiProgress {
  SubproblemSlots shadows, subproblems;
  SubproblemSlots reverse;  // grid point k solved again in the reverse sweep
  long long interrupted_designs = 0, interrupted_samples = 0;
  long long pool_designs = 0, pool_samples = 0;  // the seed pool's evaluations
  double seconds_before = 0.0;  // elapsed in the runs before a resume
  Json resumed = nullptr;       // statistics.resumed
};

// The checkpoint's finished work, checked against this study (each claimed point was
// re-evaluated by read_subproblem_checkpoint).
void resume(const Problem& problem, const SolverContext& context, const std::string& fingerprint,
            const std::vector<std::vector<double>>& interior, NbiProgress& progress) {
  const std::size_t m = problem.objectives().size();
  std::optional<SubproblemCheckpoint> checkpoint = read_subproblem_checkpoint(
      problem, context, "nbi", fingerprint,
      {{"shadows", m}, {"subproblems", interior.size()}, {"reverse", progress.reverse.size()}});
  if (!checkpoint) return;
  progress.shadows = std::move(checkpoint->lists["shadows"]);
  progress.subproblems = std::move(checkpoint->lists["subproblems"]);
  progress.reverse = std::move(checkpoint->lists["reverse"]);
  for (std::size_t i = 0; i < progress.shadows.size(); ++i) {
    if (!progress.shadows[i]) continue;
    const std::string where = checkpoint->where("shadows", i);
    if (!progress.shadows[i]->point) throw bad_checkpoint(context, where + ": no design (a shadow optimum is a design)");
    if (progress.shadows[i]->record.value("objective", Json()) != problem.objectives()[i].name) {
      throw bad_checkpoint(context, where + ".record.objective = " + progress.shadows[i]->record.value("objective", Json()).dump() +
                                        ": this study's objective " + std::to_string(i) + " is '" +
                                        problem.objectives()[i].name + "'");
    }
  }
  const std::size_t shadows = finished_count(progress.shadows), subproblems = finished_count(progress.subproblems);
  if (subproblems > 0 && shadows < m) {
    throw bad_checkpoint(context, "subproblems: " + std::to_string(subproblems) + " finished with only " +
                                      std::to_string(shadows) + " of " + std::to_string(m) +
                                      " shadow optima (the subproblems come after all of them)");
  }
  for (const char* list : {"subproblems", "reverse"}) {
    const SubproblemSlots& slots = list == std::string("subproblems") ? progress.subproblems : progress.reverse;
    for (std::size_t task = 0; task < slots.size(); ++task) {
      if (!slots[task]) continue;
      const Json& record = slots[task]->record;
      const std::string where = checkpoint->where(list, task);
      if (record.value("beta", Json()) != Json(interior[task])) {
        throw bad_checkpoint(context, where + ".record.beta = " + record.value("beta", Json()).dump() +
                                          ": this study's grid point " + std::to_string(task) + " is " +
                                          Json(interior[task]).dump());
      }
      // The sweeps compare these: a result's merit, and a start's name.
      if (slots[task]->point && !(record.contains("t") && record["t"].is_number())) {
        throw bad_checkpoint(context, where + ".record.t = " + record.value("t", Json()).dump() +
                                          ": a subproblem with a design needs its merit t (a number)");
      }
      if (!(record.contains("start") && record["start"].is_string())) {
        throw bad_checkpoint(context, where + ".record.start = " + record.value("start", Json()).dump() +
                                          ": the name of the subproblem's start (a string)");
      }
    }
  }
  if (finished_count(progress.reverse) > 0 && finished_count(progress.subproblems) < interior.size()) {
    throw bad_checkpoint(context, "reverse: " + std::to_string(finished_count(progress.reverse)) + " finished with only " +
                                      std::to_string(finished_count(progress.subproblems)) + " of " +
                                      std::to_string(interior.size()) + " subproblems (the reverse sweep comes after all of them)");
  }
  progress.seconds_before = checkpoint->seconds;
  progress.resumed = {{"checkpoint", context.checkpoint_file},
                      {"shadows", shadows},
                      {"subproblems", subproblems},
                      {"reverse", finished_count(progress.reverse)},
                      {"recheck_sample_evaluations", checkpoint->recheck_samples}};
  solver_line(context, "nbi: resuming from " + context.checkpoint_file + ": " + std::to_string(shadows) + " of " +
                           std::to_string(m) + " shadow optima and " + std::to_string(subproblems) + " of " +
                           std::to_string(interior.size()) + " subproblems finished, " +
                           std::to_string(finished_count(progress.reverse)) + " of the reverse sweep");
}

// The reverse sweep starts from the better, on the grid point's own merit t, of its two results:
// true when that is the reverse sweep's (the first sweep's on a tie).
bool reverse_is_better(const std::optional<FinishedSubproblem>& first, const std::optional<FinishedSubproblem>& reverse) {
  if (!reverse || !reverse->point) return false;
  if (!first || !first->point) return true;
  return reverse->record.value("t", -kInf) > first->record.value("t", -kInf);
}

// Every candidate front point so far: the shadow optima, then each grid point's better result
// of its two sweeps.
std::vector<SolutionPoint> candidates_of(const NbiProgress& progress) {
  std::vector<SolutionPoint> candidates;
  for (const std::optional<FinishedSubproblem>& f : progress.shadows) {
    if (f && f->point) candidates.push_back(*f->point);
  }
  for (std::size_t k = 0; k < progress.subproblems.size(); ++k) {
    const std::optional<FinishedSubproblem> no_result;
    const std::optional<FinishedSubproblem>& reverse = k < progress.reverse.size() ? progress.reverse[k] : no_result;
    const std::optional<FinishedSubproblem>& f = reverse_is_better(progress.subproblems[k], reverse) ? reverse : progress.subproblems[k];
    if (f && f->point) candidates.push_back(*f->point);
  }
  return candidates;
}

Json records_of(const SubproblemSlots& list, double& seconds) {
  Json records = Json::array();
  seconds = 0.0;
  for (const std::optional<FinishedSubproblem>& f : list) {
    if (!f) continue;
    records.push_back(f->record);
    seconds += f->record.value("seconds", 0.0);
  }
  return records;
}

// "objective 'a' has" or "objectives 'a', 'b' have", with their payoff rows.
std::string degenerate_message(const Problem& problem, const Chim& chim, const Json& payoff) {
  std::string names, rows;
  for (std::size_t i : chim.degenerate_objectives) {
    names += (names.empty() ? "'" : ", '") + problem.objectives()[i].name + "'";
    rows += (rows.empty() ? "" : ", ") + payoff[i].dump();
  }
  const bool several = chim.degenerate_objectives.size() > 1;
  return std::string("NBI: ") + (several ? "objectives " : "objective ") + names + (several ? " have" : " has") +
         " the same value at every shadow optimum (payoff " + (several ? "rows " : "row ") + rows +
         "): constant, or never in conflict with the others at their optima, so NBI cannot normalize " +
         (several ? "them" : "it") + " (utopia - nadir = 0) and its front would be degenerate; remove " +
         (several ? "them" : "it") + " from \"objectives\" (or optimize " + (several ? "them" : "it") +
         " alone), or use nsga2 or weighted_sum, which need no normalization";
}

// Shadow optimum i: the shadow solver on objective i alone, its design re-evaluated with all the
// objectives (a record without a point when it found none: the message says why). Nullopt when a
// stop request interrupted it (its cost goes to `interrupted_*`).
std::optional<FinishedSubproblem> solve_shadow(const Solver& shadow_solver, const Problem& problem,
                                               const SolverContext& inner, std::size_t i, const std::string& what,
                                               std::atomic<long long>& interrupted_designs,
                                               std::atomic<long long>& interrupted_samples) {
  const auto t0 = Clock::now();
  const SolverResult r = run_sub_solver(shadow_solver, *single_objective_problem(problem, i), inner, what);
  std::optional<FinishedSubproblem> finished = finished_unless_stopped(r, interrupted_designs, interrupted_samples);
  if (!finished) return std::nullopt;
  FinishedSubproblem& f = *finished;
  std::vector<double> values;
  if (!r.best || !evaluate_full_design(problem, r.best->design, inner.threads, values, f.sample_evaluations)) {
    // Not found: no point; the message says why (the record never reaches the statistics).
    f.record = {{"objective", problem.objectives()[i].name}, {"status", to_string(r.status)},
                {"message", r.message}, {"seconds", seconds_since(t0)}};
    return finished;
  }
  f.point = SolutionPoint{r.best->design, values, problem.score(values)};
  f.record = {{"objective", problem.objectives()[i].name}, {"design", problem.design_to_json(r.best->design)},
              {"objectives", values}, {"status", to_string(r.status)}, {"seconds", seconds_since(t0)},
              {"design_evaluations", f.design_evaluations}, {"sample_evaluations", f.sample_evaluations}};
  return finished;
}

// The grid points' starts in the order a sweep's farm hands them out: task and start.
using Starts = std::vector<std::pair<std::size_t, Solved>>;

// One solve() call, phase by phase: the shadow optima, the payoff matrix and the CHIM (the
// normalization and the utopia plane), the first sweep of subproblems and the reverse sweep,
// then the front. It holds what every phase reads and writes: the study, its grid, what has
// been done (the checkpoint's content) and the statistics so far. A phase that ends the run
// returns its result.
class NbiRun {
 public:
  NbiRun(const Problem& problem, const SolverContext& context, const NbiOptions& options, Clock::time_point t_start,
         SolverResult result)
      : problem_(problem),
        context_(context),
        options_(options),
        t_start_(t_start),
        m_(problem.objectives().size()),
        grid_(simplex_grid(static_cast<int>(m_), options.points - 1)),
        interior_(interior_points(grid_)),
        fingerprint_(study_fingerprint(problem, OptionDeclarations<NbiOptions>::to_json(options))),
        result_(std::move(result)) {
    progress_.shadows.resize(m_);
    progress_.subproblems.resize(interior_.size());
    if (options_.reverse_sweep) progress_.reverse.resize(interior_.size());
    resume(problem_, context_, fingerprint_, interior_, progress_);
  }

  SolverResult run(const Solver& shadow_solver) {
    if (finished_count(progress_.shadows) < m_) {
      if (std::optional<SolverResult> ended = find_shadow_optima(shadow_solver)) return *ended;
    }
    if (std::optional<SolverResult> ended = normalize_to_chim()) return *ended;
    prepare_starts();
    if (std::optional<SolverResult> ended = first_sweep()) return *ended;
    if (std::optional<SolverResult> ended = reverse_sweep()) return *ended;
    return assemble_front();
  }

 private:
  double elapsed() const { return progress_.seconds_before + seconds_since(t_start_); }

  void checkpoint() const {
    // A shadow objective without a design (not found) is not kept: a resume runs it again.
    SubproblemSlots shadows = progress_.shadows;
    for (std::optional<FinishedSubproblem>& f : shadows) {
      if (f && !f->point) f.reset();
    }
    write_subproblem_checkpoint(context_, "nbi", fingerprint_,
                                {{"shadows", &shadows}, {"subproblems", &progress_.subproblems}, {"reverse", &progress_.reverse}},
                                elapsed());
  }

  // The result from what has been done (the counts of every finished unit and of interrupted
  // ones), with `status` and `message`.
  SolverResult finish(SolverStatus status, const std::string& message, bool with_front) {
    result_.design_evaluations = progress_.interrupted_designs + progress_.pool_designs;
    result_.sample_evaluations = progress_.interrupted_samples + progress_.pool_samples;
    for (const auto* list : {&progress_.shadows, &progress_.subproblems, &progress_.reverse}) {
      for (const std::optional<FinishedSubproblem>& f : *list) {
        if (!f) continue;
        result_.design_evaluations += f->design_evaluations;
        result_.sample_evaluations += f->sample_evaluations;
      }
    }
    double shadow_seconds = 0.0, subproblem_seconds = 0.0;
    stats_["shadows"] = records_of(progress_.shadows, shadow_seconds);
    stats_["shadow_seconds"] = shadow_seconds;
    stats_["subproblems"] = records_of(progress_.subproblems, subproblem_seconds);
    double reverse_seconds = 0.0;
    stats_["reverse"] = records_of(progress_.reverse, reverse_seconds);
    stats_["subproblem_seconds"] = subproblem_seconds + reverse_seconds;
    stats_["grid_points"] = grid_.size();
    const std::vector<SolutionPoint> candidates = candidates_of(progress_);
    if (with_front) result_.front = front_of(problem_, candidates, options_.filter_dominated);
    stats_["candidates"] = candidates.size();
    stats_["filtered_out"] = with_front ? candidates.size() - result_.front.size() : 0;
    if (!progress_.resumed.is_null()) stats_["resumed"] = progress_.resumed;
    stats_["seconds"] = elapsed();
    result_.statistics = stats_;
    result_.status = status;
    result_.message = message;
    return result_;
  }

  SolverResult stopped(const std::string& where) {
    checkpoint();
    return finish(SolverStatus::kStopped,
                  "NBI stopped on request " + where + "; the front is that of the points found so far" +
                      checkpoint_note(context_),
                  true);
  }

  std::string shadows_done() const {
    return "after " + std::to_string(finished_count(progress_.shadows)) + " of " + std::to_string(m_) + " shadow optima";
  }

  // 1. Shadow optima: one task each, a whole shadow-solver run on one rank's threads.
  std::optional<SolverResult> find_shadow_optima(const Solver& shadow_solver) {
    if (context_.stop_requested()) return stopped(shadows_done());
    const SolverContext inner = task_context(context_);
    std::atomic<long long> interrupted_designs{0}, interrupted_samples{0};
    std::atomic<int> interrupted{-1};  // the objective whose shadow solver a stop interrupted
    const auto what = [&](std::size_t i) {
      return "nbi: shadow optimum " + std::to_string(i + 1) + " of " + std::to_string(m_) + " (" +
             problem_.objectives()[i].name + ")";
    };
    SubproblemFarm farm;
    farm.what = what;
    farm.run = [&](std::size_t i) -> std::optional<FinishedSubproblem> {
      if (inner.stop_requested()) return std::nullopt;
      std::optional<FinishedSubproblem> f =
          solve_shadow(shadow_solver, problem_, inner, i, what(i), interrupted_designs, interrupted_samples);
      if (!f) interrupted = static_cast<int>(i);
      return f;
    };
    farm.collected = [&](std::size_t) { checkpoint(); };
    farm.on_abort = [&] { checkpoint(); };
    run_subproblem_farm(problem_, context_, progress_.shadows, farm);
    progress_.interrupted_designs += interrupted_designs;
    progress_.interrupted_samples += interrupted_samples;
    return settle_shadow_optima(interrupted);
  }

  // In objective order, as when the shadow optima were found one after the other: the first
  // one not finished (a stop) or not found ends the run there. `interrupted`: the objective
  // whose shadow solver a stop interrupted (-1: none).
  std::optional<SolverResult> settle_shadow_optima(int interrupted) {
    for (std::size_t i = 0; i < m_; ++i) {
      if (!progress_.shadows[i]) {
        // A later objective's shadow not found is found again on resume (the checkpoint leaves
        // it out); only its cost stays.
        for (std::optional<FinishedSubproblem>& f : progress_.shadows) {
          if (f && !f->point) {
            progress_.interrupted_designs += f->design_evaluations;
            progress_.interrupted_samples += f->sample_evaluations;
            f.reset();
          }
        }
        std::string note;
        if (interrupted >= 0) {
          note = " (the shadow solver of objective '" + problem_.objectives()[static_cast<std::size_t>(interrupted)].name +
                 "' was interrupted)";
        }
        return stopped(shadows_done() + note);
      }
      if (!progress_.shadows[i]->point) {
        // The cost of the ones up to this one; those after it do not count (they would not
        // have run one after the other).
        progress_.interrupted_designs += progress_.shadows[i]->design_evaluations;
        progress_.interrupted_samples += progress_.shadows[i]->sample_evaluations;
        const std::string message = progress_.shadows[i]->record.value("message", std::string());
        for (std::size_t j = i; j < m_; ++j) progress_.shadows[j].reset();
        return finish(SolverStatus::kInfeasible,
                      "shadow optimum of objective '" + problem_.objectives()[i].name + "' not found: " + message, false);
      }
    }
    return std::nullopt;
  }

  // 2. Payoff matrix and CHIM (the utopia plane); a degenerate one ends here.
  std::optional<SolverResult> normalize_to_chim() {
    shadows_ = shadow_optima(progress_.shadows);
    chim_ = normalize(problem_, shadows_, sub_, stats_);
    if (chim_.degenerate_objectives.size() == m_) {
      // Every objective has its best value at every shadow optimum: one design is best in all of
      // them; the front is that one point (no trade-off to draw).
      return finish(SolverStatus::kConverged,
                    "NBI: the objectives do not conflict: every shadow optimum has the same objective values, so the "
                    "front is one point and no subproblem was solved (check that these are the objectives meant)",
                    true);
    }
    if (!chim_.degenerate_objectives.empty()) {
      return finish(SolverStatus::kFailed, degenerate_message(problem_, chim_, stats_["payoff"]), false);
    }
    return std::nullopt;
  }

  // The subproblems' starts besides the solved grid points: the shadow optima, and the seed
  // pool. The pool is evaluated on every solve() (a resumed one too, and on every rank): 64
  // designs against the subproblems' thousands; its cost counts once per solve(), as in an
  // uninterrupted run.
  void prepare_starts() {
    for (std::size_t j = 0; j < m_; ++j) {
      std::vector<double> beta(m_, 0.0);
      beta[j] = 1.0;
      shadow_starts_.push_back(
          {beta, free_design(problem_.design_space(), shadows_.designs[j]), "shadows[" + std::to_string(j) + "]"});
    }
    pool_ = seed_pool(problem_, options_.seed_designs, context_, shadows_);
    stats_["seed_designs"] = {{"feasible", pool_.feasible}, {"of", options_.seed_designs}, {"sample_evaluations", pool_.samples}};
    progress_.pool_designs = pool_.designs;
    progress_.pool_samples = pool_.samples;
  }

  // One sweep in waves: each wave is a farm of the unfinished tasks of `slots` whose start is
  // settled (starts(): task and start, in the order the farm hands them out), each one
  // single-threaded SQP run, as many at a time as the rank has threads. False on a stop.
  bool run_sweep(SubproblemSlots& slots, const std::function<Starts()>& starts,
                 const std::function<FinishedSubproblem(std::size_t, const Solved&)>& solve, const std::string& done_line) {
    while (finished_count(slots) < slots.size()) {
      if (context_.stop_requested()) return false;
      std::map<std::size_t, Solved> start_of_task;
      SubproblemFarm farm;
      for (auto& [k, start] : starts()) {
        farm.tasks.push_back(k);
        start_of_task[k] = std::move(start);
      }
      farm.threads = context_.threads;
      farm.run = [&](std::size_t k) -> std::optional<FinishedSubproblem> {
        if (context_.stop_requested()) return std::nullopt;
        return solve(k, start_of_task.at(k));
      };
      farm.collected = [&](std::size_t k) {
        checkpoint();
        solver_line(context_, "nbi: subproblem " + std::to_string(k + 1) + " of " + std::to_string(slots.size()) + done_line);
      };
      farm.on_abort = [&] { checkpoint(); };
      const FarmOutcome outcome = run_subproblem_farm(problem_, context_, slots, farm);
      if (outcome.stopped && finished_count(slots) < slots.size()) return false;
    }
    return true;
  }

  // 3. One subproblem per interior grid point, warm-started from the nearest solved point. Each
  // depends on the ones before it that could be its start, so they run in waves: a farm of the
  // subproblems whose start is known (start_of), then the next wave. The starts, and so the
  // front, are those of the one-by-one run in grid order, whatever the ranks and threads.
  std::optional<SolverResult> first_sweep() {
    const std::size_t n = interior_.size();
    const auto starts = [&] {
      Starts settled;
      for (std::size_t k = 0; k < n; ++k) {
        if (progress_.subproblems[k]) continue;
        if (std::optional<Solved> start = start_of(k, shadow_starts_, interior_, progress_.subproblems, problem_.design_space(),
                                                      [](std::size_t j) { return "subproblems[" + std::to_string(j) + "]"; })) {
          settled.emplace_back(k, std::move(*start));
        }
      }
      return settled;
    };
    const auto solve = [&](std::size_t k, const Solved& start) {
      return solve_subproblem(problem_, options_, chim_, sub_, interior_[k], start, &pool_);
    };
    if (run_sweep(progress_.subproblems, starts, solve, " solved")) return std::nullopt;
    return stopped("after " + std::to_string(finished_count(progress_.subproblems)) + " of " + std::to_string(n) +
                   " subproblems (all shadow optima found)");
  }

  // 3b. The reverse sweep: every grid point solved again, in reverse grid order, from the nearest
  // of the shadow optima and the points after it (their better result), in waves as above. A
  // chain of warm starts can hold every point of a front in the basin of the first shadow
  // optimum's branch; the reverse chain starts from the other end.
  std::optional<SolverResult> reverse_sweep() {
    const std::vector<std::vector<double>> reversed(interior_.rbegin(), interior_.rend());
    const auto starts = [&] { return reverse_starts(reversed); };
    const auto solve = [&](std::size_t k, const Solved& start) { return solve_again(k, start); };
    if (run_sweep(progress_.reverse, starts, solve, " done in the reverse sweep")) return std::nullopt;
    return stopped("in the reverse sweep, after " + std::to_string(finished_count(progress_.reverse)) + " of " +
                   std::to_string(interior_.size()) + " subproblems (all subproblems solved once)");
  }

  // The reverse sweep's settled starts: the unfinished grid points, in reverse grid order
  // (`reversed`: the interior points in that order), whose start is known.
  Starts reverse_starts(const std::vector<std::vector<double>>& reversed) const {
    const std::size_t n = interior_.size();
    SubproblemSlots best(n);  // by index in the reverse order
    std::vector<bool> from_reverse(n, false);
    for (std::size_t r = 0; r < n; ++r) {
      const std::size_t k = n - 1 - r;
      if (!progress_.reverse[k]) continue;
      from_reverse[r] = reverse_is_better(progress_.subproblems[k], progress_.reverse[k]);
      best[r] = from_reverse[r] ? progress_.reverse[k] : progress_.subproblems[k];
    }
    const auto name_of = [&](std::size_t r) {
      return std::string(from_reverse[r] ? "reverse[" : "subproblems[") + std::to_string(n - 1 - r) + "]";
    };
    Starts starts;
    for (std::size_t r = 0; r < n; ++r) {
      if (progress_.reverse[n - 1 - r]) continue;
      if (std::optional<Solved> start = start_of(r, shadow_starts_, reversed, best, problem_.design_space(), name_of, true)) {
        starts.emplace_back(n - 1 - r, std::move(*start));
      }
    }
    return starts;
  }

  // Grid point k in the reverse sweep, from `start`; when that is the first sweep's start, from
  // a second one instead (second_start), or not at all.
  FinishedSubproblem solve_again(std::size_t k, const Solved& start) const {
    if (start.name != progress_.subproblems[k]->record.value("start", std::string())) {
      return solve_subproblem(problem_, options_, chim_, sub_, interior_[k], start, nullptr);
    }
    if (std::optional<Solved> second = second_start(k)) {
      return solve_subproblem(problem_, options_, chim_, sub_, interior_[k], *second, nullptr);
    }
    FinishedSubproblem same;
    same.record = {{"beta", interior_[k]}, {"start", start.name}, {"status", "not solved again: the first sweep's start"}};
    return same;
  }

  // The first sweep's start would give the same result again. The nearest (L1, ties to the first
  // in grid order) other grid point the first sweep solved gives a second start instead: the
  // subproblem next to a shadow optimum otherwise only ever starts from the shadow, and near the
  // five-bar's GDI optimum (on a reach cliff) a shadow a few 1e-4 m off left it well below the
  // front. The first sweep's results are final while this sweep runs, so the choice does not
  // depend on the threads. Nullopt: no other solved point.
  std::optional<Solved> second_start(std::size_t k) const {
    const std::string first_start = progress_.subproblems[k]->record.value("start", std::string());
    std::optional<std::size_t> nearest;
    for (std::size_t j = 0; j < interior_.size(); ++j) {
      if (j == k || !progress_.subproblems[j] || !progress_.subproblems[j]->point) continue;
      if ("subproblems[" + std::to_string(j) + "]" == first_start) continue;
      if (!nearest || l1_distance(interior_[j], interior_[k]) < l1_distance(interior_[*nearest], interior_[k]) - kSameDistance) {
        nearest = j;
      }
    }
    if (!nearest) return std::nullopt;
    return Solved{interior_[*nearest], free_design(problem_.design_space(), progress_.subproblems[*nearest]->point->design),
                  "subproblems[" + std::to_string(*nearest) + "]"};
  }

  // 4. The front.
  SolverResult assemble_front() {
    std::ostringstream message;
    const std::size_t candidates = candidates_of(progress_).size();
    finish(SolverStatus::kConverged, "", true);
    message << "NBI: " << result_.front.size() << " non-dominated points of " << candidates << " (" << m_
            << " shadow optima, " << interior_.size() << " subproblems"
            << (options_.reverse_sweep ? ", each solved again in reverse order" : "") << ")";
    result_.message = message.str();
    return result_;
  }

  const Problem& problem_;
  const SolverContext& context_;
  const NbiOptions& options_;
  const Clock::time_point t_start_;
  const std::size_t m_;
  const std::vector<std::vector<double>> grid_;
  const std::vector<std::vector<double>> interior_;
  const std::string fingerprint_;
  SolverResult result_;
  Json stats_ = Json::object();
  NbiProgress progress_;
  // Set by the phases, in order.
  ShadowOptima shadows_;
  Subproblem sub_;
  Chim chim_;
  std::vector<Solved> shadow_starts_;
  SeedPool pool_;
};

}  // namespace

SolverResult NbiSolver::solve(const Problem& problem, const SolverContext& context) const {
  const auto t_start = Clock::now();
  SolverResult result;
  const Solver* shadow_solver = sub_solver_for_solve(options_.shadow_solver, "nbi", "shadow solver", result);
  if (!shadow_solver) return result;
  return NbiRun(problem, context, options_, t_start, std::move(result)).run(*shadow_solver);
}

}  // namespace hapsyn::plugins
