// The hapsyn command-line program: run, validate, plugins, describe, scene, view.
//
// Exit codes: 0 the command did its work (for `run`: result.json written; the solver's outcome
// is its "status"), 1 bad input (problem file, options, plugins, output directory) or an output
// that could not be written, 2 usage error, 3 unexpected internal error, 4 `run` stopped on
// request (SIGINT, SIGTERM, SIGUSR1): result.json holds the best so far with status "stopped",
// the checkpoint is kept and `hapsyn run FILE --resume` continues (a job script can tell this
// from a finished run and requeue); likewise `sweep` and `compare` stopped (the same command
// continues them, reusing the finished runs). A second signal ends the process at once with 128 + signal.
#include <hapsyn/internal/compare.hpp>
#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/internal/groups.hpp>
#include <hapsyn/internal/merge.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/parallel.hpp>
#include <hapsyn/internal/plot.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/scene_export.hpp>
#include <hapsyn/internal/study.hpp>
#include <hapsyn/internal/study_runner.hpp>
#include <hapsyn/internal/sweep.hpp>

#include "ranks.hpp"
#include "summary.hpp"
#include "reference_command.hpp"
#if HAPSYN_WITH_VIEW
#include "report_command.hpp"
#include "view_command.hpp"
#endif

#include <CLI/CLI.hpp>

#include <boost/filesystem.hpp>

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

