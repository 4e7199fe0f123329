// Running a loaded study: output-directory guards and lock, seed, run log, the solver call, and
// the result files (staged, then committed with result.json first), each a named step of run_study.
#include <hapsyn/json_text.hpp>
#include <hapsyn/cluster.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/internal/plot.hpp>
#include <hapsyn/internal/groups.hpp>
#include <hapsyn/internal/maps.hpp>
#include <hapsyn/internal/solve_recording.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/parallel.hpp>
#include <hapsyn/plugin.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/internal/study_runner.hpp>

#include <hapsyn/read_file.hpp>

#include <boost/filesystem.hpp>

#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstring>
#include <exception>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <random>
#include <sstream>

namespace hapsyn {

namespace fs = boost::filesystem;

namespace {

// Where and with what a run happens, fixed before the solver starts.
struct RunSetup {
  std::string out_dir;
  fs::path result_file;
  fs::path checkpoint_file;
  fs::path staging;  // <out>/.staging-<pid>: the outputs until result.json commits them
  int threads = 1;
  std::uint64_t seed = 0;
  std::vector<std::string> warnings;
  Cluster* cluster = nullptr;  // the run's processes (null: this one alone)
  std::string problem_file;    // absolute, or ""
  Json problem_document;       // as given (RunOptions::problem_document)
  bool stop_seen = false;      // a stop was requested during the solve
};

constexpr int kThreadsPerHardwareThread = 4;
constexpr int kMaxThreads = 1024;
constexpr std::uint64_t kMaxResultBytes = std::uint64_t{1} << 30;

// The file's "threads" as a count, range-checked here as well as by the schema: a value that
// does not fit an int would otherwise wrap.
int file_threads(const Json& resolved) {
  if (!resolved.contains("threads")) return 0;
  const Json& t = resolved["threads"];
  const bool in_range = t.is_number_unsigned() ? t.get<std::uint64_t>() <= static_cast<std::uint64_t>(INT_MAX)
                        : t.is_number_integer() ? t.get<std::int64_t>() >= 0 && t.get<std::int64_t>() <= INT_MAX
                                                : false;
  if (!in_range) {
    throw Error("problem", "threads = " + t.dump() + ": must be an integer in [0, " + std::to_string(INT_MAX) +
                               "] (0 = all cores)");
  }
  return t.get<int>();
}

// True when result_file holds a study that ended for good (any status but "stopped"); an
// unreadable result.json counts as finished, so that it is never removed without --force.
bool finished_study(const fs::path& result_file, bool& stopped) {
  stopped = false;
  try {
    const Json doc = parse_json_text(read_regular_file(result_file.string(), "output", "result", kMaxResultBytes),
                                     result_file.string(), "output");
    stopped = doc.is_object() && doc.value("status", "") == "stopped";
  } catch (const std::exception&) {
  }
  return !stopped;
}

// "" when an entry can be created in `dir`, else why not. Tried, not inferred from the mode
// bits: access(2) says yes to root on /proc or a read-only mount. The probe is removed at once.
std::string cannot_create_in(const fs::path& dir) {
  std::string probe = (dir / ".hapsyn-probe-XXXXXX").string();
  if (::mkdtemp(probe.data()) == nullptr) return std::strerror(errno);
  ::rmdir(probe.c_str());
  return "";
}

// Refuses an output directory where a file this run writes is something else (a directory, a
// FIFO): the move into place would fail after the whole solve. run.log is checked when opened.
void check_output_names_free(const std::string& out_dir) {
  for (const char* name : {"result.json", "samples.csv", "maps.csv", "groups.csv", "front.csv", "checkpoint.json"}) {
    const fs::path file = fs::path(out_dir) / name;
    struct stat st {};
    if (::lstat(file.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
      throw Error("output", file.string() + " is " + (S_ISDIR(st.st_mode) ? "a directory" : S_ISLNK(st.st_mode) ? "a symbolic link" : "not a regular file") +
                                ", where a run writes a file; remove it, or choose another --out");
    }
  }
}

// The part of check_output_directory for a directory that exists.
void check_existing_output(const std::string& out_dir, const RunOptions& options) {
  const std::string why = cannot_create_in(out_dir);
  if (!why.empty()) throw Error("output", "the output directory " + out_dir + " is not writable: " + why);
  check_output_names_free(out_dir);
  const fs::path result_file = fs::path(out_dir) / "result.json";
  struct stat st {};
  if (options.force || ::lstat(result_file.c_str(), &st) != 0) return;
  bool stopped = false;
  if (finished_study(result_file, stopped)) {
    if (options.resume) {
      throw Error("output", result_file.string() + ": the study in " + out_dir +
                                " has finished; there is nothing to resume (pass --force to run it again)");
    }
    throw Error("output", out_dir + " already holds a finished study (" + result_file.string() +
                              "); pass --force to overwrite it, or --out for another directory");
  }
  if (!options.resume) {
    throw Error("output", out_dir + " holds a stopped study (" + result_file.string() +
                              " has status \"stopped\"); pass --resume to continue it, or --force to start over");
  }
}

// The part of check_output_directory for a directory still to be created: the nearest existing
// ancestor must be a writable directory, and every new name must fit the file system.
void check_creatable_output(const std::string& out_dir) {
  fs::path ancestor = fs::absolute(fs::path(out_dir));
  std::vector<std::string> missing;
  struct stat st {};
  while (::stat(ancestor.c_str(), &st) != 0) {
    if (errno != ENOENT || !ancestor.has_parent_path() || ancestor == ancestor.parent_path()) {
      throw Error("output", "cannot create the output directory " + out_dir + ": " + ancestor.string() + ": " +
                                std::strerror(errno));
    }
    missing.push_back(ancestor.filename().string());
    ancestor = ancestor.parent_path();
  }
  if (!S_ISDIR(st.st_mode)) {
    throw Error("output", "cannot create the output directory " + out_dir + ": " + ancestor.string() + " is not a directory");
  }
  const std::string why = cannot_create_in(ancestor);
  if (!why.empty()) {
    throw Error("output", "cannot create the output directory " + out_dir + ": " + ancestor.string() +
                              " is not writable: " + why);
  }
  const long name_max = ::pathconf(ancestor.c_str(), _PC_NAME_MAX);
  for (const std::string& name : missing) {
    if (name_max > 0 && static_cast<long>(name.size()) > name_max) {
      throw Error("output", "cannot create the output directory " + out_dir + ": the name \"" + name.substr(0, 40) +
                                "...\" is " + std::to_string(name.size()) + " characters, more than the " +
                                std::to_string(name_max) + " its file system allows");
    }
  }
}

// The seed of the checkpoint a resumed run continues from (none when not resuming or absent).
std::optional<std::uint64_t> checkpoint_seed(const fs::path& checkpoint_file, const RunOptions& options) {
  boost::system::error_code ec;
  if (!options.resume || options.force || !fs::exists(checkpoint_file, ec)) return std::nullopt;
  Json checkpoint;
  try {
    checkpoint = Json::parse(read_regular_file(checkpoint_file.string(), "output", "checkpoint", kMaxResultBytes));
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
  if (resolved.contains("seed")) {
    if (!resolved["seed"].is_number_unsigned()) {
      throw Error("problem", "seed = " + resolved["seed"].dump() + ": must be an integer in [0, 18446744073709551615]");
    }
    return resolved["seed"].get<std::uint64_t>();
  }
  return std::random_device{}();
}

// Creates the output directory (check_output_directory has said it can be).
void create_output_directory(const std::string& out_dir) {
  boost::system::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec || !fs::is_directory(out_dir, ec)) {
    throw Error("output", "cannot create the output directory " + out_dir + (ec ? ": " + ec.message() : ""));
  }
}

// Rough size of the files written after the solve: samples.csv and maps.csv hold one row per
// sample (at most) and about 16 characters per cell.
void check_output_space(const Study& study, const RunOptions& options, const std::string& out_dir) {
  const Json& output = study.resolved["output"];
  const SampleSet& samples = study.problem->samples();
  const std::uint64_t rows = static_cast<std::uint64_t>(samples.size());
  std::uint64_t needed = 0;
  std::string what = "result.json, run.log, checkpoint";
  if (options.write_samples && output.value("samples_csv", true)) {
    const std::uint64_t columns = 3 + static_cast<std::uint64_t>(samples.dimension()) + local_columns(*study.problem).size();
    needed += rows * columns * 16;
    what += ", samples.csv (" + std::to_string(rows) + " rows x " + std::to_string(columns) + " columns)";
  }
  if (options.write_samples && output.value("maps", true)) {
    needed += rows * (5 + study.problem->objectives().size()) * 16;
    what += ", maps.csv";
  }
  check_free_space(out_dir, needed, what);
}

// Files of an earlier run in the output directory: result.json goes first, so that from the
// first removal on the directory no longer claims a finished study; stale staging directories
// (of killed runs: none can be alive, this run holds the lock) go too.
void remove_previous_outputs(const std::string& out_dir) {
  boost::system::error_code ec;
  fs::remove(fs::path(out_dir) / "result.json", ec);
  if (ec) throw Error("output", "cannot remove the earlier " + out_dir + "/result.json: " + ec.message());
  std::vector<fs::path> stale;
  for (fs::directory_iterator it(out_dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const bool output = name == "samples.csv" || name == "maps.csv" || name == "groups.csv" || name.rfind("front.", 0) == 0 ||
                        name.rfind("map_", 0) == 0 || name.rfind("timeline.", 0) == 0;
    boost::system::error_code ignored;
    if (name.rfind(".staging-", 0) == 0 || (output && fs::is_regular_file(it->symlink_status(ignored)))) {
      stale.push_back(it->path());
    }
  }
  for (const fs::path& p : stale) fs::remove_all(p, ec);
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

// A front point as result.json lists it: the variables the study frees, the fixed ones being in
// "design_fixed" once (a URDF study fixes dozens of file parameters, the same on every point).
Json front_point_to_json(const Problem& problem, const SolutionPoint& p) {
  Json j = point_to_json(problem, p);
  std::map<std::string, bool> every_component_fixed;
  for (const DesignComponent& c : problem.design_space().components()) {
    auto it = every_component_fixed.emplace(c.variable, true).first;
    it->second = it->second && c.fixed;
  }
  for (const auto& [variable, fixed] : every_component_fixed) {
    if (fixed) j["design"].erase(variable);
  }
  return j;
}

// The body of result.json: provenance, the run, the solver's result.
Json result_document(const Study& study, const RunSetup& run, const SolverResult& result, const std::string& started) {
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
  if (run.cluster != nullptr && run.cluster->size() > 1) {
    Json hosts = Json::array();
    for (int r = 0; r < run.cluster->size(); ++r) hosts.push_back(run.cluster->host(r));
    doc["ranks"] = {{"count", run.cluster->size()}, {"hosts", hosts}, {"distributed", study.solver->specs().distributed}};
  }
  if (run.cluster != nullptr && run.cluster->shard().second > 1) {
    // complete: the share ran to its end (a signal did not stop it first); merge refuses others.
    doc["shard"] = {{"index", run.cluster->shard().first + 1},
                    {"count", run.cluster->shard().second},
                    {"complete", !run.stop_seen},
                    {"problem_file", run.problem_file},
                    {"problem_document", run.problem_document}};
  }
  doc["machine"] = machine_info();
  doc["started"] = started;
  doc["status"] = to_string(result.status);
  doc["message"] = result.message;
  doc["evaluations"] = {{"designs", result.design_evaluations}, {"samples", result.sample_evaluations}};
  if (const std::string summary = study.problem->mechanism().specs().summary; !summary.empty()) {
    doc["mechanism_summary"] = summary;
  }
  doc["samples_in_scene"] = study.problem->samples().size();
  doc["scene"] = study.problem->samples().info;
  if (result.best) doc["best"] = point_to_json(*study.problem, *result.best);
  if (!result.front.empty()) {
    Json front = Json::array();
    for (const SolutionPoint& p : result.front) front.push_back(front_point_to_json(*study.problem, p));
    doc["front"] = front;
  }
  doc["statistics"] = result.statistics;
  return doc;
}

// "indicators" of a study with a front or reference indicators (else nothing to add).
void add_indicators(const Study& study, const SolverResult& result, double solve_s, Json& doc) {
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
  indicators["wall_time_s"] = solve_s;
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

// Which per-sample files of the best design the options and the file ask for.
struct BestDesignFiles {
  bool samples = false, maps = false, groups = false;
  bool any() const { return samples || maps || groups; }
};
BestDesignFiles best_design_files(const Study& study, const RunOptions& options) {
  const Json& output = study.resolved["output"];
  BestDesignFiles want;
  want.samples = options.write_samples && output.value("samples_csv", true);
  want.maps = options.write_samples && output.value("maps", true);
  want.groups = options.write_samples && output.value("groups", true) && !study.problem->samples().groups.empty();
  return want;
}

// samples.csv, maps.csv and the map plots of the best design, as the options and the file ask,
// into `dir` (the staging directory); each file written is named in doc["files"]. The records
// are the solve's when it recorded this design (a fixed design: `recording`), else one pass on
// `threads` threads. `note` tells the user what takes long on a big scene.
void write_best_design_files(const Study& study, const SolverResult& result, const RunOptions& options, int threads,
                             const SolveRecording* recording, const std::string& dir,
                             const std::function<void(const std::string&)>& note, Json& doc) {
  const Json& output = study.resolved["output"];
  const BestDesignFiles want = best_design_files(study, options);
  if (!result.best || !want.any()) return;
  const bool reuse = recording && recording->complete() && recording->design() == result.best->design;
  SampleRecords evaluated;
  if (reuse) {
    note("taking the solve's records of the " + std::to_string(study.problem->samples().size()) + " samples");
  } else {
    note("evaluating the best design on each of the " + std::to_string(study.problem->samples().size()) + " samples");
    evaluated = record_samples(*study.problem, result.best->design, threads);
  }
  const SampleRecords& records = reuse ? recording->records() : evaluated;
  if (want.groups) write_group_files(study, records, dir, doc);
  if (want.samples) {
    note("writing samples.csv");
    write_file_atomically((fs::path(dir) / "samples.csv").string(), samples_csv(*study.problem, records));
    doc["files"]["samples"] = "samples.csv";
  }
  if (want.maps) {
    note("writing maps.csv");
    const PositionMaps maps = position_maps(*study.problem, records);
    write_file_atomically((fs::path(dir) / "maps.csv").string(), maps_csv(maps));
    doc["files"]["maps"] = "maps.csv";
    if (output.value("plots", false)) {
      note("plotting the maps");
      std::string message;
      doc["files"]["plots"] = plot_maps(maps, dir, message);
      if (!message.empty()) doc["plot_message"] = message;
    }
  }
}

// front.csv: one row per front point, the design components (design.<name>), then the objectives.
// The free components only: the fixed ones are the same in every row (a URDF study has dozens,
// once listed before the two that vary); result.json's "design_fixed" holds them once.
std::string front_csv(const Problem& problem, const std::vector<SolutionPoint>& front) {
  std::ostringstream csv;
  csv.precision(12);
  const std::vector<DesignComponent>& components = problem.design_space().components();
  const std::vector<int>& free = problem.design_space().free_indices();
  for (std::size_t k = 0; k < free.size(); ++k) {
    csv << (k ? "," : "") << "design." << components[static_cast<std::size_t>(free[k])].name;
  }
  for (std::size_t o = 0; o < problem.objectives().size(); ++o) {
    csv << (o || !free.empty() ? "," : "") << problem.objectives()[o].name;
  }
  csv << "\n";
  for (const SolutionPoint& p : front) {
    for (std::size_t k = 0; k < free.size(); ++k) csv << (k ? "," : "") << p.design[free[k]];
    for (std::size_t o = 0; o < p.objectives.size(); ++o) csv << (o || !free.empty() ? "," : "") << p.objectives[o];
    csv << "\n";
  }
  return csv.str();
}

// The fixed design components, once: {name: value}.
Json fixed_design(const Problem& problem) {
  Json fixed = Json::object();
  for (const DesignComponent& c : problem.design_space().components()) {
    if (c.fixed) fixed[c.name] = c.lower;
  }
  return fixed;
}

std::string format_value(double v) {
  std::ostringstream s;
  s << std::setprecision(6) << v;
  return s.str();
}

// "design.l1" and its bound's path "design.l1.upper" ("design.l.upper[2]" for a vector's component).
std::string bound_path(const DesignComponent& c, const char* side) {
  return "design." + c.variable + "." + side + (c.name != c.variable ? "[" + std::to_string(c.index) + "]" : "");
}

// -1 when x lies on free component k's lower bound, +1 on its upper, 0 else: within half a step
// of the grid's end points, or 1e-9 of the range for a continuous component.
int bound_side(const DesignSpace& space, std::size_t k, double x) {
  const DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
  const double tolerance = c.step > 0.0 ? 0.5 * c.step : 1e-9 * std::max({c.upper - c.lower, std::abs(c.lower), std::abs(c.upper)});
  const double top = c.step > 0.0 ? space.grid_value(k, space.grid_count(k) - 1) : c.upper;
  if (std::abs(x - c.lower) <= tolerance) return -1;
  if (std::abs(x - top) <= tolerance) return 1;
  return 0;
}

// True when the bound on `side` of `c` is the mechanism's hard limit (a length's 0): it cannot
// be widened, so an optimum there is no hint to widen the box.
bool at_hard_limit(const Mechanism& mechanism, const DesignComponent& c, int side) {
  for (const VariableDecl& d : mechanism.variables()) {
    if (d.name != c.variable) continue;
    const std::vector<double>& hard = side < 0 ? d.hard_lower : d.hard_upper;
    if (hard.empty()) return false;
    const double limit = hard.size() == 1 ? hard[0] : hard[static_cast<std::size_t>(c.index)];
    return (side < 0 ? c.lower : c.upper) == limit;
  }
  return false;
}

}  // namespace

std::vector<std::string> bound_warnings(const Problem& problem, const SolverResult& result) {
  std::vector<std::string> warnings;
  const DesignSpace& space = problem.design_space();
  for (std::size_t k = 0; k < space.free_size(); ++k) {
    const int index = space.free_indices()[k];
    const DesignComponent& c = space.components()[static_cast<std::size_t>(index)];
    if (c.integer) continue;  // integer codes (sizes, gears) are enumerations: an end is no hint
    for (const int side : {-1, 1}) {
      if (at_hard_limit(problem.mechanism(), c, side)) continue;
      const char* name = side < 0 ? "lower" : "upper";
      const std::string widen = "; widen " + bound_path(c, name) + " to check";
      const std::string at = " is at its " + std::string(name) + " bound";
      if (result.best && bound_side(space, k, result.best->design[index]) == side) {
        warnings.push_back("design." + c.name + " = " + format_value(result.best->design[index]) + at +
                           ": the optimum may lie beyond it" + widen);
        continue;
      }
      std::size_t on = 0;
      for (const SolutionPoint& p : result.front) on += bound_side(space, k, p.design[index]) == side;
      if (on > 0) {
        warnings.push_back("design." + c.name + at + " in " + std::to_string(on) + " of " +
                           std::to_string(result.front.size()) + " front points: the front may extend beyond it" + widen);
      }
    }
  }
  return warnings;
}

namespace {

// The message of `e` without an output Error's "output: " (the run's error adds its own).
std::string without_component(const std::exception& e) {
  const auto* error = dynamic_cast<const Error*>(&e);
  const std::string what = e.what();
  return error && error->component() == "output" && what.rfind("output: ", 0) == 0 ? what.substr(8) : what;
}

// The staged outputs of one run: files are written into <out>/.staging-<pid> and moved into
// <out> by commit(), result.json first, so that the directory never mixes two runs' files.
class StagedOutputs {
 public:
  explicit StagedOutputs(const RunSetup& run) : run_(run) {
    boost::system::error_code ec;
    fs::create_directory(run.staging, ec);
    if (ec) throw Error("output", "cannot create " + run.staging.string() + ": " + ec.message());
  }
  ~StagedOutputs() {
    boost::system::error_code ignored;
    fs::remove_all(run_.staging, ignored);
  }
  StagedOutputs(const StagedOutputs&) = delete;
  StagedOutputs& operator=(const StagedOutputs&) = delete;

  std::string dir() const { return run_.staging.string(); }
  void write_result(const Json& doc) const {
    write_file_atomically((run_.staging / "result.json").string(), doc.dump(2) + "\n");
  }
  // Moves result.json into the output directory, then every other staged file. result.json goes
  // first because the earlier study's files are gone (remove_previous_outputs): from that move on
  // the directory holds this study and only its files, so no moment shows this run's files
  // without the result.json that claims them (the window "result.json last" had, which a kill can
  // hit). A file that cannot be moved is reported in `errors`, dropped from doc["files"], and
  // result.json is rewritten in place.
  void commit(Json& doc, std::vector<std::string>& errors) const {
    std::vector<fs::path> staged;
    boost::system::error_code ec;
    for (fs::directory_iterator it(run_.staging, ec), end; !ec && it != end; it.increment(ec)) {
      if (it->path().filename() != "result.json") staged.push_back(it->path());
    }
    if (ec) throw Error("output", "cannot list " + run_.staging.string() + ": " + ec.message());
    move_file((run_.staging / "result.json").string(), run_.result_file.string());
    for (const fs::path& file : staged) {
      try {
        move_file(file.string(), (fs::path(run_.out_dir) / file.filename()).string());
      } catch (const Error& e) {
        errors.push_back(without_component(e));
        drop_file(doc, file.filename().string());
      }
    }
    if (!errors.empty()) {
      doc["output_errors"] = errors;
      write_file_atomically(run_.result_file.string(), doc.dump(2) + "\n");
    }
    sync_directory(run_.out_dir);
  }

 private:
  static void drop_file(Json& doc, const std::string& name) {
    Json& files = doc["files"];
    for (auto it = files.begin(); it != files.end();) {
      if (it->is_array()) {
        Json kept = Json::array();
        for (const Json& f : *it) {
          if (f != name) kept.push_back(f);
        }
        *it = kept;
      }
      it = *it == name ? files.erase(it) : std::next(it);
    }
  }
  const RunSetup& run_;
};

// A gnuplot message names the directory the plots were made in: the staging one, soon gone.
void name_output_directory_in_plot_message(const std::string& staging, const std::string& out_dir, Json& doc) {
  if (!doc.contains("plot_message")) return;
  std::string message = doc["plot_message"];
  for (std::size_t at; (at = message.find(staging)) != std::string::npos;) message.replace(at, staging.size(), out_dir);
  doc["plot_message"] = message;
}

// front.png/.svg of a Pareto study with plots: true (its first two or three objectives).
void plot_front_of(const Study& study, const SolverResult& result, const std::string& dir, Json& doc) {
  std::vector<std::string> names, senses;
  for (const Objective& o : study.problem->objectives()) {
    names.push_back(o.name);
    senses.push_back(o.sense == Sense::kMinimize ? "minimize" : "maximize");
  }
  std::vector<std::vector<double>> points;
  for (const SolutionPoint& p : result.front) points.emplace_back(p.objectives.begin(), p.objectives.end());
  const std::string why = plot_front(dir, names, senses, points);
  if (names.size() < 2) return;
  if (why.empty()) {
    doc["files"]["front_plot"] = "front.png, front.svg";
  } else {
    doc["plot_message"] = why;
  }
}

// A history column as numbers, null as NaN (a gap in the plot).
std::vector<double> history_column(const Json& column) {
  std::vector<double> values;
  for (const Json& v : column) values.push_back(v.is_number() ? v.get<double>() : std::nan(""));
  return values;
}

// The GA's figure: every run's best (solid) and mean (dashed) score, one colour per run, its
// key naming the runs while they are few enough to tell apart.
ConvergenceFigure ga_convergence(const Json& runs) {
  ConvergenceFigure figure;
  figure.title = "convergence: best (solid) and mean (dashed) score of each run's population";
  figure.panels = {"score (weighted objectives, maximized)"};
  const bool named = runs.size() > 1 && runs.size() <= 12;
  for (const Json& run : runs) {
    if (!run.contains("history")) continue;
    const Json& h = run.at("history");
    const int index = run.at("run").get<int>();
    const std::vector<double> evaluations = history_column(h.at("evaluations"));
    const std::string name = runs.size() > 1 ? "run " + std::to_string(index + 1) : "";
    figure.curves.push_back({named ? name : runs.size() == 1 ? "best" : "", 0, index, false, evaluations,
                             history_column(h.at("best"))});
    figure.curves.push_back({runs.size() == 1 ? "mean" : "", 0, index, true, evaluations, history_column(h.at("mean"))});
  }
  return figure;
}

// NSGA-II's figure: each objective's ideal on the first front, one panel each, and the
// hypervolume when the history has it.
ConvergenceFigure front_convergence(const Study& study, const Json& history) {
  ConvergenceFigure figure;
  figure.title = "convergence: the ideal point of the first front";
  const std::vector<double> evaluations = history_column(history.at("evaluations"));
  for (const Objective& o : study.problem->objectives()) {
    figure.panels.push_back("ideal " + o.name + (o.sense == Sense::kMinimize ? " (minimize)" : " (maximize)"));
    figure.curves.push_back({"", figure.panels.size() - 1, 0, false, evaluations,
                             history_column(history.at("ideal").at(o.name))});
  }
  if (history.contains("hypervolume")) {
    figure.panels.push_back("hypervolume (indicators.reference_point)");
    figure.curves.push_back({"", figure.panels.size() - 1, 0, false, evaluations, history_column(history.at("hypervolume"))});
  }
  return figure;
}

// convergence.png/.svg of a solver that records a history (ga: statistics.runs[i].history,
// nsga2: statistics.history), with plots: true.
void plot_convergence_of(const Study& study, const SolverResult& result, const std::string& dir, Json& doc) {
  const Json& statistics = result.statistics;
  ConvergenceFigure figure;
  if (statistics.contains("history")) {
    figure = front_convergence(study, statistics.at("history"));
  } else if (statistics.contains("runs") && statistics.at("runs").is_array()) {
    figure = ga_convergence(statistics.at("runs"));
  }
  if (figure.curves.empty()) return;
  const std::string why = plot_convergence(dir, figure);
  if (why.empty()) {
    doc["files"]["convergence_plot"] = "convergence.png, convergence.svg";
  } else {
    doc["plot_message"] = why;
  }
}

// Every output of a finished solve, staged then committed. A failure after result.json is
// staged keeps the solve: result.json is committed with "output_errors" and the error thrown after.
void write_outputs(const Study& study, const SolverResult& result, const RunOptions& options, const RunSetup& run,
                   const SolveRecording* recording, std::ostream* progress, std::ostream& log, Json& doc) {
  const auto t0 = std::chrono::steady_clock::now();
  const bool big = study.problem->samples().size() >= 10000;
  const auto note = [&](const std::string& line) {
    if (!big) return;
    if (progress) *progress << "outputs: " << line << "\n";
    log << "outputs: " << line << "\n";
  };
  StagedOutputs staged(run);
  doc["files"] = Json::object();
  doc["output_directory"] = run.out_dir;
  staged.write_result(doc);  // first: whatever fails next, the solve is on disk
  std::vector<std::string> errors;
  try {
    if (!result.front.empty()) {
      write_file_atomically((fs::path(staged.dir()) / "front.csv").string(), front_csv(*study.problem, result.front));
      doc["files"]["front"] = "front.csv";
      doc["design_fixed"] = fixed_design(*study.problem);
      if (study.resolved["output"].value("plots", false)) plot_front_of(study, result, staged.dir(), doc);
    }
    if (study.resolved["output"].value("plots", false)) plot_convergence_of(study, result, staged.dir(), doc);
    write_best_design_files(study, result, options, run.threads, recording, staged.dir(), note, doc);
  } catch (const std::exception& e) {
    errors.push_back(without_component(e));
  }
  name_output_directory_in_plot_message(staged.dir(), run.out_dir, doc);
  doc["phases"]["outputs_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  doc["wall_time_s"] = doc["phases"]["scene_s"].get<double>() + doc["phases"]["solve_s"].get<double>() +
                       doc["phases"]["outputs_s"].get<double>();
  staged.write_result(doc);
  staged.commit(doc, errors);
  if (!errors.empty()) {
    throw Error("output", errors.front() + "; " + run.result_file.string() + " holds the solve (see its \"output_errors\")");
  }
}

// "stopped": the checkpoint stays for --resume; a share's stays whatever its status, since it is
// what merge combines (one share may hold every task: a grid of one chunk converges in it); any
// other outcome: it has served.
void finish_checkpoint(const RunSetup& run, const Json& doc) {
  if (doc["status"] == "stopped" || doc.contains("shard")) return;
  boost::system::error_code ignored;
  fs::remove(run.checkpoint_file, ignored);
}

}  // namespace

std::string output_directory_of(const Study& study, const RunOptions& options) {
  return options.output_directory.empty() ? study.output_directory : options.output_directory;
}

void check_output_directory(const std::string& out_dir, const RunOptions& options) {
  if (out_dir.empty()) throw Error("output", "the output directory is empty: give output.directory or --out");
  // result.json records the directory: a name that is not UTF-8 could not be written into it.
  try {
    check_json_text_rules(Json(out_dir), "output directory");
  } catch (const Error& e) {
    throw Error("output", std::string(e.what()).substr(e.component().size() + 2));
  }
  struct stat st {};
  if (::stat(out_dir.c_str(), &st) == 0) {
    if (!S_ISDIR(st.st_mode)) throw Error("output", "the output directory " + out_dir + " is not a directory");
    check_existing_output(out_dir, options);
  } else if (errno == ENOENT) {
    check_creatable_output(out_dir);
  } else {
    throw Error("output", "the output directory " + out_dir + ": " + std::strerror(errno));
  }
}

int run_threads(const Json& resolved, const RunOptions& options, std::vector<std::string>& warnings) {
  if (options.threads < 0) {
    throw Error("output", "threads = " + std::to_string(options.threads) + ": must be >= 0 (0 = the file's, else all cores)");
  }
  const int hardware = hardware_threads();
  const int from_file = file_threads(resolved);
  const int threads = options.threads > 0 ? options.threads : from_file > 0 ? from_file : hardware;
  const int cap = std::min(kMaxThreads, kThreadsPerHardwareThread * std::max(1, hardware));
  if (threads <= cap) return threads;
  const std::string source = options.threads > 0 ? "--threads " + std::to_string(threads)
                                                  : "threads = " + std::to_string(threads) + " (problem file)";
  warnings.push_back(source + ": capped to " + std::to_string(cap) + " (" + std::to_string(kThreadsPerHardwareThread) +
                     " x the " + std::to_string(hardware) + " hardware threads)");
  return cap;
}

namespace {

// The solve and the outputs, once the directory is locked and the log open.
Json solve_and_write(Study& study, const RunOptions& options, RunSetup& run, std::ostream& log) {
  std::ostream* progress = options.quiet ? nullptr : options.progress ? options.progress : &std::cerr;
  SolverContext context;
  context.threads = run.threads;
  context.seed = run.seed;
  context.progress = progress;
  context.stop = options.stop;
  context.output_directory = run.out_dir;
  context.log = &log;
  context.checkpoint_file = run.checkpoint_file.string();
  context.resume = options.resume && !options.force;
  context.reference_point = study.reference_point;  // for a solver's per-generation hypervolume
  if (study.solver->specs().distributed) {
    context.ranks = run.cluster;
  } else if (options.signal != nullptr) {
    context.stop = options.signal;  // rank 0 alone: its own signal, at once
  }

  // A fixed design is the only one the solve can evaluate: its per-sample records are kept for
  // the outputs instead of evaluating it again (docs/design.md section 11.6). Not on the block
  // path, which the evaluator does not record.
  std::optional<SolveRecording> recording;
  if (study.problem->dimension() == 0 && !study.problem->block_path() && best_design_files(study, options).any()) {
    recording.emplace(*study.problem, study.problem->full_design(nullptr));
  }
  const std::string started = iso_time_now();
  const auto t0 = std::chrono::steady_clock::now();
  SolverResult result = study.solver->solve(*study.problem, context);
  run.stop_seen = context.stop_requested();
  const double solve_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  Json doc = result_document(study, run, result, started);
  doc["phases"] = {{"scene_s", options.scene_time_s}, {"solve_s", solve_s}, {"outputs_s", 0.0}};
  doc["wall_time_s"] = options.scene_time_s + solve_s;
  std::vector<std::string> warnings = run.warnings;
  for (const std::string& w : bound_warnings(*study.problem, result)) {
    warnings.push_back(w);
    log << "warning: " << w << "\n";
  }
  if (!warnings.empty()) doc["warnings"] = warnings;
  add_indicators(study, result, solve_s, doc);
  try {
    write_outputs(study, result, options, run, recording ? &*recording : nullptr, progress, log, doc);
  } catch (...) {
    // The solve outlives a failed write: its best design is in the log at least.
    if (doc.contains("best")) log << "best: " << doc["best"].dump() << "\n";
    throw;
  }
  finish_checkpoint(run, doc);
  return doc;
}

}  // namespace

namespace {

Json run_here(Study& study, const RunOptions& options, Cluster* cluster, const std::function<void(const RunSetup&)>& started) {
  const Json& resolved = study.resolved;
  RunSetup run;
  run.cluster = cluster;
  if (!options.problem_file.empty()) run.problem_file = fs::absolute(options.problem_file).string();
  run.problem_document = options.problem_document;
  run.out_dir = output_directory_of(study, options);
  run.result_file = fs::path(run.out_dir) / "result.json";
  run.checkpoint_file = fs::path(run.out_dir) / "checkpoint.json";
  run.staging = fs::path(run.out_dir) / (".staging-" + std::to_string(::getpid()));
  run.threads = run_threads(resolved, options, run.warnings);
  check_output_directory(run.out_dir, options);
  create_output_directory(run.out_dir);
  const DirectoryLock lock(run.out_dir);
  check_output_directory(run.out_dir, options);  // again under the lock: another run may have finished meanwhile
  run.seed = choose_seed(resolved, options, run.checkpoint_file);
  check_output_space(study, options, run.out_dir);
  // Opened (appending: nothing changes yet) before the previous study goes, so that a refused
  // log (a symbolic link) leaves that study untouched; emptied after, for a fresh run.
  LogFile log_file((fs::path(run.out_dir) / "run.log").string(), true);
  remove_previous_outputs(run.out_dir);
  if (!options.resume || options.force) log_file.truncate();
  std::ostream& log = log_file.stream();
  log << "hapsyn " << version() << " " << (options.resume ? "resume" : "run") << " " << resolved["name"].get<std::string>()
      << " at " << iso_time_now() << ", seed " << run.seed << ", " << run.threads << " threads\n";
  std::ostream& warn = options.progress ? *options.progress : std::cerr;
  for (const std::string& w : run.warnings) {
    warn << "hapsyn: warning: " << w << "\n";
    log << "warning: " << w << "\n";
  }
  if (cluster != nullptr && cluster->size() > 1) {
    // mpirun binds each rank to one core by default when there are at most 2 ranks: the rank's
    // threads would then share that core.
    cpu_set_t allowed;
    CPU_ZERO(&allowed);
    if (::sched_getaffinity(0, sizeof allowed, &allowed) == 0 && CPU_COUNT(&allowed) < run.threads) {
      const std::string w = "rank 0 may run on " + std::to_string(CPU_COUNT(&allowed)) + " CPU(s) but runs " +
                            std::to_string(run.threads) + " threads: start mpirun with --bind-to none (or --map-by " +
                            "ppr:1:node:PE=" + std::to_string(run.threads) + ") so that each thread has a core";
      warn << "hapsyn: warning: " << w << "\n";
      log << "warning: " << w << "\n";
      run.warnings.push_back(w);
    }
    log << "ranks: " << cluster->size() << " (" << (study.solver->specs().distributed ? "distributed" : "solver on rank 0 alone")
        << ")\n";
  }
  started(run);
  try {
    Json doc = solve_and_write(study, options, run, log);
    log << "finished: status " << doc["status"].get<std::string>() << ", wall time " << doc["wall_time_s"].get<double>()
        << " s\n";
    return doc;
  } catch (const std::exception& e) {
    log << "failed: " << e.what() << "\n";
    throw;
  }
}

// What rank 0 tells the other ranks before the solve: the seed and checkpoint it chose, or the
// error that ended the run before it started.
std::string go_message(const RunSetup& run) {
  return Json{{"seed", run.seed}, {"checkpoint", run.checkpoint_file.string()}, {"out", run.out_dir}}.dump();
}

// Ranks 1..N-1: no output directory, no log, no files; the same solve as rank 0 (a distributed
// solver) or none (rank 0 solves alone), then rank 0's result.
Json follow_rank0(Study& study, const RunOptions& options, Cluster& cluster) {
  std::string go;
  cluster.broadcast(go);
  Json message = Json::parse(go);
  if (message.contains("error")) throw Error("mpi", "rank 0 ended the run: " + message["error"].get<std::string>());
  // An error here is (the ranks being alike) rank 0's too: this rank still takes part in the
  // last broadcast, so that rank 0 is not left waiting, and then lets rank 0 report it.
  std::exception_ptr own;
  if (study.solver->specs().distributed) try {
    std::vector<std::string> ignored;
    SolverContext context;
    context.threads = run_threads(study.resolved, options, ignored);
    context.seed = message["seed"].get<std::uint64_t>();
    context.stop = options.stop;
    context.checkpoint_file = message["checkpoint"].get<std::string>();  // read (on resume), never written
    context.resume = options.resume && !options.force;
    context.reference_point = study.reference_point;
    context.ranks = &cluster;
    (void)study.solver->solve(*study.problem, context);
  } catch (...) {
    own = std::current_exception();
  }
  std::string result;
  cluster.broadcast(result);
  message = Json::parse(result);
  if (message.contains("error")) throw Error("mpi", "rank 0 ended the run: " + message["error"].get<std::string>());
  if (own) std::rethrow_exception(own);
  return message;
}

}  // namespace

Json run_study(Study& study, const RunOptions& options) {
  Cluster* cluster = options.cluster;
  if (cluster == nullptr || cluster->size() == 1) return run_here(study, options, cluster, [](const RunSetup&) {});
  if (!cluster->root()) return follow_rank0(study, options, *cluster);
  // Rank 0: the others wait for the go (sent once the output directory is ready), then for the
  // result; an error sends what they wait for next, so none waits for a message that never comes.
  try {
    Json doc = run_here(study, options, cluster, [&](const RunSetup& run) {
      std::string go = go_message(run);
      cluster->broadcast(go);
    });
    std::string result = doc.dump();
    cluster->broadcast(result);
    return doc;
  } catch (const std::exception& e) {
    std::string error = Json{{"error", e.what()}}.dump();
    cluster->broadcast(error);
    throw;
  }
}

}  // namespace hapsyn
