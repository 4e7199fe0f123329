// The hapsyn command-line program: run, validate, plugins, describe, scene.
//
// Exit codes: 0 the command did its work (for `run`: result.json written; the solver's outcome
// is its "status"), 1 bad input (problem file, options, plugins, output directory), 2 usage
// error, 3 unexpected internal error.
#include <hapsyn/compare.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/plot.hpp>
#include <hapsyn/problem_file.hpp>
#include <hapsyn/registry.hpp>
#include <hapsyn/study.hpp>
#include <hapsyn/study_runner.hpp>
#include <hapsyn/sweep.hpp>

#include <CLI/CLI.hpp>

#include <boost/filesystem.hpp>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace {

using hapsyn::Json;

hapsyn::Study load(const std::string& file, const std::vector<std::string>& sets, const hapsyn::Registry& registry) {
  Json doc = hapsyn::read_problem_file(file);
  for (const std::string& s : sets) hapsyn::apply_override(doc, s);
  return hapsyn::load_study(doc, registry);
}

std::string format_number(double v) {
  std::ostringstream s;
  s << std::setprecision(6) << v;
  return s.str();
}

void print_summary(const Json& result, std::ostream& out) {
  const Json& problem = result["problem"];
  out << "hapsyn " << result["hapsyn"]["version"].get<std::string>() << " | " << problem["name"].get<std::string>()
      << " | solver " << problem["solver"]["plugin"].get<std::string>() << ", " << result["threads"] << " threads, seed "
      << result["seed"] << "\n";
  out << "status: " << result["status"].get<std::string>();
  if (!result["message"].get<std::string>().empty()) out << " (" << result["message"].get<std::string>() << ")";
  out << "\n";
  auto print_point = [&](const Json& point, const std::string& indent) {
    out << indent << "design:";
    for (auto it = point["design"].begin(); it != point["design"].end(); ++it) {
      const std::string unit = problem["design"][it.key()].value("unit", "");
      out << " " << it.key() << " = " << it.value().dump() << (unit.empty() ? "" : " " + unit);
    }
    out << "\n" << indent << "objectives:";
    for (auto it = point["objectives"].begin(); it != point["objectives"].end(); ++it) {
      out << " " << it.key() << " = " << format_number(it.value().get<double>());
    }
    out << "\n";
  };
  if (result.contains("best")) {
    out << "best\n";
    print_point(result["best"], "  ");
  }
  if (result.contains("front")) {
    out << "front: " << result["front"].size() << " non-dominated points\n";
    for (const Json& p : result["front"]) print_point(p, "  ");
  }
  // A solver's own summary lines (ga: the cluster table of its runs).
  if (result["statistics"].is_object() && result["statistics"].contains("report")) {
    for (const Json& line : result["statistics"]["report"]) out << line.get<std::string>() << "\n";
  }
  out << "evaluations: " << result["evaluations"]["designs"] << " designs, " << result["evaluations"]["samples"]
      << " sample solves; wall time " << format_number(result["wall_time_s"].get<double>()) << " s\n";
  out << "result: " << result["output_directory"].get<std::string>() << "/result.json\n";
}

std::string schema_type(const Json& s) {
  if (!s.contains("type")) return "any";
  if (s["type"].is_string()) return s["type"];
  std::string t;
  for (const Json& x : s["type"]) t += (t.empty() ? "" : "|") + x.get<std::string>();
  return t;
}

void describe_properties(const Json& schema, const std::string& prefix, std::ostream& out) {
  if (!schema.contains("properties")) return;
  for (auto it = schema["properties"].begin(); it != schema["properties"].end(); ++it) {
    const Json& p = it.value();
    out << "  " << std::left << std::setw(22) << (prefix + it.key()) << " " << std::setw(8) << schema_type(p) << " default "
        << std::setw(10) << (p.contains("default") ? p["default"].dump() : std::string("(required)")) << " "
        << std::setw(6) << p.value("unit", "") << " " << p.value("description", "");
    std::string rules;
    if (p.contains("minimum")) rules += " >= " + p["minimum"].dump();
    if (p.contains("exclusiveMinimum")) rules += " > " + p["exclusiveMinimum"].dump();
    if (p.contains("maximum")) rules += " <= " + p["maximum"].dump();
    if (p.contains("exclusiveMaximum")) rules += " < " + p["exclusiveMaximum"].dump();
    if (p.contains("enum")) rules += " one of " + p["enum"].dump();
    if (!rules.empty()) out << " [" << rules.substr(1) << "]";
    out << "\n";
    if (schema_type(p) == "object") describe_properties(p, prefix + it.key() + ".", out);
  }
}

