#include "view_data.hpp"

#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/internal/maps.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/internal/study.hpp>
#include <hapsyn/json_text.hpp>
#include <hapsyn/read_file.hpp>

#include <boost/filesystem.hpp>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

namespace hapsyn_cli {
namespace {

namespace fs = boost::filesystem;
using hapsyn::Json;

constexpr std::uint64_t kMaxResultBytes = std::uint64_t{1} << 30;
constexpr std::uint64_t kMaxSamplesCsvBytes = std::uint64_t{4} << 30;

// A loaded study with the design to show and where that design came from.
struct Source {
  hapsyn::Study study;
  Eigen::VectorXd design;  // full design vector
  std::string kind;        // "result directory" or "problem file"
  std::string samples_csv; // the result's samples.csv, "" when there is none
};

// The full design from a design object {"l": [..], "r": 0.4} (result.json's best.design).
Eigen::VectorXd design_from_json(const hapsyn::Problem& problem, const Json& design, const std::string& where) {
  const auto& components = problem.design_space().components();
  Eigen::VectorXd full(static_cast<Eigen::Index>(components.size()));
  for (std::size_t k = 0; k < components.size(); ++k) {
    const hapsyn::DesignComponent& c = components[k];
    const auto it = design.find(c.variable);
    const Json* value = it == design.end() ? nullptr : &*it;
    if (value && value->is_array()) value = static_cast<std::size_t>(c.index) < value->size() ? &(*value)[c.index] : nullptr;
    if (!value || !value->is_number()) {
      throw hapsyn::Error("view", where + "." + c.variable + ": no number for design component " + c.name);
    }
    full[static_cast<Eigen::Index>(k)] = value->get<double>();
  }
  return full;
}

// The design `hapsyn run` evaluates with the evaluate solver: the fixed values; free
// components (another solver's study) at the midpoint of their bounds, integers rounded.
Eigen::VectorXd midpoint_design(const hapsyn::Problem& problem) {
  const auto& space = problem.design_space();
  Eigen::VectorXd free(static_cast<Eigen::Index>(space.free_size()));
  for (std::size_t k = 0; k < space.free_size(); ++k) {
    const hapsyn::DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
    const double mid = 0.5 * (c.lower + c.upper);
    free[static_cast<Eigen::Index>(k)] = c.integer ? std::round(mid) : mid;
  }
  return problem.full_design(free.data());
}

hapsyn::LoadSettings quiet_settings(std::ostream* progress) {
  hapsyn::LoadSettings settings;
  settings.progress = progress;
  return settings;
}

Source load_result_dir(const fs::path& dir, const hapsyn::Registry& registry, std::ostream* progress) {
  const std::string file = (dir / "result.json").string();
  const Json result =
      hapsyn::parse_json_text(hapsyn::read_regular_file(file, "view", "result", kMaxResultBytes), file, "view");
  if (!result.contains("problem") || !result["problem"].is_object()) {
    throw hapsyn::Error("view", file + ": no \"problem\" object: not a result.json that hapsyn run wrote");
  }
  if (!result.contains("best") || !result["best"].contains("design")) {
    throw hapsyn::Error("view", file + ": no \"best.design\" (status " + result.value("status", std::string("?")) +
                                    "): the study found no design to show");
  }
  // The problem's relative paths are relative to its file, which the result names only for a
  // share; otherwise they are tried against the result's folder, then the current directory.
  std::string problem_file = file;
  if (result.contains("shard") && result["shard"].contains("problem_file")) problem_file = result["shard"]["problem_file"];
  const hapsyn::ProblemDirectoryScope scope(problem_file);
  // The resolved problem holds the loader's notes, which are no keys of a problem file and which
  // the loader derives again: "aggregation" (several objectives under a single-objective
  // solver) and each design variable's "unit".
  Json problem = result["problem"];
  problem.erase("aggregation");
  if (problem.contains("design")) {
    for (auto& entry : problem["design"].items()) entry.value().erase("unit");
  }
  Source s{hapsyn::load_study(problem, registry, {}, quiet_settings(progress)), {}, "result directory", {}};
  s.design = design_from_json(*s.study.problem, result["best"]["design"], file + ": best.design");
  const fs::path csv = dir / "samples.csv";
  if (fs::is_regular_file(csv)) s.samples_csv = csv.string();
  return s;
}

Source load_problem_file(const std::string& file, const hapsyn::Registry& registry, std::ostream* progress) {
  const Json document = hapsyn::read_problem_file(file);
  const hapsyn::ProblemDirectoryScope scope(file);
  Source s{hapsyn::load_study(document, registry, {}, quiet_settings(progress)), {}, "problem file", {}};
  s.design = midpoint_design(*s.study.problem);
  return s;
}

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

// samples.csv read back into SampleRecords (status and the local-value columns by name).
hapsyn::SampleRecords read_samples_csv(const std::string& file, const hapsyn::Problem& problem) {
  std::istringstream in(hapsyn::read_regular_file(file, "view", "samples.csv", kMaxSamplesCsvBytes));
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = split_csv_line(line);
  const std::vector<std::string> locals = hapsyn::local_columns(problem);
  auto column = [&](const std::string& name) {
    for (std::size_t c = 0; c < header.size(); ++c) {
      if (header[c] == name) return c;
    }
    throw hapsyn::Error("view", file + ": no column \"" + name + "\" (the study's columns are those hapsyn run writes)");
  };
  const std::size_t status = column("status");
  std::vector<std::size_t> local_at;
  for (const std::string& l : locals) local_at.push_back(column(l));
  const int n = problem.samples().size();
  hapsyn::SampleRecords records;
  records.status.resize(static_cast<std::size_t>(n));
  records.has_locals.assign(static_cast<std::size_t>(n), 0);
  records.locals.setZero(n, static_cast<Eigen::Index>(locals.size()));
  int row = 0;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (row >= n) throw hapsyn::Error("view", file + ": more rows than the scene's " + std::to_string(n) + " samples");
    const std::vector<std::string> cells = split_csv_line(line);
    if (cells.size() != header.size()) {
      throw hapsyn::Error("view", file + ": row " + std::to_string(row + 1) + " has " + std::to_string(cells.size()) +
                                      " cells, the header " + std::to_string(header.size()));
    }
    records.status[static_cast<std::size_t>(row)] = cells[status];
    bool all = !locals.empty();
    for (std::size_t k = 0; k < locals.size(); ++k) {
      const std::string& cell = cells[local_at[k]];
      all = all && !cell.empty();
      records.locals(row, static_cast<Eigen::Index>(k)) = cell.empty() ? 0.0 : std::strtod(cell.c_str(), nullptr);
    }
    records.has_locals[static_cast<std::size_t>(row)] = all ? 1 : 0;
    ++row;
  }
  if (row != n) {
    throw hapsyn::Error("view", file + ": " + std::to_string(row) + " rows, the scene has " + std::to_string(n) +
                                    " samples (was the study run with other scene options?)");
  }
  return records;
}

Eigen::Vector3d position_of(const hapsyn::SampleSet& samples, int i) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int c = 0; c < std::min(3, samples.dimension()); ++c) p[c] = samples.pose(i)[c];
  return p;
}

