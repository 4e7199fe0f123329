#include <hapsyn/error.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/plot.hpp>
#include <hapsyn/problem_file.hpp>
#include <hapsyn/read_file.hpp>
#include <hapsyn/solver.hpp>
#include <hapsyn/study.hpp>
#include <hapsyn/study_runner.hpp>
#include <hapsyn/sweep.hpp>

#include <boost/filesystem.hpp>

#include <cstdlib>
#include <fstream>

#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
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
    return Json::parse(text);
  } catch (const Json::parse_error&) {
    return Json(text);
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
  const fs::path script = dir / "sweep.gnuplot";
  {
    std::ofstream out(script.string());
    out << "set datafile separator ','\nset logscale xy\nset xlabel 'run time [s]'\n"
           "set ylabel 'max objective error vs reference'\nset grid\nset key off\n";
    for (const char* term : {"pngcairo size 800,600", "svg size 800,600"}) {
      const std::string ext = std::string(term).rfind("svg", 0) == 0 ? "svg" : "png";
      out << "set terminal " << term << "\nset output 'sweep." << ext << "'\n"
          << "plot 'sweep.csv'"
          << " using (column('run_time_s')):(column('objective_error') > 0 ? column('objective_error') : 1/0) "
             "with linespoints pt 7, '' using (column('run_time_s')):(column('objective_error') > 0 ? "
             "column('objective_error') : 1/0):(column('label')) with labels offset 1,1 font ',8'\n";
    }
  }
  const std::string why = run_gnuplot(dir.string(), "sweep.gnuplot");
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
    stored = Json::parse(read_regular_file(file.string(), component, "result", kMaxResultBytes));
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

Json run_sweep(const Json& problem, const SweepOptions& options, const Registry& registry) {
  if (options.axes.empty()) throw Error("sweep", "at least one --vary is required");
  std::vector<std::vector<std::string>> combos;
  std::vector<Json> combo_values;
  combinations(options.axes, combos, combo_values);
  // Validate every run (and the reference) before any of them starts. Scene builds get the
  // sweep's threads, as the runs do.
  LoadSettings settings;
  settings.threads = options.threads;
  auto make_doc = [&](const std::vector<std::string>& sets) {
    Json doc = problem;
    for (const std::string& s : sets) apply_override(doc, s);
    return doc;
  };
  for (std::size_t c = 0; c < combos.size(); ++c) {
    try {
      load_study(make_doc(combos[c]), registry, {}, settings);
    } catch (const Error& e) {
      throw Error("sweep", "run with " + combo_values[c].dump() + ": " + e.what());
    }
  }
  const bool separate_reference = !options.reference.empty();
  if (separate_reference) load_study(make_doc(options.reference), registry, {}, settings);

  const fs::path out(options.output_directory);
  fs::create_directories(out);
  RunOptions base;
  base.threads = options.threads;
  base.seed = options.seed;
  base.quiet = options.quiet;
  base.write_samples = false;
  base.stop = options.stop;
  // A run's time covers everything a user waits for: validation, the scene (built or read from
  // its cache: scene knobs cost there, not in the solver) and the solve. A finished run of the
  // same problem in its folder is reused; a stopped one is resumed from its checkpoint.
  auto run_one = [&](const std::vector<std::string>& sets, const std::string& name, const Json& values) {
    const auto t0 = std::chrono::steady_clock::now();
    const fs::path dir = out / name;
    Study study = load_study(make_doc(sets), registry, {}, settings);
    RunRecord record{values, Json(), false};
    if (!options.force) {
      if (std::optional<Json> stored = reusable_result(dir.string(), study.resolved, options.seed, "sweep", "this sweep")) {
        record.result = std::move(*stored);
        if (!record.result.contains("sweep_run_time_s")) record.result["sweep_run_time_s"] = record.result["wall_time_s"];
        record.reused = true;
        return record;
      }
    }
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
    try {
      record.result = run_study(study, run_options);
    } catch (const Error& e) {
      throw Error("sweep", dir.string() + " (" + values.dump() + "): " + e.what());
    }
    record.result["sweep_run_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    // The run time is kept with the result, for a later sweep that reuses it.
    write_file_atomically((dir / "result.json").string(), record.result.dump(2) + "\n");
    return record;
  };
  const auto stop_requested = [&] { return options.stop != nullptr && options.stop->load(); };
  const std::string stopped_status = to_string(SolverStatus::kStopped);

  std::vector<RunRecord> runs;
  std::string stopped_at;  // the run folder that was stopped, or "" when none was
  for (std::size_t c = 0; c < combos.size() && stopped_at.empty(); ++c) {
    const std::string name = "run-" + std::to_string(c);
    if (stop_requested()) {
      stopped_at = name + " (not started)";
      break;
    }
    if (!options.quiet) std::cerr << "sweep: run " << (c + 1) << "/" << combos.size() << " " << combo_values[c].dump() << "\n";
    RunRecord record = run_one(combos[c], name, combo_values[c]);
    if (record.result["status"] == stopped_status) {
      stopped_at = name;
    } else {
      runs.push_back(std::move(record));
    }
  }
  Json reference = nullptr;
  if (stopped_at.empty()) {
    if (!separate_reference) {
      reference = runs.back().result;
    } else if (stop_requested()) {
      stopped_at = "reference (not started)";
    } else {
      RunRecord record = run_one(options.reference, "reference", Json::object());
      if (record.result["status"] == stopped_status) {
        stopped_at = "reference";
      } else {
        reference = record.result;
      }
    }
  }

  Json summary;
  summary["status"] = stopped_at.empty() ? "finished" : "stopped";
  if (!stopped_at.empty()) {
    summary["message"] = "stopped on request at " + stopped_at + " after " + std::to_string(runs.size()) + " of " +
                         std::to_string(combos.size()) +
                         " runs; run the same command again to continue (finished runs are reused, a stopped one "
                         "resumes from its checkpoint)";
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
  std::string csv;
  summary["runs"] = tabulate_runs(runs, reference, options.axes, csv);
  write_file_atomically((out / "sweep.csv").string(), csv);
  write_file_atomically((out / "sweep.json").string(), summary.dump(2) + "\n");
  if (have_reference) write_plot(out, std::cerr);
  summary["output_directory"] = out.string();
  return summary;
}

}  // namespace hapsyn
