#pragma once
/// \file
/// Block bounds of runs of a grid line (header only; grid and culling share it, as
/// "shared/bounds/run_bounds.hpp"; BLOCK_BOUNDS.md sections 13.5 and 13.6). Within a line's verified run
/// (LineBound::verified()), a run of consecutive designs is ruled out at once when, at one
/// sample, every design of the run fails (all infeasible in a worst-case study) or the study's
/// score is bounded strictly below a threshold that a real design already reaches
/// (Problem::block_score_bound, from MechanismAcceleration::sample_envelope and MetricAcceleration::envelope_bound).
/// No design that ties or beats the threshold is ever ruled out, so a grid optimum found with
/// block bounds is the optimum found without them.
///
/// The runs adapt to the line: they start at kFirst designs, double after a run is ruled out and
/// halve after one is not, within [kMin, kMax]; a try that rules nothing out tries the first half
/// of its run at once (when that half holds kMin designs or more). After a try that rules nothing out the next one
/// waits `gap` designs, doubled on every such try in a row, so that on lines where the bounds do
/// not help the tries cost little beside the designs' own evaluations. A try takes first the
/// sample that ruled out the same part of the previous line (the run that contains its first
/// design, or the next one): which critical sample bounds a run changes along a line, and the
/// caller's order only remembers the last one (BLOCK_BOUNDS.md section 13.5).
///
/// Before any run, a line is cut to the values where the first kReachSamples samples of the
/// caller's list can be solved (Problem::reachable_interval, from
/// MechanismAcceleration::reachable_interval): the designs of the line outside that interval fail at a
/// sample and are ruled out at once, without an envelope (in a worst-case study a failed sample
/// makes a design infeasible).
///
/// The framework checks the mechanism's claims: every kCheckEvery-th ruled-out run (the first of
/// each thread included) has its middle design evaluated exactly at the deciding sample; a
/// design that reaches the sample where the bound says all fail, or scores above the bound,
/// stops the run with an Error naming the run, the sample and the option that turns the bounds
/// off, instead of a silently wrong optimum. A line cut by a sample's reachable interval has,
/// on the same clock, its excluded design nearest the interval solved at that sample, which
/// must fail.
#include "shared/bounds/line_bound.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/problem.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// How a RunBounds' tries adapt, per solver.
struct RunPolicy {
  /// Samples tried per run (the first ones of the caller's list).
  std::size_t samples = 2;
  /// The wait after failed tries carries over from line to line (else each line starts
  /// afresh): for grids of many short lines, where a try costs about what the designs of a
  /// short run cost.
  bool carry_wait = false;
};

class RunBounds {
 public:
  /// How a try ended.
  enum class Outcome {
    kNotDue,          ///< no try: the run would be too short, or the last failed try asks to wait
    kNotRuledOut,     ///< tried: no sample bounds the run below the threshold
    kAllFail,         ///< every design of the run fails at a sample
    kBelowThreshold,  ///< every design of the run scores strictly below the threshold
  };
  struct Try {
    Outcome outcome = Outcome::kNotDue;
    long long last = -1;  ///< the run's last line index, when ruled out
    bool ruled_out() const { return outcome == Outcome::kAllFail || outcome == Outcome::kBelowThreshold; }
  };

  using Policy = RunPolicy;
  /// Samples whose reachable intervals cut a line (the first ones of the caller's list).
  static constexpr std::size_t kReachSamples = 2;

  /// \param problem the study; the runs vary its last free design component.
  /// \param solver the solver's name, which prefixes the spot check's error.
  /// \param policy how the tries adapt (Policy).
  RunBounds(const Problem& problem, const char* solver, Policy policy = {})
      : problem_(problem),
        solver_(solver),
        policy_(policy),
        component_(problem.design_space().free_indices().empty() ? -1 : problem.design_space().free_indices().back()),
        full_(problem.design_space().size(), 0.0),
        check_x_(problem.design_space().free_size(), 0.0) {}

  /// Starts a line: `free_design` is a free design vector of the line (its last component is
  /// ignored). With Policy::carry_wait the run size and the wait carry over from the line before
  /// (the designs still to wait count from the new line's start), so that where the bounds do
  /// not pay, tries stay rare on short lines too; else both start afresh. No allocation.
  void start_line(const double* free_design) {
    const std::size_t n = check_x_.size();
    std::copy(free_design, free_design + n, check_x_.begin());
    problem_.design_space().expand(free_design, full_.data());
    if (policy_.carry_wait) {
      next_ = std::max(0LL, next_ - (seen_ + 1));
    } else {
      size_ = kFirst;
      gap_ = kMin;
      next_ = 0;
    }
    seen_ = -1;
    reach_pending_ = true;
    deciders_before_.swap(deciders_);
    deciders_.clear();
    decider_cursor_ = 0;
  }

