// The per-sample path of evaluate(), the batch path of interpreted metrics, evaluate_parallel().
#include <hapsyn/accel/mechanism_acceleration.hpp>
#include <hapsyn/accel/lanes.hpp>
#include <hapsyn/accel/metric_acceleration.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/internal/solve_recording.hpp>
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

const Evaluation& Evaluator::evaluate(const double* free_design, EvalData& ws, const EvalOptions& options) const {
  check_design(free_design);
  Evaluation& out = ws.result;
  reset_evaluation(out);

  space_.expand(free_design, ws.full.data());
  if (!constraints_hold(ws.full.data(), ws, out)) return out;

  std::unique_ptr<const MechanismModel> owned;
  const MechanismModel* model = mechanism_accel_->build_in(ws.full.data(), *ws.scratch);
  if (!model) {
    owned = mechanism_->build(ws.full.data());
    model = owned.get();
  }
  std::copy(identity_accumulator_.begin(), identity_accumulator_.end(), ws.accumulator.begin());
  std::fill(ws.argument.begin(), ws.argument.end(), -1);
  const bool prune = std::isfinite(options.prune_below) && prunable_;
  const std::vector<double>* front = options.prune_dominated_by;
  const bool prune_front = front && !front->empty() && worst_case_ && all_maximized_;
  if (batch_ > 0) return evaluate_batched(*model, ws, options, prune, prune_front);
  if (block_path_ && !options.per_sample && !options.on_sample) {
    return evaluate_blocks(*model, ws, options, prune, prune_front);
  }
  const std::vector<int>& indices = options.subset ? *options.subset : order_;
  for (const int sample : indices) {
    // Set before solve(): a mechanism may read the scene (its dimension, its attributes).
    bind_sample(ws.quantities, sample);
    model->solve(samples_->pose(sample), needs_, *ws.scratch, ws.quantities);
    ++out.samples_evaluated;
    if (ws.quantities.status != SampleStatus::kReachable && any_worst_case_) {
      out.status = EvalStatus::kSampleFailed;
      out.failed_sample = sample;
      out.failed_status = ws.quantities.status;
      return out;
    }
    accumulate_locals(sample, ws, options.on_sample != nullptr);
    if (options.on_sample) (*options.on_sample)(sample, ws.quantities, ws.nested_locals);
    if ((prune_front && front_dominates(*front, ws.accumulator.data(), ws.objective_bound.data())) ||
        (prune && score_bound(ws.accumulator.data(), out.samples_evaluated) < options.prune_below)) {
      mark_pruned(ws.argument.data(), out);
      return out;
    }
  }
  combine_objectives(ws, out);
  return out;
}