namespace {

using hapsyn::Json;
using hapsyn_cli::format_number;
using hapsyn_cli::print_summary;

// ---- graceful stop: SIGINT, SIGTERM and SIGUSR1 (which SLURM sends before a time limit) ----

// Set by the first signal; solvers poll it, write their checkpoint and return "stopped".
std::atomic<bool> stop_requested{false};
// Under MPI with several ranks: the stop every rank agreed on (set inside task farms only, so
// that all ranks leave a loop together); solvers see this one, the handlers set the one above.
std::atomic<bool> stop_agreed{false};

// Under mpirun every rank gets the signal: only the launcher's rank 0 says so (set before the
// handlers are installed).
bool signal_notes = true;

// Async-signal-safe: an atomic store and write(2). A second signal ends the process at once
// (exit status 128 + signal, as a shell reports a killed job).
extern "C" void on_stop_signal(int signal_number) {
  if (stop_requested.exchange(true)) {
    static const char kNow[] = "\nhapsyn: second signal: stopping now, without writing results\n";
    [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, kNow, sizeof kNow - 1);
    ::_exit(128 + signal_number);
  }
  static const char kFirst[] =
      "\nhapsyn: stop requested: finishing the current step, writing the checkpoint and the best so far "
      "(signal again to stop at once)\n";
  if (!signal_notes) return;
  [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, kFirst, sizeof kFirst - 1);
}

void install_stop_handlers() {
  signal_notes = hapsyn_cli::launcher_rank() == 0;
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  for (int s : {SIGINT, SIGTERM, SIGUSR1}) ::sigaction(s, &action, nullptr);
}

hapsyn::Study load(const std::string& file, const std::vector<std::string>& sets, const hapsyn::Registry& registry,
                   const hapsyn::LoadSettings& settings = {}) {
  Json doc = hapsyn::read_problem_file(file);
  for (const std::string& s : sets) hapsyn::apply_override(doc, s);
  // Relative paths in the file (data files, reference front) are relative to the file first.
  const hapsyn::ProblemDirectoryScope scope(file);
  return hapsyn::load_study(doc, registry, {}, settings);
}

// The scene build gets the run's --threads (capped as the run caps it) and progress lines.
hapsyn::LoadSettings load_settings(int threads, bool quiet) {
  hapsyn::LoadSettings settings;
  if (threads > 0) {
    hapsyn::RunOptions options;
    options.threads = threads;
    std::vector<std::string> warnings;  // the run itself reports the cap
    settings.threads = hapsyn::run_threads(Json::object(), options, warnings);
  }
  settings.progress = quiet ? nullptr : &std::cerr;
  return settings;
}

constexpr int kExitStopped = 4;

// A shell word: quoted unless it is plain.
std::string shell_word(const std::string& s) {
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-+=.,/:@") ==
                        std::string::npos) {
    return s;
  }
  std::string quoted = "'";
  for (char c : s) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string schema_type(const Json& s) {
  if (!s.contains("type")) return "any";
  if (s["type"].is_string()) return s["type"];
  std::string t;
  for (const Json& x : s["type"]) t += (t.empty() ? "" : "|") + x.get<std::string>();
  return t;
}

// The cross-field rules declared next to the options ("x-rules"), with their fields' full paths.
void describe_rules(const Json& schema, const std::string& prefix, std::ostream& out) {
  const auto rules = schema.find("x-rules");
  if (rules == schema.end()) return;
  for (const Json& r : *rules) {
    std::string fields;
    for (const Json& f : r["fields"]) fields += (fields.empty() ? "" : ", ") + prefix + f.get<std::string>();
    out << "  rule (" << fields << "): " << r["rule"].get<std::string>() << "\n";
  }
}

// What `describe` shows as an option's default: "(required)" for a key the problem file must
// give, "(none)" for an optional key that stays absent when left out.
std::string shown_default(const Json& schema, const std::string& key) {
  const Json& p = schema["properties"][key];
  if (p.contains("default")) return p["default"].dump();
  const Json required = schema.value("required", Json::array());
  return std::find(required.begin(), required.end(), Json(key)) != required.end() ? "(required)" : "(none)";
}

void describe_properties(const Json& schema, const std::string& prefix, std::ostream& out) {
  if (!schema.contains("properties")) return;
  for (auto it = schema["properties"].begin(); it != schema["properties"].end(); ++it) {
    const Json& p = it.value();
    out << "  " << std::left << std::setw(22) << (prefix + it.key()) << " " << std::setw(8) << schema_type(p) << " default "
        << std::setw(10) << shown_default(schema, it.key()) << " "
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
    if (schema_type(p) == "array" && p.contains("items")) describe_properties(p["items"], prefix + it.key() + "[].", out);
  }
  describe_rules(schema, prefix, out);
}

// The design variables and constraints of a mechanism created with `options` (a JSON object's
// text, "" for the defaults). A mechanism that cannot be created without options (serial_chain
// needs its chain file) says so and how to ask, instead of failing the whole command.
void describe_design(const std::string& name, const std::string& options, const hapsyn::Registry& registry) {
  std::shared_ptr<hapsyn::Mechanism> mechanism;
  try {
    const Json o = options.empty() ? Json::object() : hapsyn::parse_problem_text(options, "--options");
    mechanism = registry.create_mechanism(name, o, "mechanism");
  } catch (const hapsyn::Error& e) {
    if (!options.empty()) throw;
    std::cout << "design variables: depend on the options (with the defaults: " << e.what()
              << "); list them with: hapsyn describe " << name << " --options '{...}'\n";
    return;
  }
  if (const std::string summary = mechanism->specs().summary; !summary.empty()) std::cout << "built: " << summary << "\n";
  std::cout << "design variables (default bounds; hard limits):\n";
  for (const hapsyn::VariableDecl& v : mechanism->variables()) {
    auto list = [](const std::vector<double>& x) {
      std::string s;
      for (double d : x) s += (s.empty() ? "" : ", ") + format_number(d);
      return x.size() == 1 ? s : "[" + s + "]";
    };
    std::cout << "  " << std::left << std::setw(6) << v.name << (v.size > 1 ? "[" + std::to_string(v.size) + "]" : "")
              << (v.integer ? " integer" : " real") << " [" << list(v.default_lower) << ", " << list(v.default_upper)
              << "] " << v.unit << "; limits [" << (v.hard_lower.empty() ? "-inf" : list(v.hard_lower)) << ", "
              << (v.hard_upper.empty() ? "inf" : list(v.hard_upper)) << "]  "
              << v.description << "\n";
  }
  const auto constraints = mechanism->constraints();
  if (!constraints.empty()) {
    std::cout << "design constraints (g <= 0):\n";
    for (const auto& c : constraints) std::cout << "  " << c.name << ": " << c.description << "\n";
  }
}

int describe(const std::string& name, bool json, const std::string& options, const hapsyn::Registry& registry) {
  const hapsyn::PluginRecord& r = registry.find(name);
  if (json) {
    std::cout << r.schema.dump(2) << "\n";
    return 0;
  }
  std::cout << r.name << " (" << r.kind << " plugin, version " << r.version << ")\n"
            << "  " << r.description << "\n"
            << "  file: " << r.file << "\n"
            << "  thread safety: " << hapsyn::to_string(r.thread_safety) << "\n";
  if (r.schema.contains("description") && r.schema["description"] != r.description) {
    std::cout << "  " << r.schema["description"].get<std::string>() << "\n";
  }
  std::cout << "options:\n";
  if (!r.schema.contains("properties") || r.schema["properties"].empty()) std::cout << "  (none)\n";
  describe_properties(r.schema, "", std::cout);
  if (r.kind == "mechanism") describe_design(name, options, registry);
  return 0;
}

int list_plugins(const hapsyn::Registry& registry) {
  std::vector<std::string> errors;
  const auto records = registry.list(&errors);
  // The name column fits the longest name (motion_feasibility ran into KIND at a fixed width).
  std::size_t width = 4;
  for (const auto& r : records) width = std::max(width, r.name.size());
  const int name_width = static_cast<int>(width) + 2;
  std::cout << std::left << std::setw(name_width) << "NAME" << std::setw(11) << "KIND" << std::setw(10) << "VERSION"
            << "FILE\n";
  for (const auto& r : records) {
    std::cout << std::left << std::setw(name_width) << r.name << std::setw(11) << r.kind << std::setw(10) << r.version
              << r.file << "\n";
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

int scene_command(const std::string& file, const std::vector<std::string>& sets, const std::string& csv,
                  const std::string& plot, std::optional<int> threads, const std::vector<std::string>& attributes,
                  const hapsyn::Registry& registry) {
  Json doc = hapsyn::read_problem_file(file);
  for (const std::string& s : sets) hapsyn::apply_override(doc, s);
  const hapsyn::ProblemDirectoryScope scope(file);
  const hapsyn::BuiltScene built = hapsyn::build_scene_alone(doc, registry, threads, attributes, &std::cerr);
  const hapsyn::SampleSet& set = built.samples;
  std::cout << "scene " << built.plugin << ": " << set.size() << " samples (";
  for (std::size_t c = 0; c < set.coordinates.size(); ++c) std::cout << (c ? ", " : "") << set.coordinates[c];
  std::cout << "; unit " << set.unit << ") in " << format_number(built.build_time_s) << " s\n";
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
    boost::system::error_code ignored;  // a file that does not exist yet is no directory
    if (boost::filesystem::is_directory(path, ignored) || csv.back() == '/') {
      throw hapsyn::Error("scene", "--csv " + csv + " is a directory; give a file name, e.g. " +
                                       (path / "samples.csv").lexically_normal().string());
    }
    // Only a missing parent is created ("x.csv" has none; "./x.csv" has one that exists).
    const boost::filesystem::path parent = path.parent_path();
    if (!parent.empty() && !boost::filesystem::is_directory(parent, ignored)) {
      boost::system::error_code ec;
      boost::filesystem::create_directories(parent, ec);
      if (ec) throw hapsyn::Error("output", "--csv " + csv + ": cannot create " + parent.string() + ": " + ec.message());
    }
    hapsyn::write_file_atomically(csv, hapsyn::scene_csv(set));
    std::cout << "csv: " << csv << " (" << set.size() << " rows)\n";
  }
  if (!plot.empty()) {
    if (!set.lattice) {
      throw hapsyn::Error("scene", "--plot needs a lattice scene (one that declares a SampleLattice), e.g. human_arm");
    }
    const std::string why = hapsyn::plot_lattice_density(set, plot);
    if (!why.empty()) {
      throw hapsyn::Error("scene", (hapsyn::gnuplot_available() ? "--plot: " + why
                                                                : std::string("--plot needs gnuplot, which is not installed "
                                                                              "(apt-get install gnuplot-nox)")) +
                                       "; " + plot + "/density_slices.dat and .gp were written");
    }
    std::cout << "plot: " << plot << "/density_slices.png\n";
  }
  return 0;
}

void print_sweep(const Json& summary, std::ostream& out) {
  const Json& reference_time = summary["reference"]["run_time_s"];
  out << "sweep: " << summary["runs"].size() << " runs; reference " << summary["reference"]["overrides"].dump() << " ("
      << (reference_time.is_number() ? format_number(reference_time.get<double>()) + " s" : std::string("not run")) << ")\n";
  if (summary.value("status", "") == "stopped") out << "stopped: " << summary.value("message", "") << "\n";
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
  if (summary.contains("shard") && summary.value("status", "") != "stopped") {
    out << "shard " << summary["shard"]["index"] << "/" << summary["shard"]["count"]
        << " done; when every share is, combine them: hapsyn merge DIR1 DIR2 ... --out DIR\n";
  }
}

// ---- the command line ----

// Every option of every subcommand (subcommands share file, sets, threads, seed).
struct Arguments {
  std::string file;
  std::vector<std::string> sets;
  std::string out_dir;
  int threads = 0;
  std::uint64_t seed = 0;
  bool quiet = false, resume = false, force = false;
  std::string shard;
  double rank_timeout = 120.0;
  std::vector<std::string> merge_dirs;
  std::string plugin_name;
  bool describe_json = false;
  std::string describe_options;
  std::string csv_out, plot_dir;
  std::vector<std::string> scene_attributes;
  std::vector<std::string> vary, reference;
  std::string sweep_out = "results/sweep";
  std::uint64_t sweep_seed = 1;
  bool sweep_progress = false;
  hapsyn::CompareOptions compare;
  std::string view_host = "127.0.0.1";
  int view_port = 8080;
  std::string report_out;
};

struct Commands {
  CLI::App* run = nullptr;
  CLI::Option* run_seed = nullptr;
  CLI::App* validate = nullptr;
  CLI::App* plugins = nullptr;
  CLI::App* describe = nullptr;
  CLI::App* scene = nullptr;
  CLI::Option* scene_threads = nullptr;
  CLI::App* sweep = nullptr;
  CLI::App* compare = nullptr;
  CLI::App* merge = nullptr;
  CLI::App* reference = nullptr;
  CLI::App* view = nullptr;
  CLI::App* report = nullptr;
};

// --seed: a whole number that fits 64 bits. Checked on the text, before CLI11 converts it: a
// conversion would turn "-1" into 2^64 - 1.
const CLI::Validator kSeed(
    [](std::string& text) -> std::string {
      if (!text.empty() && text.find_first_not_of("0123456789") == std::string::npos) {
        errno = 0;
        [[maybe_unused]] const unsigned long long value = std::strtoull(text.c_str(), nullptr, 10);
        if (errno != ERANGE) return "";
      }
      return "--seed " + text + ": must be a whole number in [0, 18446744073709551615]";
    },
    "SEED");

void define_study_commands(CLI::App& app, Arguments& a, Commands& c) {
  c.run = app.add_subcommand("run", "Run a study and write result.json (+ samples.csv)");
  c.run->add_option("file", a.file, "Problem file (JSON)")->required();
  c.run->add_option("--set", a.sets, "Override a key: path=value (value read as JSON when it parses, else a string)");
  c.run->add_option("--out", a.out_dir, "Output directory (overrides output.directory)");
  c.run->add_option("--threads", a.threads, "Worker threads (default: all cores)")->check(CLI::NonNegativeNumber);
  c.run_seed = c.run->add_option("--seed", a.seed, "Random seed (default: from the file, else drawn)")->check(kSeed);
  c.run->add_flag("--quiet,-q", a.quiet, "No progress output");
  c.run->add_flag("--resume", a.resume, "Continue from the output directory's checkpoint (every solver that can run long checkpoints)");
  c.run->add_flag("--force", a.force, "Overwrite a finished study (an existing result.json) in the output directory");
  c.run->add_option("--shard", a.shard,
                    "Run only share i of N (1 <= i <= N) of the solver's work into its own --out (a SLURM job array "
                    "task: --shard $((SLURM_ARRAY_TASK_ID+1))/$SLURM_ARRAY_TASK_COUNT); combine with hapsyn merge");
  c.run->add_option("--rank-timeout", a.rank_timeout,
                    "Under mpirun: seconds a rank may stay silent inside a task farm before the job ends naming it")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();

  c.merge = app.add_subcommand("merge", "Combine the shares of a --shard run (one output directory each) into one result");
  c.merge->add_option("dirs", a.merge_dirs, "The shares' output directories")->required();
  c.merge->add_option("--out", a.out_dir, "Output directory of the merged study")->required();
  c.merge->add_option("--threads", a.threads, "Worker threads for the final check (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  c.merge->add_flag("--quiet,-q", a.quiet, "No progress output");
  c.merge->add_flag("--force", a.force, "Overwrite a finished study in --out");

  c.validate = app.add_subcommand("validate", "Check a problem file completely without running it");
  c.validate->add_option("file", a.file, "Problem file (JSON)")->required();
  c.validate->add_option("--set", a.sets, "Override a key: path=value");
  c.validate->add_option("--out", a.out_dir, "Output directory to check as `run` would (default: output.directory)");
  c.validate->add_flag("--resume", a.resume, "Check the output directory for `run --resume`");
  c.validate->add_flag("--force", a.force, "Check the output directory for `run --force`");

  c.plugins = app.add_subcommand("plugins", "List the plugins found (name, kind, version, file)");

  c.describe = app.add_subcommand("describe", "Show a plugin's options, defaults and units");
  c.describe->add_option("name", a.plugin_name, "Plugin name")->required();
  c.describe->add_flag("--json", a.describe_json, "Print the options schema derived from the plugin's declarations");
  c.describe->add_option("--options", a.describe_options,
                         "A mechanism's options as a JSON object: list the design variables they give (e.g. a URDF's)");

  c.scene = app.add_subcommand("scene",
                               "Build a problem file's scene alone: summary, CSV export, reachability-density plots");
  c.scene->add_option("file", a.file, "Problem or scene file (JSON); only its \"scene\" section is read")->required();
  c.scene->add_option("--set", a.sets, "Override a key: path=value (e.g. scene.options.lattice_step=0.2)");
  c.scene->add_option("--csv", a.csv_out, "Write the samples as CSV: pose columns, then every attribute as name[i]");
  c.scene->add_option("--plot", a.plot_dir, "Write reachability-density slices (gnuplot) into this directory");
  c.scene_threads =
      c.scene->add_option("--threads", a.threads, "Threads for building (sets scene.options.threads when the scene has it)")
          ->check(CLI::NonNegativeNumber);
  c.scene->add_option("--attribute", a.scene_attributes, "Request a per-sample attribute (e.g. M_v, M_a); repeatable");

  c.view = app.add_subcommand("view", "Show a study in the browser: its mechanism, samples and local values (local web server)");
  c.view->add_option("path", a.file,
                     "Problem file (JSON), result directory (holding result.json), or the output directory of "
                     "hapsyn sweep or compare")
      ->required();
  c.view->add_option("--port", a.view_port, "TCP port (0: any free port)")->check(CLI::Range(0, 65535))->capture_default_str();
  c.view->add_option("--host", a.view_host, "Address to listen on (another than loopback exposes the study to the network)")
      ->capture_default_str();
  c.report = app.add_subcommand("report", "Write a result directory's views (mechanism, samples, front, convergence) "
                                          "as one self-contained HTML file (no server)");
  c.report->add_option("path", a.file, "Result directory (holding result.json), or the output directory of hapsyn sweep or compare")
      ->required();
  c.report->add_option("-o,--output", a.report_out, "HTML file to write (default: RESULT_DIR/report.html)");
}

// `hapsyn reference`: the JSON the documentation's reference pages are generated from
// (scripts/gen-reference.py). In no help group: it serves the docs build.
void define_reference_command(CLI::App& app, Commands& c) {
  c.reference = app.add_subcommand("reference", "Print the CLI, the problem schema, result.json's fields and every "
                                                "plugin's declarations as JSON (for the docs' reference pages)");
  c.reference->group("");
}

void define_batch_commands(CLI::App& app, Arguments& a, Commands& c) {
  c.sweep = app.add_subcommand("sweep",
                               "Run a study across values of some keys; error against a reference run versus time");
  c.sweep->add_option("file", a.file, "Problem file (JSON)")->required();
  c.sweep->add_option("--vary", a.vary, "path[,path...]=v1,v2,...: keys set together to each value (repeatable: a grid)")
      ->required();
  c.sweep->add_option("--reference", a.reference,
                      "path=value overrides of the reference run (repeatable; default: the last combination)");
  c.sweep->add_option("--set", a.sets, "Override a key in every run: path=value");
  c.sweep->add_option("--out", a.sweep_out, "Output directory (sweep.csv, sweep.json, sweep.png/svg, one folder per run)")
      ->capture_default_str();
  c.sweep->add_option("--threads", a.threads, "Worker threads per run (default: all cores)")->check(CLI::NonNegativeNumber);
  c.sweep->add_option("--seed", a.sweep_seed, "Random seed of every run")->check(kSeed)->capture_default_str();
  c.sweep->add_flag("--progress", a.sweep_progress, "Show each run's progress");
  c.sweep->add_flag("--force", a.force,
                    "Run every case again (default: a folder's finished result of the same problem and seed is reused)");
  c.sweep->add_option("--shard", a.shard,
                      "Run only share i of N (1 <= i <= N) of the runs into its own --out (a SLURM job array task); "
                      "combine the shares with hapsyn merge");
  c.sweep->add_option("--rank-timeout", a.rank_timeout,
                      "Under mpirun: seconds a rank may stay silent inside the farm of runs before the job ends naming it")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();

  c.compare = app.add_subcommand(
      "compare", "Run several studies on this machine: one table (front quality, evaluations, time) and plots");
  c.compare->add_option("files", a.compare.files, "Problem files (JSON), run in this order")->required();
  c.compare->add_option("--set", a.compare.overrides, "Override a key in every study: path=value");
  c.compare->add_option("--out", a.compare.output_directory, "Output directory (one folder per study)")
      ->capture_default_str();
  c.compare->add_option("--threads", a.compare.threads, "Worker threads per study")->check(CLI::NonNegativeNumber);
  c.compare->add_option("--seed", a.seed, "Random seed of every study")->check(kSeed);
  c.compare->add_flag("--force", a.compare.force,
                      "Run every study again (default: a folder's finished result of the same problem and seed is reused)");
  c.compare->add_option("--shard", a.shard,
                        "Run only share i of N (1 <= i <= N) of the studies into its own --out (a SLURM job array "
                        "task); combine the shares with hapsyn merge");
  c.compare->add_option("--rank-timeout", a.rank_timeout,
                        "Under mpirun: seconds a rank may stay silent inside the farm of studies before the job ends "
                        "naming it")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

// The processes of this run (see ranks.hpp); kept for main()'s error report.
std::unique_ptr<hapsyn::Cluster> run_cluster;

// Starts the run's worker threads before the study loads, so that the scheduler has placed them
// by the time the solver's first parallel loop starts (hapsyn::start_worker_threads). A bad
// thread count is left to the load and the run, which report it.
void start_workers_for(const Json& document, int threads_option) {
  hapsyn::RunOptions options;
  options.threads = threads_option;
  std::vector<std::string> ignored;  // the run reports the cap
  try {
    hapsyn::start_worker_threads(hapsyn::run_threads(document, options, ignored));
  } catch (const hapsyn::Error&) {
  }
}

int run_command(const Arguments& a, const Commands& c, const hapsyn::Registry& registry) {
  run_cluster = hapsyn_cli::make_run_cluster(a.shard, a.rank_timeout, &stop_requested, &stop_agreed);
  hapsyn::Cluster* cluster = run_cluster.get();
  const bool several = cluster != nullptr && cluster->size() > 1;
  const bool quiet = a.quiet || !(cluster == nullptr || cluster->root());
  const auto t0 = std::chrono::steady_clock::now();
  Json document;  // the problem as given (with --set), recorded for hapsyn merge in a share
  hapsyn::Study study = hapsyn_cli::load_on_ranks(cluster, [&] {
    document = hapsyn::read_problem_file(a.file);
    for (const std::string& s : a.sets) hapsyn::apply_override(document, s);
    start_workers_for(document, a.threads);
    const hapsyn::ProblemDirectoryScope scope(a.file);
    return hapsyn::load_study(document, registry, {}, load_settings(a.threads, quiet));
  });
  if (!a.shard.empty() && !study.solver->specs().shardable) {
    throw hapsyn::Error("shard", "--shard " + a.shard + ": solver " + study.solver_plugin +
                                     " cannot be split into shares (grid, culling and ga can; sweep and compare split "
                                     "their cases); run it whole, or on several ranks with mpirun");
  }
  hapsyn::RunOptions options;
  options.scene_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  options.output_directory = a.out_dir;
  options.threads = a.threads;
  if (*c.run_seed) options.seed = a.seed;
  options.quiet = quiet;
  options.resume = a.resume;
  options.force = a.force;
  options.cluster = cluster;
  options.problem_file = a.file;
  options.problem_document = document;
  options.stop = several ? &stop_agreed : &stop_requested;
  options.signal = &stop_requested;
  const Json result = hapsyn::run_study(study, options);
  const bool stopped = result["status"] == "stopped";
  if (hapsyn_cli::rank_of(cluster) != 0) return stopped ? kExitStopped : 0;  // rank 0 reports
  print_summary(result, std::cout);
  if (result.contains("shard") && result["shard"].value("complete", false)) {
    std::cout << "shard " << result["shard"]["index"] << "/" << result["shard"]["count"]
              << " done; when every share is, combine them: hapsyn merge DIR1 DIR2 ... --out DIR\n";
    return 0;
  }
  if (!stopped) return 0;
  std::string again = "hapsyn run " + shell_word(a.file);
  for (const std::string& s : a.sets) again += " --set " + shell_word(s);
  if (!a.out_dir.empty()) again += " --out " + shell_word(a.out_dir);
  if (!a.shard.empty()) again += " --shard " + a.shard;
  std::cout << "stopped; resume with: " << again << " --resume\n";
  return kExitStopped;
}

int merge_command(const Arguments& a, const hapsyn::Registry& registry) {
  hapsyn::check_merge_output(a.out_dir, a.merge_dirs);
  // A sweep's or a comparison's shares (their cases), else a study's.
  if (hapsyn::is_sweep_output(a.merge_dirs.front())) {
    const Json summary = hapsyn::merge_sweep_shards(a.merge_dirs, a.out_dir, registry, a.threads);
    print_sweep(summary, std::cout);
    return 0;
  }
  if (hapsyn::is_compare_output(a.merge_dirs.front())) {
    const Json summary = hapsyn::merge_compare_shards(a.merge_dirs, a.out_dir, registry, a.threads);
    hapsyn::print_compare(summary, std::cout);
    return 0;
  }
  hapsyn::RunOptions options;
  options.output_directory = a.out_dir;
  options.threads = a.threads;
  options.quiet = a.quiet;
  options.force = a.force;
  options.stop = &stop_requested;
  const Json result = hapsyn::merge_shard_directories(a.merge_dirs, registry, options);
  print_summary(result, std::cout);
  return result["status"] == "stopped" ? kExitStopped : 0;
}

int validate_command(const Arguments& a, const hapsyn::Registry& registry) {
  hapsyn::Study study = load(a.file, a.sets, registry, load_settings(0, false));
  hapsyn::RunOptions options;
  options.output_directory = a.out_dir;
  options.resume = a.resume;
  options.force = a.force;
  // The file is valid only if `run` would start: the output directory is checked as run_study does.
  std::vector<std::string> warnings;
  hapsyn::run_threads(study.resolved, options, warnings);
  const std::string out_dir = hapsyn::output_directory_of(study, options);
  // An output directory `run` cannot create or write is an error; one holding a finished (or
  // stopped) study is a note: the file is valid, `run` only needs --force (or --resume).
  hapsyn::RunOptions writable_only = options;
  writable_only.force = true;
  hapsyn::check_output_directory(out_dir, writable_only);
  std::string note;
  try {
    hapsyn::check_output_directory(out_dir, options);
  } catch (const hapsyn::Error& e) {
    note = e.what();
  }
  std::cout << a.file << ": valid (" << study.problem->dimension() << " free design variables, "
            << study.problem->samples().size() << " samples, " << study.problem->objectives().size()
            << " objective(s), solver " << study.solver_plugin << "; output " << out_dir << ")\n";
  for (const std::string& w : warnings) std::cout << "warning: " << w << "\n";
  if (!note.empty()) std::cout << "note: " << note << "\n";
  return 0;
}

int sweep_command(const Arguments& a, const hapsyn::Registry& registry) {
  // Under mpirun the runs are shared out over the ranks; under --shard only this share runs.
  run_cluster = hapsyn_cli::make_run_cluster(a.shard, a.rank_timeout, &stop_requested, &stop_agreed);
  hapsyn::Cluster* cluster = run_cluster.get();
  const bool root = hapsyn_cli::rank_of(cluster) == 0;
  Json summary;
  try {
    Json doc = hapsyn::read_problem_file(a.file);
    for (const std::string& s : a.sets) hapsyn::apply_override(doc, s);
    hapsyn::SweepOptions options;
    for (const std::string& v : a.vary) options.axes.push_back(hapsyn::parse_sweep_axis(v));
    options.reference = a.reference;
    options.output_directory = a.sweep_out;
    options.threads = a.threads;
    options.seed = a.sweep_seed;
    options.quiet = !a.sweep_progress;
    options.stop = cluster != nullptr && cluster->size() > 1 ? &stop_agreed : &stop_requested;
    options.force = a.force;
    options.cluster = cluster;
    const hapsyn::ProblemDirectoryScope scope(a.file);  // the file's relative paths, as `run` reads them
    summary = hapsyn::run_sweep(doc, options, registry);
  } catch (const hapsyn::Error&) {
    // run_sweep throws the same error on every rank: rank 0 reports it.
    if (!root) throw hapsyn_cli::QuietExit{1};
    throw;
  }
  const int code = summary.value("status", "") == "stopped" ? kExitStopped : 0;
  if (root) print_sweep(summary, std::cout);
  return code;
}

int dispatch(const Commands& c, Arguments& a, const hapsyn::Registry& registry) {
  // Only the commands that run studies stop gracefully; the others keep the default (Ctrl-C ends
  // them at once, which loses nothing).
  if (*c.run || *c.sweep || *c.compare || *c.merge) install_stop_handlers();
  if (*c.run) return run_command(a, c, registry);
  if (*c.merge) return merge_command(a, registry);
  if (*c.validate) return validate_command(a, registry);
  if (*c.plugins) return list_plugins(registry);
  if (*c.describe) return describe(a.plugin_name, a.describe_json, a.describe_options, registry);
  if (*c.reference) {
    std::cout << hapsyn_cli::reference_document(*c.reference->get_parent(), registry).dump(2) << "\n";
    return 0;
  }
  if (*c.sweep) return sweep_command(a, registry);
  if (*c.compare) {
    // As sweep_command: the studies shared out over mpirun's ranks, or this --shard's share.
    run_cluster = hapsyn_cli::make_run_cluster(a.shard, a.rank_timeout, &stop_requested, &stop_agreed);
    const bool root = hapsyn_cli::rank_of(run_cluster.get()) == 0;
    if (c.compare->count("--seed") > 0) a.compare.seed = a.seed;
    a.compare.stop = run_cluster != nullptr && run_cluster->size() > 1 ? &stop_agreed : &stop_requested;
    a.compare.cluster = run_cluster.get();
    Json summary;
    try {
      summary = hapsyn::run_compare(a.compare, registry);
    } catch (const hapsyn::Error&) {
      if (!root) throw hapsyn_cli::QuietExit{1};  // the same error on every rank: rank 0 reports it
      throw;
    }
    if (root) hapsyn::print_compare(summary, std::cout);
    return summary.value("status", "") == "stopped" ? kExitStopped : 0;
  }
  if (*c.view) {
#if HAPSYN_WITH_VIEW
    return hapsyn_cli::view_command(a.file, a.view_host, a.view_port, registry);
#else
    throw hapsyn::Error("view", "this hapsyn was built without the view (configure with -DHAPSYN_WITH_VIEW=ON)");
#endif
  }
  if (*c.report) {
#if HAPSYN_WITH_VIEW
    return hapsyn_cli::report_command(a.file, a.report_out, registry);
#else
    throw hapsyn::Error("report", "this hapsyn was built without the view (configure with -DHAPSYN_WITH_VIEW=ON)");
#endif
  }
  if (*c.scene) {
    const std::optional<int> threads = c.scene_threads->count() > 0 ? std::optional<int>(a.threads) : std::nullopt;
    return scene_command(a.file, a.sets, a.csv_out, a.plot_dir, threads, a.scene_attributes, registry);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hapsyn: optimization-driven design of haptic interfaces and robot mechanisms"};
  app.set_version_flag("--version", std::string("hapsyn ") + hapsyn::version());
  app.require_subcommand(1);
  Arguments arguments;
  Commands commands;
  define_study_commands(app, arguments, commands);
  define_batch_commands(app, arguments, commands);
  define_reference_command(app, commands);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  // The cluster goes before MPI is finalized (after main returns), on every path.
  struct ClusterReset {
    ~ClusterReset() { run_cluster.reset(); }
  } reset;
  try {
    hapsyn::Registry registry;
    return dispatch(commands, arguments, registry);
  } catch (const hapsyn_cli::QuietExit& e) {
    return e.code;
  } catch (const hapsyn::Error& e) {
    // Under MPI an error rank 0 passed on is rank 0's to report; another rank's own error names
    // the rank and ends the job (rank 0 may be waiting for this one).
    // Refused before the cluster exists (the same on every rank): the launcher's rank 0 says it.
    if (run_cluster == nullptr && hapsyn_cli::launcher_rank() > 0) return 1;
    if (const int rank = hapsyn_cli::rank_of(run_cluster.get()); rank != 0) {
      if (e.component() == "mpi" && std::string(e.what()).find("rank 0 ended the run") != std::string::npos) return 1;
      std::cerr << "hapsyn: error: rank " << rank << " on " << run_cluster->host(rank) << ": " << e.what() << "\n";
      hapsyn::abort_job(*run_cluster, 1);
    }
    std::cerr << "hapsyn: error: " << e.what() << "\n";
    return 1;
  } catch (const boost::filesystem::filesystem_error& e) {
    // A path the file system refuses (too long, a file where a directory is expected): bad
    // input, named by boost's message ("<operation>: <reason>: \"<path>\"").
    std::cerr << "hapsyn: error: output: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "hapsyn: internal error: " << e.what() << "\n";
    return 3;
  }
}
