#pragma once
/// \file
/// Metrics: a named scalar over (mechanism, design, scene), built from per-sample local values
/// and their reductions.
///
/// A metric maps each sample's quantities to k local values; the framework reduces each local
/// value over the samples (min, max or sum) and the metric combines the reduced values into
/// its scalar. A *worst-case* metric uses only min/max reductions and a combine that is
/// non-decreasing in its min-reduced values and non-increasing in its max-reduced ones; its
/// value over any subset of samples is then an upper bound of its value over the whole scene
/// (the per-sample bound that culling uses: GII(p) <= sigma_min(J(p,a)) / sigma_max(J(p,b))).
#include <hapsyn/quantities.hpp>
#include <hapsyn/accel/sample_block.hpp>
#include <hapsyn/accel/sample_envelope.hpp>

#include <limits>
#include <string>
#include <vector>

namespace hapsyn {

enum class Reduction { kMin, kMax, kSum };

/// One local (per-sample) value of a metric.
struct LocalValue {
  std::string name;  ///< column name in per-sample CSV, e.g. "sigma_min_J"
  Reduction reduction = Reduction::kMin;
  std::string unit;
};

/// How a metric aggregates samples.
enum class Aggregation {
  kWorstCase,  ///< min/max over samples; every sample must be reachable, else infeasible
  kAveraging,  ///< sums over samples; unreachable samples are passed to local() too
};

/// Metric plugin: the one pure virtual is local(); everything else has a default.
///
/// Life cycle: created once per study (options filled from its declarations, see
/// hapsyn/options.hpp); needs(), scene_attributes(), locals() and aggregation() are read ONCE,
/// when the study is loaded, and must not change afterwards; local() then runs for every
/// (design, sample) pair, concurrently from several threads unless the class declares
/// ThreadSafety::kSerialized; combine() runs once per design evaluation, and also on PARTIAL
/// reductions (a chunk of samples, the samples seen before pruning stops, a culling subset).
///
/// What the framework checks centrally, so a metric need not: the mechanism provides every
/// Need flag in needs() (else the study is refused at load), the scene has the attributes the
/// metric lists (a missing one gives attribute_row(k) == nullptr), every local value and the
/// combined value is finite (a NaN or inf is reported as an error naming the plugin, the design
/// and the sample, never averaged away).
///
/// Worst-case monotonicity rule: when every reduction is min or max (aggregation() is
/// kWorstCase), combine() must be non-decreasing in each min-reduced value and non-increasing
/// in each max-reduced value. Culling and grid pruning rely on it to bound the full-scene value
/// from a subset of samples; a combine() that breaks it makes them return wrong optima.
class Metric {
 public:
  virtual ~Metric() = default;
  /// Computes the local values of one sample.
  /// \param q   the mechanism's quantities at the sample (only those in needs() are meaningful);
  ///            `q.sample` / `q.scene` give the sample's index and scene, `q.attribute_row(k)`
  ///            the sample's row of the k-th name in scene_attributes() (resolved once per
  ///            study: no lookup by name per sample).
  /// \param out locals().size() values, written in the order of locals(), in their units.
  /// Worst-case metrics see only reachable samples; averaging metrics see every sample and read
  /// q.status. Called concurrently (see the class comment); must not allocate, lock or throw:
  /// it runs millions of times in the per-sample loop.
  virtual void local(const SampleQuantities& q, double* out) const = 0;
  /// Quantities needed at each sample (Need flags); the mechanism computes nothing else.
  /// Default: the Jacobian.
  virtual Needs needs() const { return kNeedJacobian; }
  /// Scene attributes needed (e.g. "human_velocity_axes"); the scene builds only those some
  /// metric asks for. Default: none.
  virtual std::vector<std::string> scene_attributes() const { return {}; }
  /// Declared local values, with their reductions and units (column names of samples.csv).
  /// Default: one value "value", reduced by min.
  virtual std::vector<LocalValue> locals() const { return {LocalValue{"value", Reduction::kMin, ""}}; }
  /// Combines the reduced local values into the metric's value.
  /// \param reduced  locals().size() reduced values, in the order of locals()
  /// \param samples  how many samples the reduction covered (for averages; > 0 except on an
  ///                 empty subset)
  /// Also called on partial reductions (see the class comment): must return a finite value for
  /// any finite input, and obey the worst-case monotonicity rule. Default: reduced[0].
  virtual double combine(const double* reduced, int samples) const { return reduced[0]; }
  /// kWorstCase when every reduction is min or max (the default rule), else kAveraging.
  virtual Aggregation aggregation() const;

