#pragma once
/// \file
/// The worst-case monotonicity spot check that grid pruning and culling share (header only;
/// both include it as "shared/bounds/worst_case_check.hpp").
///
/// Both rely on the rule of hapsyn/metric.hpp: a worst-case metric's value over a subset of the
/// samples bounds its value over the whole scene from above. A third-party metric whose
/// combine() breaks it makes them cut designs that are in fact better, silently. The check
/// compares, on designs that get a full workspace search anyway, a subset value with the full
/// one; a subset value below the full value (beyond 1e-12 relative) is a breach, and the solver
/// returns status failed with breach_message().
#include <hapsyn/problem.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// An objective whose value over a subset of samples came out below its value over the scene.
struct MonotonicityBreach {
  int objective = 0;         ///< index into Problem::objectives()
  double subset_value = 0.0;
  double full_value = 0.0;
  long long subset_samples = 0;
  Json design;               ///< Problem::design_to_json of the design
};

/// True when `subset_value` may stand as an upper bound of `full_value` (>= within 1e-12 relative).
inline bool bound_holds(double subset_value, double full_value) {
  return subset_value >= full_value - 1e-12 * std::max(1.0, std::abs(full_value));
}

/// The first objective (with a positive weight, or any when `all_objectives`) whose
/// `subset_objectives` value does not bound its `full_objectives` value; nullopt when all do.
inline std::optional<MonotonicityBreach> compare_bounds(const Problem& problem, const double* free_design,
                                                        const std::vector<double>& subset_objectives,
                                                        const std::vector<double>& full_objectives,
                                                        long long subset_samples, bool all_objectives) {
  for (std::size_t o = 0; o < full_objectives.size(); ++o) {
    if (!all_objectives && !(problem.objectives()[o].weight > 0.0)) continue;
    if (bound_holds(subset_objectives[o], full_objectives[o])) continue;
    return MonotonicityBreach{static_cast<int>(o), subset_objectives[o], full_objectives[o], subset_samples,
                              problem.design_to_json(problem.full_design(free_design))};
  }
  return std::nullopt;
}

/// Spot check of a design whose full evaluation `full` (feasible, from `scratch`) just
/// completed: evaluates it again on the first half of sample_order() without the design's
/// critical samples (so that the reduced values differ from the full ones, and so does the
/// sample count), and compares each objective with the full value. Costs half a full
/// evaluation; callers run it on the few designs that improve their best or front. `subset` is
/// the caller's buffer (no allocation once it has grown). Nothing to check with one sample.
inline std::optional<MonotonicityBreach> spot_check(const Problem& problem, const double* free_design,
                                                    Problem::EvalScratch& scratch, std::vector<int>& subset,
                                                    bool all_objectives) {
  const Evaluation& full = scratch.last();
  const std::vector<double> full_objectives = full.objectives;  // the next evaluate() reuses `full`
  const std::vector<int>& order = problem.sample_order();
  const std::size_t half = order.size() / 2;
  subset.clear();
  for (std::size_t i = 0; i < order.size() && subset.size() < half; ++i) {
    bool critical = false;
    for (const std::vector<int>& list : full.critical_samples) {
      critical = critical || std::find(list.begin(), list.end(), order[i]) != list.end();
    }
    if (!critical) subset.push_back(order[i]);
  }
  if (subset.empty()) return std::nullopt;
  EvalOptions options;
  options.subset = &subset;
  const Evaluation& part = problem.evaluate(free_design, scratch, options);
  if (part.status != EvalStatus::kFeasible) return std::nullopt;  // cannot happen: every sample was reachable
  return compare_bounds(problem, free_design, part.objectives, full_objectives, part.samples_evaluated,
                        all_objectives);
}

/// "metric 'm' (objective 'o') breaks the worst-case monotonicity rule: ...; <consequence>".
inline std::string breach_message(const Problem& problem, const MonotonicityBreach& b, const std::string& consequence) {
  const Objective& o = problem.objectives()[static_cast<std::size_t>(b.objective)];
  const std::string& metric = problem.metrics()[static_cast<std::size_t>(o.metric)].plugin;
  std::ostringstream s;
  s.precision(17);
  s << "metric '" << metric << "' (objective '" << o.name
    << "') breaks the worst-case monotonicity rule: its value over " << b.subset_samples << " of the "
    << problem.samples().size() << " samples is " << b.subset_value << ", below its value over the whole scene "
    << b.full_value << " (design " << b.design.dump()
    << "), so a subset of samples does not bound it from above (its combine() must be non-decreasing in min-reduced "
       "and non-increasing in max-reduced values); "
    << consequence;
  return s.str();
}

}  // namespace hapsyn::plugins
