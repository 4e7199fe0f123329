#pragma once
// The study `hapsyn view` shows and its design: from a problem file or a result directory.
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/study.hpp>
#include <hapsyn/json.hpp>

#include <Eigen/Core>
#include <ostream>
#include <string>

namespace hapsyn_cli {

/// A loaded study with the design to show and where that design came from.
struct ViewSource {
  hapsyn::Study study;
  Eigen::VectorXd design;   ///< full design vector
  std::string kind;         ///< "result directory" or "problem file"
  std::string samples_csv;  ///< the result's samples.csv, "" when there is none
  hapsyn::Json result;      ///< a result directory's result.json (null for a problem file)
  std::string result_file;  ///< its path, for messages
};

/// The full design from a design object {"l": [..], "r": 0.4} (result.json's best.design, or a
/// front point's design with design_fixed). \throws hapsyn::Error("view", ...) naming
/// `where`.variable and the component when a component has no number.
Eigen::VectorXd design_from_json(const hapsyn::Problem& problem, const hapsyn::Json& design, const std::string& where);

/// A result directory (holding result.json): its problem reloaded, its best design (a front
/// without one, as nsga2 writes: the front point of the highest score, design_fixed added).
/// \throws hapsyn::Error("view", ...) naming result.json when it has no "problem" object or
///         neither "best.design" nor a front; the loader's errors.
ViewSource load_result_dir(const std::string& dir, const hapsyn::Registry& registry, std::ostream* progress);

/// A problem file: every fixed design component's value, every free one at the midpoint of its
/// bounds (rounded for integer variables). \throws the loader's errors.
ViewSource load_problem_file(const std::string& file, const hapsyn::Registry& registry, std::ostream* progress);

}  // namespace hapsyn_cli
