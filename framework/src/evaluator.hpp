#pragma once
// The evaluator behind hapsyn::Problem (private to the framework): see Evaluator.
#include <hapsyn/accel/sample_block.hpp>
#include <hapsyn/problem.hpp>

#include <memory>
#include <string>
#include <vector>

namespace hapsyn {

/// Per-thread evaluation state (mechanism scratch, accumulators): what Problem::EvalScratch
/// holds. Not shareable. Cache-line aligned: two threads' scratches, written
/// per design, never share a line (false sharing made a 2-thread grid slower than 1 thread).
struct alignas(64) EvalData {
  std::unique_ptr<MechanismScratch> scratch;
  SampleQuantities quantities;
  Eigen::VectorXd full;
  std::vector<double> locals;       // flat local values of the current sample
  std::vector<double> accumulator;  // flat reduced values
  std::vector<int> argument;        // flat sample index attaining each reduction
  std::vector<double> g;
  std::vector<std::vector<double>> nested_locals;  // for SampleCallback
  std::vector<double> objective_bound;             // per objective, for Pareto pruning
  // Batched evaluation (a metric with MetricAcceleration::batch_size() > 0), empty otherwise: the
  // quantities of up to batch samples, pointers to them, and their flat local values.
  std::vector<SampleQuantities> batch_quantities;
  std::vector<const SampleQuantities*> batch_pointers;
  std::vector<double> batch_locals;
  // Block path (Problem::block_path()), null otherwise: the block's quantities, its local
  // values (local j of lane i at [j * kBlockLanes + i]), gathered poses of a subset, and the
  // reductions before the block (restored when pruning replays the block lane by lane).
  std::unique_ptr<QuantityBlock> block;
  std::vector<double> block_locals;
  std::vector<double> gathered;
  // The current block's first position in order_ (its attributes in attribute_blocks_), or
  // SIZE_MAX for a block of a subset; the pointers QuantityBlock::attribute_lane_data shows.
  std::size_t block_first = SIZE_MAX;
  std::vector<const double*> attribute_lane_pointers;
  std::vector<double> saved_accumulator;
  std::vector<int> saved_argument;
  // Design lanes (evaluate_designs): each lane's full design and reductions.
  std::vector<double> lane_full;      // lane i's full design at [i * design size]
  std::vector<double> lane_accumulator;  // lane-minor: local j of lane i at [j * kBlockLanes + i]
  std::vector<int> lane_argument;
  Evaluation result;
};

/// The evaluation machinery behind Problem (its private implementation): the per-sample path, the
/// batch path of interpreted metrics, the block path and design lanes, with their per-thread data
/// (EvalData). Problem forwards its public API here; nothing outside the framework sees it.
class SolveRecording;  // hapsyn/internal/solve_recording.hpp

class Evaluator {
 public:
  // The public methods are Problem's (hapsyn/problem.hpp carries their contracts); those taking
  // an EvalData take what Problem::EvalScratch holds.
  Evaluator(std::string mechanism_plugin, std::shared_ptr<const Mechanism> mechanism,
            std::shared_ptr<const SampleSet> samples, std::vector<MetricEntry> metrics,
            std::vector<Objective> objectives, DesignSpace space);
  // Not copyable: the block copies of the scene attributes are referred to by pointer.
  Evaluator(const Evaluator&) = delete;
  Evaluator& operator=(const Evaluator&) = delete;

  std::shared_ptr<const Problem> with_objectives(std::vector<Objective> objectives) const;
  std::shared_ptr<const Problem> with_design_space(DesignSpace space) const;

  const DesignSpace& design_space() const { return space_; }
  const SampleSet& samples() const { return *samples_; }
  const Mechanism& mechanism() const { return *mechanism_; }
  const std::vector<MetricEntry>& metrics() const { return metrics_; }
  const std::vector<Objective>& objectives() const { return objectives_; }
  std::size_t dimension() const { return space_.free_size(); }
  std::size_t constraint_count() const { return constraint_names_.size(); }
  const std::vector<std::string>& constraint_names() const { return constraint_names_; }
  bool worst_case() const { return worst_case_; }
  double block_score_bound(const double* full_design, int component, double lower, double upper, int sample) const;
  bool reachable_interval(const double* full_design, int component, int sample, double& lower, double& upper) const;
  const MechanismAcceleration& mechanism_acceleration() const { return *mechanism_accel_; }
  bool block_path() const { return block_path_; }
  Needs needs() const { return needs_; }
  const std::vector<int>& sample_order() const { return order_; }
  void bind_sample(SampleQuantities& q, int sample) const {
    q.sample = sample;
    q.scene = samples_.get();
    q.twist = twist_ ? twist_->row(sample).data() : nullptr;
    q.twist_rate = twist_rate_ ? twist_rate_->row(sample).data() : nullptr;
  }

  std::unique_ptr<EvalData> make_eval_data() const;

  const Evaluation& evaluate(const double* free_design, EvalData& eval_scratch,
                             const EvalOptions& options = {}) const;
  void evaluate_designs(const double* const* free_designs, int count, EvalData& eval_scratch,
                        const EvalOptions& options, std::vector<Evaluation>& outs) const;

  using ParallelOptions = Problem::ParallelOptions;
  Evaluation evaluate_parallel(const double* free_design, int threads, const ParallelOptions& options) const;
  Evaluation evaluate_parallel(const double* free_design, int threads) const {
    return evaluate_parallel(free_design, threads, ParallelOptions{});
  }
  bool constraints(const double* free_design, double* g) const;