// The reachable sample nearest the reachable samples' centroid, -1 when none is reachable.
int drawn_sample(const hapsyn::SampleSet& samples, const hapsyn::SampleRecords& records) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  int count = 0;
  for (int i = 0; i < samples.size(); ++i) {
    if (records.status[static_cast<std::size_t>(i)] != "reachable") continue;
    centroid += position_of(samples, i);
    ++count;
  }
  if (count == 0) return -1;
  centroid /= count;
  int best = -1;
  double nearest = std::numeric_limits<double>::infinity();
  for (int i = 0; i < samples.size(); ++i) {
    if (records.status[static_cast<std::size_t>(i)] != "reachable") continue;
    const double d = (position_of(samples, i) - centroid).squaredNorm();
    if (d < nearest) nearest = d, best = i;
  }
  return best;
}

Json segments_json(const Source& s, int sample) {
  Json out = Json::array();
  if (sample < 0) return out;
  const hapsyn::Mechanism& mechanism = s.study.problem->mechanism();
  const auto model = mechanism.build(s.design.data());
  const auto scratch = mechanism.make_scratch();
  for (const hapsyn::Segment& segment : model->segments(s.study.problem->samples(), sample, *scratch)) {
    Json points = Json::array();
    for (const Eigen::Vector3d& p : segment.points) points.push_back({p.x(), p.y(), p.z()});
    out.push_back({{"name", segment.name}, {"points", points}});
  }
  return out;
}

