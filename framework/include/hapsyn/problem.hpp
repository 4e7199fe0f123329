#pragma once
/// \file
/// The evaluation interface every solver sees: bounds, integer components, grid steps,
/// constraints, objectives, and design evaluation (full or on a subset of samples).
///
/// This is also where the framework checks plugin input and output once, centrally: a solver
/// passing a design component that is NaN/inf or outside the bounds, a mechanism returning a
/// NaN/inf constraint, and a metric returning a NaN/inf local or combined value raise
/// hapsyn::Error naming the plugin, the design and the sample. A free design is passed as a raw
/// pointer to dimension() values: its size cannot be checked here and is the caller's contract.
#include <hapsyn/design_space.hpp>
#include <hapsyn/mechanism.hpp>
#include <hapsyn/metric.hpp>
#include <hapsyn/scene.hpp>

#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace hapsyn {

class MechanismAcceleration;  // hapsyn/accel/mechanism_acceleration.hpp
class MetricAcceleration;     // hapsyn/accel/metric_acceleration.hpp
class Evaluator;              // the framework's private implementation of Problem
struct EvalData;              // an EvalScratch's contents (private)

enum class Sense { kMaximize, kMinimize };

/// One objective of the study: a metric with a sense and, for weighted sums, a weight.
struct Objective {
  std::string name;      ///< label (defaults to the metric's plugin name)
  int metric = 0;        ///< index into Problem::metrics()
  Sense sense = Sense::kMaximize;
  double weight = 1.0;   ///< weight in the scalar score (weighted-sum studies)
};

/// A metric instance in the problem, with its plugin name.
struct MetricEntry {
  std::string plugin;
  std::shared_ptr<const Metric> metric;
};

enum class EvalStatus {
  kFeasible,            ///< every objective computed
  kConstraintViolated,  ///< a design constraint g(p) <= 0 failed; no sample evaluated
  kSampleFailed,        ///< a worst-case metric met an unreachable/singular/invalid sample
  kPruned,              ///< stopped early: the score's upper bound fell below EvalOptions::prune_below
};
const char* to_string(EvalStatus status);

/// Result of one design evaluation.
struct Evaluation {
  EvalStatus status = EvalStatus::kFeasible;
  std::vector<double> objectives;  ///< per objective, natural value (valid when feasible; an
                                   ///< upper bound for worst-case metrics on a sample subset)
  double score = -std::numeric_limits<double>::infinity();  ///< sum_i w_i * s_i * f_i, s = +1
                                   ///< maximize, -1 minimize; -inf when not feasible
  int failed_constraint = -1;      ///< index, for kConstraintViolated
  int failed_sample = -1;          ///< sample index, for kSampleFailed
  SampleStatus failed_status = SampleStatus::kReachable;
  long long samples_evaluated = 0; ///< mechanism solves performed
  /// For worst-case metrics: per metric, per local value, the sample attaining the reduction
  /// (the critical samples culling collects), also when kPruned (over the samples seen).
  /// -1 for sum reductions.
  std::vector<std::vector<int>> critical_samples;
  /// Per metric, the reduced local values (same order as Metric::locals()).
  std::vector<std::vector<double>> reduced;
};

/// Called for every evaluated sample when a per-sample record is wanted.
/// Arguments: sample index, the mechanism's quantities, per metric the local values.
using SampleCallback =
    std::function<void(int sample, const SampleQuantities& q, const std::vector<std::vector<double>>& locals)>;

struct EvalOptions {
  /// Null: every sample, in sample_order(). Otherwise exactly these samples (indices into
  /// samples()), in this order; an empty list evaluates no sample (the reductions keep their
  /// identity values and combine() sees samples = 0).
  const std::vector<int>* subset = nullptr;
  /// Worst-case studies only: stop with kPruned as soon as the score's upper bound (computed
  /// from the samples seen so far) is strictly below this value. Exact: a design whose score
  /// is >= prune_below is never pruned.
  double prune_below = -std::numeric_limits<double>::infinity();
  /// Called per evaluated sample (sequential evaluation only; takes the per-sample path).
  const SampleCallback* on_sample = nullptr;
  /// Take the per-sample path even when the study has a block path (Problem::block_path());
  /// tests and benchmarks compare the two.
  bool per_sample = false;
  /// Pareto pruning, worst-case studies with every objective maximized: stop with kPruned as
  /// soon as the objectives' upper bounds (from the samples seen so far) are dominated by one of
  /// these points. Flat, objectives().size() natural values per point; the points must be
  /// mutually non-dominated and sorted by the first objective, descending. Exact: a design that
  /// is not dominated by any of the points is never pruned.
  const std::vector<double>* prune_dominated_by = nullptr;
  /// evaluate_designs only: the caller vouches that every design's constraints hold, so they
  /// are not evaluated again. A grid solver sets it for the designs inside a line's feasible
  /// run when its ends were checked and the mechanism promises MechanismAcceleration::constraints_quasiconvex
  /// along the line (plugins/solvers/shared/bounds/line_bound.hpp). Builds with assertions check anyway.
  bool constraints_verified = false;
};