int describe(const std::string& name, const hapsyn::Registry& registry) {
  const hapsyn::PluginRecord& r = registry.find(name);
  std::cout << r.name << " (" << r.kind << " plugin, version " << r.version << ")\n"
            << "  " << r.description << "\n"
            << "  file: " << r.file << "\n"
            << "  thread safety: " << r.thread_safety << "\n";
  if (r.schema.contains("description")) std::cout << "  " << r.schema["description"].get<std::string>() << "\n";
  std::cout << "options:\n";
  if (!r.schema.contains("properties") || r.schema["properties"].empty()) std::cout << "  (none)\n";
  describe_properties(r.schema, "", std::cout);
  if (r.kind == "mechanism") {
    auto mechanism = registry.create_mechanism(name, Json::object(), "mechanism");
    std::cout << "design variables (default bounds; hard limits):\n";
    for (const hapsyn::VariableDecl& v : mechanism->variables()) {
      auto list = [](const std::vector<double>& x) {
        std::string s;
        for (double d : x) s += (s.empty() ? "" : ", ") + format_number(d);
        return x.size() == 1 ? s : "[" + s + "]";
      };
      std::cout << "  " << std::left << std::setw(6) << v.name << (v.size > 1 ? "[" + std::to_string(v.size) + "]" : "")
                << (v.integer ? " integer" : " real") << " [" << list(v.default_lower) << ", " << list(v.default_upper)
                << "] " << v.unit << "; limits [" << list(v.hard_lower) << ", " << list(v.hard_upper) << "]  "
                << v.description << "\n";
    }
    const auto constraints = mechanism->constraints();
    if (!constraints.empty()) {
      std::cout << "design constraints (g <= 0):\n";
      for (const auto& c : constraints) std::cout << "  " << c.name << ": " << c.description << "\n";
    }
  }
  return 0;
}

int list_plugins(const hapsyn::Registry& registry) {
  std::vector<std::string> errors;
  const auto records = registry.list(&errors);
  std::cout << std::left << std::setw(16) << "NAME" << std::setw(11) << "KIND" << std::setw(10) << "VERSION" << "FILE\n";
  for (const auto& r : records) {
    std::cout << std::left << std::setw(16) << r.name << std::setw(11) << r.kind << std::setw(10) << r.version << r.file
              << "\n";
  }
  if (records.empty()) {
    std::cout << "(no plugins found; search path:";
    for (const auto& d : registry.search_path()) std::cout << " " << d;
    std::cout << ")\n";
  }
  for (const std::string& e : errors) std::cerr << "hapsyn: warning: " << e << "\n";
  return 0;
}


// ---- hapsyn scene: build a problem file's scene alone, summarize, export CSV, plot density ----

// Shortest text that reads back as the same double.
std::string exact_number(double v) {
  char buffer[32];
  const auto r = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, r.ptr);
}

// CSV: the pose columns, then every attribute (alphabetical) flattened as name[i] (name alone
// for a single column).
std::string samples_csv(const hapsyn::SampleSet& set) {
  std::string text;
  for (std::size_t c = 0; c < set.coordinates.size(); ++c) text += (c ? "," : "") + set.coordinates[c];
  for (const auto& [name, values] : set.attributes) {
    for (Eigen::Index c = 0; c < values.cols(); ++c) {
      text += "," + (values.cols() == 1 ? name : name + "[" + std::to_string(c) + "]");
    }
  }
  text += "\n";
  for (int i = 0; i < set.size(); ++i) {
    for (int c = 0; c < set.dimension(); ++c) text += (c ? "," : "") + exact_number(set.pose(i)[c]);
    for (const auto& [name, values] : set.attributes) {
      for (Eigen::Index c = 0; c < values.cols(); ++c) text += "," + exact_number(values(i, c));
    }
    text += "\n";
  }
  return text;
}

