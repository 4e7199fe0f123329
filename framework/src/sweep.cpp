#include <hapsyn/cluster.hpp>
#include <hapsyn/json_text.hpp>
#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/internal/case_batch.hpp>
#include <hapsyn/internal/plot.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/solver.hpp>
#include <hapsyn/internal/study.hpp>
#include <hapsyn/internal/study_runner.hpp>
#include <hapsyn/internal/sweep.hpp>

#include <boost/filesystem.hpp>

#include <cstdlib>
#include <fstream>
#include <functional>

#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>

namespace hapsyn {

namespace fs = boost::filesystem;

namespace {
// Splits on `separator` outside brackets, braces and quotes (so JSON values may hold commas).
std::vector<std::string> split_top_level(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::string current;
  int depth = 0;
  bool quoted = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '\\' && i + 1 < text.size()) {
        current += c;
        current += text[++i];
        continue;
      }
      if (c == '"') quoted = false;
    } else if (c == '"') {
      quoted = true;
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if (c == ']' || c == '}') {
      --depth;
    } else if (c == separator && depth == 0) {
      parts.push_back(current);
      current.clear();
      continue;
    }
    current += c;
  }
  parts.push_back(current);
  return parts;
}

Json as_value(const std::string& text) {
  try {
    return parse_json_text(text, "value", "sweep");
  } catch (const Error&) {
    return Json(text);  // not JSON (or too deep to be a value): the text itself
  }
}

std::string assignment(const std::string& path, const Json& value) {
  return path + "=" + (value.is_string() ? value.get<std::string>() : value.dump());
}
}  // namespace

SweepAxis parse_sweep_axis(const std::string& spec) {
  const auto eq = spec.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size()) {
    throw Error("sweep", "--vary '" + spec + "': expected path[,path...]=value1,value2,...");
  }
  SweepAxis axis;
  for (const std::string& p : split_top_level(spec.substr(0, eq), ',')) {
    if (p.empty()) throw Error("sweep", "--vary '" + spec + "': empty path");
    axis.paths.push_back(p);
  }
  for (const std::string& v : split_top_level(spec.substr(eq + 1), ',')) {
    if (v.empty()) throw Error("sweep", "--vary '" + spec + "': empty value");
    axis.values.push_back(as_value(v));
  }
  return axis;
}

