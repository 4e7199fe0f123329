#include <hapsyn/cluster.hpp>
#include <hapsyn/internal/compare.hpp>
#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/internal/case_batch.hpp>
#include <hapsyn/internal/plot.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/solver.hpp>
#include <hapsyn/internal/study.hpp>
#include <hapsyn/internal/study_runner.hpp>

#include <boost/filesystem.hpp>

#include <cmath>
#include <fstream>
#include <optional>
#include <iomanip>
#include <set>
#include <sstream>

namespace hapsyn {

namespace fs = boost::filesystem;

namespace {

Json indicator(const Json& result, const char* key) {
  if (!result.contains("indicators") || !result["indicators"].contains(key)) return nullptr;
  return result["indicators"][key];
}

double max_of(const Json& per_objective) {
  if (!per_objective.is_object()) return NAN;
  double m = 0.0;
  for (auto it = per_objective.begin(); it != per_objective.end(); ++it) m = std::max(m, it.value().get<double>());
  return m;
}

std::vector<std::string> objective_names(const Json& result) {
  std::vector<std::string> names;
  for (const Json& o : result["problem"]["objectives"]) names.push_back(o["name"]);
  return names;
}

// Objective columns of a result's front (or its single design), one row per point.
std::string points_csv(const Json& result, const std::vector<std::string>& names) {
  std::ostringstream csv;
  csv.precision(12);
  for (std::size_t i = 0; i < names.size(); ++i) csv << (i ? "," : "") << names[i];
  csv << "\n";
  auto row = [&](const Json& point) {
    for (std::size_t i = 0; i < names.size(); ++i) csv << (i ? "," : "") << point["objectives"][names[i]].get<double>();
    csv << "\n";
  };
  if (result.contains("front")) {
    for (const Json& p : result["front"]) row(p);
  } else if (result.contains("best")) {
    row(result["best"]);
  }
  return csv.str();
}

// Fronts overlaid (two objectives): the reference front as a line, each Pareto study's points,
// each single-design study as a large star (Unal's Figures 3 and 7).
std::string plot_fronts(const fs::path& out, const std::vector<Json>& results, const Json& rows) {
  const std::vector<std::string> names = objective_names(results.front());
  if (names.size() != 2) return "fronts plot: only for two objectives";
  // Objectives carry no unit of their own: each axis names its objective and sense.
  const auto axis = [&](std::size_t k) {
    const Json& o = results.front()["problem"]["objectives"][k];
    return gnuplot_quote(names[k] + (o.contains("sense") ? " (" + o["sense"].get<std::string>() + ")" : ""));
  };
  std::ostringstream script;
  script << "set datafile separator ','\nset grid\nset title 'Pareto fronts compared'\n"
         << "set xlabel " << axis(0) << "\nset ylabel " << axis(1) << "\n";
  std::string reference_file;
  for (const Json& r : results) {
    const Json& section = r["problem"].contains("indicators") ? r["problem"]["indicators"] : Json::object();
    if (section.contains("reference_front")) {
      reference_file = section["reference_front"];
      break;
    }
  }
  std::ostringstream plot;
  plot << "plot ";
  bool first = true;
  if (!reference_file.empty()) {
    try {
      const Json reference = read_problem_file(reference_file);
      Json ref_doc = reference;
      std::ofstream(out / "reference_front.csv") << points_csv(ref_doc, names);
      plot << "'reference_front.csv' using 1:2 with linespoints lc rgb 'gray60' pt 1 ps 0.5 title 'reference front (exhaustive)'";
      first = false;
    } catch (const Error&) {
      // No reference line: the other curves still plot.
    }
  }
  int style = 0;
  for (std::size_t i = 0; i < results.size(); ++i) {
    const std::string name = rows[i]["study"];
    const std::string file = name + "/points.csv";
    std::ofstream(out / file) << points_csv(results[i], names);
    const bool single = !results[i].contains("front");
    const bool dense = !single && results[i]["front"].size() > 30;  // e.g. an exhaustive front
    static const char* const kStyles[] = {"pt 7 ps 1.4", "pt 6 ps 1.8", "pt 9 ps 1.4", "pt 4 ps 1.6", "pt 11 ps 1.4"};
    plot << (first ? "" : ", ") << gnuplot_quote(file) << " using 1:2 with points "
         << (single ? "pt 3 ps 3" : dense ? "pt 7 ps 0.4" : kStyles[style % 5]) << " title "
         << gnuplot_quote(name + " (" + rows[i]["solver"].get<std::string>() + ")");
    first = false;
    if (!single && !dense) ++style;
  }
  script << plot.str() << "\n";
  FigureStyle figure;
  figure.width = 1000;
  figure.height = 650;
  figure.key = true;
  return render_figure(out.string(), "fronts", "Pareto fronts compared", figure, script.str());
}

// Local values over the workspace for a study with one design (its samples.csv): one heat map
// per local value (Unal's Figure 2: singular values of J and M over the workspace).
std::string plot_samples(const fs::path& dir) {
  std::ifstream in((dir / "samples.csv").string());
  std::string header;
  if (!std::getline(in, header)) return "no samples.csv";
  std::vector<std::string> columns;
  std::stringstream split(header);
  for (std::string c; std::getline(split, c, ',');) columns.push_back(c);
  std::vector<std::size_t> locals;
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (columns[i].find('.') != std::string::npos) locals.push_back(i);
  }
  if (columns.size() < 3 || locals.empty()) return "samples.csv has no local values";
  // The scenes' x, y, z are positions in metres; other coordinates are named as they are.
  const auto axis = [](const std::string& c) { return gnuplot_quote(c == "x" || c == "y" || c == "z" ? c + " [m]" : c); };
  const std::string title = "local values of the design over the workspace (samples.csv)";
  std::ostringstream script;
  script << "set datafile separator ','\nset size ratio -1\nset palette rgbformulae 33,13,10\n"
         << "set xlabel " << axis(columns[1]) << "\nset ylabel " << axis(columns[2]) << "\n"
         << "set multiplot layout 1," << locals.size() << " title " << gnuplot_quote(title) << "\n";
  for (std::size_t k : locals) {
    script << "set title " << gnuplot_quote(columns[k]) << "\n"
           << "plot 'samples.csv' every ::1 using 2:3:" << (k + 1) << " with points pt 5 ps 0.6 palette\n";
  }
  script << "unset multiplot\n";
  FigureStyle style;
  style.width = 1200;
  style.height = 420;
  return render_figure(dir.string(), "local_values", title, style, script.str());
}

std::string cell(const Json& v, int precision = 4) {
  if (v.is_null()) return "-";
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_number_float()) {
    const double d = v.get<double>();
    if (!std::isfinite(d)) return "-";
    std::ostringstream s;
    s << std::setprecision(precision) << d;
    return s.str();
  }
  if (v.is_string()) return v.get<std::string>();
  return v.dump();
}

