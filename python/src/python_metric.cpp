#include "python_metric.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/json.hpp>
#include <hapsyn/scene.hpp>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace py = pybind11;

namespace hapsyn::python {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The studies whose metrics' callbacks the calling thread is inside, innermost last.
thread_local std::vector<const void*> t_callback_studies;

// Marks the calling thread as inside a callback of `study`'s metric while it lives.
class CallbackScope {
 public:
  explicit CallbackScope(const void* study) { t_callback_studies.push_back(study); }
  ~CallbackScope() { t_callback_studies.pop_back(); }
  CallbackScope(const CallbackScope&) = delete;
  CallbackScope& operator=(const CallbackScope&) = delete;
};

// A Python value as a message shows it: its repr (at most 80 characters) and its type.
std::string shown(py::handle value) {
  std::string r = py::cast<std::string>(py::repr(value));
  if (r.size() > 80) r = r.substr(0, 77) + "...";
  return r + " (" + py::cast<std::string>(py::type::handle_of(value).attr("__name__")) + ")";
}

// py::cast<T>, with a pybind11 cast error ("Unable to cast Python instance ...") turned into
// ours, naming what was read and what it must be.
template <class T>
T cast_as(py::handle value, const std::string& component, const std::string& what, const char* rule) {
  try {
    return py::cast<T>(value);
  } catch (const py::cast_error&) {
    throw Error(component, what + " = " + shown(value) + ": must be " + rule);
  }
}

// The items of an iterable declaration, or our error naming it.
py::iterator items_of(const py::object& value, const std::string& component, const std::string& what, const char* rule) {
  if (!py::isinstance<py::iterable>(value) || py::isinstance<py::str>(value)) {
    throw Error(component, what + " = " + shown(value) + ": must be " + rule);
  }
  return py::iter(value);
}

struct QuantityName {
  const char* name;
  Needs need;
};
constexpr QuantityName kQuantities[] = {
    {"jacobian", kNeedJacobian}, {"inertia", kNeedInertia},           {"effective_mass", kNeedEffectiveMass},
    {"gravity", kNeedGravity},   {"max_velocity", kNeedActuatorLimits}, {"max_torque", kNeedActuatorLimits},
    {"joint_velocity", kNeedJointVelocity}, {"joint_acceleration", kNeedJointAcceleration},
    {"velocity_torque", kNeedVelocityTorque},
};

// count x rows x cols (or count x rows for vectors) from one member of each sample's quantities;
// the shape is the largest a reachable sample has, NaN elsewhere (unreachable samples' members
// hold whatever the mechanism left there and must not be read).
template <class Get>
py::array stack(const SampleQuantities* const* q, int count, bool matrix, Get get) {
  Eigen::Index rows = 0, cols = 0;
  for (int i = 0; i < count; ++i) {
    if (q[i]->status != SampleStatus::kReachable) continue;
    const auto& m = get(*q[i]);
    rows = std::max(rows, m.rows());
    cols = std::max(cols, m.cols());
  }
  std::vector<py::ssize_t> shape{count, static_cast<py::ssize_t>(rows)};
  if (matrix) shape.push_back(static_cast<py::ssize_t>(cols));
  py::array_t<double> out(shape);
  double* data = out.mutable_data();
  const Eigen::Index stride = rows * (matrix ? cols : 1);
  std::fill(data, data + count * stride, kNaN);
  for (int i = 0; i < count; ++i) {
    if (q[i]->status != SampleStatus::kReachable) continue;
    const auto& m = get(*q[i]);
    double* row = data + i * stride;
    for (Eigen::Index r = 0; r < m.rows(); ++r) {
      for (Eigen::Index c = 0; c < m.cols(); ++c) row[matrix ? r * cols + c : r] = m(r, c);  // C order
    }
  }
  return std::move(out);
}

Reduction reduction_of(const std::string& word, const std::string& where) {
  if (word == "min") return Reduction::kMin;
  if (word == "max") return Reduction::kMax;
  if (word == "sum") return Reduction::kSum;
  throw Error("problem", where + " = \"" + word + "\": must be one of \"min\", \"max\", \"sum\"");
}

}  // namespace

Needs need_of(const std::string& quantity, const std::string& component, const std::string& json_path) {
  std::string known;
  for (const QuantityName& n : kQuantities) {
    if (quantity == n.name) return n.need;
    known += (known.empty() ? "" : ", ") + std::string(n.name);
  }
  throw Error(component, json_path + " = \"" + quantity + "\": unknown quantity (known: " + known + ")");
}

