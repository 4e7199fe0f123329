#include "minmax_sqp.hpp"

#include <nlopt.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <iomanip>
#include <set>

namespace hapsyn::plugins {

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Progress lines of a run at most every settings.report_interval seconds (SqpSettings::report).
struct Reporter {
  const SqpSettings* settings = nullptr;
  Clock::time_point start = Clock::now(), last = Clock::now();

  void tick(const char* stage, long long evaluations, double best) {
    if (!settings || !settings->report) return;
    const auto now = Clock::now();
    if (std::chrono::duration<double>(now - last).count() < settings->report_interval) return;
    last = now;
    std::ostringstream line;
    line << stage << ": " << evaluations << " evaluations";
    if (best > -kInf) line << ", best score " << std::setprecision(6) << best;
    line << " (" << std::fixed << std::setprecision(1) << std::chrono::duration<double>(now - start).count() << " s)";
    settings->report(line.str());
  }
};

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct LocalIndex {
  std::size_t metric, local;
  Reduction reduction;
};

std::vector<LocalIndex> flat_locals(const Problem& problem, std::vector<std::size_t>* base) {
  std::vector<LocalIndex> locals;
  for (std::size_t m = 0; m < problem.metrics().size(); ++m) {
    if (base) base->push_back(locals.size());
    const auto declared = problem.metrics()[m].metric->locals();
    for (std::size_t l = 0; l < declared.size(); ++l) locals.push_back({m, l, declared[l].reduction});
  }
  return locals;
}

std::string nlopt_result_name(nlopt::result r) {
  switch (r) {
    case nlopt::SUCCESS: return "success";
    case nlopt::STOPVAL_REACHED: return "stopval_reached";
    case nlopt::FTOL_REACHED: return "ftol_reached";
    case nlopt::XTOL_REACHED: return "xtol_reached";
    case nlopt::MAXEVAL_REACHED: return "maxeval_reached";
    case nlopt::MAXTIME_REACHED: return "maxtime_reached";
    default: return "failure";
  }
}

// ---- the mechanism's design constraints g(p) <= 0 (both stages) ----
// Smooth functions of the design (e.g. the five-bar's reach and footprint): handed to SLSQP as
// inequality constraints with central finite-difference gradients, so that it follows them
// instead of falling off the cliff of an infeasible design.
struct DesignConstraints {
  const Problem* problem = nullptr;
  std::size_t n = 0;
  std::vector<double> lower, upper, p, ga, gb;
};

void design_constraints(unsigned count, double* c, unsigned dim, const double* y, double* grad, void* data) {
  DesignConstraints& d = *static_cast<DesignConstraints*>(data);
  d.p.assign(y, y + d.n);
  for (std::size_t k = 0; k < d.n; ++k) d.p[k] = std::clamp(d.p[k], d.lower[k], d.upper[k]);
  d.problem->constraints(d.p.data(), c);
  if (!grad) return;
  std::fill(grad, grad + static_cast<std::size_t>(count) * dim, 0.0);
  d.ga.resize(count);
  d.gb.resize(count);
  for (std::size_t k = 0; k < d.n; ++k) {
    const double keep = d.p[k];
    const double h = 1e-7 * std::max(d.upper[k] - d.lower[k], 1e-9);
    const double a = std::min(keep + h, d.upper[k]);
    const double b = std::max(keep - h, d.lower[k]);
    d.p[k] = a;
    d.problem->constraints(d.p.data(), d.ga.data());
    d.p[k] = b;
    d.problem->constraints(d.p.data(), d.gb.data());
    d.p[k] = keep;
    for (unsigned i = 0; i < count; ++i) grad[i * dim + k] = a > b ? (d.ga[i] - d.gb[i]) / (a - b) : 0.0;
  }
}

void add_design_constraints(nlopt::opt& opt, DesignConstraints& d, double tolerance) {
  if (d.problem->constraint_count() == 0) return;
  opt.add_inequality_mconstraint(design_constraints, &d, std::vector<double>(d.problem->constraint_count(), tolerance));
}

// ---- epigraph stage ----

struct Epigraph {
  const Problem* problem = nullptr;
  const MinMaxGoal* goal = nullptr;
  Problem::EvalScratch* eval_scratch = nullptr;
  std::vector<LocalIndex> locals;  // the z layout
  std::vector<int> active;         // active samples
  std::size_t n = 0;               // design dimension
  double tolerance = 1e-8;
  std::vector<double> lower, upper;
  long long evaluations = 0, samples = 0;
  std::vector<double> values;  // scratch: local values per active sample (active x locals)
  std::vector<double> probe, goal_c, goal_ca, goal_cb;  // scratch for finite differences
  // The best iterate that satisfied every constraint: SLSQP returns its last iterate, which on
  // a stop (round-off, budget) may violate them.
  std::vector<double> best_y;
  double best_objective = -kInf;
  Reporter* reporter = nullptr;
  double best_merit = -kInf;  // of the fully evaluated candidates so far (for reports)