namespace {

struct RunRecord {
  Json values;          // path -> value
  Json result;          // result.json of the run
  bool reused = false;  // read from its folder, not run by this sweep
};

std::vector<std::vector<double>> front_of(const Json& result) {
  std::vector<std::vector<double>> points;
  if (!result.contains("front")) return points;
  for (const Json& p : result["front"]) {
    std::vector<double> v;
    for (auto it = p["objectives"].begin(); it != p["objectives"].end(); ++it) v.push_back(it.value());
    points.push_back(v);
  }
  return points;
}

// Design components in SI units, in the order of the design object.
std::vector<double> design_of(const Json& result) {
  std::vector<double> v;
  if (!result.contains("best")) return v;
  for (auto it = result["best"]["design"].begin(); it != result["best"]["design"].end(); ++it) {
    if (it.value().is_array()) {
      for (const Json& x : it.value()) v.push_back(x.get<double>());
    } else {
      v.push_back(it.value().get<double>());
    }
  }
  return v;
}

Json errors_against(const Json& run, const Json& reference) {
  Json e;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  double objective_error = nan, design_distance = nan;
  if (run.contains("best") && reference.contains("best")) {
    objective_error = 0.0;
    for (auto it = reference["best"]["objectives"].begin(); it != reference["best"]["objectives"].end(); ++it) {
      if (!run["best"]["objectives"].contains(it.key())) continue;
      objective_error = std::max(objective_error, std::abs(run["best"]["objectives"][it.key()].get<double>() - it.value().get<double>()));
    }
    const auto a = design_of(run), b = design_of(reference);
    if (a.size() == b.size()) {
      design_distance = 0.0;
      for (std::size_t i = 0; i < a.size(); ++i) design_distance += (a[i] - b[i]) * (a[i] - b[i]);
      design_distance = std::sqrt(design_distance);
    }
  }
  e["objective_error"] = std::isnan(objective_error) ? Json(nullptr) : Json(objective_error);
  e["design_distance"] = std::isnan(design_distance) ? Json(nullptr) : Json(design_distance);
  const auto rf = front_of(reference);
  e["igd"] = rf.empty() ? Json(nullptr) : Json(inverted_generational_distance(front_of(run), rf));
  return e;
}

std::string csv_cell(const Json& v) {
  if (v.is_null()) return "";
  if (v.is_string()) return v.get<std::string>();
  return v.dump();
}

void write_plot(const fs::path& dir, std::ostream& log) {
  // One series (the runs, labelled by their case): no key.
  const std::string body =
      "set datafile separator ','\nset logscale xy\nset grid\n"
      "set title 'speed against accuracy: each run against the reference'\n"
      "set xlabel 'run time [s]'\nset ylabel 'largest objective error vs the reference (objective units)'\n"
      "plot 'sweep.csv' using (column('run_time_s')):(column('objective_error') > 0 ? column('objective_error') : 1/0) "
      "with linespoints pt 7 notitle, '' using (column('run_time_s')):(column('objective_error') > 0 ? "
      "column('objective_error') : 1/0):(column('label')) with labels offset 1,1 font ',8' notitle\n";
  const std::string why = render_figure(dir.string(), "sweep", "speed against accuracy", FigureStyle{}, body);
  if (!why.empty()) log << "sweep: no plot written (the CSV has the data): " << why << "\n";
}

// Every combination of the axes' values, the last axis fastest: its overrides and its values
// (path -> value).
void combinations(const std::vector<SweepAxis>& axes, std::vector<std::vector<std::string>>& combos,
                  std::vector<Json>& combo_values) {
  combos = {{}};
  combo_values = {Json::object()};
  for (const SweepAxis& axis : axes) {
    std::vector<std::vector<std::string>> next;
    std::vector<Json> next_values;
    for (std::size_t c = 0; c < combos.size(); ++c) {
      for (const Json& v : axis.values) {
        auto sets = combos[c];
        Json values = combo_values[c];
        for (const std::string& p : axis.paths) {
          sets.push_back(assignment(p, v));
          values[p] = v;
        }
        next.push_back(sets);
        next_values.push_back(values);
      }
    }
    combos = std::move(next);
    combo_values = std::move(next_values);
  }
}

// The runs against the reference: the rows of sweep.json's "runs" (returned) and sweep.csv.
Json tabulate_runs(const std::vector<RunRecord>& runs, const Json& reference, const std::vector<SweepAxis>& axes,
                   std::string& csv_text) {
  Json rows = Json::array();
  std::ostringstream csv;
  csv.precision(10);
  std::vector<std::string> objective_names;
  if (reference.is_object() && reference.contains("best")) {
    for (auto it = reference["best"]["objectives"].begin(); it != reference["best"]["objectives"].end(); ++it) {
      objective_names.push_back(it.key());
    }
  }
  csv << "label";
  for (const SweepAxis& axis : axes) csv << "," << axis.paths[0];
  csv << ",run_time_s,solve_time_s,scene_from_cache,designs,samples,status";
  for (const auto& n : objective_names) csv << "," << n;
  csv << ",objective_error,design_distance,igd,time_ratio_to_reference\n";
  const Json reference_time = reference.is_null() ? Json(nullptr) : reference["sweep_run_time_s"];
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const Json& r = runs[i].result;
    const Json from_cache = r.contains("scene") && r["scene"].contains("from_cache") ? r["scene"]["from_cache"] : Json(nullptr);
    Json row = {{"values", runs[i].values},
                {"run_time_s", r["sweep_run_time_s"]},
                {"solve_time_s", r["wall_time_s"]},
                {"scene_from_cache", from_cache},
                {"evaluations", r["evaluations"]},
                {"status", r["status"]},
                {"reused", runs[i].reused},
                {"errors", errors_against(r, reference.is_null() ? Json::object() : reference)}};
    if (r.contains("best")) row["objectives"] = r["best"]["objectives"];
    rows.push_back(row);
    std::string label;
    for (const SweepAxis& axis : axes) label += (label.empty() ? "" : " ") + csv_cell(runs[i].values[axis.paths[0]]);
    csv << '"' << label << '"';
    for (const SweepAxis& axis : axes) csv << "," << csv_cell(runs[i].values[axis.paths[0]]);
    csv << "," << r["sweep_run_time_s"].get<double>() << "," << r["wall_time_s"].get<double>() << "," << csv_cell(from_cache)
        << "," << r["evaluations"]["designs"] << "," << r["evaluations"]["samples"]
        << "," << r["status"].get<std::string>();
    for (const auto& n : objective_names) {
      csv << "," << (r.contains("best") && r["best"]["objectives"].contains(n) ? r["best"]["objectives"][n].dump() : "");
    }
    csv << "," << csv_cell(row["errors"]["objective_error"]) << "," << csv_cell(row["errors"]["design_distance"]) << ","
        << csv_cell(row["errors"]["igd"]) << ","
        << (reference_time.is_null() ? std::string() : csv_cell(Json(r["sweep_run_time_s"].get<double>() / reference_time.get<double>())))
        << "\n";
  }
  csv_text = csv.str();
  return rows;
}