// What rank 0 needs of a study's result.json for the table and the plots: no statistics or
// per-sample data, front points reduced to their objectives, of the problem its objectives and
// indicators. Small enough to send from any rank.
Json essentials(const Json& result) {
  Json e = Json::object();
  for (const char* key : {"status", "best", "indicators", "evaluations", "wall_time_s"}) {
    if (result.contains(key)) e[key] = result[key];
  }
  if (result.contains("front")) {
    Json front = Json::array();
    for (const Json& p : result["front"]) front.push_back({{"objectives", p["objectives"]}});
    e["front"] = std::move(front);
  }
  e["problem"] = Json::object();
  for (const char* key : {"objectives", "indicators"}) {
    if (result.contains("problem") && result["problem"].contains(key)) e["problem"][key] = result["problem"][key];
  }
  return e;
}

// A study of the comparison: its file, its document (overrides applied) and its name.
struct CompareCase {
  std::string file;
  Json doc;
  std::string name;
  std::string reference;  // the study of this comparison whose front it is measured against, if any
};

// A study's default output directory, absolute (where `hapsyn run` would write it: relative
// to the working directory).
fs::path default_output_of(const CompareCase& k) {
  const Json& output = k.doc.value("output", Json::object());
  const std::string dir = output.is_object() && output.contains("directory") && output["directory"].is_string()
                              ? output["directory"].get<std::string>()
                              : "results/" + k.name;
  return fs::absolute(dir).lexically_normal();
}

