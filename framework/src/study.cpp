// Loading a study: load_study validates a problem document against the framework's schema of a
// problem file (problem_file_schema.cpp) and builds the plugins, the design space, the scene and
// the problem.
#include <hapsyn/data_file.hpp>
#include <hapsyn/design_space.hpp>
#include <hapsyn/error.hpp>
#include "sample_checks.hpp"
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/internal/reference.hpp>
#include <hapsyn/schema.hpp>
#include <hapsyn/internal/study.hpp>

#include "serialized_plugins.hpp"

#include <boost/filesystem.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace hapsyn {

namespace {

// Records plugin `name` among the plugins the study uses (each plugin file once).
void note_plugin(Study& study, const Registry& registry, const std::string& name) {
  const PluginRecord& r = registry.find(name);
  for (const PluginRecord& p : study.plugins) {
    if (p.file == r.file) return;
  }
  study.plugins.push_back(r);
}

// A name that becomes part of a path (the study's results/<name>, a plugin's libhapsyn_<name>.so)
// must not be able to leave its folder: [A-Za-z0-9._-], not starting with '.', at most 100.
void check_safe_name(const std::string& path, const std::string& name) {
  std::string rule;
  if (name.empty()) {
    rule = "must not be empty";
  } else if (name.size() > kMaxNameLength) {
    rule = "must have at most " + std::to_string(kMaxNameLength) + " characters (it has " +
           std::to_string(name.size()) + ")";
  } else if (name[0] == '.') {
    rule = "must not start with '.'";
  } else {
    for (const char c : name) {
      const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                      c == '_' || c == '-';
      if (!ok) {
        rule = std::string("must use only letters, digits, '.', '_' and '-' (it becomes part of a file path; '") +
               (c == '/' ? "/" : c == '\\' ? "\\" : std::string(1, c)) + "' is not allowed)";
        break;
      }
    }
  }
  if (!rule.empty()) throw Error("problem", path + " = " + render_value(Json(name)) + ": " + rule);
}

// registry.find, with an unknown plugin blamed on the key that named it.
const PluginRecord& find_plugin(const Registry& registry, const std::string& path, const std::string& name) {
  check_safe_name(path, name);
  try {
    return registry.find(name);
  } catch (const Error& e) {
    throw Error("problem", path + " = \"" + name + "\": " + e.what());
  }
}

// A single-objective study maximizes the weighted sum: with every weight 0 every design scores 0,
// and the solver would report an arbitrary design as converged.
void check_weights_not_all_zero(const Json& objectives) {
  std::string names;
  for (const Json& o : objectives) {
    if (o["weight"].get<double>() != 0.0) return;
    names += (names.empty() ? "" : ", ") + o["name"].get<std::string>();
  }
  throw Error("problem", "objectives: every weight is 0 (" + names +
                             "): the weighted sum would be 0 for every design; give at least one objective a "
                             "nonzero \"weight\"");
}

// The metric and the objective of each entry of the "objectives" section (its options resolved
// in place); the scene attributes the metrics need are added to `request`.
// An in-process metric (InProcessMetric): created by its factory, serialised when it says so, and
// recorded among the study's plugins once.
std::shared_ptr<Metric> create_in_process(const InProcessMetric& m, const Json& options, const std::string& path,
                                          Study& study) {
  std::shared_ptr<Metric> metric = m.create(options, path);
  if (!metric) throw Error("problem", path + ".metric = \"" + m.name + "\": the metric's factory returned nothing");
  if (m.thread_safety == ThreadSafety::kSerialized) metric = serialized(std::move(metric));
  const bool known = std::any_of(study.plugins.begin(), study.plugins.end(),
                                 [&](const PluginRecord& p) { return p.name == m.name && p.file == m.origin; });
  if (!known) {
    PluginRecord record;
    record.name = m.name;
    record.kind = "metric";
    record.version = m.version;
    record.description = m.description;
    record.thread_safety = m.thread_safety;
    record.file = m.origin;
    study.plugins.push_back(record);
  }
  return metric;
}

// `requested_by`: for each scene attribute requested, per metric, the objectives that need it (for
// messages).
void load_objectives(Json& objs, const Registry& registry, const std::vector<InProcessMetric>& in_process, Study& study,
                     std::vector<MetricEntry>& metrics, std::vector<Objective>& objectives, SceneRequest& request,
                     std::map<std::string, std::map<std::string, std::string>>& requested_by) {
  std::set<std::string> objective_names;
  for (std::size_t i = 0; i < objs.size(); ++i) {
    const std::string path = "objectives[" + std::to_string(i) + "]";
    Json& o = objs[i];
    const std::string metric_name = o["metric"];
    check_safe_name(path + ".metric", metric_name);
    const auto own = std::find_if(in_process.begin(), in_process.end(),
                                  [&](const InProcessMetric& m) { return m.name == metric_name; });
    std::shared_ptr<Metric> metric;
    if (own != in_process.end()) {
      // A metric given in-process (Python) under a plugin's name would replace that plugin for
      // this study without a word.
      const std::vector<std::string> plugins = registry.known_names();
      if (std::find(plugins.begin(), plugins.end(), metric_name) != plugins.end()) {
        throw Error("problem", path + ".metric = \"" + metric_name + "\": a metric given in Python (" + own->origin +
                                   ") has the name of the plugin " + metric_name + "; register it under another name");
      }
      metric = create_in_process(*own, o["options"], path, study);
    } else {
      const PluginRecord& record = find_plugin(registry, path + ".metric", metric_name);
      if (record.kind != "metric") {
        throw Error("problem", path + ".metric = \"" + metric_name + "\": '" + metric_name + "' is a " + record.kind +
                                   " plugin, not a metric plugin");
      }
      metric = registry.create_metric(metric_name, o["options"], path, &o["options"]);
      note_plugin(study, registry, metric_name);
    }
    if (!o.contains("name")) o["name"] = metric_name;
    const std::string name = o["name"];
    // An objective's name heads columns of the CSV files: a comma, a quote or a line break would
    // split or shift them.
    if (name.find_first_of(",\"\r\n") != std::string::npos) {
      throw Error("problem", path + ".name = " + render_value(o["name"]) +
                                 ": may not contain a comma, a double quote or a line break (it names CSV columns)");
    }
    if (!objective_names.insert(name).second) {
      throw Error("problem", path + ".name = \"" + name +
                                 "\": duplicate objective name (give each objective a distinct \"name\")");
    }
    if (!std::isfinite(o["weight"].get<double>())) {
      throw Error("problem", path + ".weight = " + render_value(o["weight"]) + ": must be finite");
    }
    for (const std::string& a : metric->specs().scene_attributes) {
      request.attributes.push_back(a);
      std::string& paths = requested_by[a][metric_name];
      paths += (paths.empty() ? "" : ", ") + path;
    }
    // The demanded motion (twist, twist_rate) that joint rates need is not requested here: a
    // scene of motion always carries it, and the Problem names the way out when a scene lacks it.
    Objective objective;
    objective.name = name;
    objective.metric = static_cast<int>(metrics.size());
    objective.sense = o["sense"] == "minimize" ? Sense::kMinimize : Sense::kMaximize;
    objective.weight = o["weight"];
    objectives.push_back(objective);
    metrics.push_back(MetricEntry{metric_name, metric});
  }
}

// The scene's samples: the plugin created (options resolved in place) and built with what the
// metrics request; its lattice declaration checked and its bounding box cached.
// output.timeline names a trajectory of the scene: checked at load, not after the solve.
void check_timeline_option(const Json& resolved, const SampleSet& samples) {
  if (!resolved.contains("output") || !resolved["output"].contains("timeline")) return;
  const std::string label = resolved["output"]["timeline"];
  std::string known;
  for (const SampleGrouping& g : samples.groups) {
    if (g.name != "trajectory") continue;
    for (const std::string& l : g.labels) {
      if (l == label) return;
      known += (known.empty() ? "" : ", ") + l;
    }
  }
  throw Error("problem", "output.timeline = \"" + label + "\": " +
                             (known.empty() ? std::string("the scene has no trajectories (only scenes of recorded motion do)")
                                            : "no trajectory of that name (the scene has: " + known + ")"));
}

std::shared_ptr<SampleSet> build_samples(Json& resolved, const Registry& registry, Study& study,
                                         const SceneRequest& request,
                                         const std::map<std::string, std::map<std::string, std::string>>& requested_by) {
  const std::string scene_name = resolved["scene"]["plugin"];
  find_plugin(registry, "scene.plugin", scene_name);
  std::shared_ptr<Scene> scene =
      registry.create_scene(scene_name, resolved["scene"]["options"], "scene", &resolved["scene"]["options"]);
  note_plugin(study, registry, scene_name);
  std::shared_ptr<SampleSet> samples;
  try {
    samples = std::make_shared<SampleSet>(scene->build(request));
  } catch (const Error& e) {
    // A scene refusing an attribute it lacks names the attribute; the study adds who needs it.
    std::string needed;
    for (const auto& [attribute, by_metric] : requested_by) {
      if (std::string(e.what()).find("'" + attribute + "'") == std::string::npos) continue;
      for (const auto& [metric, paths] : by_metric) {
        needed += "; '" + attribute + "' is needed by " + paths + " (metric '" + metric + "': `hapsyn describe " + metric +
                  "` names the scene it needs)";
      }
    }
    throw Error("problem", std::string("scene.options: ") + e.what() + needed);
  }
  if (samples->size() > kMaxSceneSamples) {
    throw Error("problem", "scene.plugin = \"" + scene_name + "\": the scene has " + std::to_string(samples->size()) +
                               " samples, more than the " + std::to_string(kMaxSceneSamples) +
                               " a study may have; use coarser scene options");
  }
  check_lattice(*samples, scene_name);
  check_groups(*samples, scene_name);
  check_finite_samples(*samples, scene_name);
  check_timeline_option(resolved, *samples);
  if (samples->size() > 0) samples->cache_bounds();
  return samples;
}

// The optional "indicators" section: a reference point with one finite value per objective,
// and a reference front read from a result.json holding the study's objectives.
void load_indicators(Json& resolved, const Problem& problem, Study& study) {
  if (!resolved.contains("indicators")) return;
  const Json section = resolved["indicators"];
  const std::size_t m = problem.objectives().size();
  if (section.contains("reference_point")) {
    const Json& point = section["reference_point"];
    if (point.size() != m) {
      throw Error("problem", "indicators.reference_point = " + render_value(point) + ": must have " + std::to_string(m) +
                                 " values (one per objective)");
    }
    for (std::size_t i = 0; i < m; ++i) {
      const double v = point[i].get<double>();
      if (!std::isfinite(v)) {
        throw Error("problem", "indicators.reference_point[" + std::to_string(i) + "] = " + render_value(point[i]) + ": must be finite");
      }
      study.reference_point.push_back(v);
    }
  }
  if (section.contains("reference_front")) {
    // Relative to the problem file first: `hapsyn run dir/problem.json` from anywhere.
    const std::string path = resolve_problem_path(section["reference_front"].get<std::string>());
    resolved["indicators"]["reference_front"] = path;
    if (!boost::filesystem::exists(path)) {
      // Not written yet (a fresh checkout; compare runs the reference study first): the study
      // is valid, its result.json records why it has no reference indicators.
      study.reference_front_missing = path;
      return;
    }
    Json reference;
    try {
      reference = read_problem_file(path);
    } catch (const Error& e) {
      throw Error("problem", "indicators.reference_front = \"" + path + "\": cannot be read as a result.json (" + e.what() + ")");
    }
    std::vector<std::string> names;
    for (const Objective& o : problem.objectives()) names.push_back(o.name);
    try {
      study.reference_front = front_of_result(reference, names, path);
    } catch (const Error& e) {
      throw Error("problem", std::string("indicators.reference_front: ") + e.what());
    }
    if (study.reference_front.empty()) {
      throw Error("problem", "indicators.reference_front = \"" + path + "\": the front is empty");
    }
  }
}

}  // namespace

