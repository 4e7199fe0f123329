#include <hapsyn/error.hpp>
#include "sample_checks.hpp"
#include <hapsyn/internal/plot.hpp>
#include <hapsyn/internal/scene_export.hpp>

#include <boost/filesystem.hpp>

#include <algorithm>
#include <charconv>
#include <chrono>

namespace hapsyn {

namespace {

// Shortest text that reads back as the same double.
std::string exact_number(double v) {
  char buffer[32];
  const auto r = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, r.ptr);
}

// The "scene" section's plugin name, after checking the section's shape.
std::string scene_plugin_of(const Json& problem) {
  if (!problem.is_object() || !problem.contains("scene")) throw Error("problem", "scene: missing");
  const Json& scene = problem["scene"];
  if (!scene.is_object()) {
    throw Error("problem", "scene = " + render_value(scene) + ": must be an object {\"plugin\", \"options\"}");
  }
  for (auto it = scene.begin(); it != scene.end(); ++it) {
    if (it.key() != "plugin" && it.key() != "options") {
      throw Error("problem", "scene." + it.key() + ": unknown key; known keys: options, plugin");
    }
  }
  if (!scene.contains("plugin") || !scene["plugin"].is_string()) {
    throw Error("problem", "scene.plugin = " + render_value(scene.value("plugin", Json())) +
                               ": must be a plugin name (string)");
  }
  return scene["plugin"];
}

}  // namespace

BuiltScene build_scene_alone(const Json& problem, const Registry& registry, std::optional<int> threads,
                             const std::vector<std::string>& attributes, std::ostream* progress) {
  BuiltScene built;
  built.plugin = scene_plugin_of(problem);
  const Json options = problem["scene"].value("options", Json::object());
  const auto plugin = registry.create_scene(built.plugin, options, "scene");
  SceneRequest request;
  request.attributes = attributes;
  request.threads = threads.value_or(0);
  request.progress = progress;
  const auto start = std::chrono::steady_clock::now();
  built.samples = plugin->build(request);
  built.build_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  check_lattice(built.samples, built.plugin);
  check_groups(built.samples, built.plugin);
  check_weights(built.samples, built.plugin);
  check_finite_samples(built.samples, built.plugin);
  return built;
}

std::string scene_csv(const SampleSet& set) {
  std::string text;
  for (std::size_t c = 0; c < set.coordinates.size(); ++c) text += (c ? "," : "") + set.coordinates[c];
  for (const auto& [name, values] : set.attributes) {
    for (Eigen::Index c = 0; c < values.cols(); ++c) {
      text += "," + (values.cols() == 1 ? name : name + "[" + std::to_string(c) + "]");
    }
  }
  const bool weighted = !set.weights.empty();
  if (weighted) text += ",weight";
  text += "\n";
  for (int i = 0; i < set.size(); ++i) {
    for (int c = 0; c < set.dimension(); ++c) text += (c ? "," : "") + exact_number(set.pose(i)[c]);
    for (const auto& [name, values] : set.attributes) {
      for (Eigen::Index c = 0; c < values.cols(); ++c) text += "," + exact_number(values(i, c));
    }
    if (weighted) text += "," + exact_number(set.weights[static_cast<std::size_t>(i)]);
    text += "\n";
  }
  return text;
}

std::string plot_lattice_density(const SampleSet& set, const std::string& directory) {
  if (!set.lattice) throw Error("scene", "no lattice to plot: the scene declares no SampleLattice");
  const SampleLattice& lattice = *set.lattice;
  LatticeField density;
  density.per_axis = lattice.per_axis;
  density.step = lattice.step;
  density.lattice_to_plot = lattice.lattice_to_poses;
  density.origin = lattice.origin;
  density.lattice_frame = lattice.frame;
  const double candidates = lattice.candidates_per_point;
  const std::size_t n = static_cast<std::size_t>(density.per_axis);
  density.values.assign(n * n * n, 0.0);
  for (const long long index : lattice.index_of_sample) {
    density.values[static_cast<std::size_t>(index)] += 1.0 / candidates;
  }
  boost::filesystem::create_directories(directory);
  return plot_lattice_slices(directory, "density_slices",
                             "reachable " + lattice.candidates + " / " + std::to_string(lattice.candidates_per_point) +
                                 " per position; slices by height",
                             density, std::max(1e-9, *std::max_element(density.values.begin(), density.values.end())));
}

}  // namespace hapsyn