// The per-sample loop of evaluate() for studies with a batched metric (MetricAcceleration::batch_size()):
// up to batch_ samples are solved, their local values computed with one local_batch() call per
// metric, then reduced one by one exactly as the per-sample loop does (same order, same checks,
// same pruning decisions after each sample). Kept apart so that the per-sample loop is untouched.
const Evaluation& Evaluator::evaluate_batched(const MechanismModel& model, EvalData& ws, const EvalOptions& options,
                                            bool prune, bool prune_front) const {
  Evaluation& out = ws.result;
  const std::vector<int>& indices = options.subset ? *options.subset : order_;
  const std::size_t n = indices.size();
  long long folded = 0;  // samples reduced so far (the per-sample loop's samples_evaluated)
  for (std::size_t first = 0; first < n; first += static_cast<std::size_t>(batch_)) {
    const int capacity = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(batch_), n - first));
    int count = 0;
    bool failed = false;
    for (; count < capacity; ++count) {
      const int sample = indices[first + static_cast<std::size_t>(count)];
      SampleQuantities& q = ws.batch_quantities[static_cast<std::size_t>(count)];
      bind_sample(q, sample);
      model.solve(samples_->pose(sample), needs_, *ws.scratch, q);
      ++out.samples_evaluated;
      if (q.status != SampleStatus::kReachable && any_worst_case_) {
        failed = true;  // the samples before it are reduced first, as the per-sample loop would
        break;
      }
    }
    for (std::size_t m = 0; m < metrics_.size(); ++m) {
      for (int i = 0; i < count; ++i) {
        SampleQuantities& q = ws.batch_quantities[static_cast<std::size_t>(i)];
        q.attributes = metric_attributes_[m].data();
        q.attribute_count = static_cast<int>(metric_attributes_[m].size());
      }
      if (count == 0) continue;
      const std::size_t k = static_cast<std::size_t>(local_offset_[m + 1] - local_offset_[m]);
      double* locals = ws.batch_locals.data() + static_cast<std::size_t>(batch_) * local_offset_[m];
      if (metric_accel_[m]->batch_size() == 0) {  // a metric without a batch beside one with
        for (int i = 0; i < count; ++i) metrics_[m].metric->local(*ws.batch_pointers[static_cast<std::size_t>(i)], locals + i * k);
        continue;
      }
      // A batch_size() > 0 without a local_batch() override writes nothing: the NaN left here is
      // then reported as the metric's, not reduced as a stale value.
      std::fill_n(locals, static_cast<std::size_t>(count) * k, std::numeric_limits<double>::quiet_NaN());
      metric_accel_[m]->local_batch(ws.batch_pointers.data(), count, locals);
    }
    for (int i = 0; i < count; ++i) {
      const SampleQuantities& q = ws.batch_quantities[static_cast<std::size_t>(i)];
      for (std::size_t m = 0; m < metrics_.size(); ++m) {
        const int k = local_offset_[m + 1] - local_offset_[m];
        const double* block = ws.batch_locals.data() + static_cast<std::size_t>(batch_) * local_offset_[m];
        std::copy(block + i * k, block + (i + 1) * k, ws.locals.begin() + local_offset_[m]);
      }
      fold_locals(q.sample, ws, options.on_sample != nullptr, q);
      ++folded;
      if (options.on_sample) (*options.on_sample)(q.sample, q, ws.nested_locals);
      if ((prune_front && front_dominates(*options.prune_dominated_by, ws.accumulator.data(), ws.objective_bound.data())) ||
          (prune && score_bound(ws.accumulator.data(), folded) < options.prune_below)) {
        mark_pruned(ws.argument.data(), out);
        return out;
      }
    }
    if (failed) {
      const SampleQuantities& q = ws.batch_quantities[static_cast<std::size_t>(count)];
      out.status = EvalStatus::kSampleFailed;
      out.failed_sample = q.sample;
      out.failed_status = q.status;
      return out;
    }
  }
  combine_objectives(ws, out);
  return out;
}

// The live SolveRecording of this design over every sample, claimed, or null (the usual case:
// one atomic load). Only for a study without a block path: the callback adds a copy of each
// sample's locals to the same computations, so the evaluation is unchanged bit for bit. On the
// block path a callback would take the chunks to the per-sample path, whose sums of averaging
// metrics (coverage) can differ from the block path's in the last bit: the solve would change.
SolveRecording* Evaluator::claim_recording(const double* free_design, const ParallelOptions& options) const {
  if (options.subset || block_path_ || !SolveRecording::any()) return nullptr;
  Eigen::VectorXd full(static_cast<Eigen::Index>(space_.size()));
  space_.expand(free_design, full.data());
  return SolveRecording::claim(mechanism_.get(), samples_.get(), metrics_, full);
}

Evaluation Evaluator::evaluate_parallel(const double* free_design, int threads, const ParallelOptions& options) const {
  check_design(free_design);
  SolveRecording* recording = claim_recording(free_design, options);
  if (!recording) return evaluate_chunks(free_design, threads, options, nullptr);
  try {
    Evaluation e = evaluate_chunks(free_design, threads, options, &recording->callback());
    recording->finish(e.status == EvalStatus::kFeasible);
    return e;
  } catch (...) {
    recording->finish(false);
    throw;
  }
}

