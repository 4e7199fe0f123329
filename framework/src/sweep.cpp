#include <hapsyn/cluster.hpp>
#include <hapsyn/json_text.hpp>
#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/internal/plot.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/read_file.hpp>
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

// A result.json is a few MB at most (a front, statistics); anything far larger is not one.
constexpr std::uint64_t kMaxResultBytes = 1ULL << 30;

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

}  // namespace

std::optional<Json> reusable_result(const std::string& directory, const Json& resolved,
                                    const std::optional<std::uint64_t>& seed, const std::string& component,
                                    const std::string& what) {
  const fs::path file = fs::path(directory) / "result.json";
  boost::system::error_code ec;
  if (!fs::exists(file, ec)) return std::nullopt;
  const std::string remedy = "; delete it, or choose another --out";
  Json stored;
  try {
    stored = parse_json_text(read_regular_file(file.string(), component, "result", kMaxResultBytes), file.string(), component.c_str());
  } catch (const std::exception& e) {
    throw Error(component, file.string() + ": not a readable result (" + e.what() + ")" + remedy);
  }
  if (!stored.is_object() || !stored.contains("problem") || !stored.contains("status") || !stored["status"].is_string()) {
    throw Error(component, file.string() + ": not a hapsyn result (no \"problem\" or \"status\")" + remedy);
  }
  if (stored["problem"] != resolved) {
    const Json patch = Json::diff(stored["problem"], resolved);
    const std::string at = patch.empty() ? std::string("/") : patch[0].value("path", std::string("/"));
    const Json here = stored["problem"].contains(Json::json_pointer(at)) ? stored["problem"][Json::json_pointer(at)] : Json("(absent)");
    const Json there = resolved.contains(Json::json_pointer(at)) ? resolved[Json::json_pointer(at)] : Json("(absent)");
    throw Error(component, directory + " holds a result of another problem (first difference at " + at + ": " + here.dump() +
                               " there, " + there.dump() + " in " + what + ")" + remedy);
  }
  if (seed && (!stored.contains("seed") || stored["seed"] != *seed)) {
    throw Error(component, directory + " holds a result run with seed " + stored.value("seed", Json()).dump() + ", " + what +
                               " has seed " + std::to_string(*seed) + remedy);
  }
  if (stored["status"] == to_string(SolverStatus::kStopped)) return std::nullopt;
  return stored;
}

std::pair<long long, long long> shard_tasks(const Cluster& cluster, long long count) {
  // Plain variables: a structured binding cannot be captured by a lambda in C++17.
  const std::pair<int, int> share = cluster.shard();
  const int index = share.first, shards = share.second;
  if (shards <= 1) return {0, count};
  // The split ShardCluster::run_tasks makes (contiguous shares, (count*i)/N in long double).
  const auto bound = [&](int i) { return static_cast<long long>(static_cast<long double>(count) * i / shards); };
  return {bound(index), bound(index + 1)};
}