py::dict quantities_dict(const SampleQuantities* const* q, int count, Needs needs,
                         const std::vector<std::string>& attributes) {
  py::dict d;
  py::array_t<long long> sample(count);
  py::array_t<std::int8_t> status(count);
  for (int i = 0; i < count; ++i) {
    sample.mutable_at(i) = q[i]->sample;
    status.mutable_at(i) = static_cast<std::int8_t>(q[i]->status);
  }
  d["sample"] = sample;
  d["status"] = status;
  const int dimension = count > 0 && q[0]->scene ? q[0]->scene->dimension() : 0;
  py::array_t<double> pose(std::vector<py::ssize_t>{count, dimension});
  for (int i = 0; i < count; ++i) {
    const double* p = q[i]->scene->pose(q[i]->sample);
    std::copy(p, p + dimension, pose.mutable_data() + i * dimension);
  }
  d["pose"] = pose;
  d["q"] = stack(q, count, false, [](const SampleQuantities& s) -> const JointVector& { return s.q; });
  if (needs & kNeedJacobian) {
    d["jacobian"] = stack(q, count, true, [](const SampleQuantities& s) -> const TaskJointMatrix& { return s.jacobian; });
  }
  if (needs & kNeedInertia) {
    d["inertia"] = stack(q, count, true, [](const SampleQuantities& s) -> const JointMatrix& { return s.inertia; });
  }
  if (needs & kNeedEffectiveMass) {
    d["effective_mass"] =
        stack(q, count, true, [](const SampleQuantities& s) -> const TaskMatrix& { return s.effective_mass; });
  }
  if (needs & kNeedGravity) {
    d["gravity"] = stack(q, count, false, [](const SampleQuantities& s) -> const JointVector& { return s.gravity; });
  }
  if (needs & kNeedActuatorLimits) {
    d["max_velocity"] =
        stack(q, count, false, [](const SampleQuantities& s) -> const JointVector& { return s.max_velocity; });
    d["max_torque"] = stack(q, count, false, [](const SampleQuantities& s) -> const JointVector& { return s.max_torque; });
  }
  if (needs & kNeedJointVelocity) {
    d["joint_velocity"] =
        stack(q, count, false, [](const SampleQuantities& s) -> const JointVector& { return s.joint_velocity; });
  }
  if (needs & kNeedJointAcceleration) {
    d["joint_acceleration"] =
        stack(q, count, false, [](const SampleQuantities& s) -> const JointVector& { return s.joint_acceleration; });
  }
  if (needs & kNeedVelocityTorque) {
    d["velocity_torque"] =
        stack(q, count, false, [](const SampleQuantities& s) -> const JointVector& { return s.velocity_torque; });
  }
  py::dict attribute_arrays;
  for (std::size_t k = 0; k < attributes.size(); ++k) {
    const int kk = static_cast<int>(k);
    const AttributeMatrix* m = count > 0 && q[0]->attributes && kk < q[0]->attribute_count ? q[0]->attributes[kk] : nullptr;
    if (!m) continue;  // the scene lacks it: absent from the dict, as attribute_row() gives null
    const Eigen::Index cols = m->cols();
    py::array_t<double> a(std::vector<py::ssize_t>{count, static_cast<py::ssize_t>(cols)});
    for (int i = 0; i < count; ++i) {
      const double* row = q[i]->attribute_row(kk);
      std::copy(row, row + cols, a.mutable_data() + i * cols);
    }
    attribute_arrays[py::str(attributes[k])] = a;
  }
  d["attributes"] = attribute_arrays;
  return d;
}

