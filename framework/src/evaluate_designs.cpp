// Design lanes: evaluate_designs(), kBlockLanes designs per mechanism call.
#include <hapsyn/accel/mechanism_acceleration.hpp>
#include <hapsyn/accel/lanes.hpp>
#include <hapsyn/accel/metric_acceleration.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/parallel.hpp>
#include <hapsyn/problem.hpp>

#include "evaluator.hpp"
#include "evaluator_steps.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <sstream>

namespace hapsyn {

using namespace evaluator_detail;

// Design lanes (evaluate_designs). Lane i's design is lane_design[i]: the caller's free vector
// when every component is free, else its expansion at ws.lane_full[i * size]. Its reductions are
// kept lane-minor, local j of lane i at ws.lane_accumulator / lane_argument[j * kBlockLanes + i],
// so that starting and folding a group are loops over the lanes that compile to vector code.
// Most designs here are decided at their first sample: what a design costs is this bookkeeping,
// not the arithmetic, so a lane's Evaluation is written only when the lane is decided
// (docs/design.md section 13.4).
void Evaluator::evaluate_designs(const double* const* free_designs, int count, EvalData& ws,
                               const EvalOptions& options, std::vector<Evaluation>& outs) const {
  assert(count >= 1 && count <= kBlockLanes);
  size_evaluations(outs, count);
  const auto one_by_one = [&](int from, const bool* pending) {
    for (int i = from; i < count; ++i) {
      if (!pending || pending[i]) outs[static_cast<std::size_t>(i)] = evaluate(free_designs[i], ws, options);
    }
  };
  // Design lanes serve worst-case studies (their first samples decide most designs).
  if (!block_path_ || !worst_case_ || options.per_sample || options.on_sample || count == 1) {
    return one_by_one(0, nullptr);
  }
  bool active[kBlockLanes] = {};
  const double* lane_design[kBlockLanes];
  int left = start_lanes(free_designs, count, options.constraints_verified, ws, outs, active, lane_design);
  if (left == 0) return;
  int any = 0;
  while (!active[any]) ++any;
  const bool prune = std::isfinite(options.prune_below) && prunable_;
  const std::vector<double>* front = options.prune_dominated_by;
  const bool prune_front = front && !front->empty() && worst_case_ && all_maximized_;
  const std::vector<int>& indices = options.subset ? *options.subset : order_;
  const std::size_t lane_samples = std::min<std::size_t>(indices.size(), kBlockLanes);
  const double* designs[kBlockLanes];
  for (std::size_t t = 0; t < lane_samples && left > 0; ++t) {
    for (int i = 0; i < kBlockLanes; ++i) {  // decided and unused lanes repeat a live design
      designs[i] = lane_design[i < count && active[i] ? i : any];
    }
    const int sample = indices[t];
    if (!mechanism_accel_->solve_designs(designs, count, samples_->pose(sample), needs_, *ws.scratch, *ws.block)) {
      return one_by_one(0, active);  // these designs cannot share a vector: from scratch, one by one
    }
    std::fill_n(ws.block->samples, kBlockLanes, sample);
    const int non_finite = fold_lanes(sample, count, ws, options, prune, prune_front, outs, active, left);
    if (non_finite >= 0) {
      // The per-sample loop meets the same value and reports it with the design and sample.
      EvalOptions alone = options;
      alone.per_sample = true;
      (void)evaluate(free_designs[non_finite], ws, alone);
      throw Error("problem", "sample " + std::to_string(sample) +
                                 " gave a non-finite local value in a design lane but not alone (docs/design.md section 13.4)");
    }
    for (any = 0; left > 0 && !active[any];) ++any;
  }
  if (left == 0) return;
  if (lane_samples == indices.size()) {  // every sample seen: the surviving designs are complete
    const std::size_t size = space_.size(), k = local_reduction_.size();
    for (int i = 0; i < count; ++i) {
      if (!active[i]) continue;
      for (std::size_t j = 0; j < k; ++j) {
        ws.accumulator[j] = ws.lane_accumulator[j * kBlockLanes + static_cast<std::size_t>(i)];
        ws.argument[j] = ws.lane_argument[j * kBlockLanes + static_cast<std::size_t>(i)];
      }
      std::copy_n(lane_design[i], size, ws.full.data());
      combine_objectives(ws, outs[static_cast<std::size_t>(i)]);
    }
    return;
  }
  one_by_one(0, active);  // undecided after the first samples: the block path finishes them
}

// Makes outs hold at least `count` evaluations, new ones sized for the study. Existing ones are
// not checked per call (that cost as much as a lane's fold): the lanes' writers size what they
// write (mark_pruned, combine_objectives), and whole evaluations are assigned.
void Evaluator::size_evaluations(std::vector<Evaluation>& outs, int count) const {
  const std::size_t old = outs.size();
  if (old >= static_cast<std::size_t>(count)) return;
  outs.resize(static_cast<std::size_t>(count));
  for (std::size_t i = old; i < outs.size(); ++i) {
    outs[i].objectives.resize(objectives_.size());
    outs[i].critical_samples.resize(metrics_.size());
    outs[i].reduced.resize(metrics_.size());
  }
}

// Each lane's evaluate() up to its first sample: bounds, constraints (unless the caller verified
// them), identity reductions. Sets active[i] for the designs that go on to their samples and
// returns how many do; their outs hold a reset evaluation, the others a constraint violation.
int Evaluator::start_lanes(const double* const* free_designs, int count, bool constraints_verified, EvalData& ws,
                         std::vector<Evaluation>& outs, bool* active, const double** lane_design) const {
  const std::size_t free = free_lower_.size(), size = space_.size(), k = local_reduction_.size();
  // Component by component over all the lanes (unused lanes repeat the last design), so that
  // the comparisons are vector ones; a design out of bounds is then named by check_design.
  bool inside = true;
  for (std::size_t c = 0; c < free; ++c) {
    double v[kBlockLanes];
    for (int i = 0; i < kBlockLanes; ++i) v[i] = free_designs[std::min(i, count - 1)][c];
    const double lower = free_lower_[c], upper = free_upper_[c];
    bool in = true;
    for (int i = 0; i < kBlockLanes; ++i) in &= (v[i] >= lower) & (v[i] <= upper);
    inside &= in;
  }
  if (!inside) {
    for (int i = 0; i < count; ++i) check_design(free_designs[i]);  // throws with the component named
  }
  for (std::size_t j = 0; j < k; ++j) {
    for (int i = 0; i < kBlockLanes; ++i) {
      ws.lane_accumulator[j * kBlockLanes + static_cast<std::size_t>(i)] = identity_accumulator_[j];
      ws.lane_argument[j * kBlockLanes + static_cast<std::size_t>(i)] = -1;
    }
  }
  int live = 0;
  for (int i = 0; i < count; ++i) {
    Evaluation& out = outs[static_cast<std::size_t>(i)];
    reset_evaluation(out);
    if (free == size) {
      lane_design[i] = free_designs[i];
    } else {
      double* full = ws.lane_full.data() + static_cast<std::size_t>(i) * size;
      space_.expand(free_designs[i], full);
      lane_design[i] = full;
    }
    if (!constraints_verified) {
      if (!constraints_hold(lane_design[i], ws, out)) continue;
    } else {
      // The caller's line bound checked the run's ends under the mechanism's quasiconvexity
      // promise; a broken promise is a plugin bug that builds with assertions catch here.
      assert(constraints_hold(lane_design[i], ws, out) &&
             "EvalOptions::constraints_verified for a design that violates a constraint");
    }
    active[i] = true;
    ++live;
  }
  return live;
}

// One sample of every active lane (solved into ws.block), as the per-sample loop takes it: the
// metrics' local values are computed for the lanes that reach it; a failing sample ends the
// design, the local values are reduced with the tie rule, and the bound may prune it. Clears
// active[i] and decrements `left` for each lane decided here. Returns the first lane with a
// non-finite local value (the caller reports it), else -1.
int Evaluator::fold_lanes(int sample, int count, EvalData& ws, const EvalOptions& options, bool prune,
                        bool prune_front, std::vector<Evaluation>& outs, bool* active, int& left) const {
  const std::size_t k = local_reduction_.size();
  constexpr std::size_t L = kBlockLanes;
  // Which lanes fold this sample: active and reachable. The reductions of all lanes are updated
  // together under that mask (lane-minor: a vector per local value).
  bool folds[L] = {};
  bool any_folds = false;
  for (int i = 0; i < count; ++i) {
    folds[i] = active[i] && ws.block->lane_status(i) == SampleStatus::kReachable;
    any_folds |= folds[i];
  }
  // Where the sample fails for every design (often: a line's neighbours share their failures),
  // there are no local values to compute.
  if (any_folds) block_locals(ws);
  const double* locals = ws.block_locals.data();
  for (std::size_t j = 0; j < k; ++j) {
    bool finite = true;
    for (std::size_t i = 0; i < L; ++i) finite &= !folds[i] || std::isfinite(locals[j * L + i]);
    if (!finite) {
      for (int i = 0; i < count; ++i) {
        if (folds[i] && !std::isfinite(locals[j * L + static_cast<std::size_t>(i)])) return i;
      }
    }
    double* acc = ws.lane_accumulator.data() + j * L;
    int* arg = ws.lane_argument.data() + j * L;
    const Reduction reduction = local_reduction_[j];
    for (std::size_t i = 0; i < L; ++i) {
      const double v = locals[j * L + i];
      const bool take = folds[i] && better(reduction, v, sample, acc[i], arg[i]);
      acc[i] = take ? v : acc[i];
      arg[i] = take ? sample : arg[i];
    }
  }
  // Every active lane has seen the same samples (they start together and fold each one).
  const int seen = outs[static_cast<std::size_t>(std::find(active, active + count, true) - active)].samples_evaluated + 1;
  double bound[L];
  const bool bounded = prune && !prune_front && score_bound_lanes(ws.lane_accumulator.data(), seen, bound);
  double* lane_acc = ws.accumulator.data();  // one lane's reductions, for the helpers (free here)
  int* lane_arg = ws.argument.data();
  for (int i = 0; i < count; ++i) {
    if (!active[i]) continue;
    Evaluation& out = outs[static_cast<std::size_t>(i)];
    out.samples_evaluated = seen;
    if (!folds[i]) {
      out.status = EvalStatus::kSampleFailed;
      out.failed_sample = sample;
      out.failed_status = ws.block->lane_status(i);
      active[i] = false;
      --left;
      continue;
    }
    if (!prune && !prune_front) continue;
    if (bounded && !(bound[i] < options.prune_below)) continue;
    for (std::size_t j = 0; j < k; ++j) {
      lane_acc[j] = ws.lane_accumulator[j * L + static_cast<std::size_t>(i)];
      lane_arg[j] = ws.lane_argument[j * L + static_cast<std::size_t>(i)];
    }
    if (bounded || (prune_front && front_dominates(*options.prune_dominated_by, lane_acc, ws.objective_bound.data())) ||
        (prune && score_bound(lane_acc, seen) < options.prune_below)) {
      mark_pruned(lane_arg, out);
      active[i] = false;
      --left;
    }
  }
  return -1;
}

// score_bound() of every lane at once (lane-minor reductions), bit for bit: each objective's
// combined values added in objective order from 0. False when a metric has no combine_block.
bool Evaluator::score_bound_lanes(const double* lane_accumulator, int samples, double* bound) const {
  constexpr std::size_t L = kBlockLanes;
  std::fill_n(bound, L, 0.0);
  double combined[L];
  for (std::size_t o = 0; o < objectives_.size(); ++o) {
    const std::size_t m = static_cast<std::size_t>(objectives_[o].metric);
    if (!metric_accel_[m]->combine_block(lane_accumulator + static_cast<std::size_t>(local_offset_[m]) * L, samples,
                                           combined)) {
      return false;
    }
    const double weight = objectives_[o].weight;
    for (std::size_t i = 0; i < L; ++i) bound[i] += weight * combined[i];
  }
  return true;
}

}  // namespace hapsyn
