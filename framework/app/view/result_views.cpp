#include "result_views.hpp"

#include "view_json.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/json_text.hpp>
#include <hapsyn/read_file.hpp>

#include <boost/filesystem.hpp>

#include <algorithm>
#include <numeric>
#include <vector>

namespace hapsyn_cli {
namespace {

using hapsyn::Json;

// The samples a front design is tried at, nearest `drawn` first (the middle of the scene when
// no sample is drawn), at most kMaxDrawTries: one order for every point.
std::vector<int> draw_order(const hapsyn::SampleSet& samples, int drawn) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  if (drawn >= 0) {
    centre = sample_position(samples, drawn);
  } else if (samples.size() > 0) {
    for (int i = 0; i < samples.size(); ++i) centre += sample_position(samples, i);
    centre /= samples.size();
  }
  std::vector<double> distance(static_cast<std::size_t>(samples.size()));
  for (int i = 0; i < samples.size(); ++i) distance[static_cast<std::size_t>(i)] = (sample_position(samples, i) - centre).squaredNorm();
  std::vector<int> order(static_cast<std::size_t>(samples.size()));
  std::iota(order.begin(), order.end(), 0);
  const auto tries = std::min<std::ptrdiff_t>(kMaxDrawTries, static_cast<std::ptrdiff_t>(order.size()));
  // Ties by index, so that the drawn sample itself comes first among equals.
  std::partial_sort(order.begin(), order.begin() + tries, order.end(), [&](int a, int b) {
    const double da = distance[static_cast<std::size_t>(a)], db = distance[static_cast<std::size_t>(b)];
    return da < db || (da == db && (a == drawn || (b != drawn && a < b)));
  });
  order.resize(static_cast<std::size_t>(tries));
  return order;
}

// The design drawn at the first sample of `order` it reaches: {"drawn_sample", "segments"}.
Json drawing(const hapsyn::Problem& problem, const Eigen::VectorXd& design, const std::vector<int>& order) {
  const hapsyn::Mechanism& mechanism = problem.mechanism();
  const auto model = mechanism.build(design.data());
  const auto scratch = mechanism.make_scratch();
  for (int sample : order) {
    const std::vector<hapsyn::Segment> segments = model->segments(problem.samples(), sample, *scratch);
    if (segments.empty()) continue;
    return {{"drawn_sample", sample}, {"segments", segments_json(segments)}};
  }
  return {{"drawn_sample", nullptr}, {"segments", Json::array()}};
}

Json objectives_json(const hapsyn::Problem& problem) {
  Json out = Json::array();
  for (const hapsyn::Objective& o : problem.objectives()) {
    // The plugin API declares no unit of an objective (only of local values): null.
    out.push_back({{"name", o.name},
                   {"metric", problem.metrics()[static_cast<std::size_t>(o.metric)].plugin},
                   {"sense", o.sense == hapsyn::Sense::kMaximize ? "maximize" : "minimize"},
                   {"unit", nullptr}});
  }
  return out;
}

// The solver's runs and convergence for the page's plots: statistics.runs (ga: each run's record
// with its history), statistics.clusters (ga), statistics.history (nsga2), as result.json has them.
Json statistics_json(const Json& result) {
  Json out = Json::object();
  if (!result.contains("statistics") || !result["statistics"].is_object()) return out;
  for (const char* key : {"algorithm", "runs", "clusters", "history"}) {
    if (result["statistics"].contains(key)) out[key] = result["statistics"][key];
  }
  return out;
}

// A row's numbers (null kept: a missing measurement) as "prefix" + key.
void add_numbers(const Json& object, const std::string& prefix, Json& values) {
  if (!object.is_object()) return;
  for (const auto& [key, value] : object.items()) {
    if (value.is_number() || value.is_null()) values[prefix + key] = value;
  }
}

Json sweep_table(const Json& sweep, const std::string& file) {
  Json rows = Json::array();
  for (const Json& run : sweep.at("runs")) {
    std::string label;
    if (run.contains("values") && run["values"].is_object()) {
      for (const auto& [path, value] : run["values"].items()) label += (label.empty() ? "" : ", ") + path + "=" + value.dump();
    }
    Json values = Json::object();
    for (const char* key : {"run_time_s", "solve_time_s"}) {
      if (run.contains(key)) values[key] = run[key];
    }
    for (const char* group : {"errors", "evaluations", "objectives"}) {
      if (run.contains(group)) add_numbers(run[group], std::string(group) + ".", values);
    }
    rows.push_back({{"label", label.empty() ? run.value("case", std::string("?")) : label}, {"values", values}});
  }
  return {{"kind", "sweep"}, {"file", file}, {"rows", rows}};
}

Json compare_table(const Json& compare, const std::string& file) {
  Json rows = Json::array();
  for (const Json& row : compare.at("rows")) {
    Json values = Json::object();
    add_numbers(row, "", values);
    rows.push_back({{"label", row.value("study", std::string("?"))}, {"values", values}});
  }
  return {{"kind", "compare"}, {"file", file}, {"rows", rows}};
}

}  // namespace