// A study whose indicators.reference_front names the result.json another study of this
// comparison writes by default reads it where the comparison writes it, DIR/<name>/: the
// comparison's own reference study (once, the later studies read the stale or missing file at
// its default place, and GD, IGD and the gaps were "-" without a word).
void point_references_into_the_comparison(std::vector<CompareCase>& cases, const std::string& out) {
  for (CompareCase& k : cases) {
    const Json& indicators = k.doc.value("indicators", Json::object());
    if (!indicators.is_object() || !indicators.contains("reference_front") || !indicators["reference_front"].is_string()) {
      continue;
    }
    const fs::path named = indicators["reference_front"].get<std::string>();
    // As resolve_problem_path reads it: beside the problem file first, else the working directory.
    const std::vector<fs::path> readings = {
        fs::absolute(named, fs::absolute(fs::path(k.file).parent_path())).lexically_normal(),
        fs::absolute(named).lexically_normal()};
    for (const CompareCase& reference : cases) {
      if (&reference == &k) continue;
      const fs::path written = default_output_of(reference) / "result.json";
      if (std::find(readings.begin(), readings.end(), written) == readings.end()) continue;
      k.doc["indicators"]["reference_front"] = (fs::absolute(fs::path(out) / reference.name) / "result.json").string();
      k.reference = reference.name;
      break;
    }
  }
}

Study load_case(const CompareCase& k, const CompareOptions& options, const Registry& registry) {
  try {
    // Relative paths in a problem file are relative to that file first.
    const ProblemDirectoryScope scope(k.file);
    LoadSettings settings;
    settings.threads = options.threads;
    return load_study(k.doc, registry, {}, settings);
  } catch (const Error& e) {
    throw Error("compare", k.file + ": " + e.what());
  }
}

// A study's row of the table (its essentials in `result`).
Json study_row(const CompareCase& k, const Json& result, const std::string& solver, bool reused, const fs::path& out) {
  return {{"study", k.name},
          {"file", k.file},
          {"solver", solver},
          {"status", result["status"]},
          {"reused", reused},
          {"points", result.contains("front") ? result["front"].size() : (result.contains("best") ? 1 : 0)},
          {"hypervolume", indicator(result, "hypervolume")},
          {"spacing", indicator(result, "spacing")},
          {"spacing_relative", indicator(result, "spacing_relative")},
          {"generational_distance", indicator(result, "generational_distance")},
          {"inverted_generational_distance", indicator(result, "inverted_generational_distance")},
          {"max_domination_gap", indicator(result, "max_domination_gap")},
          {"best_dominated", indicator(result, "best_dominated")},
          {"best_domination_gap", indicator(result, "best_domination_gap")},
          {"reference", k.reference.empty() ? Json(nullptr) : Json(k.reference)},
          {"reference_front_missing", indicator(result, "reference_front_missing")},
          {"designs", result["evaluations"]["designs"]},
          {"samples", result["evaluations"]["samples"]},
          {"wall_time_s", result["wall_time_s"]},
          {"output_directory", (out / k.name).string()}};
}

// The fronts overlaid, and the local values of each study that wrote samples.csv.
void add_plots(const fs::path& out, const std::vector<Json>& finished, const Json& rows, Json& summary) {
  const std::string why = plot_fronts(out, finished, rows);
  summary["plots"]["fronts"] = why.empty() ? Json("fronts.png, fronts.svg") : Json("not written: " + why);
  for (const Json& row : rows) {
    const fs::path dir = row["output_directory"].get<std::string>();
    if (!fs::exists(dir / "samples.csv")) continue;
    const std::string w = plot_samples(dir);
    summary["plots"][row["study"].get<std::string>()] =
        w.empty() ? Json(row["study"].get<std::string>() + "/local_values.png, .svg") : Json("not written: " + w);
  }
}

