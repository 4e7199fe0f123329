#pragma once
/// \file
/// The closed-form inverse kinematics of a Chain (chain.hpp): the shared closed_form_ik engine
/// (shared/closed_form_ik/six_r_ik.hpp: every solution of a 6R arm whose axes the classifier
/// recognises) with the chain's joint limits and solve_ik's selection rules on top.
///
/// - Applies to 6 revolute joints and the full-pose task (closed_form_applicability()); the
///   chain's axes then pick a family (ChainGeometry::describe()) or none.
/// - solve() picks, among the engine's solutions (without limits) moved into the joint limits by
///   whole turns (ik_shift_into_limits, tolerance kClosedFormLimitTolerance), the one closest to
///   home (ik_home_distance, the numerical IK's measure; ties: the engine's order) or the first in
///   the engine's order (first_found). To polish only what it uses it ranks the engine's raw
///   candidates first (closest_to_home: those inside the limits to 1e-6 rad by their distance;
///   first_found: engine order) and polishes in that order until one reproduces the target and
///   lies inside the limits; a closest-to-home candidate that the polish moved farther than the
///   next one's distance sends it to the full solve (all_solutions()), so the pick is always the
///   closest of all solutions. Only when none lies inside are the rest polished, to tell
///   kJointLimit from kUnreachable.
/// - Statuses are proved, not guessed: kJointLimit when solutions exist and every one lies
///   outside the limits, kUnreachable when the pose has none. Two caveats, both the engine's: at a
///   singular configuration with a continuum of solutions the engine returns one representative
///   (another member might lie inside the limits), and the 1-D search family (only axes 5 x 6 or
///   1 x 2 meet) can miss roots (six_r_ik.hpp measures about 2 % of random poses, 0.1 % away from
///   singularities); there "unreachable" and "invalid" are as good as the search.
#include "chain.hpp"
#include "chain_ik.hpp"

#include "shared/closed_form_ik/six_r_ik.hpp"

#include <Eigen/Geometry>
#include <array>
#include <string>

namespace hapsyn::plugins {

/// A closed-form solution may stand this far outside a joint limit before it is out [rad]; it
/// is clamped onto the limit (the haptic6r mechanism's tolerance, so both admit the same
/// solutions).
constexpr double kClosedFormLimitTolerance = 1e-9;

/// Per-thread scratch of ChainClosedFormIk::solve (no heap).
struct ClosedFormScratch {
  closed_form_ik::IkScratch engine;
  closed_form_ik::IkSolutions solutions;
  std::array<int, 128> order{};     ///< candidates ranked by the selection rule
  std::array<double, 128> key{};    ///< their distances to home
  std::array<bool, 128> failed{};   ///< candidate i did not polish onto the target (not polished again)
};

/// Why the closed form does not apply to a chain and task ("" when it does: 6 revolute joints,
/// full-pose task), e.g. "task position (the closed form needs the full pose)".
std::string closed_form_applicability(const Chain& chain, const IkTask& task);

/// The chain in product-of-exponentials form (PoeChain::from_local_frames of its joint origins,
/// axes and tip). Allocates (model build only).
closed_form_ik::PoeChain poe_chain_of(const Chain& chain);

/// The closed-form IK of one design's chain (immutable; solve() is const and thread-safe with a
/// per-thread scratch).
class ChainClosedFormIk {
 public:
  /// \throws hapsyn::Error ("closed_form_ik") when the chain has no closed-form family; the
  /// message carries ChainGeometry::describe(). Call only when closed_form_applicability() is "".
  explicit ChainClosedFormIk(const Chain& chain);

  /// One target (the tip pose in the base frame). q (n values): kConverged the solution picked
  /// (inside the limits); kJointLimit the first solution found (outside the limits, as the engine
  /// wraps it into (-pi, pi]); kUnreachable q untouched. Allocation-free.
  IkStatus solve(const Chain& chain, const Eigen::Isometry3d& target, const double* home, bool first_found, double* q,
                 ClosedFormScratch& scratch) const;

  /// solve() from all_solutions(): the same contract and pick (the reference the ranked path is
  /// tested against, and its fallback when the polish moves a candidate). Allocation-free.
  IkStatus solve_from_all(const Chain& chain, const Eigen::Isometry3d& target, const double* home, bool first_found,
                          double* q, ClosedFormScratch& scratch) const;

  /// Every solution of the target without limits (the engine's solve(): polished, wrapped into
  /// (-pi, pi], duplicates merged) in scratch.solutions. Allocation-free.
  const closed_form_ik::IkSolutions& all_solutions(const Eigen::Isometry3d& target, ClosedFormScratch& scratch) const;

  const closed_form_ik::ChainGeometry& geometry() const { return engine_.geometry(); }

 private:
  // Polishes raw candidate i; true when it reproduces the target, then wrapped into (-pi, pi] in out.
  bool polished(const Eigen::Isometry3d& target, const ClosedFormScratch& scratch, int i, closed_form_ik::Vector6d& out) const;

  closed_form_ik::ClosedFormIk6R engine_;
};

}  // namespace hapsyn::plugins
