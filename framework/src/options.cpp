#include <hapsyn/options.hpp>

namespace hapsyn::detail {

std::shared_ptr<const Solver> find_sub_solver(const PluginArguments& arguments, const std::string& relative_path) {
  // Absent when the options were made without a registry (make_options): the solver then
  // reports a failed status instead of running without its sub-solver.
  const auto it = arguments.sub_solvers.find(relative_path);
  return it == arguments.sub_solvers.end() ? nullptr : it->second;
}

}  // namespace hapsyn::detail
