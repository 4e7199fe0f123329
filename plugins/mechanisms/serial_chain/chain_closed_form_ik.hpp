#pragma once
/// \file
/// The closed-form inverse kinematics of a Chain (chain.hpp): the shared closed_form_ik engine
/// (shared/closed_form_ik/six_r_ik.hpp: every solution of a 6R arm whose axes the classifier
/// recognises) with the chain's joint limits and solve_ik's selection rules on top.
///
/// - Applies to 6 revolute joints and the full-pose task (closed_form_applicability()); the
///   chain's axes then pick a family (ChainGeometry::describe()) or none.
/// - solve() asks the engine for every solution without limits, moves each into the joint
///   limits by whole turns (ik_shift_into_limits, tolerance kClosedFormLimitTolerance) and picks,
///   among those inside, the one closest to home (ik_home_distance, the numerical IK's measure;
///   ties: the engine's order) or the first in the engine's order (first_found).
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

  const closed_form_ik::ChainGeometry& geometry() const { return engine_.geometry(); }

 private:
  closed_form_ik::ClosedFormIk6R engine_;
};

}  // namespace hapsyn::plugins
