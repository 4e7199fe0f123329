#pragma once
/// \file
/// The closed-form inverse kinematics of a Chain (chain.hpp): the shared closed_form_ik engine
/// (shared/closed_form_ik/six_r_ik.hpp: every solution of a 6R arm whose axes the classifier
/// recognises) with the chain's joint limits and solve_ik's selection rules on top.
///
/// - Applies to 6 or 7 revolute joints and the full-pose task (closed_form_applicability()); a
///   6R chain's axes then pick a family (ChainGeometry::describe()) or none.
/// - 7R (redundant) chains (the free functions below: chain_redundant_joint.cpp): one joint k is discretised, as the human_arm scene does with its
///   joint 3: `steps` values over its limits (redundant_grid()), and for each value the 6R left
///   with joint k locked there (locked_poe_chain(): its rotation folded into the next joint's
///   origin) gets its own engine, built with the model. A target's solutions are the union over
///   the grid of each 6R's solutions with q_k set to the grid value; selection and statuses are
///   the 6R path's over that union (exact among the grid's solutions; a solution whose q_k lies
///   between grid values is not found: the grid is the resolution of the self-motion). k is the
///   user's (RedundantJointSettings::joint) or chosen by choose_redundant_joint().
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
#include <vector>

namespace hapsyn::plugins {

/// A closed-form solution may stand this far outside a joint limit before it is out [rad]; it
/// is clamped onto the limit (the haptic6r mechanism's tolerance, so both admit the same
/// solutions).
constexpr double kClosedFormLimitTolerance = 1e-9;

/// Most values a 7R chain's redundant joint may take (ik.redundant_steps' maximum).
constexpr int kMaxRedundantSteps = 1000;

/// Per-thread scratch of ChainClosedFormIk::solve (no heap).
struct ClosedFormScratch {
  closed_form_ik::IkScratch engine;
  closed_form_ik::IkSolutions solutions;
  std::array<int, 128> order{};     ///< candidates ranked by the selection rule
  std::array<double, 128> key{};    ///< their distances to home
  std::array<bool, 128> failed{};   ///< candidate i did not polish onto the target (not polished again)
  std::array<double, 7> first{};    ///< 7R: the first solution found (reported with kJointLimit)
  std::array<int, kMaxRedundantSteps> grid_order{};     ///< 7R: grid values in visiting order
  std::array<double, kMaxRedundantSteps> grid_bound{};  ///< 7R: (grid value - home)^2 per grid value
};

/// Why the closed form does not apply to a chain and task ("" when it does: 6 or 7 revolute
/// joints, full-pose task), e.g. "the task is not the full pose (the closed form needs it)".
std::string closed_form_applicability(const Chain& chain, const IkTask& task);

/// The chain in product-of-exponentials form (PoeChain::from_local_frames of its joint origins,
/// axes and tip). Allocates (model build only).
closed_form_ik::PoeChain poe_chain_of(const Chain& chain);

/// How a 7R chain's redundancy is discretised (ik.redundant_joint, ik.redundant_steps).
struct RedundantJointSettings {
  int joint = -1;  ///< 0-based index of the discretised joint; -1: choose_redundant_joint()
  int steps = 17;  ///< grid values (>= 2; the human_arm scene's joint3_steps default)
};

/// The chain with joint k (0-based) locked at `value` [rad]: the PoeChain of the other n - 1
/// joints, Rot(axis_k, value) folded with O_k into the next joint's origin (into the tip for
/// the last joint). Allocates (model build only).
closed_form_ik::PoeChain locked_poe_chain(const Chain& chain, int k, double value);

/// Whether a 6R chain's Jacobian has full rank (sigma_min > 1e-6 sigma_max) at one of two fixed
/// generic configurations (no zero or right angle, no symmetry): false when a self-motion
/// remains at every configuration. Allocation-free.
bool generic_full_rank(const closed_form_ik::PoeChain& chain);

/// The values a discretised joint takes: `steps` values evenly over [lower, upper], both ends
/// included; over [-pi, pi) (pi left out: it is -pi) when the joint has infinite limits or
/// limits spanning 2 pi or more.
std::vector<double> redundant_grid(const ChainJoint& joint, int steps);

/// Why locking joint k of a 7R chain does not leave a 6R with a closed form ("" when it does):
/// the 6R is classified at the angles 0, 1, -2 and sqrt(2) rad (a family other than kUnsupported
/// at each), and at each its Jacobian must have full rank at one of two fixed generic
/// configurations (locking a joint that does not remove the self-motion, such as the elbow of an
/// arm with spherical shoulder and wrist, or a joint at a value that aligns its neighbours'
/// axes, such as an iiwa-like arm's joint 2 at 0, leaves a 6R whose family would return one
/// representative of a continuum). `geometry` (may be null) gets the 6R's classification at 0.
std::string redundant_joint_unsuitability(const Chain& chain, int k, closed_form_ik::ChainGeometry* geometry = nullptr);

/// The joint a 7R chain discretises under ik.redundant_joint "auto": joints tried from the
/// middle outward, 4, 3, 5, 2, 6, 1, 7 (1-based), the first whose 6R has a family without the
/// 1-D search (spherical wrist, three parallel axes, SCARA pair: exact and faster), else the
/// first with any family; -1 when none. Allocates (model build only).
int choose_redundant_joint(const Chain& chain);

/// The closed-form IK of one design's chain (immutable; solve() is const and thread-safe with a
/// per-thread scratch).
class ChainClosedFormIk {
 public:
  /// \throws hapsyn::Error ("closed_form_ik") when the chain has no closed-form family; the
  /// message carries ChainGeometry::describe(). Call only when closed_form_applicability() is "".
  /// A 7R chain discretises redundancy.joint (or choose_redundant_joint()'s) in redundancy.steps
  /// values; it throws when locking that joint leaves no closed form
  /// (redundant_joint_unsuitability(), or a grid value's 6R unsupported or rank-deficient at
  /// both of its test configurations), naming the joint and the value.
  explicit ChainClosedFormIk(const Chain& chain, const RedundantJointSettings& redundancy = {});

