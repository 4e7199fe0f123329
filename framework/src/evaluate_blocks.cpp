// The block path of evaluate(): kBlockLanes samples per mechanism and metric call.
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

// The per-sample loop of evaluate() on the block path: kBlockLanes samples are solved and their
// local values computed per call, then reduced lane by lane in sample order with the per-sample
// loop's tie rule. Pruning is decided once per block: the bounds only fall as samples are added
// (worst-case metrics), so a block whose end is not pruned had no pruned prefix; a block whose
// end is pruned is replayed lane by lane from the reductions before it, to stop at the very
// sample the per-sample loop stops at. A failing sample ends the evaluation after the lanes
// before it, as in the per-sample loop; samples_evaluated counts the same samples.
const Evaluation& Evaluator::evaluate_blocks(const MechanismModel& model, EvalData& ws, const EvalOptions& options,
                                           bool prune, bool prune_front) const {
  Evaluation& out = ws.result;
  const std::vector<int>* subset = options.subset;
  const std::size_t n = subset ? subset->size() : order_.size();
  const int dimension = samples_->dimension();
  QuantityBlock& q = *ws.block;
  PoseBlock poses;
  poses.dimension = dimension;
  // ws.block_first says which block of order_ the metrics see (their attributes' block copy);
  // other paths share the scratch, so it is reset however this function ends.
  struct ResetBlockFirst {
    std::size_t& first;
    ~ResetBlockFirst() { first = SIZE_MAX; }
  } reset{ws.block_first};
  // A subset that is a run of order_ on block boundaries reads the blocks of the full order.
  const std::size_t run = subset ? order_run(*subset) : 0;
  const bool in_order = run != SIZE_MAX;
  for (std::size_t first = 0; first < n; first += kBlockLanes) {
    const int count = static_cast<int>(std::min<std::size_t>(kBlockLanes, n - first));
    ws.block_first = in_order ? run + first : SIZE_MAX;
    poses.count = count;
    const int* lane_sample = in_order ? order_.data() + run + first : subset->data() + first;
    for (int c = 0; c < dimension; ++c) {
      if (!in_order) {
        double* lane = ws.gathered.data() + static_cast<std::size_t>(c) * kBlockLanes;
        for (int i = 0; i < kBlockLanes; ++i) lane[i] = samples_->pose(lane_sample[std::min(i, count - 1)])[c];
        poses.coordinate[c] = lane;
      } else {
        poses.coordinate[c] = block_poses_.data() + static_cast<std::size_t>(c) * block_stride_ + run + first;
      }
    }
    // The lanes' samples, padded with the last one (a kernel reads every lane).
    for (int i = 0; i < kBlockLanes; ++i) q.samples[i] = lane_sample[std::min(i, count - 1)];
    mechanism_accel_->solve_block(model, poses, needs_, *ws.scratch, q);
    if (!worst_case_) {  // averaging: every lane counts, whatever its status; nothing to prune
      fold_block_sums(model, ws, lane_sample, count);
      continue;
    }
    int valid = 0;  // reachable lanes before the first failing one
    while (valid < count && q.lane_status(valid) == SampleStatus::kReachable) ++valid;
    if (valid > 0 && fold_block(model, ws, options, lane_sample, valid, prune, prune_front)) {
      mark_pruned(ws.argument.data(), out);
      return out;
    }
    if (valid < count) {
      ++out.samples_evaluated;
      out.status = EvalStatus::kSampleFailed;
      out.failed_sample = lane_sample[valid];
      out.failed_status = q.lane_status(valid);
      return out;
    }
  }
  combine_objectives(ws, out);
  return out;
}

// Whether one of the first `lanes` values v[0..kBlockLanes) of local i may move its worst-case
// reduction from `current`: a value not strictly worse, or not finite (NaN, or an infinity that
// compares as worse). The lanes are tested without branches or early exit (one vector compare
// per lane group: the scan ran once per block and cost a sixth of an unpruned five-bar grid).
bool Evaluator::block_moves(std::size_t i, const double* v, double current, int lanes) const {
  const bool min = local_reduction_[i] == Reduction::kMin;
  if (lanes < kBlockLanes) {  // a block's last lanes: rare, lane by lane
    for (int lane = 0; lane < lanes; ++lane) {
      if (!std::isfinite(v[lane]) || !(min ? v[lane] > current : v[lane] < current)) return true;
    }
    return false;
  }
  // y = v + (v - v) is v where v is finite and NaN elsewhere, and a NaN is never strictly
  // worse. LanesSse2: this file is compiled for the baseline instruction set, whose vectors
  // hold pairs of lanes (a 64-byte Lanes would be compared lane by lane there).
  const LanesSse2 x = LanesSse2::load(v);
  const LanesSse2 y = x + (x - x);
  return !(min ? all_greater(y, current) : all_less(y, current));
}

