#pragma once
/// \file
/// Solver `sequential`: sequential (lexicographic) optimization as Unal et al. (2008, section 6,
/// Figures 6-7) implement it after Stocco: for each grid value of one design variable (`variable`,
/// default "r"), the best design for the first objective with that variable fixed (a
/// single-objective sub-solver, default `culling`); then, among those designs, the best for the
/// second objective. The result is that one design (`best`); every per-value design is in the
/// statistics (Figure 6). Against a reference front (the problem's "indicators" section)
/// result.json reports whether the design is dominated and by how much in each objective.
#include <hapsyn/options.hpp>
#include <hapsyn/solver.hpp>

#include <string>

namespace hapsyn::plugins {

struct SequentialOptions {
  std::string variable;
  SubSolver sub_solver;

  static void declare(OptionDeclarations<SequentialOptions>& d) {
    d.describe(
        "Sequential optimization (Unal 2008, Figures 6-7): for each grid value of one design variable, the best "
        "design for the first objective (sub-solver); among those, the best for the second objective. Exactly two "
        "objectives.");
    d.add(&SequentialOptions::variable, "variable", "r",
          "The independent design variable (a free component with a grid step), e.g. the five-bar's r");
    d.add(&SequentialOptions::sub_solver, "sub_solver", "culling",
          "Single-objective solver of the first objective per value: {\"plugin\", \"options\"}");
  }
};

class SequentialSolver : public Solver {
 public:
  using Options = SequentialOptions;
  explicit SequentialSolver(const SequentialOptions& options) : options_(options) {}
  /// Two objectives make a comparison with fronts, not a weighted sum.
  /// Under MPI the values are a task farm: each one's sub-solver runs whole on one rank (its
  /// threads, no progress lines of its own), and the design chosen is the same whatever the
  /// number of ranks (the values are independent).
  SolverSpecs specs() const override { return {true, true, false}; }
  /// \throws Error("sequential", ...) unless there are exactly two objectives and `variable` is a
  ///         free design component with a grid step; or when the sub-solver refuses the first
  ///         objective's problem with the variable fixed ("<sub_solver's path>: <its message>").
  void check(const Problem& problem) const override;
  /// The chosen design (kConverged); kInfeasible when no value gave a feasible design; kFailed
  /// without a sub-solver (options made without a registry); kStopped on a stop request
  /// (between values, and inside the sub-solver), with the best among the finished values (an
  /// interrupted sub-solver's best is not used).
  ///
  /// Checkpoint (context.checkpoint_file): written after every value (its record, design,
  /// objective values and counts); on --resume the finished ones are skipped, after their
  /// designs are re-evaluated and found to give the claimed values, and the result is that of
  /// an uninterrupted run. The sub-solver runs without a checkpoint of its own. Under MPI the
  /// finished ones need not be the first ones (each entry names its task).
  /// \throws Error("checkpoint", ...) on --resume with a checkpoint that fails the checks.
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;

 private:
  std::size_t free_index(const Problem& problem) const;
  SequentialOptions options_;
};

}  // namespace hapsyn::plugins
