#include "study_binding.hpp"

#include "python_metric.hpp"

#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/internal/maps.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/internal/study_runner.hpp>

#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <limits>
#include <streambuf>
#include <thread>

namespace py = pybind11;

namespace hapsyn::python {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Progress lines written by the solver on its thread, taken by the thread that called run()
// (which alone may call Python).
class LineQueue {
 public:
  void push(std::string line) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      lines_.push_back(std::move(line));
    }
    ready_.notify_one();
  }
  void close() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    ready_.notify_one();
  }
  /// Waits up to `timeout` for lines; moves them into `out`. True once closed and drained.
  bool wait(std::vector<std::string>& out, std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait_for(lock, timeout, [&] { return closed_ || !lines_.empty(); });
    out.assign(std::make_move_iterator(lines_.begin()), std::make_move_iterator(lines_.end()));
    lines_.clear();
    return closed_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<std::string> lines_;
  bool closed_ = false;
};

// An ostream buffer that cuts what the solver writes into lines for a LineQueue.
class LineBuffer : public std::streambuf {
 public:
  explicit LineBuffer(LineQueue& queue) : queue_(queue) {}
  ~LineBuffer() override {
    if (!line_.empty()) queue_.push(line_);
  }

 protected:
  int_type overflow(int_type c) override {
    if (c == traits_type::eof()) return traits_type::not_eof(c);
    if (c == '\n') {
      queue_.push(std::move(line_));
      line_.clear();
    } else {
      line_.push_back(static_cast<char>(c));
    }
    return c;
  }

 private:
  LineQueue& queue_;
  std::string line_;
};

py::array_t<double> matrix(py::ssize_t rows, py::ssize_t cols) {
  py::array_t<double> a(std::vector<py::ssize_t>{rows, cols});
  std::fill(a.mutable_data(), a.mutable_data() + rows * cols, kNaN);
  return a;
}

}  // namespace

std::shared_ptr<Registry> make_registry(const std::vector<std::string>& plugin_path) {
  std::vector<std::string> path = plugin_path;
  for (const std::string& d : Registry::default_search_path()) path.push_back(d);
  return std::make_shared<Registry>(path);
}

StudyHandle::StudyHandle(const std::string& document, bool is_file, const std::vector<std::string>& overrides,
                         const std::vector<std::string>& plugin_path, const py::dict& metrics)
    : registry_(make_registry(plugin_path)) {
  // Python metrics: factories called (with the GIL) when load_study meets their names.
  std::vector<InProcessMetric> in_process;
  for (const auto& item : metrics) {
    InProcessMetric m;
    m.name = py::cast<std::string>(item.first);
    m.version = "python";
    m.description = "metric written in Python";
    m.origin = "python:" + py::cast<std::string>(py::repr(item.second));
    m.thread_safety = ThreadSafety::kSerialized;
    const py::object factory = py::reinterpret_borrow<py::object>(item.second);
    const std::string name = m.name;
    m.create = [factory, name, this](const Json& options, const std::string& json_path) -> std::shared_ptr<Metric> {
      py::gil_scoped_acquire gil;
      const py::object instance = factory(options.dump(), json_path);
      return std::make_shared<PythonMetric>(instance, name, json_path, this);
    };
    in_process.push_back(std::move(m));
  }
  {
    py::gil_scoped_release release;  // scenes may take a while to build
    Json doc = is_file ? read_problem_file(document) : parse_problem_text(document, "<dict>");
    for (const std::string& s : overrides) apply_override(doc, s);
    // Relative paths in a problem file are relative to that file first, as for `hapsyn run`.
    const ProblemDirectoryScope scope(is_file ? document : std::string());
    study_ = std::make_unique<Study>(load_study(doc, *registry_, in_process));
    scratch_ = study_->problem->make_eval_scratch();
  }
  // The factories (Python objects) are released here, with the GIL held.
}

StudyHandle::~StudyHandle() {
  // A Python metric's destructor takes the GIL itself; releasing it here lets that work from
  // any thread order. Members go in reverse order: scratch, study, then the registry.
  py::gil_scoped_release release;
  scratch_.reset();
  study_.reset();
}

