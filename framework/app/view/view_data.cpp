#include "view_data.hpp"

#include "result_views.hpp"
#include "samples_csv_reader.hpp"
#include "view_figure.hpp"
#include "view_json.hpp"
#include "view_source.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/internal/maps.hpp>
#include <hapsyn/parallel.hpp>

#include <boost/filesystem.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace hapsyn_cli {
namespace {

namespace fs = boost::filesystem;
using hapsyn::Json;

// The reachable sample nearest the reachable samples' centroid, -1 when none is reachable.
int drawn_sample(const hapsyn::SampleSet& samples, const hapsyn::SampleRecords& records) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  int count = 0;
  for (int i = 0; i < samples.size(); ++i) {
    if (records.status[static_cast<std::size_t>(i)] != "reachable") continue;
    centroid += sample_position(samples, i);
    ++count;
  }
  if (count == 0) return -1;
  centroid /= count;
  int best = -1;
  double nearest = std::numeric_limits<double>::infinity();
  for (int i = 0; i < samples.size(); ++i) {
    if (records.status[static_cast<std::size_t>(i)] != "reachable") continue;
    const double d = (sample_position(samples, i) - centroid).squaredNorm();
    if (d < nearest) nearest = d, best = i;
  }
  return best;
}

Json drawing_json(const ViewSource& s, int sample) {
  if (sample < 0) return Json::array();
  const hapsyn::Mechanism& mechanism = s.study.problem->mechanism();
  const auto model = mechanism.build(s.design.data());
  const auto scratch = mechanism.make_scratch();
  return segments_json(model->segments(s.study.problem->samples(), sample, *scratch));
}

Json study_json(const ViewSource& s, int sample) {
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
              {"segments", drawing_json(s, sample)},
              {"figure", figure_json(samples, sample)},
              // The mechanisms' convention (haptic6r, serial_chain's default): gravity along -z of
              // the base frame; the scene frame is drawn as the base frame.
              {"gravity", {0.0, 0.0, -1.0}},
              {"unit", samples.unit}};
  if (sample >= 0) {
    const Eigen::Vector3d p = sample_position(samples, sample);
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

Json samples_json(const ViewSource& s, const hapsyn::SampleRecords& records, const std::string& origin) {
  const hapsyn::SampleSet& samples = s.study.problem->samples();
  Json positions = Json::array(), status = Json::array();
  for (int i = 0; i < samples.size(); ++i) {
    const Eigen::Vector3d p = sample_position(samples, i);
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
  std::optional<Batch> batch;  // a sweep's or comparison's directory: its table, one run shown
  ViewSource source = [&] {
    if (fs::is_directory(p)) {
      if (!fs::is_regular_file(p / "result.json")) {
        batch = find_batch(path);
        if (batch) return load_result_dir(batch->run_dir, registry, progress);
        throw hapsyn::Error("view", path + " is a directory without result.json: give a problem file or a result directory");
      }
      return load_result_dir(path, registry, progress);
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
    records = hapsyn::record_samples(problem, source.design, hapsyn::hardware_threads());
    origin = "evaluated";
  }
  const int sample = drawn_sample(problem.samples(), records);
  ViewData data;
  data.name = source.study.resolved.value("name", std::string());
  data.study = study_json(source, sample);
  data.meshes = load_view_meshes(problem.mechanism(), source.design.data(), problem.samples(), sample, MeshLimits{}, progress);
  data.study["meshes"] = data.meshes.list;
  data.samples = samples_json(source, records, origin);
  data.result = view_result_json(source, sample);
  data.result["batch"] = batch ? batch->table : Json(nullptr);
  data.source = std::make_shared<const ViewSource>(std::move(source));
  return data;
}

}  // namespace hapsyn_cli
