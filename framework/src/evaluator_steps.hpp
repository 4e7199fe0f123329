#pragma once
// The steps the evaluator's paths share (per sample, batches, blocks, design lanes), defined
// inline: they run per sample or per block, and each path's file must be able to inline them as
// when they were one file.
#include <hapsyn/error.hpp>

#include "evaluator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace hapsyn {
namespace evaluator_detail {

inline std::string format_design(const Evaluator& problem, const Eigen::VectorXd& full) {
  return problem.design_to_json(full).dump();
}

// An evaluation's verdict before its design is looked at: feasible until shown otherwise.
inline void reset_evaluation(Evaluation& out) {
  out.status = EvalStatus::kFeasible;
  out.failed_constraint = -1;
  out.failed_sample = -1;
  out.failed_status = SampleStatus::kReachable;
  out.samples_evaluated = 0;
  out.score = -std::numeric_limits<double>::infinity();
}

inline bool better(Reduction r, double value, int index, double current, int current_index) {
  switch (r) {
    case Reduction::kMin: return value < current || (value == current && index < current_index);
    case Reduction::kMax: return value > current || (value == current && index < current_index);
    case Reduction::kSum: return false;
  }
  return false;
}

// The message of an out-of-bounds or non-finite design component. Out of line and cold: inlined,
// its stream set-up made check_design, which runs for every design, spill and save registers.
[[noreturn, gnu::cold, gnu::noinline]] void throw_bad_component(const DesignComponent& c, double v);

// The first quantity the mechanism filled (those the metrics need) that is not finite, or null.
// Only called once a local value came out non-finite: the per-sample loop pays nothing for it.
const char* non_finite_quantity(const SampleQuantities& q, Needs needs);

}  // namespace evaluator_detail

inline void Evaluator::check_design(const double* free_design) const {
  for (std::size_t k = 0; k < free_lower_.size(); ++k) {
    const double v = free_design[k];
    if (v >= free_lower_[k] && v <= free_upper_[k]) continue;  // false for NaN too
    evaluator_detail::throw_bad_component(space_.components()[static_cast<std::size_t>(space_.free_indices()[k])], v);
  }
}

// evaluate() in named steps. Each returns early the way evaluate() does; the per-sample steps are
// in this file so that the compiler can inline them into the sample loop.

inline bool Evaluator::constraints_hold(const double* full, EvalData& ws, Evaluation& out) const {
  if (constraint_names_.empty()) return true;
  mechanism_->evaluate_constraints(full, *samples_, ws.g.data());
  for (std::size_t i = 0; i < constraint_names_.size(); ++i) {
    if (std::isnan(ws.g[i])) {
      throw Error("problem", "mechanism '" + mechanism_plugin_ + "' returned constraint '" + constraint_names_[i] +
                                 "' = nan for design " +
                                 evaluator_detail::format_design(*this, Eigen::Map<const Eigen::VectorXd>(full, static_cast<Eigen::Index>(space_.size()))));
    }
    if (ws.g[i] > 0.0) {
      out.status = EvalStatus::kConstraintViolated;
      out.failed_constraint = static_cast<int>(i);
      return false;
    }
  }
  return true;
}

inline void Evaluator::accumulate_locals(int sample, EvalData& ws, bool keep_locals) const {
  for (std::size_t m = 0; m < metrics_.size(); ++m) {
    ws.quantities.attributes = metric_attributes_[m].data();
    ws.quantities.attribute_count = static_cast<int>(metric_attributes_[m].size());
    metrics_[m].metric->local(ws.quantities, ws.locals.data() + local_offset_[m]);
  }
  fold_locals(sample, ws, keep_locals, ws.quantities);
}

inline void Evaluator::fold_locals(int sample, EvalData& ws, bool keep_locals, const SampleQuantities& q) const {
  // The sample's weight factor for sum reductions (1 when unweighted: v * 1.0 is v exactly).
  const double scale = sample_scale_.empty() ? 1.0 : sample_scale_[static_cast<std::size_t>(sample)];
  for (std::size_t m = 0; m < metrics_.size(); ++m) {
    const int begin = local_offset_[m];
    const int end = local_offset_[m + 1];
    for (int i = begin; i < end; ++i) {
      const double v = ws.locals[static_cast<std::size_t>(i)];
      if (!std::isfinite(v)) refuse_non_finite_local(m, i - begin, sample, ws, q);
      const std::size_t ui = static_cast<std::size_t>(i);
      if (local_reduction_[ui] == Reduction::kSum) {
        ws.accumulator[ui] += v * scale;
      } else if (evaluator_detail::better(local_reduction_[ui], v, sample, ws.accumulator[ui], ws.argument[ui])) {
        ws.accumulator[ui] = v;
        ws.argument[ui] = sample;
      }
    }
    if (keep_locals) std::copy(ws.locals.begin() + begin, ws.locals.begin() + end, ws.nested_locals[m].begin());
  }
}