std::optional<Batch> find_batch(const std::string& folder) {
  namespace fs = boost::filesystem;
  const fs::path dir(folder);
  for (const char* name : {"sweep.json", "compare.json"}) {
    const std::string file = (dir / name).string();
    if (!fs::is_regular_file(file)) continue;
    const Json doc = hapsyn::parse_json_text(hapsyn::read_regular_file(file, "view", name, std::uint64_t{1} << 28), file, "view");
    const bool sweep = std::string(name) == "sweep.json";
    const char* list = sweep ? "runs" : "rows";
    if (!doc.contains(list) || !doc[list].is_array() || doc[list].empty()) {
      throw hapsyn::Error("view", file + ": no \"" + list + "\" to show (an unfinished " + (sweep ? "sweep" : "comparison") + "?)");
    }
    Batch batch;
    batch.table = sweep ? sweep_table(doc, file) : compare_table(doc, file);
    // Each run's folder, by its name inside this directory (the directory may have moved).
    const Json& shown = sweep ? doc[list].back() : doc[list].front();
    const std::string run = sweep ? shown.value("case", std::string())
                                  : fs::path(shown.value("output_directory", std::string())).filename().string();
    batch.run_dir = (dir / run).string();
    batch.table["shown"] = sweep ? batch.table["rows"].back()["label"] : batch.table["rows"].front()["label"];
    return batch;
  }
  return std::nullopt;
}

Json view_result_json(const ViewSource& source, int drawn_sample) {
  const Json& result = source.result;
  if (!result.is_object()) return {{"front", nullptr}, {"statistics", Json::object()}};
  if (!result.contains("front") || !result["front"].is_array()) return {{"front", nullptr}, {"statistics", statistics_json(result)}};
  const hapsyn::Problem& problem = *source.study.problem;
  const Json fixed = result.contains("design_fixed") ? result.at("design_fixed") : Json::object();
  Json variables = Json::array();
  const hapsyn::DesignSpace& space = problem.design_space();
  for (int k : space.free_indices()) variables.push_back(space.components()[static_cast<std::size_t>(k)].name);
  const std::vector<int> order = draw_order(problem.samples(), drawn_sample);
  Json points = Json::array();
  const Json& front = result.at("front");
  for (std::size_t i = 0; i < front.size(); ++i) {
    const std::string where = source.result_file + ": front[" + std::to_string(i) + "].design";
    Json design = fixed;
    if (front[i].contains("design") && front[i].at("design").is_object()) design.update(front[i].at("design"));
    const Eigen::VectorXd full = design_from_json(problem, design, where);
    Json point = drawing(problem, full, order);
    point["design"] = problem.design_to_json(full);
    point["objectives"] = front[i].contains("objectives") ? front[i].at("objectives") : Json::object();
    point["score"] = front[i].contains("score") ? front[i].at("score") : Json();
    points.push_back(std::move(point));
  }
  return {{"front", {{"objectives", objectives_json(problem)}, {"variables", variables}, {"points", points}}},
          {"statistics", statistics_json(result)}};
}

}  // namespace hapsyn_cli