  Eigen::VectorXd full_design(const double* free_design) const;
  Json design_to_json(const Eigen::VectorXd& full_design) const;
  double score(const std::vector<double>& objectives) const;

 private:
  void check_design(const double* free_design) const;
  // evaluate_parallel's two steps: the recording of the solve, if one waits for this design
  // (hapsyn/internal/solve_recording.hpp), and the chunks, each through `on_sample` when not null.
  SolveRecording* claim_recording(const double* free_design, const ParallelOptions& options) const;
  Evaluation evaluate_chunks(const double* free_design, int threads, const ParallelOptions& options,
                             const SampleCallback* on_sample) const;
  // The steps of evaluate().
  bool constraints_hold(const double* full, EvalData& ws, Evaluation& out) const;
  void accumulate_locals(int sample, EvalData& ws, bool keep_locals) const;
  // `q`: the sample's quantities, blamed instead of the metric when a local value is not finite.
  void fold_locals(int sample, EvalData& ws, bool keep_locals, const SampleQuantities& q) const;
  [[noreturn]] void refuse_non_finite_local(std::size_t metric, int local, int sample, const EvalData& ws,
                                            const SampleQuantities& q) const;
  const Evaluation& evaluate_batched(const MechanismModel& model, EvalData& ws, const EvalOptions& options,
                                     bool prune, bool prune_front) const;
  const Evaluation& evaluate_blocks(const MechanismModel& model, EvalData& ws, const EvalOptions& options,
                                    bool prune, bool prune_front) const;
  bool block_moves(std::size_t i, const double* v, double current, int lanes) const;
  bool fold_block(const MechanismModel& model, EvalData& ws, const EvalOptions& options, const int* lane_sample,
                  int lanes, bool prune, bool prune_front) const;
  void fold_block_sums(const MechanismModel& model, EvalData& ws, const int* lane_sample, int lanes) const;
  void block_locals(EvalData& ws) const;
  [[noreturn]] void refuse_non_finite_block_local(const MechanismModel& model, EvalData& ws, int sample) const;
  void choose_block_path();
  void copy_attribute_blocks();
  std::size_t order_run(const std::vector<int>& subset) const;
  const double* attribute_block_start(std::size_t i) const;
  void order_extremes_first();
  void size_evaluations(std::vector<Evaluation>& outs, int count) const;
  int start_lanes(const double* const* free_designs, int count, bool constraints_verified, EvalData& ws,
                  std::vector<Evaluation>& outs, bool* active, const double** lane_design) const;
  int fold_lanes(int sample, int count, EvalData& ws, const EvalOptions& options, bool prune, bool prune_front,
                 std::vector<Evaluation>& outs, bool* active, int& left) const;
  double score_bound(const double* accumulator, long long samples) const;
  bool score_bound_lanes(const double* lane_accumulator, int samples, double* bound) const;
  void mark_pruned(const int* argument, Evaluation& out) const;
  void combine_objectives(const EvalData& ws, Evaluation& out) const;
  bool front_dominates(const std::vector<double>& front, const double* accumulator, double* bound) const;

  void resolve_demanded_motion();

  std::string mechanism_plugin_;
  std::shared_ptr<const Mechanism> mechanism_;
  const MechanismAcceleration* mechanism_accel_ = nullptr;  // never null once constructed
  std::shared_ptr<const SampleSet> samples_;
  std::vector<MetricEntry> metrics_;
  std::vector<const MetricAcceleration*> metric_accel_;  // per metric, never null
  std::vector<Objective> objectives_;
  DesignSpace space_;
  std::vector<std::string> constraint_names_;
  std::vector<int> order_;
  std::vector<double> free_lower_, free_upper_;  // bounds widened by a rounding tolerance
  std::vector<std::vector<const AttributeMatrix*>> metric_attributes_;  // per metric, see SampleQuantities::attributes
  std::vector<int> local_offset_;        // first local of metric m in the flat local array
  std::vector<Reduction> local_reduction_;
  std::vector<double> identity_accumulator_;  // per local: +inf (min), -inf (max), 0 (sum)
  // Per sample, w_i N / W: the factor of its sum-reduced local values (SampleSet::weights);
  // empty when the scene has no weights or equal ones.
  std::vector<double> sample_scale_;
  bool worst_case_ = true;
  bool any_worst_case_ = false;
  Needs needs_ = 0;
  const AttributeMatrix* twist_ = nullptr;       // the scene's kTwistAttribute, when it has one
  const AttributeMatrix* twist_rate_ = nullptr;  // the scene's kTwistRateAttribute
  bool prunable_ = false;        // worst-case, every objective maximized with weight >= 0
  bool all_maximized_ = false;   // every objective maximized
  bool block_path_ = false;
  std::size_t block_stride_ = 0;         // order_ padded to whole blocks
  std::vector<double> block_poses_;       // coordinate c of order_[k] at [c * block_stride_ + k]
  // The metrics' scene attributes in order_ by blocks, structure of arrays (one copy per
  // attribute, however many metrics list it): entry e of order_[b * kBlockLanes + i] at
  // [(b * cols + e) * kBlockLanes + i] from a 64-byte aligned start. Per metric and attribute,
  // that start (block 0) or null. See QuantityBlock::attribute_lanes.
  std::vector<std::vector<double>> attribute_blocks_;
  std::vector<int> order_position_;  // sample -> its position in order_ (block path only)
  std::vector<std::vector<const double*>> metric_attribute_blocks_;
  int batch_ = 0;  // largest MetricAcceleration::batch_size(); 0 = the per-sample path only
};

}  // namespace hapsyn