  std::size_t zsize() const { return locals.size(); }

  // Local values of design p at the active samples into `values`; false if one fails.
  bool locals_at(const double* p) {
    values.assign(active.size() * locals.size(), 0.0);
    std::size_t row = 0;
    SampleCallback record = [&](int, const SampleQuantities&, const std::vector<std::vector<double>>& per_metric) {
      for (std::size_t l = 0; l < locals.size(); ++l) {
        values[row * locals.size() + l] = per_metric[locals[l].metric][locals[l].local];
      }
      ++row;
    };
    EvalOptions o;
    o.subset = &active;
    o.on_sample = &record;
    const Evaluation& e = problem->evaluate(p, *eval_scratch, o);
    ++evaluations;
    samples += e.samples_evaluated;
    if (reporter) reporter->tick("epigraph stage", evaluations, best_merit);
    return e.status == EvalStatus::kFeasible;
  }
};

double epigraph_objective(unsigned dim, const double* y, double* grad, void* data) {
  Epigraph& g = *static_cast<Epigraph*>(data);
  const double* z = y + g.n;
  const double* e = z + g.zsize();
  const double f = g.goal->objective(z, e);
  if (grad) {
    std::fill(grad, grad + dim, 0.0);
    g.probe.assign(z, y + dim);  // (z, e)
    const std::size_t k = dim - g.n;
    for (std::size_t l = 0; l < k; ++l) {
      const double h = 1e-7 * std::max(1.0, std::abs(g.probe[l]));
      const double keep = g.probe[l];
      g.probe[l] = keep + h;
      const double fa = g.goal->objective(g.probe.data(), g.probe.data() + g.zsize());
      g.probe[l] = keep - h;
      const double fb = g.goal->objective(g.probe.data(), g.probe.data() + g.zsize());
      g.probe[l] = keep;
      grad[g.n + l] = (fa - fb) / (2 * h);
    }
  }
  return f;
}

// c[s * L + l] <= 0 for every active sample s and local l, then the goal's constraints.
void epigraph_constraints(unsigned count, double* c, unsigned dim, const double* y, double* grad, void* data) {
  Epigraph& g = *static_cast<Epigraph*>(data);
  const std::size_t L = g.locals.size();
  const std::size_t sample_rows = g.active.size() * L;
  const std::size_t gc = static_cast<std::size_t>(g.goal->constraints);
  const double* z = y + g.n;
  const double* e = z + L;
  constexpr double kUnreachable = 1e3;  // a violated constraint where a sample is not reachable
  auto fill = [&](const double* p, double* out) {
    const bool ok = g.locals_at(p);
    for (std::size_t s = 0; s < g.active.size(); ++s) {
      for (std::size_t l = 0; l < L; ++l) {
        const double v = g.values[s * L + l];
        const double sign = g.locals[l].reduction == Reduction::kMin ? 1.0 : -1.0;
        out[s * L + l] = ok ? sign * (z[l] - v) : kUnreachable;
      }
    }
  };
  fill(y, c);
  if (gc > 0) g.goal->constraint(z, e, c + sample_rows);
  double violation = 0.0;
  for (unsigned i = 0; i < count; ++i) violation = std::max(violation, c[i]);
  if (violation <= g.tolerance) {
    const double f = g.goal->objective(z, e);
    if (f > g.best_objective) {
      g.best_objective = f;
      g.best_y.assign(y, y + dim);
    }
  }
  if (!grad) return;
  std::fill(grad, grad + static_cast<std::size_t>(count) * dim, 0.0);
  // Sample rows: finite differences in the design (the locals depend on p only), exact in z.
  std::vector<double> p(y, y + g.n), ca(sample_rows), cb(sample_rows);
  for (std::size_t k = 0; k < g.n; ++k) {
    const double h = 1e-7 * std::max(g.upper[k] - g.lower[k], 1e-9);
    const double a = std::min(y[k] + h, g.upper[k]);
    const double b = std::max(y[k] - h, g.lower[k]);
    p[k] = a;
    fill(p.data(), ca.data());
    p[k] = b;
    fill(p.data(), cb.data());
    p[k] = y[k];
    for (std::size_t i = 0; i < sample_rows; ++i) grad[i * dim + k] = a > b ? (ca[i] - cb[i]) / (a - b) : 0.0;
  }
  for (std::size_t s = 0; s < g.active.size(); ++s) {
    for (std::size_t l = 0; l < L; ++l) {
      grad[(s * L + l) * dim + g.n + l] = g.locals[l].reduction == Reduction::kMin ? 1.0 : -1.0;
    }
  }
  // Goal rows: depend on (z, e) only; central differences (cheap: no sample is evaluated).
  if (gc > 0) {
    g.probe.assign(z, y + dim);
    g.goal_ca.resize(gc);
    g.goal_cb.resize(gc);
    for (std::size_t j = 0; j < dim - g.n; ++j) {
      const double h = 1e-7 * std::max(1.0, std::abs(g.probe[j]));
      const double keep = g.probe[j];
      g.probe[j] = keep + h;
      g.goal->constraint(g.probe.data(), g.probe.data() + L, g.goal_ca.data());
      g.probe[j] = keep - h;
      g.goal->constraint(g.probe.data(), g.probe.data() + L, g.goal_cb.data());
      g.probe[j] = keep;
      for (std::size_t i = 0; i < gc; ++i) grad[(sample_rows + i) * dim + g.n + j] = (g.goal_ca[i] - g.goal_cb[i]) / (2 * h);
    }
  }
}

// Samples whose local value lies within `fraction` of the extreme, per min/max local (at most
// `per_local` each, the closest first), from one full evaluation of p with every sample's values.
std::vector<int> near_critical(const Problem& problem, const std::vector<LocalIndex>& locals, const double* p,
                               Problem::EvalScratch& ws, double fraction, std::size_t per_local, long long& samples) {
  const int count = problem.samples().size();
  std::vector<double> values(static_cast<std::size_t>(count) * locals.size(), std::nan(""));
  SampleCallback record = [&](int s, const SampleQuantities&, const std::vector<std::vector<double>>& per_metric) {
    for (std::size_t l = 0; l < locals.size(); ++l) {
      values[static_cast<std::size_t>(s) * locals.size() + l] = per_metric[locals[l].metric][locals[l].local];
    }
  };
  EvalOptions o;
  o.on_sample = &record;
  samples += problem.evaluate(p, ws, o).samples_evaluated;
  std::vector<int> chosen;
  for (std::size_t l = 0; l < locals.size(); ++l) {
    std::vector<std::pair<double, int>> gap;  // distance from the extreme, relative
    double extreme = locals[l].reduction == Reduction::kMin ? kInf : -kInf;
    for (int s = 0; s < count; ++s) {
      const double v = values[static_cast<std::size_t>(s) * locals.size() + l];
      if (std::isnan(v)) continue;
      extreme = locals[l].reduction == Reduction::kMin ? std::min(extreme, v) : std::max(extreme, v);
    }
    if (!std::isfinite(extreme)) continue;
    for (int s = 0; s < count; ++s) {
      const double v = values[static_cast<std::size_t>(s) * locals.size() + l];
      if (std::isnan(v)) continue;
      const double d = std::abs(v - extreme) / std::max(std::abs(extreme), 1e-12);
      if (d <= fraction) gap.emplace_back(d, s);
    }
    std::sort(gap.begin(), gap.end());
    for (std::size_t i = 0; i < gap.size() && i < per_local; ++i) chosen.push_back(gap[i].second);
  }
  std::sort(chosen.begin(), chosen.end());
  chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
  return chosen;
}

// z's start for one round: each local's reduction over the active samples (g.values holds the
// locals of the round's start design), then the goal's extra variables from z.
void start_epigraph_variables(const Epigraph& g, const MinMaxGoal& goal, std::vector<double>& y) {
  const std::size_t L = g.locals.size();
  for (std::size_t l = 0; l < L; ++l) {
    double v = g.locals[l].reduction == Reduction::kMin ? kInf : -kInf;
    for (std::size_t s = 0; s < g.active.size(); ++s) {
      v = g.locals[l].reduction == Reduction::kMin ? std::min(v, g.values[s * L + l]) : std::max(v, g.values[s * L + l]);
    }
    y[g.n + l] = v;
  }
  if (goal.extra > 0) goal.initial_extra(y.data() + g.n, y.data() + g.n + L);
}

// One SLSQP run over y = (p, z, e) with the active set in g; y becomes SLSQP's final iterate and
// g.best_y the best iterate that met every constraint. Returns NLopt's outcome.
std::string run_epigraph_slsqp(Epigraph& g, const MinMaxGoal& goal, const SqpSettings& settings,
                               std::vector<double>& y) {
  const unsigned dim = static_cast<unsigned>(y.size());
  std::vector<double> lo(dim, -HUGE_VAL), hi(dim, HUGE_VAL);
  std::copy(g.lower.begin(), g.lower.end(), lo.begin());
  std::copy(g.upper.begin(), g.upper.end(), hi.begin());
  nlopt::opt opt(nlopt::LD_SLSQP, dim);
  opt.set_lower_bounds(lo);
  opt.set_upper_bounds(hi);
  opt.set_max_objective(epigraph_objective, &g);
  const std::size_t rows = g.active.size() * g.locals.size() + static_cast<std::size_t>(goal.constraints);
  opt.add_inequality_mconstraint(epigraph_constraints, &g, std::vector<double>(rows, settings.constraint_tolerance));
  DesignConstraints design{g.problem, g.n, g.lower, g.upper, {}, {}, {}};
  if (settings.design_constraints) add_design_constraints(opt, design, settings.constraint_tolerance);
  opt.set_xtol_rel(settings.xtol);
  opt.set_ftol_abs(settings.ftol);
  opt.set_maxeval(settings.max_evaluations);
  double f = 0.0;
  g.best_y.clear();
  g.best_objective = -kInf;
  try {
    return nlopt_result_name(opt.optimize(y, f));
  } catch (const std::exception& e) {
    // Round-off and similar NLopt stops are outcomes, not errors: the best point seen stands.
    return std::string("stopped: ") + e.what();
  }
}

// Candidates of a round: SLSQP's final iterate y and the best iterate that met every constraint;
// each is searched over the whole workspace, which is what decides. The best feasible one
// becomes `current` (and `out`'s point when it beats it); samples critical at any of them join
// `active` (`grew` says whether one did). Returns false when no candidate is feasible.
bool adopt_best_candidate(const Epigraph& g, const MinMaxGoal& goal, const std::vector<double>& y,
                          Problem::EvalScratch& eval_scratch, std::set<int>& active, std::vector<double>& current,
                          bool& grew, SqpOutcome& out) {
  std::vector<std::vector<double>> candidates = {y};
  if (!g.best_y.empty() && g.best_y != y) candidates.push_back(g.best_y);
  grew = false;
  std::vector<double> p(g.n);
  bool any_feasible = false;
  double p_merit = -kInf;
  for (const auto& cand : candidates) {
    std::vector<double> q(cand.begin(), cand.begin() + static_cast<std::ptrdiff_t>(g.n));
    for (std::size_t k = 0; k < g.n; ++k) q[k] = std::clamp(q[k], g.lower[k], g.upper[k]);
    const Evaluation& e = g.problem->evaluate(q.data(), eval_scratch);
    ++out.evaluations;
    out.samples += e.samples_evaluated;
    if (e.status != EvalStatus::kFeasible) continue;
    for (const auto& list : e.critical_samples) {
      for (int s : list) grew = active.insert(s).second || grew;
    }
    const double merit = goal.merit(e);
    if (!any_feasible || merit > p_merit) {
      p = q;
      p_merit = merit;
    }
    any_feasible = true;
    if (merit > out.merit) {
      out.merit = merit;
      out.x = q;
    }
  }
  if (any_feasible) current = p;
  return any_feasible;
}

SqpOutcome run_epigraph(const Problem& problem, std::vector<double> x, const std::vector<double>& lower,
                        const std::vector<double>& upper, const SqpSettings& settings, const MinMaxGoal& goal) {
  const auto t0 = Clock::now();
  auto eval_scratch = problem.make_eval_scratch();
  Reporter reporter{&settings};
  Epigraph g;
  g.reporter = &reporter;
  g.problem = &problem;
  g.goal = &goal;
  g.eval_scratch = eval_scratch.get();
  g.n = x.size();
  g.lower = lower;
  g.upper = upper;
  g.tolerance = settings.constraint_tolerance;
  g.locals = flat_locals(problem, nullptr);
  SqpOutcome out;
  const Evaluation& start = problem.evaluate(x.data(), *eval_scratch);
  out.samples += start.samples_evaluated;
  ++out.evaluations;
  if (start.status != EvalStatus::kFeasible) {
    out.status = "infeasible start";
    out.seconds = seconds_since(t0);
    return out;
  }
  out.x = x;
  out.merit = goal.merit(start);
  g.best_merit = out.merit;
  std::set<int> active;
  for (int s : near_critical(problem, g.locals, x.data(), *eval_scratch, 0.02, 8, out.samples)) active.insert(s);
  std::vector<double> current = x;
  const std::size_t dim = g.n + g.zsize() + static_cast<std::size_t>(goal.extra);
  for (int round = 0; round < settings.rounds; ++round) {
    g.active.assign(active.begin(), active.end());
    std::vector<double> y(dim);
    std::copy(current.begin(), current.end(), y.begin());
    if (!g.locals_at(current.data())) break;
    start_epigraph_variables(g, goal, y);
    out.status = run_epigraph_slsqp(g, goal, settings, y);
    ++out.rounds;
    bool grew = false;
    const bool adopted = adopt_best_candidate(g, goal, y, *eval_scratch, active, current, grew, out);
    g.best_merit = out.merit;
    if (!adopted) break;
    if (!grew) break;  // the full workspace agrees with the active set: converged
    for (int s : near_critical(problem, g.locals, current.data(), *eval_scratch, 0.02, 8, out.samples)) active.insert(s);
  }
  out.evaluations += g.evaluations;
  out.samples += g.samples;
  out.active_samples = active.size();
  out.seconds = seconds_since(t0);
  return out;
}

// ---- plain stage ----

struct PlainRun {
  const Problem* problem = nullptr;
  const MinMaxGoal* goal = nullptr;
  Problem::EvalScratch* eval_scratch = nullptr;
  std::vector<double> lower, upper, probe;
  long long evaluations = 0, samples = 0;
  double lowest_feasible = 0.0;
  std::vector<double> best_x;
  double best_merit = -kInf;
  Reporter* reporter = nullptr;