  /// One target (the tip pose in the base frame). q (n values): kConverged the solution picked
  /// (inside the limits); kJointLimit the first solution found (outside the limits, as the engine
  /// wraps it into (-pi, pi]); kUnreachable q untouched. Allocation-free. 7R: the union over the
  /// grid, each grid value's 6R solved in full; first_found (or no home) visits the grid values
  /// ascending (each in the engine's order), closest_to_home by their own share of the distance,
  /// (q_k - home_k)^2 (ties: ascending), and stops at the first value whose share is no smaller
  /// than the best distance so far (no solution there can be closer): exact, about half the
  /// solves. kJointLimit reports the first solution in the visiting order.
  IkStatus solve(const Chain& chain, const Eigen::Isometry3d& target, const double* home, bool first_found, double* q,
                 ClosedFormScratch& scratch) const;

  /// solve() from all_solutions(): the same contract and pick (the reference the ranked path is
  /// tested against, and its fallback when the polish moves a candidate). Allocation-free.
  IkStatus solve_from_all(const Chain& chain, const Eigen::Isometry3d& target, const double* home, bool first_found,
                          double* q, ClosedFormScratch& scratch) const;

  /// Every solution of the target without limits (the engine's solve(): polished, wrapped into
  /// (-pi, pi], duplicates merged) in scratch.solutions. Allocation-free. 6R only (a 7R chain's
  /// are every_solution()'s). \throws hapsyn::Error ("closed_form_ik") on a 7R chain.
  const closed_form_ik::IkSolutions& all_solutions(const Eigen::Isometry3d& target, ClosedFormScratch& scratch) const;

  /// Every solution without limits, n values each: 6R all_solutions(); 7R the union over the
  /// grid in solve()'s order, q_k the grid value. Allocates (tests and tools, not per sample).
  std::vector<JointVector> every_solution(const Eigen::Isometry3d& target, ClosedFormScratch& scratch) const;

  /// The 6R's geometry (7R: that of the 6R at the first grid value).
  const closed_form_ik::ChainGeometry& geometry() const { return engines_.front().geometry(); }
  /// 7R: the discretised joint (0-based) and its grid; -1 and empty for a 6R chain.
  int redundant_joint() const { return redundant_; }
  const std::vector<double>& grid() const { return grid_; }

 private:
  // Polishes raw candidate i; true when it reproduces the target, then wrapped into (-pi, pi] in out.
  bool polished(const Eigen::Isometry3d& target, const ClosedFormScratch& scratch, int i, closed_form_ik::Vector6d& out) const;

  // 7R: every solution of grid value g's 6R, q_k inserted, through f(q7) (7 values).
  template <class F>
  void for_each_redundant(const Eigen::Isometry3d& target, ClosedFormScratch& scratch, int g, F&& f) const;
  IkStatus solve_redundant(const Chain& chain, const Eigen::Isometry3d& target, const double* home, bool first_found,
                           double* q, ClosedFormScratch& scratch) const;
  const closed_form_ik::ClosedFormIk6R& engine() const { return engines_.front(); }

  std::vector<closed_form_ik::ClosedFormIk6R> engines_;  ///< 6R: one; 7R: one per grid value
  int redundant_ = -1;
  std::vector<double> grid_;
};

}  // namespace hapsyn::plugins
