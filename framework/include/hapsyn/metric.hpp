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

/// Metric plugin. local() is called concurrently from several threads.
class Metric {
 public:
  virtual ~Metric() = default;
  /// Computes the local values of one sample into out[0 .. locals().size()).
  /// For worst-case metrics only reachable samples are passed. `q.sample` and `q.scene` give
  /// the sample's index and scene; `q.attribute_row(k)` is the sample's row of the k-th name in
  /// scene_attributes(), resolved once per study by the evaluator (no lookup by name per sample).
  virtual void local(const SampleQuantities& q, double* out) const = 0;
  /// Quantities needed at each sample (Need flags). Default: the Jacobian.
  virtual Needs needs() const { return kNeedJacobian; }
  /// Scene attributes needed (e.g. "human_velocity_axes"). Default: none.
  virtual std::vector<std::string> scene_attributes() const { return {}; }
  /// Declared local values. Default: one value named after nothing, reduced by min.
  virtual std::vector<LocalValue> locals() const { return {LocalValue{"value", Reduction::kMin, ""}}; }
  /// Combines the reduced local values (same order as locals()) into the metric's value.
  /// \param reduced  one reduced value per local
  /// \param samples  number of samples in the reduction (for averages)
  virtual double combine(const double* reduced, int samples) const { return reduced[0]; }
  /// Worst-case when every reduction is min or max (the default rule); see the file comment.
  virtual Aggregation aggregation() const;
};

}  // namespace hapsyn