Json study_json(const Source& s, int sample) {
  const hapsyn::Json& resolved = s.study.resolved;
  const hapsyn::SampleSet& samples = s.study.problem->samples();
  Json objectives = Json::array();
  for (const hapsyn::Objective& o : s.study.problem->objectives()) objectives.push_back(o.name);
  Json doc = {{"name", resolved.value("name", std::string())},
              {"source", s.kind},
              {"mechanism", resolved["mechanism"]["plugin"]},
              {"scene", resolved["scene"]["plugin"]},
              {"solver", s.study.solver_plugin},
              {"objectives", objectives},
              {"design", s.study.problem->design_to_json(s.design)},
              {"drawn_sample", sample >= 0 ? Json(sample) : Json(nullptr)},
              {"segments", segments_json(s, sample)},
              // The mechanisms' convention (haptic6r, serial_chain's default): gravity along -z of
              // the base frame; the scene frame is drawn as the base frame.
              {"gravity", {0.0, 0.0, -1.0}},
              {"unit", samples.unit}};
  if (sample >= 0) {
    const Eigen::Vector3d p = position_of(samples, sample);
    doc["drawn_position"] = {p.x(), p.y(), p.z()};
  }
  return doc;
}

// The local-value columns: name, unit, the metric, the objectives that use it, min and max over
// the samples that have them, and one value per sample (null where a sample has none).
Json columns_json(const hapsyn::Problem& problem, const hapsyn::SampleRecords& records) {
  const std::vector<std::string> names = hapsyn::local_columns(problem);
  Json columns = Json::array();
  std::size_t c = 0;
  for (std::size_t m = 0; m < problem.metrics().size(); ++m) {
    Json objectives = Json::array();
    for (const hapsyn::Objective& o : problem.objectives()) {
      if (o.metric == static_cast<int>(m)) objectives.push_back(o.name);
    }
    for (const hapsyn::LocalValue& local : problem.metrics()[m].metric->locals()) {
      Json values = Json::array();
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (int i = 0; i < problem.samples().size(); ++i) {
        const double v = records.locals(i, static_cast<Eigen::Index>(c));
        if (!records.has_locals[static_cast<std::size_t>(i)] || !std::isfinite(v)) {
          values.push_back(nullptr);
          continue;
        }
        values.push_back(v);
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
      columns.push_back({{"name", names[c]},
                         {"local", local.name},
                         {"metric", problem.metrics()[m].plugin},
                         {"objectives", objectives},
                         {"unit", local.unit},
                         {"min", std::isfinite(lo) ? Json(lo) : Json(nullptr)},
                         {"max", std::isfinite(hi) ? Json(hi) : Json(nullptr)},
                         {"values", values}});
      ++c;
    }
  }
  return columns;
}

Json samples_json(const Source& s, const hapsyn::SampleRecords& records, const std::string& origin) {
  const hapsyn::SampleSet& samples = s.study.problem->samples();
  Json positions = Json::array(), status = Json::array();
  for (int i = 0; i < samples.size(); ++i) {
    const Eigen::Vector3d p = position_of(samples, i);
    positions.push_back(p.x());
    positions.push_back(p.y());
    positions.push_back(p.z());
    status.push_back(records.status[static_cast<std::size_t>(i)]);
  }
  return {{"count", samples.size()},
          {"coordinates", samples.coordinates},
          {"unit", samples.unit},
          {"positions", positions},
          {"status", status},
          {"values_from", origin},
          {"columns", columns_json(*s.study.problem, records)}};
}

}  // namespace

ViewData load_view_data(const std::string& path, const hapsyn::Registry& registry, std::ostream* progress) {
  const fs::path p(path);
  Source source = [&] {
    if (fs::is_directory(p)) {
      if (!fs::is_regular_file(p / "result.json")) {
        throw hapsyn::Error("view", path + " is a directory without result.json: give a problem file or a result directory");
      }
      return load_result_dir(p, registry, progress);
    }
    return load_problem_file(path, registry, progress);
  }();
  const hapsyn::Problem& problem = *source.study.problem;
  std::string origin = "samples.csv";
  hapsyn::SampleRecords records;
  if (!source.samples_csv.empty()) {
    records = read_samples_csv(source.samples_csv, problem);
  } else {
    if (progress) *progress << "hapsyn view: evaluating the design on each of the " << problem.samples().size() << " samples\n";
    records = hapsyn::record_samples(problem, source.design);
    origin = "evaluated";
  }
  const int sample = drawn_sample(problem.samples(), records);
  ViewData data;
  data.name = source.study.resolved.value("name", std::string());
  data.study = study_json(source, sample);
  data.samples = samples_json(source, records, origin);
  return data;
}

}  // namespace hapsyn_cli