// Reachability density per lattice position (reachable orientations / orientations tried), as
// slices through the shoulder along x_S (x_S points down: each slice is one height), written
// as gnuplot data + script and rendered to density_slices.png (Fennel 2022, Figure 3).
void plot_density(const hapsyn::SampleSet& set, const std::string& directory) {
  namespace fs = boost::filesystem;
  if (!set.lattice) {
    throw hapsyn::Error("scene", "--plot needs a lattice scene (one that declares a SampleLattice), e.g. human_arm");
  }
  hapsyn::LatticeField density;
  density.per_axis = set.lattice->per_axis;
  density.step = set.lattice->step;
  const double orientations = set.lattice->candidates_per_point;
  const std::size_t n = static_cast<std::size_t>(density.per_axis);
  density.values.assign(n * n * n, 0.0);
  for (const long long index : set.lattice->index_of_sample) density.values[static_cast<std::size_t>(index)] += 1.0 / orientations;
  fs::create_directories(directory);
  const std::string why = hapsyn::plot_lattice_slices(
      directory, "density_slices", "reachable orientations / " + std::to_string(static_cast<int>(orientations)) +
                                       " per position; slices by height above the shoulder",
      density, std::max(1e-9, *std::max_element(density.values.begin(), density.values.end())));
  if (!why.empty()) {
    throw hapsyn::Error("scene", "--plot: " + why + "; " + directory + "/density_slices.dat and .gp were written");
  }
}

int scene_command(const std::string& file, const std::vector<std::string>& sets, const std::string& csv,
                  const std::string& plot, int threads, bool threads_given, const std::vector<std::string>& attributes,
                  const hapsyn::Registry& registry) {
  Json doc = hapsyn::read_problem_file(file);
  for (const std::string& s : sets) hapsyn::apply_override(doc, s);
  if (!doc.is_object() || !doc.contains("scene")) throw hapsyn::Error("problem", "scene: missing");
  const Json& scene = doc["scene"];
  if (!scene.is_object()) {
    throw hapsyn::Error("problem", "scene = " + hapsyn::render_value(scene) + ": must be an object {\"plugin\", \"options\"}");
  }
  for (auto it = scene.begin(); it != scene.end(); ++it) {
    if (it.key() != "plugin" && it.key() != "options") {
      throw hapsyn::Error("problem", "scene." + it.key() + ": unknown key; known keys: options, plugin");
    }
  }
  if (!scene.contains("plugin") || !scene["plugin"].is_string()) {
    throw hapsyn::Error("problem", "scene.plugin = " + hapsyn::render_value(scene.value("plugin", Json())) +
                                       ": must be a plugin name (string)");
  }
  const std::string name = scene["plugin"];
  Json options = scene.value("options", Json::object());
  if (threads_given) {
    const hapsyn::PluginRecord& record = registry.find(name);
    if (record.schema.contains("properties") && record.schema["properties"].contains("threads") && options.is_object()) {
      options["threads"] = threads;
    }
  }
  const auto plugin = registry.create_scene(name, options, "scene");
  hapsyn::SceneRequest request;
  request.attributes = attributes;
  const auto start = std::chrono::steady_clock::now();
  const hapsyn::SampleSet set = plugin->build(request);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "scene " << name << ": " << set.size() << " samples (";
  for (std::size_t c = 0; c < set.coordinates.size(); ++c) std::cout << (c ? ", " : "") << set.coordinates[c];
  std::cout << "; unit " << set.unit << ") in " << format_number(seconds) << " s\n";
  if (!set.attributes.empty()) {
    std::cout << "attributes:";
    for (const auto& [attribute, values] : set.attributes) std::cout << " " << attribute << "[" << values.cols() << "]";
    std::cout << "\n";
  }
  for (auto it = set.info.begin(); it != set.info.end(); ++it) {
    std::cout << "  " << it.key() << ": "
              << (it.value().is_string() ? it.value().get<std::string>() : it.value().dump()) << "\n";
  }
  if (!csv.empty()) {
    const boost::filesystem::path path(csv);
    if (path.has_parent_path()) boost::filesystem::create_directories(path.parent_path());
    hapsyn::write_file_atomically(csv, samples_csv(set));
    std::cout << "csv: " << csv << " (" << set.size() << " rows)\n";
  }
  if (!plot.empty()) {
    plot_density(set, plot);
    std::cout << "plot: " << plot << "/density_slices.png\n";
  }
  return 0;
}

}  // namespace

