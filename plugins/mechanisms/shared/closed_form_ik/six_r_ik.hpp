#pragma once
/// \file
/// All inverse-kinematics solutions of a 6R chain in closed form (IK-Geo, Elias & Wen 2022),
/// the decomposition chosen from the chain's axes (classify(), as EAIK, Ostermeier et al. 2025):
///
/// - spherical wrist (axes 4, 5, 6 meet at w; Puma, KUKA, Stanford-like arms without the
///   prismatic joint): the wrist centre's position gives (q1, q2, q3) by SP5 (up to 4), the
///   orientation (q4, q5) by SP2 and q6 by SP1: up to 8 solutions. A spherical shoulder (axes
///   1, 2, 3 meet) is solved on the reversed chain.
/// - three parallel axes 2, 3, 4 (UR type): the components along the common axis of the tool's
///   approach and position give (q1, q5) by SP6 (up to 4), q6 and q2 + q3 + q4 by SP1, q3 by SP3
///   and q2 by SP1: up to 8. Axes 3, 4, 5 parallel: the reversed chain.
/// - axes 1, 2, 3 parallel and axes 4, 5 parallel (the haptic 6R of share/serial_chain, a SCARA
///   with a wrist): the components along the common axis k of the tool's axis 6 and of its
///   position give q4 + q5 and q4 by SP4 (up to 2 each), q6 and q1 + q2 + q3 by SP1, q2 by SP3 and
///   q1 by SP1: up to 8. Axes 4, 5, 6 parallel and 2 || 3: the reversed chain.
/// - one intersecting pair 5 x 6 (or, reversed, 1 x 2), e.g. offset wrists: a 1-D search over
///   q1. For each q1 the point where axes 5 and 6 meet fixes (q2, q3, q4) by SP5 (up to 4
///   branches); the remaining error e(q1) = h5 . R_04^T R_06 h6 - h5 . h6 (the angle between axes
///   5 and 6 must match) is sampled at `search_samples` values of q1 evenly over [-pi, pi).
///   Branches of neighbouring samples are matched greedily by nearest (q2, q3, q4); an interval
///   where a branch is left unmatched (a fold, where two branches meet and end) is halved up to 6
///   times and the unmatched branches at the last halving become candidates; every sign change
///   of a matched branch is refined by the Illinois method (regula falsi) to 1e-8 rad, and a branch
///   whose e nears zero and turns back is tested at the vertex of its parabola (two close roots);
///   then (q5, q6) by SP1. Roots can still be missed where e only touches zero or near singular
///   configurations: the tests measure about 2 % of generating configurations missed on random
///   poses (0.1 % of those whose Jacobian's smallest singular value is >= 0.03).
/// - anything else (in particular the general 6R without intersecting or parallel consecutive
///   axes, IK-Geo's 2-D search): the constructor refuses it.
///
/// Every candidate is polished by Newton steps on the full pose (6 x 6 Jacobian, at most
/// `newton_steps`, fewer once the error is below accept_tolerance / 1e4) and kept when it
/// reproduces the target to `accept_tolerance` (rotation angle [rad] and position [m]); duplicates (all angles within 1e-9 rad) are merged; angles are
/// wrapped into (-pi, pi], or into [lower, upper] when limits are given (a solution outside its
/// limits after shifts by 2 pi is dropped). Near singular configurations a subproblem may be
/// degenerate (a continuum of solutions): one representative is returned.
///
/// Model / data split: ClosedFormIk6R is immutable after construction (its methods are const and
/// may run on any number of threads); each thread passes its own IkScratch and IkSolutions.
/// solve() allocates nothing.
#include "shared/closed_form_ik/poe_chain.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>

namespace hapsyn::plugins::closed_form_ik {

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// Most solutions solve() returns (a 6R has at most 16).
constexpr int kMaxSolutions = 16;

/// Options of ClosedFormIk6R.
struct IkOptions {
  int search_samples = 72;          ///< samples of q1 in the 1-D search (>= 8)
  int newton_steps = 4;             ///< polishing steps per candidate (0 = none)
  double accept_tolerance = 1e-10;  ///< pose error a solution may keep [rad and m]
  /// A raw candidate whose pose error exceeds this [rad or m] is dropped without polishing
  /// (>= accept_tolerance). Exact candidates miss by about 1e-14; dropped ones by millimetres or
  /// more. Not applied to the 1-D search family (its fold candidates are approximate).
  double polish_radius = 1e-3;
  double geometry_tolerance = 1e-9;  ///< classify()'s tolerance
  bool use_limits = false;          ///< wrap into [lower, upper] and drop solutions outside
  std::array<double, 6> lower{}, upper{};  ///< joint limits [rad] when use_limits
};

/// The solutions of one call (fixed capacity: no allocation).
struct IkSolutions {
  std::array<Vector6d, kMaxSolutions> q{};  ///< q[0..count)
  int count = 0;
  int candidates = 0;  ///< candidates the subproblems produced before polishing and filtering
};

/// Per-thread working memory of ClosedFormIk6R::solve (no heap; large enough to keep off the stack).
struct IkScratch {
  std::array<Vector6d, 128> candidate{};  ///< raw candidates (beyond 128 the rest are dropped)
  int count = 0;
};

/// The closed-form 6R solver of one chain (see the file comment).
class ClosedFormIk6R {
 public:
  /// \throws hapsyn::Error ("closed_form_ik") when the chain is not 6R, its family is
  /// kUnsupported (the message carries ChainGeometry::describe()), or an option is out of range
  /// (search_samples < 8, newton_steps < 0, accept_tolerance <= 0, polish_radius < accept_tolerance).
  explicit ClosedFormIk6R(const PoeChain& chain, const IkOptions& options = {});

  /// All solutions q with chain().forward(q) = target (to accept_tolerance).
  void solve(const Eigen::Isometry3d& target, IkScratch& scratch, IkSolutions& out) const;

  /// The two halves of solve(), for a caller that needs only some solutions (serial_chain
  /// polishes its candidates in the order of its selection rule and stops at the first one):
  /// the raw candidates of the subproblems into scratch.candidate[0..count) (unpolished, not
  /// wrapped, possibly duplicated or spurious), and the Newton polish of one of them (true when
  /// it then reproduces the target to accept_tolerance; q is not wrapped). solve() is these two,
  /// then wrapping, limits and duplicates. Allocation-free.
  void candidates(const Eigen::Isometry3d& target, IkScratch& scratch) const;
  bool polish(const Eigen::Isometry3d& target, Vector6d& q) const;

  const PoeChain& chain() const { return chain_; }
  const ChainGeometry& geometry() const { return geometry_; }
  const IkOptions& options() const { return options_; }

 private:
  bool wrap_into_limits(Vector6d& q) const;

  PoeChain chain_;
  PoeChain work_;  // the chain the family's pattern is on (chain_ or chain_.reversed())
  ChainGeometry geometry_;
  Eigen::Vector3d point_ = Eigen::Vector3d::Zero();  // wrist point / 5x6 intersection on work_
  double polish_radius_ = 0.0;  // options_.polish_radius; infinite for the 1-D search family
  IkOptions options_;
};

}  // namespace hapsyn::plugins::closed_form_ik
