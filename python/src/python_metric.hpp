#pragma once
/// \file
/// A hapsyn::Metric whose local values and combination are computed by a Python object (see
/// hapsyn.register_metric in python/hapsyn/__init__.py for the Python side's contract).
///
/// The C++ metric interface is per sample; a Python call per sample would cost microseconds
/// each. The adapter therefore declares a batch (MetricAcceleration::batch_size()): the evaluator solves up to that
/// many samples of a design and hands them over at once, and the adapter calls the object's
/// local_batch(quantities) ONCE per chunk with the chunk's quantities as NumPy arrays. Every
/// Python call is made with the GIL held (taken here, from whichever thread evaluates); the
/// study declares the metric ThreadSafety::kSerialized, so the framework never overlaps its calls.
#include <hapsyn/accel/metric_acceleration.hpp>
#include <hapsyn/metric.hpp>

#include <pybind11/pybind11.h>

#include <string>
#include <vector>

namespace hapsyn::python {

class PythonMetric final : public Metric, public MetricAcceleration {
 public:
  /// Reads the object's declarations (GIL held by the caller): `locals` (list of (name,
  /// reduction, unit)), `needs` (names), optional `scene_attributes`, optional `batch_size`
  /// (default 4096), optional `combine`.
  /// \param name the metric's name in the study (for messages)
  /// \param study identifies the study that owns the metric (see inside_callback_of)
  /// \throws Error("<json_path>: ...") for a missing or malformed declaration (a declaration of
  ///         the wrong type is named with its value, never a bare pybind11 cast error).
  PythonMetric(pybind11::object object, std::string name, const std::string& json_path, const void* study);
  ~PythonMetric() override;

  void local(const SampleQuantities& q, double* out) const override;
  void local_batch(const SampleQuantities* const* q, int count, double* out) const override;
  MetricSpecs specs() const override { return {needs_, attributes_}; }
  const MetricAcceleration* acceleration() const override { return this; }
  std::vector<LocalValue> locals() const override { return locals_; }
  double combine(const double* reduced, int samples) const override;
  int batch_size() const override { return batch_; }

 private:
  pybind11::object object_;
  pybind11::object local_batch_, combine_;  // bound methods (combine_ may be None)
  std::string name_;
  const void* study_;
  std::vector<LocalValue> locals_;
  std::vector<std::string> attributes_;
  Needs needs_ = 0;
  int batch_ = 4096;
};

/// True while the calling thread runs a Python callback of a metric owned by `study` (at any
/// depth of nested calls). A callback that evaluates its own study again would wait forever for
/// the evaluation it is part of; the study's entry points refuse it with this.
bool inside_callback_of(const void* study);

/// The Need flag of a quantity name ("jacobian", "inertia", "effective_mass", "gravity",
/// "max_velocity", "max_torque", "joint_velocity", "joint_acceleration", "velocity_torque";
/// "max_velocity" and "max_torque" both mean kNeedActuatorLimits).
/// \throws Error("<component>: <json_path> = \"x\": unknown quantity (known: ...)").
Needs need_of(const std::string& quantity, const std::string& component, const std::string& json_path);

/// The quantities of `count` samples as a dict of NumPy arrays (GIL held): "sample" (int64),
/// "status" (int8, 0 reachable, 1 unreachable, 2 singular, 3 invalid), "pose" (count x
/// dimension), "q" (joint angles), each quantity in `needs` (count x rows [x cols]; NaN where
/// a sample is not reachable), and "attributes": {name: count x columns} for `attributes`.
pybind11::dict quantities_dict(const SampleQuantities* const* q, int count, Needs needs,
                               const std::vector<std::string>& attributes);

}  // namespace hapsyn::python
