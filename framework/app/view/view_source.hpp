#pragma once
// The study `hapsyn view` shows and its design: from a problem file or a result directory.
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/study.hpp>

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
};

/// A result directory (holding result.json): its problem reloaded, its best design.
/// \throws hapsyn::Error("view", ...) naming result.json when it has no "problem" object or no
///         "best.design"; the loader's errors.
ViewSource load_result_dir(const std::string& dir, const hapsyn::Registry& registry, std::ostream* progress);

/// A problem file: every fixed design component's value, every free one at the midpoint of its
/// bounds (rounded for integer variables). \throws the loader's errors.
ViewSource load_problem_file(const std::string& file, const hapsyn::Registry& registry, std::ostream* progress);

}  // namespace hapsyn_cli