std::string compare_csv(const Json& rows) {
  std::ostringstream csv;
  csv.precision(12);
  const std::vector<std::string> columns = {"study", "solver", "status", "points", "hypervolume", "spacing",
                                            "spacing_relative", "generational_distance",
                                            "inverted_generational_distance", "designs", "samples", "wall_time_s",
                                            "time_ratio"};
  for (std::size_t i = 0; i < columns.size(); ++i) csv << (i ? "," : "") << columns[i];
  csv << ",max_domination_gap,best_dominated\n";
  for (const Json& row : rows) {
    for (std::size_t i = 0; i < columns.size(); ++i) {
      const Json& v = row[columns[i]];
      csv << (i ? "," : "") << (v.is_null() ? "" : v.is_string() ? v.get<std::string>() : v.dump());
    }
    csv << "," << (row["max_domination_gap"].is_null() ? "" : std::to_string(max_of(row["max_domination_gap"])))
        << "," << (row["best_dominated"].is_null() ? "" : row["best_dominated"].dump()) << "\n";
  }
  return csv.str();
}

// Rank 0: the rows (file order) of this share's finished studies, the plots, compare.csv and
// compare.json. A study's record is {"solver", "result": its essentials}.
Json tabulate(const std::vector<CompareCase>& cases, const std::vector<std::string>& names, const CaseBatchOutcome& o,
              const Cluster& cluster, const CompareOptions& options) {
  const fs::path out(options.output_directory);
  std::vector<Json> finished;
  Json rows = Json::array();
  for (long long c = o.first; c < o.last; ++c) {
    const std::size_t i = static_cast<std::size_t>(c);
    if (!o.records[i]) continue;
    const Json& record = *o.records[i];
    rows.push_back(study_row(cases[i], record["result"], record["solver"].get<std::string>(), o.reused[i] != 0, out));
    finished.push_back(record["result"]);
  }
  if (!rows.empty()) {
    const double first_time = rows[0]["wall_time_s"].get<double>();
    for (Json& row : rows) row["time_ratio"] = row["wall_time_s"].get<double>() / first_time;
  }
  const std::string stopped_at = first_unfinished(o, names, cluster);  // of this share
  Json summary = {{"hapsyn", version()}, {"machine", machine_info()}, {"rows", rows}, {"plots", Json::object()}};
  summary["status"] = stopped_at.empty() ? "finished" : "stopped";
  if (!stopped_at.empty()) {
    summary["message"] = "stopped on request at " + stopped_at + " after " + std::to_string(rows.size()) + " of " +
                         std::to_string(options.files.size()) +
                         " studies; run the same command again to continue (finished studies are reused, a stopped "
                         "one resumes from its checkpoint)";
  }
  add_shard_entry(summary, o, names, cluster, stopped_at);
  boost::system::error_code ec;
  summary["options"] = {{"files", options.files},
                        {"overrides", options.overrides},
                        {"seed", options.seed ? Json(*options.seed) : Json(nullptr)},
                        {"plots", options.plots}};
  summary["working_directory"] = fs::current_path(ec).string();
  if (options.plots && !finished.empty()) add_plots(out, finished, rows, summary);
  write_file_atomically((out / "compare.csv").string(), compare_csv(rows));
  summary["output_directory"] = options.output_directory;
  write_file_atomically((out / "compare.json").string(), summary.dump(2) + "\n");
  return summary;
}

// Every file read and named before any study runs, on every rank alike (a file one rank cannot
// read is every rank's error; the lowest rank's is reported). A study is loaded (validated) just
// before it runs: an earlier study may write the reference front it names.
std::vector<CompareCase> read_cases(const CompareOptions& options, Cluster& cluster) {
  std::vector<CompareCase> cases;
  Json read_error = nullptr;
  try {
    std::set<std::string> names;
    for (const std::string& file : options.files) {
      Json doc = read_problem_file(file);
      for (const std::string& s : options.overrides) apply_override(doc, s);
      const std::string name = doc.value("name", fs::path(file).stem().string());
      if (!names.insert(name).second) {
        throw Error("compare", file + ": a study named '" + name + "' is already in this comparison (give each a distinct \"name\")");
      }
      cases.push_back({file, std::move(doc), name, ""});
    }
    point_references_into_the_comparison(cases, options.output_directory);
  } catch (const std::exception& e) {
    if (cluster.size() == 1) throw;
    read_error = error_record(e, "compare");
  }
  if (cluster.size() > 1) {
    for (const std::string& bytes : cluster.all_gather(read_error.dump())) {
      const Json record = Json::parse(bytes);
      if (!record.is_null()) throw_record(record);
    }
  }
  return cases;
}

