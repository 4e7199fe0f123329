#include "view_source.hpp"

#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/json_text.hpp>
#include <hapsyn/read_file.hpp>

#include <boost/filesystem.hpp>

#include <cmath>
#include <cstdint>

namespace hapsyn_cli {
namespace {

namespace fs = boost::filesystem;
using hapsyn::Json;

constexpr std::uint64_t kMaxResultBytes = std::uint64_t{1} << 30;

}  // namespace

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

namespace {

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

}  // namespace

ViewSource load_result_dir(const std::string& folder, const hapsyn::Registry& registry, std::ostream* progress) {
  const fs::path dir(folder);
  const std::string file = (dir / "result.json").string();
  const Json result =
      hapsyn::parse_json_text(hapsyn::read_regular_file(file, "view", "result", kMaxResultBytes), file, "view");
  if (!result.contains("problem") || !result["problem"].is_object()) {
    throw hapsyn::Error("view", file + ": no \"problem\" object: not a result.json that hapsyn run wrote");
  }
  const bool has_best = result.contains("best") && result["best"].contains("design");
  const bool has_front = result.contains("front") && result["front"].is_array() && !result["front"].empty();
  if (!has_best && !has_front) {
    throw hapsyn::Error("view", file + ": no \"best.design\" and no front (status " + result.value("status", std::string("?")) +
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
  ViewSource s{hapsyn::load_study(problem, registry, {}, quiet_settings(progress)), {}, "result directory", {}, {}, {}};
  if (has_best) {
    s.design = design_from_json(*s.study.problem, result["best"]["design"], file + ": best.design");
  } else {
    // A front without a best design (nsga2): its point of the highest score.
    const Json& front = result["front"];
    std::size_t top = 0;
    const auto score = [&](std::size_t i) {
      return front[i].contains("score") && front[i]["score"].is_number() ? front[i]["score"].get<double>() : -HUGE_VAL;
    };
    for (std::size_t i = 1; i < front.size(); ++i) {
      if (score(i) > score(top)) top = i;
    }
    Json design = result.contains("design_fixed") ? result["design_fixed"] : Json::object();
    if (front[top].contains("design")) design.update(front[top]["design"]);
    s.design = design_from_json(*s.study.problem, design, file + ": front[" + std::to_string(top) + "].design");
  }
  const fs::path csv = dir / "samples.csv";
  if (fs::is_regular_file(csv)) s.samples_csv = csv.string();
  s.result = result;
  s.result_file = file;
  return s;
}

ViewSource load_problem_file(const std::string& file, const hapsyn::Registry& registry, std::ostream* progress) {
  const Json document = hapsyn::read_problem_file(file);
  const hapsyn::ProblemDirectoryScope scope(file);
  ViewSource s{hapsyn::load_study(document, registry, {}, quiet_settings(progress)), {}, "problem file", {}, {}, {}};
  s.design = midpoint_design(*s.study.problem);
  return s;
}

}  // namespace hapsyn_cli
