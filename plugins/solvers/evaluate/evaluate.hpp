#pragma once
/// \file
/// Solver `evaluate`: evaluates the one fixed design of a study (every design variable given a
/// "value"), over all samples, on the threads given.
#include <hapsyn/options.hpp>
#include <hapsyn/solver.hpp>

namespace hapsyn::plugins {

/// No options; declared for the plugin's description (`hapsyn describe evaluate`).
struct EvaluateOptions {
  static void declare(OptionDeclarations<EvaluateOptions>& d) {
    d.describe("Evaluates one fixed design over the whole scene. Every design variable must have a \"value\". "
               "No options.");
  }
};

class EvaluateSolver : public Solver {
 public:
  using Options = EvaluateOptions;
  explicit EvaluateSolver(const EvaluateOptions&) {}
  /// \throws Error when a design variable is not fixed (names it).
  void check(const Problem& problem) const override;
  /// Status kConverged with `best` for a feasible design; kInfeasible with the failing
  /// constraint or sample in the message otherwise.
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;
};

/// "sample 12 at (x = 0.05, y = 0.05) m is unreachable" (for messages).
std::string describe_sample(const Problem& problem, int sample, SampleStatus status);
/// Human-readable reason of an unsuccessful evaluation.
std::string describe_failure(const Problem& problem, const Evaluation& evaluation);

}  // namespace hapsyn::plugins
