// Running a loaded study: output-directory guards, seed, run log, the solver call, and the
// result files, each a named step of run_study.
#include <hapsyn/error.hpp>
#include <hapsyn/groups.hpp>
#include <hapsyn/maps.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/parallel.hpp>
#include <hapsyn/plugin.hpp>
#include <hapsyn/study_runner.hpp>

#include <boost/filesystem.hpp>

#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <iostream>
#include <random>

namespace hapsyn {

namespace fs = boost::filesystem;

namespace {

// Where and with what a run happens, fixed before the solver starts.
struct RunSetup {
  std::string out_dir;
  fs::path result_file;
  fs::path checkpoint_file;
  int threads = 1;
  std::uint64_t seed = 0;
};

int threads_of(const Json& resolved, const RunOptions& options) {
  if (options.threads > 0) return options.threads;
  if (resolved.contains("threads") && resolved["threads"].get<int>() > 0) return resolved["threads"].get<int>();
  return hardware_threads();
}

// A finished study is never overwritten by accident.
void refuse_finished_study(const RunSetup& run, const RunOptions& options) {
  if (!fs::exists(run.result_file) || options.force) return;
  if (options.resume) {
    throw Error("output", run.result_file.string() + ": the study in " + run.out_dir +
                              " has finished; there is nothing to resume (pass --force to run it again)");
  }
  throw Error("output", run.out_dir + " already holds a finished study (" + run.result_file.string() +
                            "); pass --force to overwrite it, or --out for another directory");
}

// The seed of the checkpoint a resumed run continues from (none when not resuming or absent).
std::optional<std::uint64_t> checkpoint_seed(const fs::path& checkpoint_file, const RunOptions& options) {
  if (!options.resume || options.force || !fs::exists(checkpoint_file)) return std::nullopt;
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
  return checkpoint["seed"].get<std::uint64_t>();
}

// options.seed, else the checkpoint's, else the file's, else drawn.
std::uint64_t choose_seed(const Json& resolved, const RunOptions& options, const fs::path& checkpoint_file) {
  const std::optional<std::uint64_t> from_checkpoint = checkpoint_seed(checkpoint_file, options);
  if (options.seed) {
    if (from_checkpoint && *from_checkpoint != *options.seed) {
      throw Error("output", "--seed " + std::to_string(*options.seed) + ": the checkpoint " + checkpoint_file.string() +
                                " was written with seed " + std::to_string(*from_checkpoint) +
                                "; resume with that seed (or without --seed)");
    }
    return *options.seed;
  }
  if (from_checkpoint) return *from_checkpoint;
  if (resolved.contains("seed")) return resolved["seed"].get<std::uint64_t>();
  return std::random_device{}();
}

// Refuses an unusable output directory before any work is done.
void prepare_output_directory(const std::string& out_dir) {
  boost::system::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec || !fs::is_directory(out_dir)) {
    throw Error("output", "cannot create the output directory " + out_dir + (ec ? ": " + ec.message() : ""));
  }
  if (::access(out_dir.c_str(), W_OK) != 0) {
    throw Error("output", "the output directory " + out_dir + " is not writable: " + std::strerror(errno));
  }
}

Json point_to_json(const Problem& problem, const SolutionPoint& p) {
  Json j;
  j["design"] = problem.design_to_json(p.design);
  Json objectives = Json::object();
  for (std::size_t i = 0; i < problem.objectives().size(); ++i) objectives[problem.objectives()[i].name] = p.objectives[i];
  j["objectives"] = objectives;
  j["score"] = p.score;
  return j;
}

// The body of result.json: provenance, the run, the solver's result.
Json result_document(const Study& study, const RunSetup& run, const SolverResult& result, const std::string& started,
                     double wall) {
  Json doc;
  doc["hapsyn"] = {{"version", version()}, {"plugin_api", HAPSYN_PLUGIN_API_VERSION}};
  doc["problem"] = study.resolved;
  Json plugins = Json::array();
  for (const PluginRecord& p : study.plugins) {
    plugins.push_back({{"name", p.name}, {"kind", p.kind}, {"version", p.version}, {"file", p.file}});
  }
  doc["plugins"] = plugins;
  doc["seed"] = run.seed;
  doc["threads"] = run.threads;
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
  return doc;
}

// "indicators" of a study with a front or reference indicators (else nothing to add).
void add_indicators(const Study& study, const SolverResult& result, double wall, Json& doc) {
  if (result.front.empty() && study.reference_front.empty() && study.reference_point.empty() &&
      study.reference_front_missing.empty()) {
    return;
  }
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

// groups.csv, result.json's "groups" and, with plots, timeline.png of the best design.
void write_group_files(const Study& study, const SampleRecords& records, const std::string& out_dir, Json& doc) {
  const std::vector<GroupTable> tables = group_tables(*study.problem, records);
  write_file_atomically((fs::path(out_dir) / "groups.csv").string(), groups_csv(tables));
  doc["files"]["groups"] = "groups.csv";
  doc["groups"] = groups_json(tables);
  const Json& output = study.resolved["output"];
  if (!output.value("plots", false)) return;
  const SampleSet& samples = study.problem->samples();
  for (const SampleGrouping& g : samples.groups) {
    if (g.name != "trajectory") continue;
    const std::string label = output.value("timeline", g.labels.front());
    std::string message;
    const std::string png = plot_timeline(*study.problem, records, g.name, label, out_dir, message);
    if (!png.empty()) doc["files"]["timeline"] = png;
    if (!message.empty()) doc["plot_message"] = message;
  }
}

// samples.csv, maps.csv and the map plots of the best design, as the options and the file ask;
// each file written is named in doc["files"].
void write_best_design_files(const Study& study, const SolverResult& result, const RunOptions& options,
                             const std::string& out_dir, Json& doc) {
  doc["files"] = Json::object();
  const Json& output = study.resolved["output"];
  const bool want_samples = options.write_samples && output.value("samples_csv", true);
  const bool want_maps = options.write_samples && output.value("maps", true);
  const bool want_groups = options.write_samples && output.value("groups", true) && !study.problem->samples().groups.empty();
  if (!result.best || !(want_samples || want_maps || want_groups)) return;
  const SampleRecords records = record_samples(*study.problem, result.best->design);
  if (want_groups) write_group_files(study, records, out_dir, doc);
  if (want_samples) {
    write_file_atomically((fs::path(out_dir) / "samples.csv").string(), samples_csv(*study.problem, records));
    doc["files"]["samples"] = "samples.csv";
  }
  if (want_maps) {
    const PositionMaps maps = position_maps(*study.problem, records);
    write_file_atomically((fs::path(out_dir) / "maps.csv").string(), maps_csv(maps));
    doc["files"]["maps"] = "maps.csv";
    if (output.value("plots", false)) {
      std::string message;
      doc["files"]["plots"] = plot_maps(maps, out_dir, message);
      if (!message.empty()) doc["plot_message"] = message;
    }
  }
}

}  // namespace

Json run_study(Study& study, const RunOptions& options) {
  const Json& resolved = study.resolved;
  RunSetup run;
  run.out_dir = options.output_directory.empty() ? study.output_directory : options.output_directory;
  run.result_file = fs::path(run.out_dir) / "result.json";
  run.checkpoint_file = fs::path(run.out_dir) / "checkpoint.json";
  run.threads = threads_of(resolved, options);
  refuse_finished_study(run, options);
  run.seed = choose_seed(resolved, options, run.checkpoint_file);
  prepare_output_directory(run.out_dir);

  std::ofstream log((fs::path(run.out_dir) / "run.log").string(), options.resume ? std::ios::app : std::ios::trunc);
  log << "hapsyn " << version() << " " << (options.resume ? "resume" : "run") << " " << resolved["name"].get<std::string>()
      << " at " << iso_time_now() << ", seed " << run.seed << ", " << run.threads << " threads\n";
  log.flush();

  SolverContext context;
  context.threads = run.threads;
  context.seed = run.seed;
  context.progress = options.quiet ? nullptr : options.progress ? options.progress : &std::cerr;
  context.stop = options.stop;
  context.output_directory = run.out_dir;
  context.log = log ? &log : nullptr;
  context.checkpoint_file = run.checkpoint_file.string();
  context.resume = options.resume && !options.force;

  const std::string started = iso_time_now();
  const auto t0 = std::chrono::steady_clock::now();
  SolverResult result = study.solver->solve(*study.problem, context);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  Json doc = result_document(study, run, result, started, wall);
  add_indicators(study, result, wall, doc);
  write_best_design_files(study, result, options, run.out_dir, doc);
  doc["output_directory"] = run.out_dir;
  write_file_atomically(run.result_file.string(), doc.dump(2) + "\n");
  // The study is finished: its checkpoint has served.
  boost::system::error_code remove_error;
  fs::remove(run.checkpoint_file, remove_error);
  if (log) log << "finished: status " << doc["status"].get<std::string>() << ", wall time " << wall << " s\n";
  return doc;
}

}  // namespace hapsyn