/// The study's problem. Immutable and shared by threads; per-thread state is an EvalScratch. Its
/// evaluation paths (per sample, batches, sample blocks, design lanes) are the framework's
/// private implementation.
class Problem {
 public:
  /// \throws Error if the scene has no samples, a non-finite one or unusable weights
  ///         (check_weights), a metric needs quantities the mechanism does not provide, the
  ///         scene is not one the mechanism serves, or an objective refers to a missing metric.
  /// With SampleSet::weights, every Reduction::kSum local value of sample i is multiplied by
  /// w_i N / W before it is summed, so averaging metrics give weighted means with no change to
  /// their combine(); min/max reductions ignore the weights (a worst case is a worst case).
  Problem(std::string mechanism_plugin, std::shared_ptr<const Mechanism> mechanism,
          std::shared_ptr<const SampleSet> samples, std::vector<MetricEntry> metrics,
          std::vector<Objective> objectives, DesignSpace space);
  /// Not copyable: the evaluator's block copies of the scene attributes are referred to by
  /// pointer (with_objectives() and with_design_space() make a new problem instead).
  Problem(const Problem&) = delete;
  Problem& operator=(const Problem&) = delete;
  ~Problem();

  /// The same study (mechanism, scene, metrics: shared, not copied) with other objectives,
  /// e.g. other weights for a weighted sum or one objective for a shadow optimum. Cheap: no
  /// plugin is created and no sample rebuilt.
  /// \throws Error as the constructor (an objective naming no metric, a non-finite weight).
  std::shared_ptr<const Problem> with_objectives(std::vector<Objective> objectives) const;
  /// The same study over another design space (same components, other bounds/steps/fixed
  /// values, e.g. one variable fixed for sequential optimization).
  /// \throws Error when `space` does not have the same components as design_space().
  std::shared_ptr<const Problem> with_design_space(DesignSpace space) const;

  const DesignSpace& design_space() const { return *view_.space; }
  const SampleSet& samples() const { return *view_.samples; }
  const Mechanism& mechanism() const { return *view_.mechanism; }
  const std::vector<MetricEntry>& metrics() const { return *view_.metrics; }
  const std::vector<Objective>& objectives() const { return *view_.objectives; }
  std::size_t dimension() const { return view_.dimension; }
  std::size_t constraint_count() const { return view_.constraint_names->size(); }
  const std::vector<std::string>& constraint_names() const { return *view_.constraint_names; }
  /// True when every metric in the study is worst-case (culling and pruning apply).
  bool worst_case() const { return view_.worst_case; }
  /// Block bound of a run of a grid line (docs/design.md section 13.5): an upper bound of the
  /// score of every design equal to `full_design` (a full design vector) except in component
  /// `component`, which runs over [lower, upper], from the mechanism's envelope of sample
  /// `sample` (MechanismAcceleration::sample_envelope) and each objective's
  /// MetricAcceleration::envelope_bound. -inf
  /// when the sample fails for every such design (all are infeasible); +inf when nothing is
  /// known (a study that is not prunable, a mechanism or a metric without envelopes). No
  /// allocation.
  double block_score_bound(const double* full_design, int component, double lower, double upper, int sample) const;
  /// Line bound of one sample (docs/design.md section 13.6): sets [lower, upper] to the interval
  /// of component `component` of `full_design` outside which sample `sample` fails
  /// (MechanismAcceleration::reachable_interval), and returns true, when a failed sample makes a design
  /// infeasible in this study (a worst-case metric) and the mechanism knows such an interval.
  /// No allocation.
  bool reachable_interval(const double* full_design, int component, int sample, double& lower, double& upper) const;
  /// The mechanism's speed layer (Mechanism::acceleration()), or a stand-in whose every hook
  /// says "not available" when it has none: never null.
  const MechanismAcceleration& mechanism_acceleration() const { return *view_.mechanism_acceleration; }
  /// True when evaluate() solves samples in blocks (hapsyn/accel/sample_block.hpp): the mechanism
  /// solves blocks for the study's needs, every metric is worst-case with a block local and no
  /// scene attributes, and the scene has at most kBlockMaxCoordinates coordinates and no
  /// demanded motion. Same results as the per-sample path (docs/design.md section 13).
  bool block_path() const { return view_.block_path; }
  /// Union of the metrics' needs: what the mechanism computes per sample, and nothing else.
  Needs needs() const { return view_.needs; }
  /// Sample order used for full evaluations. With a worst-case metric: the scene's extreme
  /// samples first (far from the centroid), so infeasible designs and worst cases are met early;
  /// otherwise the scene's own order (cache-friendly; nothing to decide early). Deterministic.
  const std::vector<int>& sample_order() const { return *view_.sample_order; }
  /// Prepares `q` for MechanismModel::solve of sample `sample`: sets q.sample, q.scene and, when
  /// the scene carries the demanded motion, q.twist / q.twist_rate (else null). The evaluator
  /// calls it before every solve(); a tool that calls solve() itself should too.
  void bind_sample(SampleQuantities& q, int sample) const;