  /// Design i of the current line (its values from `line`, whose run must be verified and end
  /// at `last`). When i lies outside the line's reachable interval (found at the line's first
  /// call, from the first kReachSamples of `samples`), rules out the designs from i to the
  /// interval's start, or to `last`. Else tries, when one is due, the run [i, min(last, i +
  /// size - 1)] at the first Policy::samples of `samples` (most useful first; the deciding
  /// sample moves to the front). `threshold` is a score a real design reaches (or -inf: then
  /// only runs that all fail are ruled out). The spot check may evaluate one design in
  /// `scratch` (it overwrites its last evaluation).
  /// \throws Error(solver, ...) when the spot check refutes the mechanism's bound.
  Try try_run(long long i, long long last, double threshold, std::vector<int>& samples, const LineBound& line,
              Problem::EvalScratch& scratch) {
    Try t;
    if (component_ < 0 || samples.empty()) return t;
    seen_ = std::max(seen_, last);
    if (reach_pending_) find_reachable(samples, line);
    if (i < reach_first_ || i > reach_last_) return unreachable_run(i, last, line, scratch);
    last = std::min(last, reach_last_);
    if (i < next_ || last - i + 1 < kMin) return t;
    long long end = std::min(last, i + size_ - 1);
    t.outcome = rule_out(i, end, threshold, samples, line, scratch);
    if (!t.ruled_out() && end - i + 1 >= 2 * kMin) {
      // The envelope of a narrower run is tighter: the first half, at once, before its designs
      // are left to the caller one by one (docs/design.md section 13.5). It starts the next
      // runs at half its size.
      end = i + (end - i + 1) / 2 - 1;
      t.outcome = rule_out(i, end, threshold, samples, line, scratch);
      if (t.ruled_out()) size_ = std::max(size_ / 4, kMin);
    }
    if (t.ruled_out()) {
      size_ = std::min(size_ * 2, kMax);
      gap_ = kMin;
      next_ = end + 1;
      t.last = end;
    } else {
      size_ = std::max(size_ / 2, kMin);
      next_ = i + gap_;
      gap_ = std::min(gap_ * 2, kMaxGap);
    }
    return t;
  }

 private:
  static constexpr long long kMin = 8, kFirst = 32, kMax = 4096, kMaxGap = 1024, kCheckEvery = 16;
  static constexpr double kInf = std::numeric_limits<double>::infinity();

  // The reachable interval of the current line: [reach_first_, reach_last_] within the line's
  // run [line.first(), line.last()], cut by each of the first kReachSamples samples; the sample
  // that set each end is its witness.
  void find_reachable(const std::vector<int>& samples, const LineBound& line) {
    reach_pending_ = false;
    reach_first_ = line.first();
    reach_last_ = line.last();
    const std::size_t tries = std::min(samples.size(), kReachSamples);
    for (std::size_t k = 0; k < tries; ++k) {
      double lower = 0.0, upper = 0.0;
      if (!problem_.reachable_interval(full_.data(), component_, samples[k], lower, upper)) continue;
      if (!(lower <= upper)) {
        if (lower > upper) {  // the sample fails everywhere (NaN: nothing is known)
          reach_first_ = line.last() + 1;
          witness_below_ = samples[k];
          return;
        }
        continue;
      }
      const long long first = first_at_or_above(lower, line);
      if (first > reach_first_) {
        reach_first_ = first;
        witness_below_ = samples[k];
      }
      const long long last = first_at_or_above(std::nextafter(upper, kInf), line) - 1;
      if (last < reach_last_) {
        reach_last_ = last;
        witness_above_ = samples[k];
      }
    }
  }

  // The first index of the line's run whose value is >= v (line.last() + 1 when none is).
  static long long first_at_or_above(double v, const LineBound& line) {
    return std::clamp(line.first_at_or_above(v), line.first(), line.last() + 1);
  }

  // Rules out the designs from i (outside the reachable interval) to the interval's start, or
  // to `last` beyond its end: each fails at the witness sample.
  Try unreachable_run(long long i, long long last, const LineBound& line, Problem::EvalScratch& scratch) {
    const bool below = i < reach_first_;
    Try t;
    t.outcome = Outcome::kAllFail;
    t.last = below ? std::min(last, reach_first_ - 1) : last;
    // The design nearest the interval is the one a wrong bound most likely cuts.
    if (ruled_out_runs_++ % kCheckEvery == 0) {
      check_fails(below ? t.last : i, below ? witness_below_ : witness_above_, line, scratch);
    }
    return t;
  }

  // The design at line index i, solved at `sample` alone, must fail there.
  void check_fails(long long i, int sample, const LineBound& line, Problem::EvalScratch& scratch) {
    const std::size_t n = check_x_.size();
    check_x_[n - 1] = line.value(i);
    check_sample_.assign(1, sample);
    EvalOptions at_sample;
    at_sample.subset = &check_sample_;
    const Evaluation& e = problem_.evaluate(check_x_.data(), scratch, at_sample);
    if (e.status != EvalStatus::kFeasible) return;
    std::ostringstream message;
    message << std::setprecision(17)
            << "the mechanism's line bound (MechanismAcceleration::reachable_interval) is wrong: it claims that sample " << sample
            << " fails for every " << problem_.design_space().components()[static_cast<std::size_t>(component_)].name
            << " outside the interval it gives, but grid value " << check_x_[n - 1]
            << " lies outside it and reaches the sample; " << solver_
            << " could cut the optimum: set solver.options.block_bounds = false, and report the mechanism";
    throw Error(solver_, message.str());
  }