void StudyHandle::refuse_reentry(const char* call) const {
  if (!inside_callback_of(this)) return;
  throw Error("python", std::string("Study.") + call +
                            "() called from inside a callback of one of this study's own Python metrics: the callback is "
                            "part of the evaluation it would wait for (it would never return); load a second Study for "
                            "a nested evaluation");
}

std::vector<std::string> StudyHandle::free_names() const {
  std::vector<std::string> names;
  const DesignSpace& space = study_->problem->design_space();
  for (int i : space.free_indices()) names.push_back(space.components()[static_cast<std::size_t>(i)].name);
  return names;
}

std::vector<std::string> StudyHandle::objective_names() const {
  std::vector<std::string> names;
  for (const Objective& o : study_->problem->objectives()) names.push_back(o.name);
  return names;
}

// The same unique names as samples.csv's columns (a metric used twice gets "[k]" suffixes).
std::vector<std::string> StudyHandle::local_names() const { return local_columns(*study_->problem); }

std::vector<double> StudyHandle::free_from_json(const std::string& design_json) const {
  const Json design = Json::parse(design_json);
  const DesignSpace& space = study_->problem->design_space();
  for (auto it = design.begin(); it != design.end(); ++it) {
    const bool known = std::any_of(space.components().begin(), space.components().end(),
                                   [&](const DesignComponent& c) { return c.variable == it.key(); });
    if (!known) {
      std::vector<std::string> names;
      for (const DesignComponent& c : space.components()) {
        if (names.empty() || names.back() != c.variable) names.push_back(c.variable);
      }
      const std::string near = nearest_name(it.key(), names);
      throw Error("python", "design." + it.key() + ": unknown design variable" +
                                (near.empty() ? "" : " (did you mean '" + near + "'?)"));
    }
  }
  // A fixed variable may be given (a whole design from a result.json), but only with its value:
  // another one would be dropped without a word.
  for (const DesignComponent& c : space.components()) {
    if (!c.fixed || !design.contains(c.variable)) continue;
    const Json& v = design[c.variable];
    const Json& value = c.name == c.variable ? v : (v.is_array() && static_cast<int>(v.size()) > c.index ? v[static_cast<std::size_t>(c.index)] : Json());
    if (!value.is_number() || value.get<double>() != c.lower) {
      throw Error("python", "design." + c.name + " = " + render_value(value) + ": this study fixes it at " +
                                render_value(Json(c.lower)) + " (give it that value or leave it out; free it in the "
                                "problem's design section to vary it)");
    }
  }
  std::vector<double> free;
  for (int i : space.free_indices()) {
    const DesignComponent& c = space.components()[static_cast<std::size_t>(i)];
    if (!design.contains(c.variable)) throw Error("python", "design." + c.variable + ": missing (a free design variable)");
    const Json& v = design[c.variable];
    const Json& value = c.name == c.variable ? v : (v.is_array() && static_cast<int>(v.size()) > c.index ? v[static_cast<std::size_t>(c.index)] : Json());
    if (!value.is_number()) {
      throw Error("python", "design." + c.name + " = " + render_value(value) + ": must be a number");
    }
    free.push_back(value.get<double>());
  }
  return free;
}

std::string StudyHandle::run(std::optional<int> threads, std::optional<std::uint64_t> seed, const std::string& out,
                             bool force, bool write_samples, const py::object& progress, bool resume) {
  refuse_reentry("run");
  RunOptions options;
  options.output_directory = out;
  options.threads = threads.value_or(0);
  options.seed = seed;
  options.force = force;
  options.resume = resume;
  options.write_samples = write_samples;
  options.quiet = progress.is_none();
  LineQueue queue;
  LineBuffer buffer(queue);
  std::ostream stream(&buffer);
  options.progress = &stream;
  std::atomic<bool> stop{false};
  options.stop = &stop;

  Json doc;
  std::exception_ptr failure;
  std::unique_ptr<py::error_already_set> callback_error;
  bool interrupted = false;
  // The solver runs on a worker thread without the GIL; this thread delivers progress lines and
  // polls for signals (KeyboardInterrupt) with the GIL held, and otherwise waits without it.
  std::thread worker([&] {
    try {
      doc = run_study(*study_, options);
    } catch (...) {
      failure = std::current_exception();
    }
    queue.close();
  });
  for (bool finished = false; !finished;) {
    std::vector<std::string> lines;
    {
      py::gil_scoped_release release;
      finished = queue.wait(lines, std::chrono::milliseconds(50));
    }
    for (const std::string& line : lines) {
      if (callback_error || progress.is_none()) break;
      try {
        progress(line);
      } catch (py::error_already_set& e) {
        callback_error = std::make_unique<py::error_already_set>(std::move(e));
        stop = true;  // a failing callback ends the run; its exception is raised afterwards
      }
    }
    if (!interrupted && PyErr_CheckSignals() != 0) {
      if (PyErr_ExceptionMatches(PyExc_KeyboardInterrupt)) {
        PyErr_Clear();  // a stop request, not an error: the run ends with status "stopped"
      } else if (!callback_error) {
        callback_error = std::make_unique<py::error_already_set>();
      } else {
        PyErr_Clear();
      }
      interrupted = true;
      stop = true;
    }
  }
  {
    py::gil_scoped_release release;
    worker.join();
  }
  if (failure) std::rethrow_exception(failure);
  if (callback_error) throw std::move(*callback_error);
  return doc.dump();
}