// Rank 0: the record of a study folder's finished result (loaded and checked; another problem's
// result is refused, never overwritten silently), or nullopt to run the study.
std::optional<Json> reusable_study(const CompareCase& k, const std::string& folder, const CompareOptions& options,
                                   const Registry& registry, bool reuse_only) {
  boost::system::error_code ec;
  if (!fs::exists(fs::path(folder) / "result.json", ec)) {
    if (reuse_only) throw Error("merge", folder + ": no result.json of this study to reuse");
    return std::nullopt;
  }
  std::optional<Study> study;
  try {
    study = load_case(k, options, registry);
  } catch (const Error&) {
    if (reuse_only) throw;
    return std::nullopt;  // it may need an earlier study's output: its task loads it again
  }
  std::optional<Json> stored = reusable_result(folder, study->resolved, options.seed, "compare", "this comparison's " + k.file);
  if (!stored) {
    if (reuse_only) throw Error("merge", folder + ": no finished result of this study to reuse (a merge runs nothing again)");
    return std::nullopt;
  }
  return Json{{"solver", study->solver_plugin}, {"result", essentials(*stored)}};
}

// Runs a study on this process alone (a stopped one is resumed from its checkpoint): its record,
// or nullopt when it stopped.
std::optional<Json> run_case(const CompareCase& k, const std::string& folder, const CompareOptions& options,
                             const Registry& registry) {
  Study study = load_case(k, options, registry);
  RunOptions run;
  run.output_directory = folder;
  run.threads = options.threads;
  run.seed = options.seed;
  run.quiet = true;
  run.stop = options.stop;
  continue_in_folder(run, options.force);
  Json result;
  try {
    result = run_study(study, run);
  } catch (const Error& e) {
    throw Error("compare", k.file + ": " + e.what());
  }
  if (result["status"] == to_string(SolverStatus::kStopped)) return std::nullopt;
  return Json{{"solver", study.solver_plugin}, {"result", essentials(result)}};
}

Json run_compare_cases(const CompareOptions& options, const Registry& registry, bool reuse_only) {
  if (options.files.empty()) throw Error("compare", "at least one problem file is required");
  Cluster& cluster = options.cluster != nullptr ? *options.cluster : Cluster::local();
  const std::vector<CompareCase> cases = read_cases(options, cluster);
  std::vector<std::string> names;  // per study, its folder name
  for (const CompareCase& k : cases) names.push_back(k.name);
  const fs::path out(options.output_directory);
  const auto folder = [&](long long c) { return (out / names[static_cast<std::size_t>(c)]).string(); };
  CaseBatch batch;
  batch.count = static_cast<long long>(cases.size());
  batch.output_directory = options.output_directory;
  batch.component = "compare";
  batch.force = options.force;
  batch.stop = options.stop;
  batch.reuse = [&](long long c) {
    return reusable_study(cases[static_cast<std::size_t>(c)], folder(c), options, registry, reuse_only);
  };
  batch.run = [&](long long c) { return run_case(cases[static_cast<std::size_t>(c)], folder(c), options, registry); };
  const CaseBatchOutcome outcome = run_case_batch(batch, cluster);  // one study at a time per rank
  return summary_on_every_rank(cluster, [&] { return tabulate(cases, names, outcome, cluster, options); }, "compare");
}

}  // namespace

Json run_compare(const CompareOptions& options, const Registry& registry) {
  return run_compare_cases(options, registry, false);
}

bool is_compare_output(const std::string& dir) {
  boost::system::error_code ec;
  return fs::is_regular_file(fs::path(dir) / "compare.json", ec);
}

