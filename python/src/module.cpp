// hapsyn._hapsyn: the compiled half of the Python package. The public API, its documentation and
// the conversions between JSON text and Python objects live in hapsyn/__init__.py; this module
// exposes the framework calls that API needs.
#include "study_binding.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/options.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

namespace py = pybind11;
using hapsyn::python::StudyHandle;

PYBIND11_MODULE(_hapsyn, m) {
  m.doc() = "Compiled core of the hapsyn Python package (use the hapsyn module, not this one).";
  // hapsyn::Error -> hapsyn.Error (a ValueError); the message is what() as the CLI prints it
  // after "hapsyn: error: ".
  py::register_exception<hapsyn::Error>(m, "Error", PyExc_ValueError);

  m.def("version", [] { return hapsyn::version(); }, "The hapsyn library version.");
  m.def(
      "plugins",
      [](const std::vector<std::string>& plugin_path) {
        const auto registry = hapsyn::python::make_registry(plugin_path);
        std::vector<std::string> errors;
        py::list out;
        for (const hapsyn::PluginRecord& r : registry->list(&errors)) {
          py::dict d;
          d["name"] = r.name;
          d["kind"] = r.kind;
          d["version"] = r.version;
          d["description"] = r.description;
          d["thread_safety"] = hapsyn::to_string(r.thread_safety);
          d["file"] = r.file;
          out.append(d);
        }
        return py::make_tuple(out, errors);
      },
      py::arg("plugin_path"), "(plugins, errors): every plugin found, and the files that failed to load.");
  m.def(
      "describe",
      [](const std::string& name, const std::vector<std::string>& plugin_path) {
        return hapsyn::python::make_registry(plugin_path)->find(name).schema.dump();
      },
      py::arg("name"), py::arg("plugin_path"), "The options schema of a plugin, as JSON text.");

  py::class_<StudyHandle>(m, "StudyHandle", "A loaded study (see hapsyn.Study).")
      .def(py::init<const std::string&, bool, const std::vector<std::string>&, const std::vector<std::string>&,
                    const py::dict&>(),
           py::arg("document"), py::arg("is_file"), py::arg("overrides"), py::arg("plugin_path"), py::arg("metrics"))
      .def("resolved", &StudyHandle::resolved, "The resolved problem as JSON text.")
      .def("free_names", &StudyHandle::free_names, "Names of the free design components, in order.")
      .def("objective_names", &StudyHandle::objective_names, "Names of the objectives, in order.")
      .def("local_names", &StudyHandle::local_names, "<metric>.<local> for every local value, in order (\"[k]\" appended to names that repeat, as in samples.csv).")
      .def("free_from_json", &StudyHandle::free_from_json, py::arg("design_json"),
           "Free design vector from a JSON object of design variables.")
      .def("run", &StudyHandle::run, py::arg("threads"), py::arg("seed"), py::arg("out"), py::arg("force"),
           py::arg("write_samples"), py::arg("progress"), py::arg("resume"), "Runs the solver; returns result.json's text.")
      .def("evaluate", &StudyHandle::evaluate, py::arg("designs"), py::arg("threads"),
           "Evaluates rows of free design values.")
      .def("time_evaluate", &StudyHandle::time_evaluate, py::arg("design"), py::arg("repeats"),
           "Seconds per evaluation of one design, timed in C++ (benchmark baseline).")
      .def("evaluate_samples", &StudyHandle::evaluate_samples, py::arg("design"), py::arg("quantities"),
           "Per-sample statuses, local values and quantities of one design.")
      .def(
          "scene", [](py::object self) { return py::cast<StudyHandle&>(self).scene(self); },
          "Views of the scene's samples, weights and attributes.");
}