py::dict StudyHandle::evaluate(const py::array_t<double, py::array::c_style | py::array::forcecast>& designs,
                               int threads) {
  refuse_reentry("evaluate");
  const Problem& problem = *study_->problem;
  const py::ssize_t dimension = static_cast<py::ssize_t>(problem.dimension());
  if (designs.ndim() != 2 || designs.shape(1) != dimension) {
    throw Error("python", "design: an array of shape (" + std::to_string(designs.ndim() == 2 ? designs.shape(0) : 1) +
                              ", " + std::to_string(designs.ndim() >= 1 ? designs.shape(designs.ndim() - 1) : 0) +
                              ") is not a list of designs with " + std::to_string(dimension) +
                              " free values each (" + std::to_string(dimension) + " free design variables)");
  }
  const py::ssize_t n = designs.shape(0);
  const py::ssize_t m = static_cast<py::ssize_t>(problem.objectives().size());
  py::array_t<double> objectives = matrix(n, m);
  py::array_t<double> score(n);
  py::array_t<long long> samples(n);
  py::array_t<long long> failed_sample(n);
  std::vector<EvalStatus> status(static_cast<std::size_t>(n));
  const double* in = designs.data();
  double* obj = objectives.mutable_data();
  double* sc = score.mutable_data();
  long long* se = samples.mutable_data();
  long long* fs = failed_sample.mutable_data();
  {
    py::gil_scoped_release release;
    std::lock_guard<std::mutex> lock(mutex_);
    for (py::ssize_t i = 0; i < n; ++i) {
      const double* row = in + i * dimension;
      Evaluation parallel;
      const Evaluation& e = threads > 1 ? (parallel = problem.evaluate_parallel(row, threads)) : problem.evaluate(row, *scratch_);
      status[static_cast<std::size_t>(i)] = e.status;
      if (e.status == EvalStatus::kFeasible) std::copy(e.objectives.begin(), e.objectives.end(), obj + i * m);
      sc[i] = e.score;
      se[i] = e.samples_evaluated;
      fs[i] = e.failed_sample;
    }
  }
  py::list names;
  for (EvalStatus s : status) names.append(py::str(to_string(s)));
  py::dict d;
  d["objectives"] = objectives;
  d["score"] = score;
  d["status"] = names;
  d["samples_evaluated"] = samples;
  d["failed_sample"] = failed_sample;
  return d;
}