  /// Optional batch interface, for metrics whose per-call cost dwarfs a sample's (a metric
  /// written in an interpreted language: hapsyn's Python binding). 0 (the default): the
  /// evaluator calls local() once per sample, as always. B > 0: the evaluator solves up to B
  /// samples of a design, then calls local_batch() once for them, then reduces them one by one
  /// in the same order as the per-sample path (so the result is the same to the last bit for a
  /// metric whose local_batch agrees with its local()). Read ONCE, at load.
  virtual int batch_size() const { return 0; }
  /// The local values of `count` samples (1 <= count <= batch_size()): q[i] is sample i's
  /// quantities (as for local(), attributes resolved), out[i * locals().size() + j] its j-th
  /// local value. Same rules as local() (worst-case metrics see reachable samples only), except
  /// that it may allocate. Default: local() per sample.
  virtual void local_batch(const SampleQuantities* const* q, int count, double* out) const {
    const int k = static_cast<int>(locals().size());
    for (int i = 0; i < count; ++i) local(*q[i], out + static_cast<long>(i) * k);
  }

  /// Optional block path (hapsyn/accel/sample_block.hpp): true when local_block() computes what
  /// local() does (read once, at load). The evaluator uses it in worst-case studies and in
  /// averaging ones (not in a study that mixes both kinds). Default: false.
  virtual bool has_local_block() const { return false; }
  /// The local values of every lane of `q`: out[j * kBlockLanes + lane] is the lane's j-th local
  /// value (to rounding what local() gives: agreement to 1e-12 relative). The lanes' samples and
  /// this metric's scene attributes are in q.samples / q.attribute_row(). Lanes whose status is
  /// not kReachable hold arbitrary quantities: a worst-case metric's outputs for them are
  /// ignored; an averaging metric's are reduced, so they must be what local() gives for such a
  /// sample. No lane may trap. Same rules as local() (concurrent, no allocation, lock or throw).
  /// Default: nothing.
  virtual void local_block(const QuantityBlock& q, double* out) const {}
  /// Optional: combine() for kBlockLanes reductions at once, each lane's bit for bit what
  /// combine() gives it. `reduced` is lane-minor: reduced[j * kBlockLanes + lane] is the lane's
  /// j-th reduced value; out[lane] receives its combined value. The evaluator calls it when it
  /// bounds several designs in one vector (Problem::evaluate_designs); lanes it will ignore may
  /// hold any values, so no lane may trap. Same rules as combine() (concurrent, no allocation,
  /// lock or throw). Returns false when not implemented (the default): the evaluator then calls
  /// combine() per lane.
  virtual bool combine_block(const double* reduced, int samples, double* out) const {
    (void)reduced, (void)samples, (void)out;
    return false;
  }

  /// Optional block bound (docs/design.md section 13.5), for worst-case metrics: an upper bound
  /// of this metric's value over the whole scene, valid for every design of the envelope's block
  /// that reaches its sample (the value at that one sample bounds the whole scene's). Use only
  /// the envelope's fields; +inf when they say nothing this metric can use (the default). Must
  /// not allocate or throw.
  virtual double envelope_bound(const SampleEnvelope& envelope) const {
    (void)envelope;
    return std::numeric_limits<double>::infinity();
  }
};

}  // namespace hapsyn