  /// Per-thread evaluation state (mechanism scratch, accumulators, the evaluator's working
  /// memory). Not shareable: one per thread. Its contents are the evaluator's business.
  class EvalScratch {
   public:
    EvalScratch();
    EvalScratch(const EvalScratch&) = delete;
    EvalScratch& operator=(const EvalScratch&) = delete;
    ~EvalScratch();
    /// The evaluation evaluate() returned last with this scratch.
    const Evaluation& last() const;

   private:
    friend class Problem;
    std::unique_ptr<EvalData> data_;
  };
  std::unique_ptr<EvalScratch> make_eval_scratch() const;

  /// Evaluates a design given as the free vector (dimension() values; not checkable through
  /// the pointer). One EvalScratch per thread: a scratch is never used by two threads at once.
  /// \throws Error on a NaN/inf or out-of-bounds component, or a NaN/inf from a plugin.
  const Evaluation& evaluate(const double* free_design, EvalScratch& eval_scratch,
                             const EvalOptions& options = {}) const;
  /// Evaluates `count` designs (1..kBlockLanes free vectors) as `count` calls of evaluate() with
  /// the same options would, into outs[0..count): the same statuses, sample counts, critical
  /// samples and objectives, bit for bit. `outs` is the caller's and is reused (no allocation
  /// once its evaluations have their sizes). Where the mechanism solves several designs per
  /// vector (MechanismAcceleration::solve_designs: the five-bar's designs of one grid line), the first
  /// samples of all the designs are solved together, one vector per sample, and most designs
  /// are decided there (unreachable, pruned, or culled at a critical sample); a design still
  /// undecided after kBlockLanes samples is finished by evaluate() (docs/design.md section 13.4).
  /// \throws Error as evaluate().
  void evaluate_designs(const double* const* free_designs, int count, EvalScratch& eval_scratch,
                        const EvalOptions& options, std::vector<Evaluation>& outs) const;

  /// How evaluate_parallel splits the work.
  struct ParallelOptions {
    /// Contiguous pieces of the sample order, evaluated on the threads and merged in order;
    /// 0 = one per thread. A fixed count (> 0) makes the result independent of the thread
    /// count bit for bit, also for averaging (sum-reduced) metrics.
    int chunks = 0;
    /// Evaluate only these samples (indices into samples(), in this order); null = all.
    const std::vector<int>* subset = nullptr;
  };
  /// Same, over all samples (or `options.subset`) split into chunks across `threads` threads
  /// (deterministic merge: the result does not depend on the thread count for a given chunk
  /// count; worst-case reductions not at all).
  Evaluation evaluate_parallel(const double* free_design, int threads, const ParallelOptions& options) const;
  Evaluation evaluate_parallel(const double* free_design, int threads) const {
    return evaluate_parallel(free_design, threads, ParallelOptions{});
  }
  /// Evaluates the design constraints into g (size constraint_count()); true when all <= 0.
  bool constraints(const double* free_design, double* g) const;

  /// Full design (all components) from a free vector.
  Eigen::VectorXd full_design(const double* free_design) const;
  /// {"l0": 0.1, "l": [..], ...} from a full design vector, grouped by variable.
  Json design_to_json(const Eigen::VectorXd& full_design) const;
  /// Score of objective values: sum_i w_i * s_i * f_i.
  double score(const std::vector<double>& objectives) const;

 private:
  // What the accessors above return, taken from the evaluator once: they are called per design
  // (and per line by the grid solvers), where a call into the evaluator cost a few percent of a
  // pruned grid on one thread.
  struct View {
    const DesignSpace* space = nullptr;
    const SampleSet* samples = nullptr;
    const Mechanism* mechanism = nullptr;
    const std::vector<MetricEntry>* metrics = nullptr;
    const std::vector<Objective>* objectives = nullptr;
    const std::vector<std::string>* constraint_names = nullptr;
    const std::vector<int>* sample_order = nullptr;
    const MechanismAcceleration* mechanism_acceleration = nullptr;
    std::size_t dimension = 0;
    bool worst_case = false, block_path = false;
    Needs needs = 0;
  };
  std::unique_ptr<const Evaluator> impl_;
  View view_;
};

}  // namespace hapsyn