void print_sweep(const Json& summary, std::ostream& out) {
  out << "sweep: " << summary["runs"].size() << " runs; reference " << summary["reference"]["overrides"].dump()
      << " (" << format_number(summary["reference"]["run_time_s"].get<double>()) << " s)\n";
  std::vector<std::string> keys;
  if (!summary["runs"].empty()) {
    for (auto it = summary["runs"][0]["values"].begin(); it != summary["runs"][0]["values"].end(); ++it) keys.push_back(it.key());
  }
  for (const auto& k : keys) out << std::left << std::setw(std::max<std::size_t>(k.size(), 8) + 2) << k;
  out << std::setw(12) << "time [s]" << std::setw(12) << "solve [s]" << std::setw(14) << "samples" << std::setw(13) << "obj. error" << std::setw(14)
      << "design dist." << std::setw(10) << "igd" << "status\n";
  auto cell = [](const Json& v) { return v.is_null() ? std::string("-") : format_number(v.get<double>()); };
  for (const Json& r : summary["runs"]) {
    for (const auto& k : keys) out << std::left << std::setw(std::max<std::size_t>(k.size(), 8) + 2) << r["values"][k].dump();
    out << std::setw(12) << format_number(r["run_time_s"].get<double>()) << std::setw(12)
        << format_number(r["solve_time_s"].get<double>()) << std::setw(14)
        << r["evaluations"]["samples"].dump() << std::setw(13) << cell(r["errors"]["objective_error"]) << std::setw(14)
        << cell(r["errors"]["design_distance"]) << std::setw(10) << cell(r["errors"]["igd"])
        << r["status"].get<std::string>() << "\n";
  }
  out << "written: " << summary["output_directory"].get<std::string>() << "/sweep.csv, sweep.json\n";
}