Evaluation Evaluator::evaluate_chunks(const double* free_design, int threads, const ParallelOptions& options,
                                      const SampleCallback* on_sample) const {
  const std::vector<int>& indices = options.subset ? *options.subset : order_;
  const long long n = static_cast<long long>(indices.size());
  const int chunk_count = static_cast<int>(std::max(1LL, std::min<long long>(options.chunks > 0 ? options.chunks : threads, n)));
  threads = std::max(1, std::min(threads, chunk_count));
  if (chunk_count == 1) {
    auto ws = make_eval_data();
    EvalOptions o;
    o.subset = options.subset;
    o.on_sample = on_sample;
    return evaluate(free_design, *ws, o);
  }
  // Each chunk is a contiguous piece of the sample order; the reductions are merged in chunk
  // order with the same tie rule (lower sample index wins) as a sequential run, so the result
  // does not depend on the thread count.
  // Chunks of the full order start on whole blocks, so that the block path reads them from its
  // block copies (order_run) instead of gathering each block.
  const auto boundary = [&](int t) -> long long {
    const long long b = n * t / chunk_count;
    return t == chunk_count ? n : (block_path_ && !options.subset ? b / kBlockLanes * kBlockLanes : b);
  };
  std::vector<std::unique_ptr<EvalData>> spaces(static_cast<std::size_t>(chunk_count));
  std::vector<std::vector<int>> chunks(static_cast<std::size_t>(chunk_count));
  for (int t = 0; t < chunk_count; ++t) {
    chunks[static_cast<std::size_t>(t)].assign(indices.begin() + boundary(t), indices.begin() + boundary(t + 1));
  }
  parallel_for_dynamic(chunk_count, threads, 1, [&](long long t, int) {
    // Made by the thread that fills it (docs/design.md section 1.5).
    spaces[static_cast<std::size_t>(t)] = make_eval_data();
    EvalOptions o;
    o.subset = &chunks[static_cast<std::size_t>(t)];
    o.on_sample = on_sample;
    evaluate(free_design, *spaces[static_cast<std::size_t>(t)], o);
  });
  Evaluation merged = spaces[0]->result;
  merged.samples_evaluated = 0;
  for (const auto& ws : spaces) merged.samples_evaluated += ws->result.samples_evaluated;
  for (const auto& ws : spaces) {
    if (ws->result.status != EvalStatus::kFeasible) {
      Evaluation failed = ws->result;  // the first chunk (in sample order) that failed
      failed.samples_evaluated = merged.samples_evaluated;
      return failed;
    }
  }
  std::vector<double> acc = identity_accumulator_;
  std::vector<int> arg(local_reduction_.size(), -1);
  for (const auto& ws : spaces) {
    for (std::size_t m = 0; m < metrics_.size(); ++m) {
      for (std::size_t j = 0; j < ws->result.reduced[m].size(); ++j) {
        const std::size_t i = static_cast<std::size_t>(local_offset_[m]) + j;
        const double v = ws->result.reduced[m][j];
        const int a = ws->result.critical_samples[m][j];
        if (local_reduction_[i] == Reduction::kSum) {
          acc[i] += v;
        } else if (better(local_reduction_[i], v, a, acc[i], arg[i])) {
          acc[i] = v;
          arg[i] = a;
        }
      }
    }
  }
  for (std::size_t m = 0; m < metrics_.size(); ++m) {
    merged.reduced[m].assign(acc.begin() + local_offset_[m], acc.begin() + local_offset_[m + 1]);
    merged.critical_samples[m].assign(arg.begin() + local_offset_[m], arg.begin() + local_offset_[m + 1]);
  }
  for (std::size_t o = 0; o < objectives_.size(); ++o) {
    const std::size_t m = static_cast<std::size_t>(objectives_[o].metric);
    merged.objectives[o] = metrics_[m].metric->combine(merged.reduced[m].data(), static_cast<int>(merged.samples_evaluated));
  }
  merged.score = score(merged.objectives);
  return merged;
}

}  // namespace hapsyn
