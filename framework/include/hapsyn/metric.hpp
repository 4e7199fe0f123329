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

#include <string>
#include <vector>

namespace hapsyn {

class MetricAcceleration;  // hapsyn/accel/metric_acceleration.hpp

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

/// What a metric needs from the mechanism and the scene: read once, at load (Metric::specs()).
struct MetricSpecs {
  /// Quantities needed at each sample (Need flags); the mechanism computes nothing else.
  /// Default: the Jacobian.
  Needs needs = kNeedJacobian;
  /// Scene attributes needed (e.g. "human_velocity_axes"); the scene builds only those some
  /// metric asks for. Default: none.
  std::vector<std::string> scene_attributes;
};

/// Metric plugin: the one pure virtual is local(); everything else has a default.
///
/// Life cycle: created once per study (options filled from its declarations, see
/// hapsyn/options.hpp); specs(), locals() and aggregation() are read ONCE,
/// when the study is loaded, and must not change afterwards; local() then runs for every
/// (design, sample) pair, concurrently from several threads unless the class declares
/// ThreadSafety::kSerialized; combine() runs once per design evaluation, and also on PARTIAL
/// reductions (a chunk of samples, the samples seen before pruning stops, a culling subset).
///
/// What the framework checks centrally, so a metric need not: the mechanism provides every
/// Need flag in specs().needs (else the study is refused at load), the scene has the attributes the
/// metric lists (a missing one gives attribute_row(k) == nullptr), every local value and the
/// combined value is finite (a NaN or inf is reported as an error naming the plugin, the design
/// and the sample, never averaged away).
///
/// Worst-case monotonicity rule: when every reduction is min or max (aggregation() is
/// kWorstCase), combine() must be non-decreasing in each min-reduced value and non-increasing
/// in each max-reduced value. Culling and grid pruning rely on it to bound the full-scene value
/// from a subset of samples; a combine() that breaks it makes them return wrong optima.
///
/// Speed: a metric with a block kernel, a vectorised combine, a bound over a block of designs or
/// a batch interface (an interpreted metric) says so through acceleration()
/// (hapsyn/accel/metric_acceleration.hpp); nothing else in this class is about speed.
class Metric {
 public:
  Metric() = default;
  Metric(const Metric&) = delete;
  Metric& operator=(const Metric&) = delete;
  virtual ~Metric() = default;
  /// Computes the local values of one sample.
  /// \param q   the mechanism's quantities at the sample (only those in specs().needs are meaningful);
  ///            `q.sample` / `q.scene` give the sample's index and scene, `q.attribute_row(k)`
  ///            the sample's row of the k-th name in specs().scene_attributes (resolved once per
  ///            study: no lookup by name per sample).
  /// \param out locals().size() values, written in the order of locals(), in their units.
  /// Worst-case metrics see only reachable samples; averaging metrics see every sample and read
  /// q.status. Called concurrently (see the class comment); must not allocate, lock or throw:
  /// it runs millions of times in the per-sample loop.
  virtual void local(const SampleQuantities& q, double* out) const = 0;
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

  /// What the metric needs (read once, at load).
  virtual MetricSpecs specs() const { return {}; }
  /// The optional speed layer (block kernel, vectorised combine, envelope bound, batch), or
  /// null (the default): the framework then calls local() per sample and combine() per design.
  /// Read once, at load; the object must live as long as the metric (usually `this`: the
  /// metric derives from MetricAcceleration too).
  virtual const MetricAcceleration* acceleration() const { return nullptr; }
};

}  // namespace hapsyn