// One run of the sweep: its overrides, its values (path -> value; {} for a separate reference),
// its folder name and its resolved problem.
struct SweepCase {
  std::vector<std::string> sets;
  Json values;
  std::string name;
  Json resolved;
};

// What rank 0 needs of a run's result.json for the tables and errors: the result without its
// problem, statistics and per-sample data, front points reduced to their objectives. Small
// enough to send from any rank.
Json essentials(const Json& result) {
  Json e = Json::object();
  for (const char* key : {"status", "best", "evaluations", "wall_time_s", "sweep_run_time_s", "hapsyn", "machine", "seed"}) {
    if (result.contains(key)) e[key] = result[key];
  }
  if (result.contains("scene") && result["scene"].is_object() && result["scene"].contains("from_cache")) {
    e["scene"] = {{"from_cache", result["scene"]["from_cache"]}};
  }
  if (result.contains("front")) {
    Json front = Json::array();
    for (const Json& p : result["front"]) front.push_back({{"objectives", p["objectives"]}});
    e["front"] = std::move(front);
  }
  return e;
}

Json axes_record(const std::vector<SweepAxis>& axes) {
  Json out = Json::array();
  for (const SweepAxis& a : axes) out.push_back({{"paths", a.paths}, {"values", a.values}});
  return out;
}

// Runs `work` on every rank (the first rank of each node first: it builds the scene caches the
// node's other ranks then read) and throws on every rank alike when it failed on any: rank 0's
// error as it is, else the first other rank's, naming it.
void on_every_rank(Cluster& cluster, const std::function<void()>& work, const std::string& component) {
  if (cluster.size() == 1) return work();
  Json error = nullptr;
  const auto attempt = [&] {
    try {
      work();
    } catch (const std::exception& e) {
      error = error_record(e, component);
    }
  };
  const bool first = first_on_node(cluster);
  if (first) attempt();
  node_barrier(cluster);
  if (!first) attempt();
  const std::vector<std::string> errors = cluster.all_gather(error.dump());
  for (std::size_t r = 0; r < errors.size(); ++r) {
    const Json record = Json::parse(errors[r]);
    if (record.is_null()) continue;
    if (r == 0) throw_record(record);
    throw Error(component, "rank " + std::to_string(r) + " on " + cluster.host(static_cast<int>(r)) + ": " +
                               record["component"].get<std::string>() + ": " + record["message"].get<std::string>());
  }
}

// A sweep being run: its inputs, its cases (the combinations, then a separate reference) and
// where they run. Shared by the steps of run_sweep_cases.
struct Sweep {
  const Json& problem;
  const SweepOptions& options;
  const Registry& registry;
  bool reuse_only;                  // a merge: every run must be reused
  LoadSettings settings;            // scene builds get the sweep's threads, as the runs do
  std::vector<Json> combo_values;   // per combination, path -> value
  std::vector<SweepCase> cases;
  std::vector<std::string> names;   // per case, its folder name
  fs::path out;

  Json document(const std::vector<std::string>& sets) const {
    Json doc = problem;
    for (const std::string& s : sets) apply_override(doc, s);
    return doc;
  }
  std::size_t combination_count() const { return combo_values.size(); }
  std::size_t reference_case() const { return cases.size() - 1; }
};

// Every run (and the reference) validated before any of them starts, on every rank alike.
void make_cases(Sweep& s, Cluster& cluster) {
  std::vector<std::vector<std::string>> combos;
  combinations(s.options.axes, combos, s.combo_values);
  const auto validate = [&] {
    for (std::size_t c = 0; c < combos.size(); ++c) {
      try {
        s.cases.push_back({combos[c], s.combo_values[c], "run-" + std::to_string(c),
                           load_study(s.document(combos[c]), s.registry, {}, s.settings).resolved});
      } catch (const Error& e) {
        throw Error("sweep", "run with " + s.combo_values[c].dump() + ": " + e.what());
      }
    }
    if (!s.options.reference.empty()) {
      s.cases.push_back({s.options.reference, Json::object(), "reference",
                         load_study(s.document(s.options.reference), s.registry, {}, s.settings).resolved});
    }
  };
  on_every_rank(cluster, validate, "sweep");
  for (const SweepCase& k : s.cases) s.names.push_back(k.name);
}

