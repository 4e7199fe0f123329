#pragma once
/// \file
/// The optional speed layer of a metric (Metric::acceleration()). Nothing here is needed for a
/// correct study: every method has a default that says "not available", and the framework then
/// calls Metric::local() per sample and Metric::combine() per design. A metric that implements
/// some of them derives from this class as well as from Metric and returns `this` from
/// acceleration():
///
///     class MyMetric final : public hapsyn::Metric, public hapsyn::MetricAcceleration {
///       const hapsyn::MetricAcceleration* acceleration() const override { return this; }
///       bool has_local_block() const override { return true; }
///       void local_block(const hapsyn::QuantityBlock& q, double* out) const override { ... }
///     };
///
/// The contracts: each hook gives what the plain path gives (to the stated tolerance), and a
/// bound is proved, rounding included. Block kernels use the vector types of
/// hapsyn/accel/lanes.hpp.
#include <hapsyn/accel/sample_block.hpp>
#include <hapsyn/accel/sample_envelope.hpp>
#include <hapsyn/metric.hpp>

#include <limits>

namespace hapsyn {

/// Speed hooks of a metric; see the file comment. Every method is optional.
class MetricAcceleration {
 public:
  virtual ~MetricAcceleration() = default;

  /// Batch interface, for metrics whose per-call cost dwarfs a sample's (a metric
  /// written in an interpreted language: hapsyn's Python binding). 0 (the default): the
  /// evaluator calls local() once per sample, as always. B > 0: the evaluator solves up to B
  /// samples of a design, then calls local_batch() once for them, then reduces them one by one
  /// in the same order as the per-sample path (so the result is the same to the last bit for a
  /// metric whose local_batch agrees with its local()). Read ONCE, at load.
  virtual int batch_size() const { return 0; }
  /// The local values of `count` samples (1 <= count <= batch_size()): q[i] is sample i's
  /// quantities (as for local(), attributes resolved), out[i * locals().size() + j] its j-th
  /// local value. Same rules as local() (worst-case metrics see reachable samples only), except
  /// that it may allocate. Must be overridden with batch_size() > 0: the default writes nothing, and
  /// the evaluator then reports the values it finds (NaN) as the metric's error.
  virtual void local_batch(const SampleQuantities* const* q, int count, double* out) const {
    (void)q, (void)count, (void)out;
  }

  /// Block path (hapsyn/accel/sample_block.hpp): true when local_block() computes what
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
  /// combine() for kBlockLanes reductions at once, each lane's bit for bit what
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

  /// Block bound (docs/design.md section 13.5), for worst-case metrics: an upper bound
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