Study load_study(const Json& input, const Registry& registry, const std::vector<InProcessMetric>& in_process,
                 const LoadSettings& settings) {
  if (!input.is_object()) throw Error("problem", "the problem must be a JSON object");
  check_json_text_rules(input);
  Json without_design = input;
  without_design.erase("design");
  Json resolved = validate_and_fill(problem_file_schema(), without_design, "");
  const Json design = input.contains("design") ? input.at("design") : Json::object();
  if (!design.is_object()) {
    throw Error("problem", "design = " + render_value(design) + ": must be an object of design variables");
  }

  check_safe_name("name", resolved["name"].get<std::string>());

  Study study;
  // Mechanism.
  const std::string mechanism_name = resolved["mechanism"]["plugin"];
  find_plugin(registry, "mechanism.plugin", mechanism_name);
  std::shared_ptr<Mechanism> mechanism =
      registry.create_mechanism(mechanism_name, resolved["mechanism"]["options"], "mechanism", &resolved["mechanism"]["options"]);
  note_plugin(study, registry, mechanism_name);

  // Design space (before anything expensive: bounds errors are found first).
  Json resolved_design;
  DesignSpace space = build_design_space(design, mechanism->variables(), resolved_design);
  resolved["design"] = resolved_design;

  // Metrics, one per objective.
  std::vector<MetricEntry> metrics;
  std::vector<Objective> objectives;
  SceneRequest request;
  request.threads = settings.threads > 0 ? settings.threads : resolved.value("threads", 0);
  request.progress = settings.progress;
  std::map<std::string, std::map<std::string, std::string>> requested_by;  // attribute -> metric -> objectives
  load_objectives(resolved["objectives"], registry, in_process, study, metrics, objectives, request, requested_by);

  // Solver (created before the scene is built: its options are checked before any work).
  study.solver_plugin = resolved["solver"]["plugin"];
  find_plugin(registry, "solver.plugin", study.solver_plugin);
  study.solver =
      registry.create_solver(study.solver_plugin, resolved["solver"]["options"], "solver", &resolved["solver"]["options"]);
  note_plugin(study, registry, study.solver_plugin);

  if (!study.solver->specs().pareto) check_weights_not_all_zero(resolved["objectives"]);

  // Scene.
  std::shared_ptr<SampleSet> samples = build_samples(resolved, registry, study, request, requested_by);
  study.problem = std::make_shared<Problem>(mechanism_name, mechanism, samples, std::move(metrics),
                                            std::move(objectives), std::move(space));
  try {
    study.solver->check(*study.problem);
  } catch (const Error& e) {
    throw Error("problem", std::string("solver: ") + e.what());
  }
  load_indicators(resolved, *study.problem, study);
  if (resolved["objectives"].size() > 1 && !study.solver->specs().pareto) {
    resolved["aggregation"] = "weighted_sum";
  }
  study.output_directory = resolved["output"].contains("directory")
                               ? resolved["output"]["directory"].get<std::string>()
                               : "results/" + resolved["name"].get<std::string>();
  study.resolved = resolved;
  return study;
}

}  // namespace hapsyn