// Rank 0: the essentials of case c's finished result, to reuse; nullopt to run it.
std::optional<Json> reusable_run(const Sweep& s, long long c) {
  const SweepCase& k = s.cases[static_cast<std::size_t>(c)];
  const std::string dir = (s.out / k.name).string();
  std::optional<Json> stored = reusable_result(dir, k.resolved, s.options.seed, "sweep", "this sweep");
  if (!stored) {
    if (s.reuse_only) {
      throw Error("merge", dir + " (" + k.values.dump() + "): no finished result of this run to reuse (a merge "
                                     "runs nothing again)");
    }
    return std::nullopt;
  }
  if (!stored->contains("sweep_run_time_s")) (*stored)["sweep_run_time_s"] = (*stored)["wall_time_s"];
  return essentials(*stored);
}

// Runs case c on this process alone (a stopped run is resumed from its checkpoint); the essentials
// of its result, or nullopt when it stopped. A run's time covers everything a user waits for:
// validation, the scene (built or read from its cache: scene knobs cost there, not in the solver)
// and the solve.
std::optional<Json> run_case(const Sweep& s, long long c) {
  const SweepCase& k = s.cases[static_cast<std::size_t>(c)];
  if (!s.options.quiet) {
    std::cerr << "sweep: "
              << (k.name == "reference" ? std::string("reference")
                                        : "run " + std::to_string(c + 1) + "/" + std::to_string(s.combination_count()))
              << " " << k.values.dump() << "\n";
  }
  const auto t0 = std::chrono::steady_clock::now();
  const fs::path dir = s.out / k.name;
  Study study = load_study(s.document(k.sets), s.registry, {}, s.settings);
  RunOptions run;
  run.threads = s.options.threads;
  run.seed = s.options.seed;
  run.quiet = s.options.quiet;
  run.write_samples = false;
  run.stop = s.options.stop;
  run.output_directory = dir.string();
  continue_in_folder(run, s.options.force);
  Json result;
  try {
    result = run_study(study, run);
  } catch (const Error& e) {
    throw Error("sweep", dir.string() + " (" + k.values.dump() + "): " + e.what());
  }
  result["sweep_run_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // The run time is kept with the result, for a later sweep that reuses it.
  write_file_atomically((dir / "result.json").string(), result.dump(2) + "\n");
  if (result["status"] == to_string(SolverStatus::kStopped)) return std::nullopt;
  return essentials(result);
}

// What the summary records of the reference, the machine and the inputs (to run it again).
void describe_inputs(const Sweep& s, const Json& reference, const std::vector<RunRecord>& runs, Json& summary) {
  const SweepOptions& options = s.options;
  const bool have_reference = !reference.is_null();
  summary["reference"] = {{"overrides", options.reference.empty() ? Json(s.combo_values.back()) : Json(options.reference)},
                          {"run_time_s", have_reference ? reference.value("sweep_run_time_s", Json(nullptr)) : Json(nullptr)},
                          {"best", have_reference && reference.contains("best") ? reference["best"] : Json(nullptr)}};
  const Json any = have_reference ? reference : runs.empty() ? Json(nullptr) : runs.front().result;
  summary["hapsyn"] = any.is_null() ? Json({{"version", version()}}) : any["hapsyn"];
  summary["machine"] = any.is_null() ? machine_info() : any["machine"];
  summary["seed"] = any.is_null() ? (options.seed ? Json(*options.seed) : Json(nullptr)) : any["seed"];
  summary["problem"] = s.problem;
  summary["problem_directory"] = problem_directory();
  summary["options"] = {{"axes", axes_record(options.axes)},
                        {"reference", options.reference},
                        {"seed", options.seed ? Json(*options.seed) : Json(nullptr)}};
}

// Rank 0: the summary of this share's runs (rows by run order, whoever ran them); writes
// sweep.csv, sweep.json and the plot.
Json sweep_summary(const Sweep& s, const CaseBatchOutcome& o, const Cluster& cluster) {
  std::vector<RunRecord> runs;
  std::vector<std::string> run_names;  // per row, its run folder
  for (long long c = o.first; c < o.last; ++c) {
    const std::size_t i = static_cast<std::size_t>(c);
    if (i >= s.combination_count() || !o.records[i]) continue;
    runs.push_back({s.cases[i].values, *o.records[i], o.reused[i] != 0});
    run_names.push_back(s.names[i]);
  }
  const Json reference = o.records[s.reference_case()] ? *o.records[s.reference_case()] : Json(nullptr);
  const std::string stopped_at = first_unfinished(o, s.names, cluster);
  Json summary;
  summary["status"] = stopped_at.empty() ? "finished" : "stopped";
  if (!stopped_at.empty()) {
    summary["message"] = "stopped on request at " + stopped_at + " after " + std::to_string(runs.size()) + " of " +
                         std::to_string(s.combination_count()) +
                         " runs; run the same command again to continue (finished runs are reused, a stopped one "
                         "resumes from its checkpoint)";
  }
  add_shard_entry(summary, o, s.names, cluster, stopped_at);
  describe_inputs(s, reference, runs, summary);
  std::string csv;
  summary["runs"] = tabulate_runs(runs, reference, s.options.axes, csv);
  // Each row names its run folder (under several ranks or shards the finished runs need not be
  // the first ones).
  for (std::size_t row = 0; row < run_names.size(); ++row) summary["runs"][row]["case"] = run_names[row];
  write_file_atomically((s.out / "sweep.csv").string(), csv);
  write_file_atomically((s.out / "sweep.json").string(), summary.dump(2) + "\n");
  if (!reference.is_null()) write_plot(s.out, std::cerr);
  summary["output_directory"] = s.out.string();
  return summary;
}

Json run_sweep_cases(const Json& problem, const SweepOptions& options, const Registry& registry, bool reuse_only) {
  if (options.axes.empty()) throw Error("sweep", "at least one --vary is required");
  Cluster& cluster = options.cluster != nullptr ? *options.cluster : Cluster::local();
  Sweep s{problem, options, registry, reuse_only, {}, {}, {}, {}, fs::path(options.output_directory)};
  s.settings.threads = options.threads;
  make_cases(s, cluster);
  CaseBatch batch;
  batch.count = static_cast<long long>(s.cases.size());
  batch.output_directory = s.out.string();
  batch.component = "sweep";
  batch.force = options.force;
  batch.stop = options.stop;
  batch.reuse = [&](long long c) { return reusable_run(s, c); };
  batch.run = [&](long long c) { return run_case(s, c); };
  const CaseBatchOutcome outcome = run_case_batch(batch, cluster);  // one run at a time per rank
  return summary_on_every_rank(cluster, [&] { return sweep_summary(s, outcome, cluster); }, "sweep");
}

}  // namespace

