#pragma once
/// \file
/// The C++ side of hapsyn.Study: a loaded study with the registry that made it, and the calls
/// the Python package wraps (load, run, evaluate, scene). Documents cross the boundary as JSON
/// text (the Python side uses the json module), arrays as NumPy arrays.
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/study.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn::python {

/// A registry over HAPSYN_PLUGIN_PATH / the build or install tree, with `plugin_path`
/// directories searched first.
std::shared_ptr<Registry> make_registry(const std::vector<std::string>& plugin_path);

class StudyHandle {
 public:
  /// Loads a study (GIL held on entry; released while the study is built).
  /// \param document   the problem as JSON text, or a file path when `is_file`
  /// \param overrides  "a.b=value" assignments (apply_override), applied in order
  /// \param metrics    Python metric objects by name (become InProcessMetric factories)
  /// \throws Error with the CLI's message for every invalid input.
  StudyHandle(const std::string& document, bool is_file, const std::vector<std::string>& overrides,
              const std::vector<std::string>& plugin_path, const pybind11::dict& metrics);
  ~StudyHandle();

  std::string resolved() const { return study_->resolved.dump(); }
  std::vector<std::string> free_names() const;
  std::vector<std::string> objective_names() const;
  std::vector<std::string> local_names() const;

  /// Runs the solver on a worker thread (see hapsyn.Study.run). Returns result.json's text.
  std::string run(std::optional<int> threads, std::optional<std::uint64_t> seed, const std::string& out,
                  bool force, bool write_samples, const pybind11::object& progress, bool resume);

  /// Evaluates designs: `designs` is free-variable rows (n x dimension). See hapsyn.Study.evaluate.
  pybind11::dict evaluate(const pybind11::array_t<double, pybind11::array::c_style | pybind11::array::forcecast>& designs,
                          int threads);
  /// Per-sample records of one design (status, local values) and the requested quantities.
  pybind11::dict evaluate_samples(const pybind11::array_t<double, pybind11::array::c_style | pybind11::array::forcecast>& design,
                                  const std::vector<std::string>& quantities);
  /// Seconds per Problem::evaluate of `design` over `repeats` calls, timed in C++ with one
  /// scratch (the baseline of benchmarks/python_evaluate_benchmark.py).
  double time_evaluate(const pybind11::array_t<double, pybind11::array::c_style | pybind11::array::forcecast>& design,
                       int repeats);
  /// Free vector from {"variable": value or [values]} (every free component required).
  std::vector<double> free_from_json(const std::string& design_json) const;

  /// Zero-copy read-only views of the scene's samples, weights and attributes (owner: `self`).
  pybind11::dict scene(pybind11::object self) const;

 private:
  // Throws when the calling thread is inside a callback of this study's own Python metric.
  void refuse_reentry(const char* call) const;

  // Declared first so that it is destroyed last: the plugins' code lives in its libraries.
  std::shared_ptr<Registry> registry_;
  std::unique_ptr<Study> study_;
  std::unique_ptr<Problem::EvalScratch> scratch_;  // for single-threaded evaluate()
  std::mutex mutex_;                               // guards scratch_
};

}  // namespace hapsyn::python
