#pragma once
/// \file
/// Solver `sequential`: sequential (lexicographic) optimization as Unal et al. (2008, section 6,
/// Figures 6-7) implement it after Stocco: for each grid value of one design variable (`variable`,
/// default "r"), the best design for the first objective with that variable fixed (a
/// single-objective sub-solver, default `culling`); then, among those designs, the best for the
/// second objective. The result is that one design (`best`); every per-value design is in the
/// statistics (Figure 6). Against a reference front (the problem's "indicators" section)
/// result.json reports whether the design is dominated and by how much in each objective.
#include <hapsyn/solver.hpp>

namespace hapsyn::plugins {

class SequentialSolver : public Solver {
 public:
  explicit SequentialSolver(const Json& options);
  /// Two objectives make a comparison with fronts, not a weighted sum.
  bool pareto() const override { return true; }
  /// \throws Error("sequential", ...) unless there are exactly two objectives and `variable` is a
  ///         free design component with a grid step.
  void check(const Problem& problem) const override;
  /// \throws Error naming solver.options.sub_solver.
  void prepare_sub_solvers(const Problem& problem, const Registry& registry) const override;
  SolverResult solve(const Problem& problem, const SolverContext& context) const override;

 private:
  std::size_t free_index(const Problem& problem) const;
  std::string variable_;
  Json sub_solver_;
};

}  // namespace hapsyn::plugins