Json merge_compare_shards(const std::vector<std::string>& dirs, const std::string& out_dir, const Registry& registry,
                          int threads) {
  const std::vector<Json> shards = gather_shards(dirs, out_dir, "compare.json", "comparison",
                                                 {{"/options/files", "files"},
                                                  {"/options/overrides", "overrides"},
                                                  {"/options/seed", "seed"},
                                                  {"/hapsyn", "hapsyn version"}});
  const Json& first = shards.front();
  CompareOptions options;
  try {
    const fs::path working = first.value("working_directory", std::string());
    boost::system::error_code ec;
    for (const std::string& file : first.at("options").at("files").get<std::vector<std::string>>()) {
      // A relative file is read from here when it is here, else from where the shares ran.
      const bool elsewhere = fs::path(file).is_relative() && !working.empty() && !fs::exists(file, ec);
      options.files.push_back(elsewhere ? (working / file).string() : file);
    }
    options.overrides = first["options"].at("overrides").get<std::vector<std::string>>();
    if (!first["options"].at("seed").is_null()) options.seed = first["options"]["seed"].get<std::uint64_t>();
    options.plots = first["options"].value("plots", true);
  } catch (const Json::exception& e) {
    throw Error("merge", dirs.front() + "/compare.json: its \"options\" are not a comparison's (" + e.what() + ")");
  }
  options.output_directory = out_dir;
  options.threads = threads;
  return run_compare_cases(options, registry, true);
}

void print_compare(const Json& summary, std::ostream& out) {
  out << std::left << std::setw(30) << "study" << std::setw(14) << "solver" << std::right << std::setw(7) << "points"
      << std::setw(12) << "hypervolume" << std::setw(10) << "spacing" << std::setw(10) << "sp./mean" << std::setw(10)
      << "GD" << std::setw(10) << "IGD" << std::setw(10) << "max gap" << std::setw(14) << "samples" << std::setw(10)
      << "time [s]" << std::setw(8) << "ratio" << "\n";
  for (const Json& r : summary["rows"]) {
    Json gap = r["max_domination_gap"];
    if (gap.is_null() && r["best_domination_gap"].is_object()) gap = r["best_domination_gap"];
    out << std::left << std::setw(30) << r["study"].get<std::string>() << std::setw(14) << r["solver"].get<std::string>()
        << std::right << std::setw(7) << cell(r["points"]) << std::setw(12) << cell(r["hypervolume"]) << std::setw(10)
        << cell(r["spacing"], 3) << std::setw(10) << cell(r["spacing_relative"], 3) << std::setw(10)
        << cell(r["generational_distance"], 3) << std::setw(10) << cell(r["inverted_generational_distance"], 3)
        << std::setw(10) << (gap.is_object() ? cell(Json(max_of(gap)), 3) : "-") << std::setw(14) << cell(r["samples"])
        << std::setw(10) << cell(r["wall_time_s"], 3) << std::setw(8) << cell(r["time_ratio"], 3) << "\n";
  }
  for (const Json& r : summary["rows"]) {
    if (r["best_dominated"].is_boolean()) {
      out << r["study"].get<std::string>() << ": its design is " << (r["best_dominated"].get<bool>() ? "" : "not ")
          << "dominated by the reference front; largest gains at no loss: " << r["best_domination_gap"].dump() << "\n";
    }
  }
  for (const Json& r : summary["rows"]) {
    if (r.value("reference_front_missing", Json()).is_string()) {
      out << "warning: " << r["study"].get<std::string>() << ": GD, IGD and the domination gap are not computed (\"-\"): "
          << r["reference_front_missing"].get<std::string>() << "\n";
    }
  }
  for (auto it = summary["plots"].begin(); it != summary["plots"].end(); ++it) {
    out << "plot " << it.key() << ": " << it.value().get<std::string>() << "\n";
  }
  if (summary.value("status", "") == "stopped") out << "stopped: " << summary["message"].get<std::string>() << "\n";
  out << "written: " << summary["output_directory"].get<std::string>() << "/compare.csv, compare.json\n";
  if (summary.contains("shard") && summary.value("status", "") != "stopped") {
    out << "shard " << summary["shard"]["index"] << "/" << summary["shard"]["count"]
        << " done; when every share is, combine them: hapsyn merge DIR1 DIR2 ... --out DIR\n";
  }
}

}  // namespace hapsyn