namespace {

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

// An error decided on rank 0 before a farm, thrown alike on every rank: {"component", "message"}.
Json error_record(const std::exception& e, const std::string& fallback_component) {
  if (const auto* error = dynamic_cast<const Error*>(&e)) {
    const std::string what = error->what();
    const std::string prefix = error->component() + ": ";
    return {{"component", error->component()},
            {"message", what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what}};
  }
  return {{"component", fallback_component}, {"message", e.what()}};
}

[[noreturn]] void throw_record(const Json& record) {
  throw Error(record["component"].get<std::string>(), record["message"].get<std::string>());
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

Json run_sweep_cases(const Json& problem, const SweepOptions& options, const Registry& registry, bool reuse_only) {
  if (options.axes.empty()) throw Error("sweep", "at least one --vary is required");
  Cluster& cluster = options.cluster != nullptr ? *options.cluster : Cluster::local();
  std::vector<std::vector<std::string>> combos;
  std::vector<Json> combo_values;
  combinations(options.axes, combos, combo_values);
  // Validate every run (and the reference) before any of them starts, on every rank alike. Scene
  // builds get the sweep's threads, as the runs do.
  LoadSettings settings;
  settings.threads = options.threads;
  auto make_doc = [&](const std::vector<std::string>& sets) {
    Json doc = problem;
    for (const std::string& s : sets) apply_override(doc, s);
    return doc;
  };
  std::vector<SweepCase> cases;
  const bool separate_reference = !options.reference.empty();
  const auto validate = [&] {
    for (std::size_t c = 0; c < combos.size(); ++c) {
      try {
        cases.push_back({combos[c], combo_values[c], "run-" + std::to_string(c),
                         load_study(make_doc(combos[c]), registry, {}, settings).resolved});
      } catch (const Error& e) {
        throw Error("sweep", "run with " + combo_values[c].dump() + ": " + e.what());
      }
    }
    if (separate_reference) {
      cases.push_back({options.reference, Json::object(), "reference",
                       load_study(make_doc(options.reference), registry, {}, settings).resolved});
    }
  };
  on_every_rank(cluster, validate, "sweep");
  const std::size_t reference_case = cases.size() - 1;
  const auto range = shard_tasks(cluster, static_cast<long long>(cases.size()));
  const long long first = range.first, last = range.second;  // captured below (C++17: no structured binding)

  const fs::path out(options.output_directory);
  // Rank 0 finds the finished runs to reuse (and refuses foreign results) before any run starts,
  // then tells the other ranks which runs are done, or the error every rank throws.
  std::vector<std::optional<Json>> results(cases.size());  // rank 0: per case, its essentials
  std::vector<char> reused(cases.size(), 0);
  {
    Json decision = Json::object();
    if (cluster.root()) {
      try {
        fs::create_directories(out);
        for (long long c = first; c < last && !options.force; ++c) {
          const SweepCase& k = cases[static_cast<std::size_t>(c)];
          const std::string dir = (out / k.name).string();
          std::optional<Json> stored = reusable_result(dir, k.resolved, options.seed, "sweep", "this sweep");
          if (!stored) {
            if (reuse_only) {
              throw Error("merge", dir + " (" + k.values.dump() + "): no finished result of this run to reuse (a merge "
                                             "runs nothing again)");
            }
            continue;
          }
          if (!stored->contains("sweep_run_time_s")) (*stored)["sweep_run_time_s"] = (*stored)["wall_time_s"];
          results[static_cast<std::size_t>(c)] = essentials(*stored);
          decision["reused"].push_back(c);
        }
      } catch (const std::exception& e) {
        decision = {{"error", error_record(e, "sweep")}};
      }
    }
    std::string bytes = decision.dump();
    cluster.broadcast(bytes);
    decision = Json::parse(bytes);
    if (decision.contains("error")) throw_record(decision["error"]);
    if (decision.contains("reused")) {
      for (const Json& c : decision["reused"]) reused[c.get<std::size_t>()] = 1;
    }
  }

  RunOptions base;
  base.threads = options.threads;
  base.seed = options.seed;
  base.quiet = options.quiet;
  base.write_samples = false;
  base.stop = options.stop;
  // A run's time covers everything a user waits for: validation, the scene (built or read from
  // its cache: scene knobs cost there, not in the solver) and the solve. A stopped run is resumed
  // from its checkpoint. The run happens on this process alone (cluster null).
  auto run_case = [&](const SweepCase& k) {
    const auto t0 = std::chrono::steady_clock::now();
    const fs::path dir = out / k.name;
    Study study = load_study(make_doc(k.sets), registry, {}, settings);
    RunOptions run_options = base;
    run_options.output_directory = dir.string();
    boost::system::error_code ec;
    if (options.force) {
      run_options.force = true;  // the sweep owns its run directories
    } else {
      // A stopped run's result.json gives way to the continued run's.
      fs::remove(dir / "result.json", ec);
      run_options.resume = fs::exists(dir / "checkpoint.json", ec);
    }
    Json result;
    try {
      result = run_study(study, run_options);
    } catch (const Error& e) {
      throw Error("sweep", dir.string() + " (" + k.values.dump() + "): " + e.what());
    }
    result["sweep_run_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    // The run time is kept with the result, for a later sweep that reuses it.
    write_file_atomically((dir / "result.json").string(), result.dump(2) + "\n");
    return result;
  };
  const auto stop_requested = [&] { return options.stop != nullptr && options.stop->load(); };
  const std::string stopped_status = to_string(SolverStatus::kStopped);

  std::vector<char> started(cases.size(), 0);  // by this process
  TaskFarm farm;
  farm.count = static_cast<long long>(cases.size());
  farm.shardable = true;
  farm.done = [&](long long c) { return reused[static_cast<std::size_t>(c)] != 0; };
  farm.run = [&](long long c, int) -> std::optional<std::string> {
    if (stop_requested()) return std::nullopt;
    const SweepCase& k = cases[static_cast<std::size_t>(c)];
    started[static_cast<std::size_t>(c)] = 1;
    if (!options.quiet) {
      std::cerr << "sweep: " << (k.name == "reference" ? std::string("reference") : "run " + std::to_string(c + 1) + "/" + std::to_string(combos.size()))
                << " " << k.values.dump() << "\n";
    }
    Json result = run_case(k);
    if (result["status"] == stopped_status) return std::nullopt;
    return essentials(result).dump();
  };
  farm.collect = [&](long long c, std::string&& bytes) { results[static_cast<std::size_t>(c)] = Json::parse(bytes); };
  (void)cluster.run_tasks(farm, 1);  // one run at a time per rank, each with options.threads

  // Rank 0 tabulates (rows by run order, whoever ran them) and writes the files; every rank
  // returns its summary.
  Json message = Json::object();
  if (cluster.root()) {
    try {
      std::vector<RunRecord> runs;
      std::string stopped_at;  // the first run of this share that did not finish
      std::size_t finished = 0;
      for (long long c = first; c < last; ++c) {
        const std::size_t i = static_cast<std::size_t>(c);
        if (!results[i]) {
          if (stopped_at.empty()) {
            stopped_at = cases[i].name + (cluster.size() == 1 && !started[i] ? " (not started)" : "");
          }
          continue;
        }
        if (i < combos.size()) {
          runs.push_back({cases[i].values, *results[i], reused[i] != 0});
          ++finished;
        }
      }
      Json reference = nullptr;
      if (results[reference_case]) reference = *results[reference_case];

      Json summary;
      summary["status"] = stopped_at.empty() ? "finished" : "stopped";
      if (!stopped_at.empty()) {
        summary["message"] = "stopped on request at " + stopped_at + " after " + std::to_string(finished) + " of " +
                             std::to_string(combos.size()) +
                             " runs; run the same command again to continue (finished runs are reused, a stopped one "
                             "resumes from its checkpoint)";
      }
      const auto [shard_index, shard_count] = cluster.shard();
      if (shard_count > 1) {
        Json names = Json::array();
        for (long long c = first; c < last; ++c) names.push_back(cases[static_cast<std::size_t>(c)].name);
        summary["shard"] = {{"index", shard_index + 1}, {"count", shard_count}, {"cases", names}};
        if (stopped_at.empty()) summary["message"] = cluster.shard_message();
      }
      const bool have_reference = !reference.is_null();
      summary["reference"] = {{"overrides", options.reference.empty() ? Json(combo_values.back()) : Json(options.reference)},
                              {"run_time_s", have_reference ? reference["sweep_run_time_s"] : Json(nullptr)},
                              {"best", have_reference && reference.contains("best") ? reference["best"] : Json(nullptr)}};
      const Json any = have_reference ? reference : runs.empty() ? Json(nullptr) : runs.front().result;
      summary["hapsyn"] = any.is_null() ? Json({{"version", version()}}) : any["hapsyn"];
      summary["machine"] = any.is_null() ? machine_info() : any["machine"];
      summary["seed"] = any.is_null() ? (options.seed ? Json(*options.seed) : Json(nullptr)) : any["seed"];
      summary["problem"] = problem;
      summary["problem_directory"] = problem_directory();
      summary["options"] = {{"axes", axes_record(options.axes)},
                            {"reference", options.reference},
                            {"seed", options.seed ? Json(*options.seed) : Json(nullptr)}};
      std::string csv;
      summary["runs"] = tabulate_runs(runs, reference, options.axes, csv);
      {
        // Each row names its run folder (under several ranks or shards the finished runs need
        // not be the first ones).
        std::size_t row = 0;
        for (long long c = first; c < last; ++c) {
          const std::size_t i = static_cast<std::size_t>(c);
          if (i < combos.size() && results[i]) summary["runs"][row++]["case"] = cases[i].name;
        }
      }
      write_file_atomically((out / "sweep.csv").string(), csv);
      write_file_atomically((out / "sweep.json").string(), summary.dump(2) + "\n");
      if (have_reference) write_plot(out, std::cerr);
      summary["output_directory"] = out.string();
      message = {{"summary", std::move(summary)}};
    } catch (const std::exception& e) {
      message = {{"error", error_record(e, "sweep")}};
    }
  }
  std::string bytes = message.dump();
  cluster.broadcast(bytes);
  if (!cluster.root()) message = Json::parse(bytes);
  if (message.contains("error")) throw_record(message["error"]);
  return std::move(message["summary"]);
}

// Hard-links (or, where links fail, copies) the tree `from` to `to`, leaving out a run's lock
// file and staging folders.
void link_tree(const fs::path& from, const fs::path& to) {
  fs::create_directories(to);
  for (fs::directory_iterator it(from), end; it != end; ++it) {
    const std::string name = it->path().filename().string();
    if (name == ".lock" || name.rfind(".staging-", 0) == 0) continue;
    const fs::path target = to / name;
    if (fs::is_directory(it->symlink_status())) {
      link_tree(it->path(), target);
    } else if (fs::is_regular_file(it->symlink_status())) {
      boost::system::error_code ec;
      fs::create_hard_link(it->path(), target, ec);
      if (ec) fs::copy_file(it->path(), target);
    }
  }
}

std::string share_name(const Json& summary) {
  return std::to_string(summary["shard"]["index"].get<int>()) + "/" + std::to_string(summary["shard"]["count"].get<int>());
}

}  // namespace

Json run_sweep(const Json& problem, const SweepOptions& options, const Registry& registry) {
  return run_sweep_cases(problem, options, registry, false);
}

bool is_sweep_output(const std::string& dir) {
  boost::system::error_code ec;
  return fs::is_regular_file(fs::path(dir) / "sweep.json", ec);
}

std::vector<Json> gather_shards(const std::vector<std::string>& dirs, const std::string& out_dir,
                                const std::string& summary_file, const std::string& what,
                                const std::vector<std::pair<std::string, std::string>>& same) {
  if (dirs.empty()) throw Error("merge", "no shard directory given");
  std::vector<Json> summaries;
  for (const std::string& dir : dirs) {
    const std::string file = (fs::path(dir) / summary_file).string();
    Json s;
    try {
      s = parse_json_text(read_regular_file(file, "merge", what + " summary", kMaxResultBytes), file, "merge");
    } catch (const std::exception& e) {
      throw Error("merge", file + ": not a readable " + what + " summary (" + e.what() + ")");
    }
    const bool shard_ok = s.is_object() && s.contains("shard") && s["shard"].is_object() &&
                          s["shard"].value("index", Json()).is_number_integer() &&
                          s["shard"].value("count", Json()).is_number_integer() &&
                          s["shard"].value("cases", Json()).is_array();
    if (!shard_ok) {
      throw Error("merge", dir + " is not a shard of a " + what + " (its " + summary_file +
                               " has no \"shard\" entry: it ran without --shard)");
    }
    summaries.push_back(std::move(s));
  }
  // One job: the same share count first (the shares' numbers mean nothing otherwise), then each
  // share once, then the same inputs.
  const int count = summaries[0]["shard"]["count"];
  for (std::size_t i = 1; i < summaries.size(); ++i) {
    if (summaries[i]["shard"]["count"] != count) {
      throw Error("merge", dirs[i] + " (shard " + share_name(summaries[i]) + ") is not of the same " + what + " as " +
                               dirs[0] + " (shard " + share_name(summaries[0]) + "): its shard count differs");
    }
  }
  std::vector<int> given(static_cast<std::size_t>(count), -1);  // share -> position in dirs
  for (std::size_t i = 0; i < summaries.size(); ++i) {
    const int index = summaries[i]["shard"]["index"];
    if (index < 1 || index > count) {
      throw Error("merge", dirs[i] + ": shard " + share_name(summaries[i]) + " is not a share of " + std::to_string(count));
    }
    int& slot = given[static_cast<std::size_t>(index - 1)];
    if (slot >= 0) {
      throw Error("merge", "shard " + share_name(summaries[i]) + " is given twice (" + dirs[static_cast<std::size_t>(slot)] +
                               ", " + dirs[i] + ")");
    }
    slot = static_cast<int>(i);
  }
  for (int k = 0; k < count; ++k) {
    if (given[static_cast<std::size_t>(k)] >= 0) continue;
    std::string have;
    for (int j = 0; j < count; ++j) {
      if (given[static_cast<std::size_t>(j)] >= 0) have += (have.empty() ? "" : ", ") + std::to_string(j + 1) + "/" + std::to_string(count);
    }
    throw Error("merge", "shard " + std::to_string(k + 1) + "/" + std::to_string(count) + " is missing (given: " + have + ")");
  }
  for (std::size_t i = 1; i < summaries.size(); ++i) {
    for (const auto& [pointer, name] : same) {
      const Json::json_pointer p(pointer);
      const Json a = summaries[0].contains(p) ? summaries[0][p] : Json(nullptr);
      const Json b = summaries[i].contains(p) ? summaries[i][p] : Json(nullptr);
      if (a == b) continue;
      const std::string detail = a.dump().size() + b.dump().size() <= 80 ? " (" + b.dump() + " there, " + a.dump() + " in " + dirs[0] + ")" : "";
      throw Error("merge", dirs[i] + " (shard " + share_name(summaries[i]) + ") is not of the same " + what + " as " +
                               dirs[0] + " (shard " + share_name(summaries[0]) + "): its " + name + " differs" + detail);
    }
  }
  for (std::size_t i = 0; i < summaries.size(); ++i) {
    if (summaries[i].value("status", "") != "finished") {
      throw Error("merge", dirs[i] + " (shard " + share_name(summaries[i]) + ") stopped before its runs finished (status " +
                               summaries[i].value("status", Json()).dump() +
                               "): run its command again to finish it, then merge");
    }
  }
  boost::system::error_code ec;
  for (std::size_t i = 0; i < summaries.size(); ++i) {
    if (fs::exists(out_dir, ec) && fs::equivalent(dirs[i], out_dir, ec)) {
      throw Error("merge", out_dir + " is shard " + share_name(summaries[i]) +
                               "'s directory: merge into another directory");
    }
  }
  std::vector<Json> ordered;
  fs::create_directories(out_dir);
  for (int k = 0; k < count; ++k) {
    const std::size_t i = static_cast<std::size_t>(given[static_cast<std::size_t>(k)]);
    for (const Json& name : summaries[i]["shard"]["cases"]) {
      const std::string folder = name.get<std::string>();
      const fs::path from = fs::path(dirs[i]) / folder;
      if (folder.empty() || folder.find('/') != std::string::npos || folder == "." || folder == ".." ||
          !fs::is_regular_file(from / "result.json", ec)) {
        throw Error("merge", from.string() + ": missing, or without result.json (shard " + share_name(summaries[i]) +
                                 "'s " + summary_file + " lists it as finished)");
      }
      const fs::path to = fs::path(out_dir) / folder;
      fs::remove_all(to);
      link_tree(from, to);
    }
    ordered.push_back(std::move(summaries[i]));
  }
  return ordered;
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
