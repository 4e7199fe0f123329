#pragma once
/// \file
/// Block bounds of grid lines (header only; grid and culling share it, as
/// "shared/bounds/line_bound.hpp"). A grid solver visits the designs in lines along the last free
/// component; when the mechanism knows an interval of that component outside which a constraint
/// is violated (MechanismAcceleration::constraint_interval), the designs of the line outside it are counted
/// as violating a constraint without being visited. The interval may be wider than the feasible
/// set, never narrower; LineBound checks the claim on every line at the excluded grid values
/// nearest the interval (the designs most likely to expose a wrong bound), so that a mechanism
/// whose bound cuts a feasible design stops the run with an error instead of a silently wrong
/// optimum (docs/design.md section 13.3). When the mechanism also promises that the line's
/// feasible values form one run (MechanismAcceleration::constraints_quasiconvex), the bound is made exact:
/// the constraints are evaluated at the run's ends (stepping inward past violators), and the
/// designs between need no constraint evaluation of their own (verified()).
#include <hapsyn/accel/mechanism_acceleration.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/accel/fast_math.hpp>
#include <hapsyn/problem.hpp>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace hapsyn::plugins {

class LineBound {
 public:
  /// \param problem the study; the bound acts on its last free design component.
  /// \param enabled false: no bound (every design of a line may be feasible).
  /// \param solver the solver's name, which prefixes its errors.
  LineBound(const Problem& problem, bool enabled, const char* solver)
      : problem_(problem),
        solver_(solver),
        enabled_(enabled && problem.design_space().free_size() > 0),
        full_(static_cast<Eigen::Index>(problem.design_space().size())),
        g_(problem.constraint_count()) {
    if (problem.design_space().free_size() > 0) {
      free_k_ = problem.design_space().free_size() - 1;
      component_ = problem.design_space().free_indices().back();
      count_ = problem.design_space().grid_counts().back();
      one_run_ = enabled_ && problem.mechanism_acceleration().constraints_quasiconvex(component_);
      if (count_ <= kMaxTabulated) {
        values_.resize(static_cast<std::size_t>(count_));
        for (long long i = 0; i < count_; ++i) values_[static_cast<std::size_t>(i)] = problem.design_space().grid_value(free_k_, i);
      }
    }
    last_ = count_ - 1;
  }

  /// The value of the line's component at grid index i (DesignSpace::grid_value, the same on
  /// every line): tabulated for lines of up to 65,536 points, so the solvers' per-design loops
  /// make no cross-library call for it.
  double value(long long i) const {
    return values_.empty() ? problem_.design_space().grid_value(free_k_, i) : values_[static_cast<std::size_t>(i)];
  }

  /// Sets the range of the line through `free_design` (its last component is ignored). Throws
  /// Error(solver, ...) when the mechanism's interval excludes a grid design whose constraints
  /// hold. No allocation.
  void update(const double* free_design) {
    first_ = 0;
    last_ = count_ - 1;
    verified_ = false;
    if (!enabled_) return;
    const DesignSpace& space = problem_.design_space();
    space.expand(free_design, full_.data());
    double lower = 0.0, upper = 0.0;
    if (!problem_.mechanism_acceleration().constraint_interval(full_.data(), component_, problem_.samples(), lower, upper)) return;
    if (!(lower <= upper)) {  // empty (or NaN: then every design is checked as usual)
      if (lower > upper) {
        first_ = count_;
        last_ = count_ - 1;
        confirm_violated(count_ / 2);
      }
      return;
    }
    // The first index at or above `lower`; the last at or below `upper` is the one before the
    // first above it.
    first_ = first_at_or_above(lower);
    last_ = first_at_or_above(std::nextafter(upper, std::numeric_limits<double>::infinity())) - 1;
    if (first_ > 0) confirm_violated(first_ - 1);
    if (last_ < count_ - 1) confirm_violated(last_ + 1);
    if (one_run_) make_exact();
  }

