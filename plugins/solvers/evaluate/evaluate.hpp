#pragma once
/// \file
/// Solver `evaluate`: evaluates the one fixed design of a study (every design variable given a
/// "value"), over all samples, on the threads given.
#include <hapsyn/solver.hpp>

namespace hapsyn::plugins {

class EvaluateSolver : public Solver {
 public:
  explicit EvaluateSolver(const Json& options);
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