inline double Evaluator::score_bound(const double* accumulator, long long samples) const {
  // The metrics over the samples seen so far bound their final values from above.
  double bound = 0.0;
  for (std::size_t o = 0; o < objectives_.size(); ++o) {
    const std::size_t m = static_cast<std::size_t>(objectives_[o].metric);
    bound += objectives_[o].weight *
             metrics_[m].metric->combine(accumulator + local_offset_[m], static_cast<int>(samples));
  }
  return bound;
}

inline bool Evaluator::front_dominates(const std::vector<double>& front, const double* accumulator, double* bound) const {
  // Upper bounds of the objectives from the reductions so far (samples seen: a count is only
  // needed by sum reductions, which worst-case metrics do not have).
  const std::size_t m = objectives_.size();
  for (std::size_t o = 0; o < m; ++o) {
    const std::size_t metric = static_cast<std::size_t>(objectives_[o].metric);
    bound[o] = metrics_[metric].metric->combine(accumulator + local_offset_[metric], 1);
  }
  const std::size_t points = front.size() / m;
  if (m == 2) {
    // Sorted by the first objective, descending (second ascending): the points with q0 >= b0 are
    // a prefix, and the last of them has the largest q1.
    std::size_t lo = 0, hi = points;  // first index with q0 < b0
    while (lo < hi) {
      const std::size_t mid = (lo + hi) / 2;
      if (front[2 * mid] >= bound[0]) lo = mid + 1; else hi = mid;
    }
    if (lo == 0) return false;
    const double q0 = front[2 * (lo - 1)], q1 = front[2 * (lo - 1) + 1];
    return q1 > bound[1] || (q1 == bound[1] && q0 > bound[0]);
  }
  for (std::size_t p = 0; p < points; ++p) {
    const double* q = front.data() + p * m;
    bool at_least = true, better = false;
    for (std::size_t o = 0; o < m && at_least; ++o) {
      at_least = q[o] >= bound[o];
      better = better || q[o] > bound[o];
    }
    if (at_least && better) return true;
  }
  return false;
}

inline void Evaluator::mark_pruned(const int* argument, Evaluation& out) const {
  // The samples attaining the reductions so far are what made the bound fall: culling collects
  // them as critical samples.
  out.critical_samples.resize(metrics_.size());  // a no-op but for a caller's unsized evaluation
  for (std::size_t m = 0; m < metrics_.size(); ++m) {
    std::vector<int>& critical = out.critical_samples[m];
    const std::size_t n = static_cast<std::size_t>(local_offset_[m + 1] - local_offset_[m]);
    critical.resize(n);  // a no-op on a reused evaluation: the samples are written in place
    for (std::size_t j = 0; j < n; ++j) critical[j] = argument[static_cast<std::size_t>(local_offset_[m]) + j];
  }
  out.status = EvalStatus::kPruned;
}

// Every metric's local values of the block in ws (its samples set), each metric with the scene
// attributes it listed, and their block copy when the block is one of order_'s.
inline void Evaluator::block_locals(EvalData& ws) const {
  QuantityBlock& q = *ws.block;
  for (std::size_t m = 0; m < metrics_.size(); ++m) {
    q.attributes = metric_attributes_[m].data();
    q.attribute_count = static_cast<int>(metric_attributes_[m].size());
    q.attribute_lane_data = nullptr;
    if (ws.block_first != SIZE_MAX && !metric_attributes_[m].empty()) {
      for (std::size_t k = 0; k < metric_attributes_[m].size(); ++k) {
        const double* start = metric_attribute_blocks_[m][k];
        ws.attribute_lane_pointers[k] =
            start ? start + ws.block_first * static_cast<std::size_t>(metric_attributes_[m][k]->cols()) : nullptr;
      }
      q.attribute_lane_data = ws.attribute_lane_pointers.data();
    }
    metric_accel_[m]->local_block(q, ws.block_locals.data() + static_cast<std::size_t>(local_offset_[m]) * kBlockLanes);
  }
}

}  // namespace hapsyn