  /// True when every design of the line the bound does not exclude satisfies the constraints
  /// (checked at the run's ends, the rest by the mechanism's quasiconvexity promise): the
  /// solver may then set EvalOptions::constraints_verified for them.
  bool verified() const { return verified_; }

  /// The first grid index of the line whose value is >= v (the line's length when none is): the
  /// arithmetic estimate, then steps to the exact index (a few at most: the values are the
  /// grid's, lower + i step rounded).
  long long first_at_or_above(double v) const {
    const DesignComponent& c = problem_.design_space().components()[static_cast<std::size_t>(component_)];
    long long i = estimate((v - c.lower) / c.step);
    while (i > 0 && value(i - 1) >= v) --i;
    while (i < count_ && value(i) < v) ++i;
    return i;
  }

  /// True when grid index `i` of the line's component lies outside the bound.
  /// (Inline and branch-light: called for every design of the grid.)
  bool excludes(long long i) const { return i < first_ || i > last_; }
  /// The first grid index the bound does not exclude (the line's length when it excludes every
  /// design): the excluded indices are those before it and those after the run it starts.
  long long first() const { return first_; }
  /// The last grid index the bound does not exclude (before first() when it excludes every
  /// design).
  long long last() const { return last_; }
  /// Designs of the line the bound excludes.
  long long excluded() const { return count_ - std::max(0LL, last_ - first_ + 1); }

 private:
  // ceil(steps) clamped to the line: a starting point, made exact by the caller.
  long long estimate(double steps) const {
    if (!(steps > 0.0)) return 0;
    if (steps >= static_cast<double>(count_)) return count_;
    return static_cast<long long>(fast::ceil_small(steps));
  }

  // Narrows [first_, last_] to the designs whose constraints hold, from both ends (the
  // interval's margin makes it a superset by at most a few designs). One run: its ends hold,
  // so everything between holds, and everything outside violates. A NaN at an end leaves the
  // run unverified: the designs' own evaluations then report it.
  void make_exact() {
    Check c = Check::kViolated;
    while (first_ <= last_ && (c = check(first_)) == Check::kViolated) ++first_;
    if (c == Check::kNaN) return;
    while (last_ > first_ && (c = check(last_)) == Check::kViolated) --last_;
    if (c == Check::kNaN) return;
    verified_ = first_ <= last_;
  }

  enum class Check { kHolds, kViolated, kNaN };
  // The constraints at grid index i of the current line (full_ holds the line).
  Check check(long long i) {
    full_(component_) = value(i);
    problem_.mechanism().evaluate_constraints(full_.data(), problem_.samples(), g_.data());
    Check c = Check::kHolds;
    for (double g : g_) {
      if (std::isnan(g)) return Check::kNaN;
      if (g > 0.0) c = Check::kViolated;
    }
    return c;
  }

  // The claim "violates a constraint" at grid index i of the current line (full_ holds the line).
  void confirm_violated(long long i) {
    if (check(i) != Check::kHolds) return;
    throw Error(solver_, "the mechanism's constraint_interval for design component " + std::to_string(component_) +
                            " excludes the design " + problem_.design_to_json(full_).dump() +
                            ", whose constraints hold: the bound would cut feasible designs (a plugin bug); "
                            "set solver.options.line_bounds = false to run without it");
  }

  static constexpr long long kMaxTabulated = 1LL << 16;

  const Problem& problem_;
  const char* solver_;
  bool enabled_;
  std::size_t free_k_ = 0;
  int component_ = -1;
  long long count_ = 1;
  Eigen::VectorXd full_;
  std::vector<double> g_;
  std::vector<double> values_;  // value(i) of every grid index, when tabulated
  long long first_ = 0, last_ = 0;
  bool one_run_ = false;   // the mechanism promises one feasible run per line
  bool verified_ = false;  // [first_, last_] is exactly that run (see verified())
};

}  // namespace hapsyn::plugins
