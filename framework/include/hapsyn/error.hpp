#pragma once
/// \file
/// The one exception type of hapsyn: bad input (problem files, options, plugin files).
/// Solver outcomes are never exceptions (see SolverResult), internal invariants use assert.
#include <stdexcept>
#include <string>

namespace hapsyn {

/// Bad input. what() is "<component>: <message>", e.g.
/// "problem: design.l1.upper = -3: must be > lower (0.01)".
class Error : public std::runtime_error {
 public:
  /// \param component who refuses the input (e.g. "problem", "registry", "fivebar")
  /// \param message what is wrong: the JSON path, the offending value and the rule
  Error(std::string component, const std::string& message)
      : std::runtime_error(component + ": " + message), component_(std::move(component)) {}
  const std::string& component() const noexcept { return component_; }

 private:
  std::string component_;
};

}  // namespace hapsyn