py::dict StudyHandle::evaluate_samples(const py::array_t<double, py::array::c_style | py::array::forcecast>& design,
                                       const std::vector<std::string>& quantities) {
  refuse_reentry("evaluate_samples");
  const Problem& problem = *study_->problem;
  if (design.ndim() != 1 || design.shape(0) != static_cast<py::ssize_t>(problem.dimension())) {
    throw Error("python", "design: samples=True needs one design (" + std::to_string(problem.dimension()) + " free values)");
  }
  Needs needs = 0;
  for (std::size_t i = 0; i < quantities.size(); ++i) {
    needs |= need_of(quantities[i], "python", "quantities[" + std::to_string(i) + "]");
  }
  const Needs missing = needs & ~problem.mechanism().specs().provides;
  if (missing != 0) {
    std::string names;
    for (const std::string& q : quantities) {
      if (need_of(q, "python", "quantities") & missing) names += (names.empty() ? "" : ", ") + q;
    }
    throw Error("python", "quantities: the mechanism '" + study_->resolved["mechanism"]["plugin"].get<std::string>() +
                              "' does not provide " + names);
  }
  const SampleSet& scene = problem.samples();
  SampleRecords records;
  std::vector<SampleQuantities> solved;
  {
    py::gil_scoped_release release;
    const Eigen::VectorXd full = problem.full_design(design.data());
    // Checks the design as Problem::evaluate does (finite, within the bounds).
    std::vector<double> g(problem.constraint_count());
    problem.constraints(design.data(), g.data());
    records = record_samples(problem, full);
    if (needs != 0) {
      // The quantities on their own pass: the metrics' needs may not include them.
      const std::unique_ptr<const MechanismModel> model = problem.mechanism().build(full.data());
      const std::unique_ptr<MechanismScratch> scratch = problem.mechanism().make_scratch();
      solved.resize(static_cast<std::size_t>(scene.size()));
      for (int i = 0; i < scene.size(); ++i) {
        SampleQuantities& q = solved[static_cast<std::size_t>(i)];
        problem.bind_sample(q, i);
        model->solve(scene.pose(i), needs, *scratch, q);
      }
    }
  }
  const py::ssize_t n = scene.size();
  const py::ssize_t k = static_cast<py::ssize_t>(records.locals.cols());
  py::array_t<double> locals = matrix(n, k);
  for (py::ssize_t i = 0; i < n; ++i) {
    if (!records.has_locals[static_cast<std::size_t>(i)]) continue;
    for (py::ssize_t j = 0; j < k; ++j) locals.mutable_at(i, j) = records.locals(i, j);
  }
  py::array status = py::array(py::cast(records.status)).attr("astype")("U");
  py::dict d;
  d["sample_status"] = status;
  d["locals"] = locals;
  d["local_names"] = local_names();
  if (needs != 0) {
    std::vector<const SampleQuantities*> pointers;
    for (const SampleQuantities& q : solved) pointers.push_back(&q);
    py::dict all = quantities_dict(pointers.data(), static_cast<int>(n), needs, {});
    py::dict chosen;
    for (const std::string& q : quantities) chosen[py::str(q)] = all[py::str(q)];
    chosen["q"] = all["q"];
    d["quantities"] = chosen;
  }
  return d;
}

double StudyHandle::time_evaluate(const py::array_t<double, py::array::c_style | py::array::forcecast>& design,
                                  int repeats) {
  refuse_reentry("time_evaluate");
  if (design.ndim() != 1 || design.shape(0) != static_cast<py::ssize_t>(study_->problem->dimension()) || repeats < 1) {
    throw Error("python", "time_evaluate: one design and repeats >= 1");
  }
  py::gil_scoped_release release;
  std::lock_guard<std::mutex> lock(mutex_);
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < repeats; ++i) study_->problem->evaluate(design.data(), *scratch_);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / repeats;
}

py::dict StudyHandle::scene(py::object self) const {
  const SampleSet& s = study_->problem->samples();
  auto view = [&](const double* data, py::ssize_t rows, py::ssize_t cols) {
    // A read-only view into the study's own memory; `self` (the Python Study) keeps it alive.
    py::array_t<double> a(std::vector<py::ssize_t>{rows, cols},
                          std::vector<py::ssize_t>{static_cast<py::ssize_t>(cols * sizeof(double)), sizeof(double)}, data, self);
    a.attr("setflags")(py::arg("write") = false);
    return a;
  };
  py::dict d;
  d["samples"] = view(s.poses.data(), s.poses.rows(), s.poses.cols());
  d["coordinates"] = s.coordinates;
  d["unit"] = s.unit;
  py::dict attributes;
  for (const auto& [name, m] : s.attributes) attributes[py::str(name)] = view(m.data(), m.rows(), m.cols());
  d["attributes"] = attributes;
  if (!s.weights.empty()) {
    py::array_t<double> w(static_cast<py::ssize_t>(s.weights.size()), s.weights.data(), self);
    w.attr("setflags")(py::arg("write") = false);
    d["weights"] = w;
  } else {
    d["weights"] = py::none();
  }
  d["info"] = s.info.dump();
  return d;
}

}  // namespace hapsyn::python
