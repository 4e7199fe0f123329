// The console summary of a finished study (summary.hpp).
#include "summary.hpp"

#include <hapsyn/internal/groups.hpp>

#include <algorithm>
#include <iomanip>
#include <sstream>

namespace hapsyn_cli {

using hapsyn::Json;

std::string format_number(double v) {
  std::ostringstream s;
  s << std::setprecision(6) << v;
  return s.str();
}

std::string format_seconds(double v) {
  std::ostringstream s;
  s << std::setprecision(3) << v;
  return s.str();
}

std::string format_design_value(const Json& v) {
  if (v.is_number_float()) {
    std::ostringstream s;
    s << std::setprecision(10) << v.get<double>();
    return s.str();
  }
  if (!v.is_array()) return v.dump();
  std::string out = "[";
  for (std::size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + format_design_value(v[i]);
  return out + "]";
}

namespace {

// The header: program, study, solver, threads, seed; the mechanism's own summary; the status.
void print_header(const Json& result, std::ostream& out) {
  const Json& problem = result["problem"];
  out << "hapsyn " << result["hapsyn"]["version"].get<std::string>() << " | " << problem["name"].get<std::string>()
      << " | solver " << problem["solver"]["plugin"].get<std::string>() << ", " << result["threads"] << " threads, seed "
      << result["seed"] << "\n";
  if (result.contains("mechanism_summary")) {
    out << "mechanism " << problem["mechanism"]["plugin"].get<std::string>() << ": "
        << result["mechanism_summary"].get<std::string>() << "\n";
  }
  out << "status: " << result["status"].get<std::string>();
  if (!result["message"].get<std::string>().empty()) out << " (" << result["message"].get<std::string>() << ")";
  out << "\n";
}

// A component is fixed when its resolved bounds coincide.
bool is_fixed(const Json& design, const std::string& name) {
  const Json& entry = design.value(name, Json::object());
  return entry.contains("lower") && entry.contains("upper") && entry["lower"] == entry["upper"];
}

// One design and its objectives. With free variables present the fixed ones (a serial_chain has
// dozens: every parameter of its file) are counted, not listed.
void print_point(const Json& problem_design, const Json& point, std::ostream& out) {
  std::size_t fixed = 0;
  for (auto it = problem_design.begin(); it != problem_design.end(); ++it) fixed += is_fixed(problem_design, it.key());
  const bool skip_fixed = fixed < problem_design.size();
  out << "  design:";
  for (auto it = point["design"].begin(); it != point["design"].end(); ++it) {
    if (skip_fixed && is_fixed(problem_design, it.key())) continue;
    const std::string unit = problem_design[it.key()].value("unit", "");
    out << " " << it.key() << " = " << format_design_value(it.value()) << (unit.empty() ? "" : " " + unit);
  }
  if (skip_fixed && fixed > 0) out << " (and " << fixed << " fixed: result.json)";
  out << "\n  objectives:";
  for (auto it = point["objectives"].begin(); it != point["objectives"].end(); ++it) {
    out << " " << it.key() << " = " << format_number(it.value().get<double>());
  }
  out << "\n";
}

// The best design, and a front: all of a short one; a long one by 10 points spread along it (as
// stored) and the last, front.csv holding all.
void print_points(const Json& result, std::ostream& out) {
  const Json& design = result["problem"]["design"];
  if (result.contains("best")) {
    out << "best\n";
    print_point(design, result["best"], out);
  }
  if (!result.contains("front")) return;
  const std::size_t n = result["front"].size();
  const std::size_t shown = std::min<std::size_t>(n, 11);
  out << "front: " << n << " non-dominated points"
      << (shown < n ? " (" + std::to_string(shown) + " shown; all in front.csv)" : "") << "\n";
  for (std::size_t k = 0; k < shown; ++k) {
    const std::size_t i = shown < n ? (k + 1 == shown ? n - 1 : k * (n - 1) / (shown - 1)) : k;
    print_point(design, result["front"][i], out);
  }
}

// The work done and its time by phase, the warnings, where the result is.
void print_footer(const Json& result, std::ostream& out) {
  out << "evaluations: " << result["evaluations"]["designs"] << " designs, " << result["evaluations"]["samples"]
      << " sample solves; wall time " << format_seconds(result["wall_time_s"].get<double>()) << " s";
  if (result.contains("phases")) {
    const Json& p = result["phases"];
    out << " (scene " << format_seconds(p["scene_s"].get<double>()) << " s, solve "
        << format_seconds(p["solve_s"].get<double>()) << " s, outputs " << format_seconds(p["outputs_s"].get<double>())
        << " s)";
  }
  out << "\n";
  for (const Json& w : result.value("warnings", Json::array())) out << "warning: " << w.get<std::string>() << "\n";
  out << "result: " << result["output_directory"].get<std::string>() << "/result.json\n";
}

}  // namespace

void print_summary(const Json& result, std::ostream& out) {
  print_header(result, out);
  print_points(result, out);
  // A solver's own summary lines (ga: the cluster table of its runs).
  if (result["statistics"].is_object() && result["statistics"].contains("report")) {
    for (const Json& line : result["statistics"]["report"]) out << line.get<std::string>() << "\n";
  }
  // Objectives per subject, activity, ... (scenes of recorded motion).
  if (result.contains("groups")) out << "per group of samples (best design):\n" << hapsyn::groups_text(result["groups"]);
  print_footer(result, out);
}

}  // namespace hapsyn_cli