PythonMetric::PythonMetric(py::object object, std::string name, const std::string& json_path, const void* study)
    : object_(std::move(object)), name_(std::move(name)), study_(study) {
  const std::string where = json_path.empty() ? name_ : json_path;
  auto require = [&](const char* attribute) {
    if (!py::hasattr(object_, attribute)) {
      throw Error("problem", where + ": the Python metric '" + name_ + "' has no '" + attribute + "'");
    }
    return object_.attr(attribute);
  };
  const py::object locals = require("locals");
  local_batch_ = require("local_batch");
  if (!PyCallable_Check(local_batch_.ptr())) {
    throw Error("problem", where + ".local_batch = " + shown(local_batch_) + ": must be a method");
  }
  int i = 0;
  for (const py::handle item : items_of(locals, "problem", where + ".locals", "a list of (name, reduction[, unit])")) {
    const std::string at = where + ".locals[" + std::to_string(i++) + "]";
    if (!py::isinstance<py::tuple>(item) && !py::isinstance<py::list>(item)) {
      throw Error("problem", at + " = " + shown(item) + ": must be a tuple (name, reduction[, unit])");
    }
    const py::tuple t = py::tuple(py::reinterpret_borrow<py::object>(item));
    if (t.size() < 2 || t.size() > 3) throw Error("problem", at + ": must be (name, reduction[, unit])");
    const char* text = "a string";
    const std::string local_name = cast_as<std::string>(t[0], "problem", at + ".name", text);
    if (local_name.empty() || local_name.find_first_of(",\"\r\n") != std::string::npos) {
      throw Error("problem", at + ".name = " + shown(t[0]) +
                                 ": must be non-empty, without a comma, a double quote or a line break (it names CSV columns)");
    }
    locals_.push_back(LocalValue{local_name,
                                 reduction_of(cast_as<std::string>(t[1], "problem", at + ".reduction", text), at + ".reduction"),
                                 t.size() == 3 ? cast_as<std::string>(t[2], "problem", at + ".unit", text) : std::string()});
  }
  if (locals_.empty()) throw Error("problem", where + ".locals: the Python metric '" + name_ + "' declares no local values");
  if (py::hasattr(object_, "needs")) {
    int k = 0;
    for (const py::handle n : items_of(object_.attr("needs"), "problem", where + ".needs", "a list of quantity names")) {
      const std::string at = where + ".needs[" + std::to_string(k++) + "]";
      needs_ |= need_of(cast_as<std::string>(n, "problem", at, "a quantity name (a string)"), "problem", at);
    }
  }
  if (py::hasattr(object_, "scene_attributes")) {
    const py::object a = object_.attr("scene_attributes");
    items_of(a, "problem", where + ".scene_attributes", "a list of attribute names");
    attributes_ = cast_as<std::vector<std::string>>(a, "problem", where + ".scene_attributes", "a list of strings");
  }
  if (py::hasattr(object_, "batch_size")) {
    const py::object b = object_.attr("batch_size");
    if (py::isinstance<py::bool_>(b)) throw Error("problem", where + ".batch_size = " + shown(b) + ": must be an integer >= 1");
    batch_ = cast_as<int>(b, "problem", where + ".batch_size", "an integer >= 1");
    if (batch_ < 1) throw Error("problem", where + ".batch_size = " + std::to_string(batch_) + ": must be >= 1");
  }
  combine_ = py::hasattr(object_, "combine") ? py::object(object_.attr("combine")) : py::object(py::none());
}

PythonMetric::~PythonMetric() {
  // The last reference may go from any thread; Python objects are released with the GIL held.
  py::gil_scoped_acquire gil;
  local_batch_ = py::object();
  combine_ = py::object();
  object_ = py::object();
}

void PythonMetric::local(const SampleQuantities& q, double* out) const {
  const SampleQuantities* one = &q;
  local_batch(&one, 1, out);
}

void PythonMetric::local_batch(const SampleQuantities* const* q, int count, double* out) const {
  // A Python exception travels as py::error_already_set up to the caller of the evaluation,
  // where pybind11 raises it again as itself.
  py::gil_scoped_acquire gil;
  py::object value;
  {
    const CallbackScope scope(study_);
    value = local_batch_(quantities_dict(q, count, needs_, attributes_));
  }
  const auto values = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  const std::size_t k = locals_.size();
  const bool shape_ok = values && ((values.ndim() == 2 && values.shape(0) == count && values.shape(1) == static_cast<py::ssize_t>(k)) ||
                                   (values.ndim() == 1 && k == 1 && values.shape(0) == count));
  if (!shape_ok) {
    std::string shape = shown(value) + ", not an array of numbers,";
    const bool array_like = py::isinstance<py::array>(value) || py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value);
    if (values && array_like) {
      shape = "shape (";
      for (py::ssize_t d = 0; d < values.ndim(); ++d) shape += (d ? ", " : "") + std::to_string(values.shape(d));
      shape += ")";
    }
    throw Error(name_, "local_batch returned " + shape + " for " + std::to_string(count) + " samples: must be (" +
                           std::to_string(count) + ", " + std::to_string(k) + ")" + (k == 1 ? " or (" + std::to_string(count) + ",)" : ""));
  }
  std::copy(values.data(), values.data() + count * static_cast<py::ssize_t>(k), out);
}

double PythonMetric::combine(const double* reduced, int samples) const {
  if (combine_.is_none()) return reduced[0];
  py::gil_scoped_acquire gil;
  py::array_t<double> r(static_cast<py::ssize_t>(locals_.size()));
  std::copy(reduced, reduced + locals_.size(), r.mutable_data());
  py::object value;
  {
    const CallbackScope scope(study_);
    value = combine_(r, samples);
  }
  // A NumPy array has __float__ but converts only at size 1: accept exactly what float() accepts
  // of a scalar, and name the rest.
  const bool scalar = !py::isinstance<py::bool_>(value) && py::hasattr(value, "__float__") &&
                      (!py::hasattr(value, "ndim") || py::cast<int>(value.attr("ndim")) == 0);
  if (!scalar) throw Error(name_, "combine returned " + shown(value) + ": must be a number");
  try {
    return py::cast<double>(py::float_(value));
  } catch (const py::error_already_set& e) {  // an int beyond a double's range: OverflowError
    throw Error(name_, "combine returned " + shown(value) + ": must be a number a double can hold (" + e.what() + ")");
  }
}

bool inside_callback_of(const void* study) {
  return std::find(t_callback_studies.begin(), t_callback_studies.end(), study) != t_callback_studies.end();
}

}  // namespace hapsyn::python