  double merit(const double* x) {
    const Evaluation& e = problem->evaluate(x, *eval_scratch);
    ++evaluations;
    samples += e.samples_evaluated;
    if (reporter) reporter->tick("plain stage", evaluations, best_merit);
    if (e.status != EvalStatus::kFeasible) return lowest_feasible - 1.0;
    const double m = goal->merit(e);
    lowest_feasible = std::min(lowest_feasible, m);
    if (m > best_merit) {
      best_merit = m;
      best_x.assign(x, x + lower.size());
    }
    return m;
  }
};

double plain_objective(unsigned n, const double* x, double* grad, void* data) {
  PlainRun& run = *static_cast<PlainRun*>(data);
  const double f = run.merit(x);
  if (grad) {
    run.probe.assign(x, x + n);
    for (unsigned k = 0; k < n; ++k) {
      const double h = 1e-6 * std::max(run.upper[k] - run.lower[k], 1e-9);
      const double a = std::min(x[k] + h, run.upper[k]);
      const double b = std::max(x[k] - h, run.lower[k]);
      run.probe[k] = a;
      const double fa = run.merit(run.probe.data());
      run.probe[k] = b;
      const double fb = run.merit(run.probe.data());
      run.probe[k] = x[k];
      grad[k] = a > b ? (fa - fb) / (a - b) : 0.0;
    }
  }
  return f;
}

SqpOutcome run_plain(const Problem& problem, std::vector<double> x, const std::vector<double>& lower,
                     const std::vector<double>& upper, const SqpSettings& settings, const MinMaxGoal& goal) {
  const auto t0 = Clock::now();
  auto eval_scratch = problem.make_eval_scratch();
  Reporter reporter{&settings};
  PlainRun run;
  run.reporter = &reporter;
  run.problem = &problem;
  run.goal = &goal;
  run.eval_scratch = eval_scratch.get();
  run.lower = lower;
  run.upper = upper;
  nlopt::opt opt(nlopt::LD_SLSQP, static_cast<unsigned>(x.size()));
  opt.set_lower_bounds(lower);
  opt.set_upper_bounds(upper);
  opt.set_max_objective(plain_objective, &run);
  DesignConstraints design{&problem, x.size(), lower, upper, {}, {}, {}};
  if (settings.design_constraints) add_design_constraints(opt, design, settings.constraint_tolerance);
  opt.set_xtol_rel(settings.xtol);
  opt.set_ftol_abs(settings.ftol);
  opt.set_maxeval(settings.max_evaluations);
  SqpOutcome out;
  double f = 0.0;
  try {
    out.status = nlopt_result_name(opt.optimize(x, f));
  } catch (const std::exception& e) {
    out.status = std::string("stopped: ") + e.what();
  }
  out.x = run.best_x;
  out.merit = run.best_merit;
  out.evaluations = run.evaluations;
  out.samples = run.samples;
  out.rounds = 1;
  out.seconds = seconds_since(t0);
  return out;
}

}  // namespace

