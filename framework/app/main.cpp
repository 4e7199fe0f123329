// The hapsyn command-line program: run, validate, plugins, describe.
//
// Exit codes: 0 the command did its work (for `run`: result.json written; the solver's outcome
// is its "status"), 1 bad input (problem file, options, plugins, output directory), 2 usage
// error, 3 unexpected internal error.
#include <hapsyn/error.hpp>
#include <hapsyn/registry.hpp>
#include <hapsyn/study.hpp>

#include <CLI/CLI.hpp>

#include <cmath>
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

}  // namespace

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

  CLI::App* validate = app.add_subcommand("validate", "Check a problem file completely without running it");
  validate->add_option("file", file, "Problem file (JSON)")->required();
  validate->add_option("--set", sets, "Override a key: path=value");

  app.add_subcommand("plugins", "List the plugins found (name, kind, version, file)");

  std::string plugin_name;
  CLI::App* describe_cmd = app.add_subcommand("describe", "Show a plugin's options, defaults and units");
  describe_cmd->add_option("name", plugin_name, "Plugin name")->required();

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
  } catch (const hapsyn::Error& e) {
    std::cerr << "hapsyn: error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "hapsyn: internal error: " << e.what() << "\n";
    return 3;
  }
  return 0;
}
