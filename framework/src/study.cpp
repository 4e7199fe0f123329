#include <hapsyn/design_space.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/parallel.hpp>
#include <hapsyn/schema.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/problem_file.hpp>
#include <hapsyn/study.hpp>
#include <hapsyn/maps.hpp>
#include <hapsyn/plugin.hpp>

#include <boost/filesystem.hpp>

#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <random>
#include <set>
#include <sstream>

namespace hapsyn {

namespace fs = boost::filesystem;

namespace {

// The framework's own rules for a problem file, in the same schema language as the plugins'
// (so its errors read the same way). "design" has variable names as keys and is checked by
// hand against the mechanism's declared variables.
const char* const kProblemSchema = R"json({
  "type": "object",
  "properties": {
    "name": {"type": "string", "description": "Study name (used for the default output directory)", "default": "study"},
    "description": {"type": "string", "description": "Free text", "default": ""},
    "mechanism": {"type": "object", "required": ["plugin"], "properties": {
        "plugin": {"type": "string", "description": "Mechanism plugin name"},
        "options": {"type": "object", "description": "Options of the mechanism plugin", "default": {}}}},
    "scene": {"type": "object", "required": ["plugin"], "properties": {
        "plugin": {"type": "string", "description": "Scene plugin name"},
        "options": {"type": "object", "description": "Options of the scene plugin", "default": {}}}},
    "objectives": {"type": "array", "minItems": 1, "items": {"type": "object", "required": ["metric"], "properties": {
        "metric": {"type": "string", "description": "Metric plugin name"},
        "name": {"type": "string", "description": "Label (default: the metric name)"},
        "sense": {"type": "string", "enum": ["maximize", "minimize"], "default": "maximize"},
        "weight": {"type": "number", "description": "Weight in a weighted-sum study", "default": 1.0},
        "options": {"type": "object", "description": "Options of the metric plugin", "default": {}}}}},
    "solver": {"type": "object", "required": ["plugin"], "properties": {
        "plugin": {"type": "string", "description": "Solver plugin name"},
        "options": {"type": "object", "description": "Options of the solver plugin", "default": {}}}},
    "output": {"type": "object", "default": {}, "properties": {
        "directory": {"type": "string", "description": "Output directory (default results/<name>)"},
        "samples_csv": {"type": "boolean", "description": "Write samples.csv for the best design", "default": true},
        "maps": {"type": "boolean", "description": "Write maps.csv: every objective per workspace position for the best design", "default": true},
        "plots": {"type": "boolean", "description": "Render the position maps with gnuplot (map_<objective>.png)", "default": false}}},
    "indicators": {"type": "object", "description": "Front-quality indicators written into result.json", "properties": {
        "reference_front": {"type": "string", "description": "result.json of a study whose front is the reference (IGD, GD, domination gaps)"},
        "reference_point": {"type": "array", "items": {"type": "number"}, "description": "Hypervolume reference point, one value per objective (natural units), worse than every front point"}}},
    "seed": {"type": "integer", "minimum": 0, "description": "Random seed (default: drawn and recorded)"},
    "threads": {"type": "integer", "minimum": 0, "description": "Worker threads (0 = all cores)"}
  },
  "required": ["mechanism", "scene", "objectives", "solver"]
})json";