  Outcome rule_out(long long first, long long last, double threshold, std::vector<int>& samples, const LineBound& line,
                   Problem::EvalScratch& scratch) {
    const double lower = line.value(first), upper = line.value(last);
    const std::size_t tries = std::min(samples.size(), policy_.samples);
    // The sample that ruled out this part of the previous line goes first: neighbouring lines
    // differ in one other component by a grid step (measured: design.md section 13.5).
    std::size_t first_try = 0;
    const int hint = decider_before(first);
    for (std::size_t k = 1; k < tries && hint >= 0; ++k) {
      if (samples[k] == hint) first_try = k;
    }
    for (std::size_t n = 0; n < tries; ++n) {
      const std::size_t k = n == 0 ? first_try : (n <= first_try ? n - 1 : n);
      const int sample = samples[k];
      const double bound = problem_.block_score_bound(full_.data(), component_, lower, upper, sample);
      if (!(bound == -kInf || bound < threshold)) continue;
      // The spot check costs a design's evaluation at one sample: every kCheckEvery-th run.
      if (ruled_out_runs_++ % kCheckEvery == 0) check(first, last, sample, bound, line, scratch);
      if (k > 0) std::rotate(samples.begin(), samples.begin() + static_cast<std::ptrdiff_t>(k),
                             samples.begin() + static_cast<std::ptrdiff_t>(k) + 1);
      deciders_.push_back({last, sample});
      return bound == -kInf ? Outcome::kAllFail : Outcome::kBelowThreshold;
    }
    return Outcome::kNotRuledOut;
  }

  // The sample that ruled out the previous line's run containing line index i, or the nearest
  // run after it; -1 when there is none. The calls of a line come with increasing i.
  int decider_before(long long i) {
    while (decider_cursor_ < deciders_before_.size() && deciders_before_[decider_cursor_].last < i) ++decider_cursor_;
    return decider_cursor_ < deciders_before_.size() ? deciders_before_[decider_cursor_].sample : -1;
  }

  // The run's middle design, evaluated exactly at the sample, must fail there when the bound
  // says every design fails, and must not score above the bound otherwise.
  void check(long long first, long long last, int sample, double bound, const LineBound& line,
             Problem::EvalScratch& scratch) {
    const std::size_t n = check_x_.size();
    const long long middle = first + (last - first) / 2;
    check_x_[n - 1] = line.value(middle);
    check_sample_.assign(1, sample);
    EvalOptions at_sample;
    at_sample.subset = &check_sample_;
    const Evaluation& e = problem_.evaluate(check_x_.data(), scratch, at_sample);
    if (e.status != EvalStatus::kFeasible || e.score <= bound) return;
    std::ostringstream message;
    message << std::setprecision(17) << "the mechanism's block bound (MechanismAcceleration::sample_envelope) is wrong: over "
            << problem_.design_space().components()[static_cast<std::size_t>(component_)].name << " in ["
            << line.value(first) << ", " << line.value(last) << "] at sample " << sample << " it claims "
            << (bound == -kInf ? std::string("that every design fails") : "a score of at most " + std::to_string(bound))
            << ", but grid value " << check_x_[n - 1] << " reaches the sample and scores " << e.score
            << " there; " << solver_ << " could cut the optimum: set solver.options.block_bounds = false, and report "
            << "the mechanism";
    throw Error(solver_, message.str());
  }

  const Problem& problem_;
  const char* solver_;
  Policy policy_;
  int component_;
  std::vector<double> full_;          // the current line's full design
  std::vector<double> check_x_;       // the current line's free design, for the spot check
  std::vector<int> check_sample_;     // the one sample it is checked at
  long long ruled_out_runs_ = 0;      // runs ruled out so far (the spot check's clock)
  long long size_ = kFirst, gap_ = kMin, next_ = 0;
  long long seen_ = -1;  // the last line index the current line's calls reached
  // The current line's reachable interval (line indices; found at the line's first try_run)
  // and the samples that set its ends.
  bool reach_pending_ = true;
  long long reach_first_ = 0, reach_last_ = std::numeric_limits<long long>::max();
  int witness_below_ = -1, witness_above_ = -1;
  // The runs ruled out by an envelope on the current line and on the line before: each run's
  // last line index and its deciding sample, in line order.
  struct Decider {
    long long last;
    int sample;
  };
  std::vector<Decider> deciders_, deciders_before_;
  std::size_t decider_cursor_ = 0;
};

}  // namespace hapsyn::plugins