std::size_t local_count(const Problem& problem) { return flat_locals(problem, nullptr).size(); }

void objectives_from_locals(const Problem& problem, const double* z, double* f) {
  std::size_t base = 0;
  std::vector<std::size_t> bases;
  for (const MetricEntry& m : problem.metrics()) {
    bases.push_back(base);
    base += m.metric->locals().size();
  }
  for (std::size_t o = 0; o < problem.objectives().size(); ++o) {
    const std::size_t m = static_cast<std::size_t>(problem.objectives()[o].metric);
    f[o] = problem.metrics()[m].metric->combine(z + bases[m], 1);
  }
}

MinMaxGoal score_goal(const Problem& problem) {
  MinMaxGoal goal;
  std::vector<std::size_t> bases;
  flat_locals(problem, &bases);
  const Problem* p = &problem;
  goal.objective = [p, bases](const double* z, const double*) {
    double score = 0.0;
    for (const Objective& o : p->objectives()) {
      const std::size_t m = static_cast<std::size_t>(o.metric);
      const double sign = o.sense == Sense::kMaximize ? 1.0 : -1.0;
      score += o.weight * sign * p->metrics()[m].metric->combine(z + bases[m], 1);
    }
    return score;
  };
  goal.merit = [](const Evaluation& e) { return e.score; };
  return goal;
}

SqpOutcome run_minmax_sqp(const Problem& problem, const std::vector<double>& x, const std::vector<double>& lower,
                          const std::vector<double>& upper, const SqpSettings& settings, const MinMaxGoal& goal) {
  SqpOutcome plain;
  if (settings.plain) plain = run_plain(problem, x, lower, upper, settings, goal);
  const bool epigraph_applies = settings.epigraph && problem.worst_case();
  if (!epigraph_applies) {
    plain.status = "plain: " + (settings.plain ? plain.status : std::string("off")) + "; epigraph: off";
    return plain;
  }
  const SqpOutcome epigraph = run_epigraph(problem, plain.x.empty() ? x : plain.x, lower, upper, settings, goal);
  SqpOutcome out = epigraph.merit > plain.merit ? epigraph : plain;
  out.status = "plain: " + (settings.plain ? plain.status : std::string("off")) + "; epigraph: " + epigraph.status;
  out.evaluations = plain.evaluations + epigraph.evaluations;
  out.samples = plain.samples + epigraph.samples;
  out.rounds = plain.rounds + epigraph.rounds;
  out.active_samples = epigraph.active_samples;
  out.seconds = plain.seconds + epigraph.seconds;
  return out;
}

}  // namespace hapsyn::plugins