// The optional "indicators" section: a reference point with one finite value per objective,
// and a reference front read from a result.json holding the study's objectives.
void load_indicators(const Json& resolved, const Problem& problem, Study& study) {
  if (!resolved.contains("indicators")) return;
  const Json& section = resolved["indicators"];
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
    const std::string path = section["reference_front"];
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

Study load_study(const Json& input, const Registry& registry) {
  if (!input.is_object()) throw Error("problem", "the problem must be a JSON object");
  Json without_design = input;
  without_design.erase("design");
  Json resolved = validate_and_fill(Json::parse(kProblemSchema), without_design, "");
  const Json design = input.contains("design") ? input.at("design") : Json::object();
  if (!design.is_object()) {
    throw Error("problem", "design = " + render_value(design) + ": must be an object of design variables");
  }

  Study study;
  auto note = [&](const std::string& name) {
    const PluginRecord& r = registry.find(name);
    for (const PluginRecord& p : study.plugins) {
      if (p.file == r.file) return;
    }
    study.plugins.push_back(r);
  };

  // Mechanism.
  const std::string mechanism_name = resolved["mechanism"]["plugin"];
  std::shared_ptr<Mechanism> mechanism =
      registry.create_mechanism(mechanism_name, resolved["mechanism"]["options"], "mechanism");
  resolved["mechanism"]["options"] = registry.resolve_options(mechanism_name, resolved["mechanism"]["options"], "mechanism.options");
  note(mechanism_name);

  // Design space (before anything expensive: bounds errors are found first).
  Json resolved_design;
  DesignSpace space = build_design_space(design, mechanism->variables(), resolved_design);
  resolved["design"] = resolved_design;

  // Metrics, one per objective.
  std::vector<MetricEntry> metrics;
  std::vector<Objective> objectives;
  std::set<std::string> objective_names;
  SceneRequest request;
  Json& objs = resolved["objectives"];
  for (std::size_t i = 0; i < objs.size(); ++i) {
    const std::string path = "objectives[" + std::to_string(i) + "]";
    Json& o = objs[i];
    const std::string metric_name = o["metric"];
    const PluginRecord& record = registry.find(metric_name);
    if (record.kind != "metric") {
      throw Error("problem", path + ".metric = \"" + metric_name + "\": '" + metric_name + "' is a " + record.kind +
                                 " plugin, not a metric plugin");
    }
    std::shared_ptr<Metric> metric = registry.create_metric(metric_name, o["options"], path);
    o["options"] = registry.resolve_options(metric_name, o["options"], path + ".options");
    note(metric_name);
    if (!o.contains("name")) o["name"] = metric_name;
    const std::string name = o["name"];
    if (!objective_names.insert(name).second) {
      throw Error("problem", path + ".name = \"" + name +
                                 "\": duplicate objective name (give each objective a distinct \"name\")");
    }
    if (!std::isfinite(o["weight"].get<double>())) {
      throw Error("problem", path + ".weight = " + render_value(o["weight"]) + ": must be finite");
    }
    for (const std::string& a : metric->scene_attributes()) request.attributes.push_back(a);
    Objective objective;
    objective.name = name;
    objective.metric = static_cast<int>(metrics.size());
    objective.sense = o["sense"] == "minimize" ? Sense::kMinimize : Sense::kMaximize;
    objective.weight = o["weight"];
    objectives.push_back(objective);
    metrics.push_back(MetricEntry{metric_name, metric});
  }

  // Solver (created before the scene is built: its options are checked before any work).
  study.solver_plugin = resolved["solver"]["plugin"];
  study.solver = registry.create_solver(study.solver_plugin, resolved["solver"]["options"], "solver");
  resolved["solver"]["options"] = registry.resolve_options(study.solver_plugin, resolved["solver"]["options"], "solver.options");
  note(study.solver_plugin);

  // Scene.
  const std::string scene_name = resolved["scene"]["plugin"];
  std::shared_ptr<Scene> scene = registry.create_scene(scene_name, resolved["scene"]["options"], "scene");
  resolved["scene"]["options"] = registry.resolve_options(scene_name, resolved["scene"]["options"], "scene.options");
  note(scene_name);
  std::shared_ptr<SampleSet> samples;
  try {
    samples = std::make_shared<SampleSet>(scene->build(request));
  } catch (const Error& e) {
    throw Error("problem", std::string("scene.options: ") + e.what());
  }

  check_lattice(*samples, scene_name);
  if (samples->size() > 0) samples->cache_bounds();
  study.problem = std::make_shared<Problem>(mechanism_name, mechanism, samples, std::move(metrics),
                                            std::move(objectives), std::move(space));
  try {
    study.solver->check(*study.problem);
  } catch (const Error& e) {
    throw Error("problem", std::string("solver: ") + e.what());
  }
  study.solver->prepare_sub_solvers(*study.problem, registry);
  study.registry = &registry;
  load_indicators(resolved, *study.problem, study);
  if (objs.size() > 1 && !study.solver->pareto()) {
    resolved["aggregation"] = "weighted_sum";
  }
  study.output_directory = resolved["output"].contains("directory")
                               ? resolved["output"]["directory"].get<std::string>()
                               : "results/" + resolved["name"].get<std::string>();
  study.resolved = resolved;
  return study;
}

namespace {

Json point_to_json(const Problem& problem, const SolutionPoint& p) {
  Json j;
  j["design"] = problem.design_to_json(p.design);
  Json objectives = Json::object();
  for (std::size_t i = 0; i < problem.objectives().size(); ++i) objectives[problem.objectives()[i].name] = p.objectives[i];
  j["objectives"] = objectives;
  j["score"] = p.score;
  return j;
}

}  // namespace

Json run_study(Study& study, const RunOptions& options) {
  Json& resolved = study.resolved;
  const int threads = options.threads > 0 ? options.threads
                      : resolved.contains("threads") && resolved["threads"].get<int>() > 0 ? resolved["threads"].get<int>()
                                                                                            : hardware_threads();
  const std::string out_dir = options.output_directory.empty() ? study.output_directory : options.output_directory;
  const fs::path result_file = fs::path(out_dir) / "result.json";
  const fs::path checkpoint_file = fs::path(out_dir) / "checkpoint.json";

  // A finished study is never overwritten by accident.
  if (fs::exists(result_file) && !options.force) {
    if (options.resume) {
      throw Error("output", result_file.string() + ": the study in " + out_dir +
                                " has finished; there is nothing to resume (pass --force to run it again)");
    }
    throw Error("output", out_dir + " already holds a finished study (" + result_file.string() +
                              "); pass --force to overwrite it, or --out for another directory");
  }

  std::uint64_t seed;
  std::optional<std::uint64_t> checkpoint_seed;
  if (options.resume && !options.force && fs::exists(checkpoint_file)) {
    Json checkpoint;
    try {
      std::ifstream in(checkpoint_file.string());
      checkpoint = Json::parse(in);
    } catch (const std::exception& e) {
      throw Error("output", checkpoint_file.string() + ": cannot be read as a checkpoint (" + e.what() +
                                "); delete it, or run without --resume");
    }
    if (!checkpoint.is_object() || !checkpoint.contains("seed") || !checkpoint["seed"].is_number_unsigned()) {
      throw Error("output", checkpoint_file.string() + ": not a checkpoint (no \"seed\"); delete it, or run without --resume");
    }
    checkpoint_seed = checkpoint["seed"].get<std::uint64_t>();
  }
  if (options.seed) {
    seed = *options.seed;
    if (checkpoint_seed && *checkpoint_seed != seed) {
      throw Error("output", "--seed " + std::to_string(seed) + ": the checkpoint " + checkpoint_file.string() +
                                " was written with seed " + std::to_string(*checkpoint_seed) +
                                "; resume with that seed (or without --seed)");
    }
  } else if (checkpoint_seed) {
    seed = *checkpoint_seed;
  } else if (resolved.contains("seed")) {
    seed = resolved["seed"].get<std::uint64_t>();
  } else {
    seed = std::random_device{}();
  }

  // Refuse an unusable output directory before any work is done.
  boost::system::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec || !fs::is_directory(out_dir)) {
    throw Error("output", "cannot create the output directory " + out_dir + (ec ? ": " + ec.message() : ""));
  }
  if (::access(out_dir.c_str(), W_OK) != 0) {
    throw Error("output", "the output directory " + out_dir + " is not writable: " + std::strerror(errno));
  }

  std::ofstream log((fs::path(out_dir) / "run.log").string(), options.resume ? std::ios::app : std::ios::trunc);
  log << "hapsyn " << version() << " " << (options.resume ? "resume" : "run") << " " << resolved["name"].get<std::string>()
      << " at " << iso_time_now() << ", seed " << seed << ", " << threads << " threads\n";
  log.flush();

  SolverContext context;
  context.threads = threads;
  context.seed = seed;
  context.progress = options.quiet ? nullptr : &std::cerr;
  context.output_directory = out_dir;
  context.registry = study.registry;
  context.log = log ? &log : nullptr;
  context.checkpoint_file = checkpoint_file.string();
  context.resume = options.resume && !options.force;

  const std::string started = iso_time_now();
  const auto t0 = std::chrono::steady_clock::now();
  SolverResult result = study.solver->solve(*study.problem, context);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  Json doc;
  doc["hapsyn"] = {{"version", version()}, {"plugin_api", HAPSYN_PLUGIN_API_VERSION}};
  doc["problem"] = resolved;
  Json plugins = Json::array();
  for (const PluginRecord& p : study.plugins) {
    plugins.push_back({{"name", p.name}, {"kind", p.kind}, {"version", p.version}, {"file", p.file}});
  }
  doc["plugins"] = plugins;
  doc["seed"] = seed;
  doc["threads"] = threads;
  doc["machine"] = machine_info();
  doc["started"] = started;
  doc["wall_time_s"] = wall;
  doc["status"] = to_string(result.status);
  doc["message"] = result.message;
  doc["evaluations"] = {{"designs", result.design_evaluations}, {"samples", result.sample_evaluations}};
  doc["samples_in_scene"] = study.problem->samples().size();
  doc["scene"] = study.problem->samples().info;
  if (result.best) doc["best"] = point_to_json(*study.problem, *result.best);
  if (!result.front.empty()) {
    Json front = Json::array();
    for (const SolutionPoint& p : result.front) front.push_back(point_to_json(*study.problem, p));
    doc["front"] = front;
  }
  doc["statistics"] = result.statistics;
  if (!result.front.empty() || !study.reference_front.empty() || !study.reference_point.empty() ||
      !study.reference_front_missing.empty()) {
    IndicatorInputs in;
    for (const Objective& o : study.problem->objectives()) {
      in.names.push_back(o.name);
      in.senses.push_back(o.sense);
    }
    for (const SolutionPoint& p : result.front) in.front.push_back(p.objectives);
    if (result.best) in.best = &result.best->objectives;
    in.reference_front = study.reference_front;
    in.reference_point = study.reference_point;
    Json indicators = front_indicators(in);
    if (!study.reference_front_missing.empty()) {
      indicators["reference_front_missing"] = study.reference_front_missing +
                                              " does not exist: run the reference study first for GD, IGD and domination gaps";
    }
    indicators["evaluations"] = doc["evaluations"];
    indicators["wall_time_s"] = wall;
    doc["indicators"] = indicators;
  }
  doc["files"] = Json::object();
  const bool want_samples = options.write_samples && resolved["output"].value("samples_csv", true);
  const bool want_maps = options.write_samples && resolved["output"].value("maps", true);
  if (result.best && (want_samples || want_maps)) {
    const SampleRecords records = record_samples(*study.problem, result.best->design);
    if (want_samples) {
      write_file_atomically((fs::path(out_dir) / "samples.csv").string(), samples_csv(*study.problem, records));
      doc["files"]["samples"] = "samples.csv";
    }
    if (want_maps) {
      const PositionMaps maps = position_maps(*study.problem, records);
      write_file_atomically((fs::path(out_dir) / "maps.csv").string(), maps_csv(maps));
      doc["files"]["maps"] = "maps.csv";
      if (resolved["output"].value("plots", false)) {
        std::string message;
        doc["files"]["plots"] = plot_maps(maps, out_dir, message);
        if (!message.empty()) doc["plot_message"] = message;
      }
    }
  }
  doc["output_directory"] = out_dir;
  write_file_atomically(result_file.string(), doc.dump(2) + "\n");
  // The study is finished: its checkpoint has served.
  boost::system::error_code remove_error;
  fs::remove(checkpoint_file, remove_error);
  if (log) log << "finished: status " << doc["status"].get<std::string>() << ", wall time " << wall << " s\n";
  return doc;
}

}  // namespace hapsyn