// Reduces the first `lanes` lanes of the block in ws (all reachable) into the accumulators and
// counts them in samples_evaluated; true when the evaluation is pruned, with the reductions and
// the count where the per-sample loop would have stopped.
bool Evaluator::fold_block(const MechanismModel& model, EvalData& ws, const EvalOptions& options,
                         const int* lane_sample, int lanes, bool prune, bool prune_front) const {
  Evaluation& out = ws.result;
  block_locals(ws);
  const bool check = prune || prune_front;
  const std::size_t k = local_reduction_.size();
  // Most blocks do not move a worst-case reduction: when no lane reaches a reduction's current
  // value (its block extreme is strictly worse), the lane-by-lane scan of that value is skipped;
  // a lane that ties or beats it goes through the per-sample tie rule below.
  bool moves = false;
  for (std::size_t i = 0; i < k && !moves; ++i) moves = block_moves(i, ws.block_locals.data() + i * kBlockLanes, ws.accumulator[i], lanes);
  if (!moves) {  // the reductions, hence the bounds, are those after the previous block: not pruned
    out.samples_evaluated += lanes;
    return false;
  }
  if (check) {  // element by element: a few values, no memmove call per block
    for (std::size_t i = 0; i < k; ++i) {
      ws.saved_accumulator[i] = ws.accumulator[i];
      ws.saved_argument[i] = ws.argument[i];
    }
  }
  const auto fold_lane = [&](int lane) {
    const int sample = lane_sample[lane];
    for (std::size_t i = 0; i < k; ++i) {
      const double v = ws.block_locals[i * kBlockLanes + static_cast<std::size_t>(lane)];
      if (!std::isfinite(v)) refuse_non_finite_block_local(model, ws, sample);
      if (better(local_reduction_[i], v, sample, ws.accumulator[i], ws.argument[i])) {
        ws.accumulator[i] = v;
        ws.argument[i] = sample;
      }
    }
    ++out.samples_evaluated;
  };
  const auto pruned = [&] {
    return (prune_front && front_dominates(*options.prune_dominated_by, ws.accumulator.data(), ws.objective_bound.data())) ||
           (prune && score_bound(ws.accumulator.data(), out.samples_evaluated) < options.prune_below);
  };
  for (int lane = 0; lane < lanes; ++lane) fold_lane(lane);
  if (!check || !pruned()) return false;
  for (std::size_t i = 0; i < k; ++i) {
    ws.accumulator[i] = ws.saved_accumulator[i];
    ws.argument[i] = ws.saved_argument[i];
  }
  out.samples_evaluated -= lanes;
  for (int lane = 0; lane < lanes; ++lane) {
    fold_lane(lane);
    if (pruned()) return true;
  }
  assert(false && "a worst-case bound rose within a block");
  return true;
}

// The block path of an averaging study: the first `lanes` lanes are reduced in sample order
// exactly as fold_locals() reduces them one by one (sums weighted, extremes by the tie rule).
void Evaluator::fold_block_sums(const MechanismModel& model, EvalData& ws, const int* lane_sample, int lanes) const {
  block_locals(ws);
  const std::size_t k = local_reduction_.size();
  for (int lane = 0; lane < lanes; ++lane) {
    const int sample = lane_sample[lane];
    const double scale = sample_scale_.empty() ? 1.0 : sample_scale_[static_cast<std::size_t>(sample)];
    for (std::size_t i = 0; i < k; ++i) {
      const double v = ws.block_locals[i * kBlockLanes + static_cast<std::size_t>(lane)];
      if (!std::isfinite(v)) refuse_non_finite_block_local(model, ws, sample);
      if (local_reduction_[i] == Reduction::kSum) {
        ws.accumulator[i] += v * scale;
      } else if (better(local_reduction_[i], v, sample, ws.accumulator[i], ws.argument[i])) {
        ws.accumulator[i] = v;
        ws.argument[i] = sample;
      }
    }
  }
  ws.result.samples_evaluated += lanes;
}

}  // namespace hapsyn