int main(int argc, char** argv) {
  CLI::App app{"hapsyn: optimization-driven design of haptic interfaces and robot mechanisms"};
  app.set_version_flag("--version", std::string("hapsyn ") + hapsyn::version());
  app.require_subcommand(1);

  std::string file;
  std::vector<std::string> sets;
  std::string out_dir;
  int threads = 0;
  std::uint64_t seed = 0;
  bool quiet = false;

  CLI::App* run = app.add_subcommand("run", "Run a study and write result.json (+ samples.csv)");
  run->add_option("file", file, "Problem file (JSON)")->required();
  run->add_option("--set", sets, "Override a key: path=value (value read as JSON when it parses, else a string)");
  run->add_option("--out", out_dir, "Output directory (overrides output.directory)");
  run->add_option("--threads", threads, "Worker threads (default: all cores)")->check(CLI::NonNegativeNumber);
  CLI::Option* seed_option = run->add_option("--seed", seed, "Random seed (default: from the file, else drawn)");
  run->add_flag("--quiet,-q", quiet, "No progress output");
  bool resume = false, force = false;
  run->add_flag("--resume", resume, "Continue from the output directory's checkpoint (solvers that checkpoint: ga)");
  run->add_flag("--force", force, "Overwrite a finished study (an existing result.json) in the output directory");

  CLI::App* validate = app.add_subcommand("validate", "Check a problem file completely without running it");
  validate->add_option("file", file, "Problem file (JSON)")->required();
  validate->add_option("--set", sets, "Override a key: path=value");

  app.add_subcommand("plugins", "List the plugins found (name, kind, version, file)");

  std::string plugin_name;
  CLI::App* describe_cmd = app.add_subcommand("describe", "Show a plugin's options, defaults and units");
  describe_cmd->add_option("name", plugin_name, "Plugin name")->required();

  std::string csv_out, plot_dir;
  std::vector<std::string> scene_attributes;
  CLI::App* scene_cmd = app.add_subcommand(
      "scene", "Build a problem file's scene alone: summary, CSV export, reachability-density plots");
  scene_cmd->add_option("file", file, "Problem or scene file (JSON); only its \"scene\" section is read")->required();
  scene_cmd->add_option("--set", sets, "Override a key: path=value (e.g. scene.options.lattice_step=0.2)");
  scene_cmd->add_option("--csv", csv_out, "Write the samples as CSV: pose columns, then every attribute as name[i]");
  scene_cmd->add_option("--plot", plot_dir, "Write reachability-density slices (gnuplot) into this directory");
  CLI::Option* scene_threads =
      scene_cmd->add_option("--threads", threads, "Threads for building (sets scene.options.threads when the scene has it)")
          ->check(CLI::NonNegativeNumber);
  scene_cmd->add_option("--attribute", scene_attributes, "Request a per-sample attribute (e.g. M_v, M_a); repeatable");

  std::vector<std::string> vary, reference;
  std::string sweep_out = "results/sweep";
  std::uint64_t sweep_seed = 1;
  CLI::App* sweep_cmd = app.add_subcommand(
      "sweep", "Run a study across values of some keys; error against a reference run versus time");
  sweep_cmd->add_option("file", file, "Problem file (JSON)")->required();
  sweep_cmd->add_option("--vary", vary,
                        "path[,path...]=v1,v2,...: keys set together to each value (repeatable: a grid)")
      ->required();
  sweep_cmd->add_option("--reference", reference,
                        "path=value overrides of the reference run (repeatable; default: the last combination)");
  sweep_cmd->add_option("--set", sets, "Override a key in every run: path=value");
  sweep_cmd->add_option("--out", sweep_out, "Output directory (sweep.csv, sweep.json, sweep.png/svg, one folder per run)");
  sweep_cmd->add_option("--threads", threads, "Worker threads per run (default: all cores)")->check(CLI::NonNegativeNumber);
  sweep_cmd->add_option("--seed", sweep_seed, "Random seed of every run");
  bool sweep_progress = false;
  sweep_cmd->add_flag("--progress", sweep_progress, "Show each run's progress");

  hapsyn::CompareOptions compare_options;
  CLI::App* compare_cmd = app.add_subcommand(
      "compare", "Run several studies on this machine: one table (front quality, evaluations, time) and plots");
  compare_cmd->add_option("files", compare_options.files, "Problem files (JSON), run in this order")->required();
  compare_cmd->add_option("--set", compare_options.overrides, "Override a key in every study: path=value");
  compare_cmd->add_option("--out", compare_options.output_directory, "Output directory (one folder per study)");
  compare_cmd->add_option("--threads", compare_options.threads, "Worker threads per study")->check(CLI::NonNegativeNumber);
  compare_cmd->add_option("--seed", seed, "Random seed of every study");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  try {
    hapsyn::Registry registry;
    if (*run) {
      hapsyn::Study study = load(file, sets, registry);
      hapsyn::RunOptions options;
      options.output_directory = out_dir;
      options.threads = threads;
      if (*seed_option) options.seed = seed;
      options.quiet = quiet;
      options.resume = resume;
      options.force = force;
      const Json result = hapsyn::run_study(study, options);
      print_summary(result, std::cout);
      return 0;
    }
    if (*validate) {
      hapsyn::Study study = load(file, sets, registry);
      std::cout << file << ": valid (" << study.problem->dimension() << " free design variables, "
                << study.problem->samples().size() << " samples, " << study.problem->objectives().size()
                << " objective(s), solver " << study.solver_plugin << ")\n";
      return 0;
    }
    if (app.got_subcommand("plugins")) return list_plugins(registry);
    if (*describe_cmd) return describe(plugin_name, registry);
    if (*sweep_cmd) {
      Json doc = hapsyn::read_problem_file(file);
      for (const std::string& s : sets) hapsyn::apply_override(doc, s);
      hapsyn::SweepOptions options;
      for (const std::string& v : vary) options.axes.push_back(hapsyn::parse_sweep_axis(v));
      options.reference = reference;
      options.output_directory = sweep_out;
      options.threads = threads;
      options.seed = sweep_seed;
      options.quiet = !sweep_progress;
      print_sweep(hapsyn::run_sweep(doc, options, registry), std::cout);
      return 0;
    }
    if (*compare_cmd) {
      if (compare_cmd->count("--seed") > 0) compare_options.seed = seed;
      hapsyn::print_compare(hapsyn::run_compare(compare_options, registry), std::cout);
      return 0;
    }
    if (*scene_cmd) {
      return scene_command(file, sets, csv_out, plot_dir, threads, scene_threads->count() > 0, scene_attributes, registry);
    }
  } catch (const hapsyn::Error& e) {
    std::cerr << "hapsyn: error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "hapsyn: internal error: " << e.what() << "\n";
    return 3;
  }
  return 0;
}