Json run_sweep(const Json& problem, const SweepOptions& options, const Registry& registry) {
  return run_sweep_cases(problem, options, registry, false);
}

bool is_sweep_output(const std::string& dir) {
  boost::system::error_code ec;
  return fs::is_regular_file(fs::path(dir) / "sweep.json", ec);
}

Json merge_sweep_shards(const std::vector<std::string>& dirs, const std::string& out_dir, const Registry& registry,
                        int threads) {
  const std::vector<Json> shards =
      gather_shards(dirs, out_dir, "sweep.json", "sweep",
                    {{"/problem", "problem"},
                     {"/options/axes", "axes"},
                     {"/options/reference", "reference"},
                     {"/options/seed", "seed"},
                     {"/hapsyn/version", "hapsyn version"}});
  const Json& first = shards.front();
  SweepOptions options;
  try {
    for (const Json& a : first.at("options").at("axes")) {
      options.axes.push_back({a.at("paths").get<std::vector<std::string>>(), a.at("values").get<std::vector<Json>>()});
    }
    options.reference = first["options"].at("reference").get<std::vector<std::string>>();
    if (!first["options"].at("seed").is_null()) options.seed = first["options"]["seed"].get<std::uint64_t>();
  } catch (const Json::exception& e) {
    throw Error("merge", dirs.front() + "/sweep.json: its \"options\" are not a sweep's (" + e.what() + ")");
  }
  options.output_directory = out_dir;
  options.threads = threads;
  options.quiet = true;
  // The problem's relative paths resolve as they did for the shares.
  const std::string folder = first.value("problem_directory", std::string());
  std::optional<ProblemDirectoryScope> scope;
  if (!folder.empty()) scope.emplace((fs::path(folder) / "sweep.json").string());
  return run_sweep_cases(first.at("problem"), options, registry, true);
}

}  // namespace hapsyn
