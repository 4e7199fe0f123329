#pragma once
/// \file
/// Numerical inverse kinematics of a Chain (chain.hpp): deterministic (no clock), seeded,
/// iteration-budgeted damped least squares (Levenberg-Marquardt) with joint limits, for full
/// poses, positions, or positions plus one orientation axis.
///
/// Algorithm (chain_ik.cpp has the details):
/// - Task error e (task.rows(), orientation rows first, then position; see task_error): position
///   p_target - p [m]; kFull the rotation vector of R_target R^T [rad]; kAxis the rotation vector
///   of the shortest rotation carrying the tip's axis a onto the target's axis b, i.e.
///   (a x b) angle(a, b) / |a x b| (= a x b to first order), on the fixed basis (u1, u2) of
///   axis_basis(b). At e = 0, de/dq = -task_jacobian (checked against finite differences).
/// - Each iteration solves (J^T J + mu I) dq = J^T e with the position rows divided by the
///   chain's reach (so rows are dimensionless), caps the step at 1 rad / 1 reach, projects it into
///   the joint limits (a joint at a bound whose step points out of the limits is held fixed and
///   the system re-solved without it), and accepts it when the error drops; mu adapts by gain
///   ratio (Nielsen): a singular Jacobian, a wrist or elbow singularity or the reach boundary
///   only make the steps shorter, never NaN. A revolute joint whose limits span 2 pi or more
///   (or are infinite) is continuous: its angle is wrapped into [lower, lower + 2 pi)
///   ((-pi, pi] when unlimited) instead of clamped.
/// - A run ends converged when |position error| < position_tolerance [m] and the orientation
///   error angle < orientation_tolerance [rad], or unconverged after max_iterations evaluations
///   or when it stalls (a local minimum of |e|: the step shrinks below 1e-14 or mu explodes).
#include "chain.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>

namespace hapsyn::plugins {

/// What of the tip pose the IK (and the task Jacobian) matches; the rest is free.
struct IkTask {
  enum class Orientation : std::uint8_t {
    kNone,  ///< position only (3 rows: a 3-DOF device)
    kAxis,  ///< the tip's axis `axis` points along the target's same axis (2 rows: rotation about it is free)
    kFull,  ///< the full orientation (3 rows)
  };
  bool position = true;                       ///< match the tip point (3 rows: v)
  Orientation orientation = Orientation::kFull;
  int axis = 2;                               ///< 0, 1, 2 = x, y, z of the tip frame (kAxis only)
  int rows() const {                          ///< matched rows, 2..6
    return (position ? 3 : 0) + (orientation == Orientation::kFull ? 3 : orientation == Orientation::kAxis ? 2 : 0);
  }
  int orientation_rows() const { return rows() - (position ? 3 : 0); }  ///< 0, 2 or 3
};

/// Options of the IK (the mechanism declares them as its own options).
struct IkSettings {
  double position_tolerance = 1e-10;     ///< converged when the position error is below [m]
  double orientation_tolerance = 1e-10;  ///< ... and the rotation error angle below [rad]
  int max_iterations = 100;              ///< error evaluations (FK + Jacobian) per start
  int restarts = 8;                      ///< extra starts after the given ones (deterministic pseudo-random, seeded)
  std::uint64_t seed = 1;                ///< seed of the restarts' starts (ik_random_start)
  /// Redundant chains only (n > task.rows()): projected-gradient steps along the self-motion
  /// toward `home` per converged solution (each re-converged; it stops early once a step is
  /// below 1e-6 rad); 0 = keep the solution as found. On the 7R test arm, 8 steps get within
  /// 0.1 % of the distance 40 steps reach, at ~1/2 of their cost.
  int nullspace_steps = 8;
};

/// How one IK ended. What kJointLimit and kUnreachable prove depends on the solver:
/// - numerical (solve_ik): kJointLimit means no start converged inside the limits but a run
///   without limits did: a guess (an in-limit solution no start reached may exist); kUnreachable
///   means no start converged at all (also a guess near the reach boundary).
/// - closed form (chain_closed_form_ik.hpp, every solution known): kJointLimit means solutions
///   exist and every one lies outside the limits; kUnreachable means the pose has no solution.
enum class IkStatus : std::uint8_t {
  kConverged,    ///< within the tolerances and the joint limits
  kJointLimit,   ///< solved only outside the joint limits (numerical: a guess; closed form: proved)
  kUnreachable,  ///< no solution (numerical: no start converged; closed form: none exists)
};

/// The task error of a tip pose (task.rows(), see the file comment), and Jacobians of the task.
using TaskVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxTask, 1>;
/// The IK's normal-equation matrices (n x n, fixed capacity).
using IkJointMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxChainJoints, kMaxChainJoints>;
using IkJointVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxChainJoints, 1>;

/// Per-thread scratch of the IK (no allocation per call). Contents are meaningless between calls.
struct IkScratch {
  ChainFrames frames;
  TaskJointMatrix jacobian;       ///< geometric 6 x n
  TaskJointMatrix task_jacobian;  ///< rows x n
  TaskVector error, trial_error;
  IkJointMatrix normal;           ///< J^T J of the scaled task Jacobian
  IkJointVector gradient, step;
  Eigen::LLT<IkJointMatrix> llt;
  std::array<double, kMaxChainJoints> trial{}, start{}, candidate{}, best{}, closest{};
};

/// How far a tip pose is from a target in the rows of a task.
struct IkResidual {
  double position = 0.0;     ///< |p_target - p| [m] (0 when !task.position)
  double orientation = 0.0;  ///< rotation angle [rad] (kFull) or angle between the axes (kAxis); 0 for kNone
  bool within(const IkSettings& s) const {  ///< the IK's convergence criterion
    return position < s.position_tolerance && orientation < s.orientation_tolerance;
  }
};
IkResidual task_residual(const IkTask& task, const Eigen::Isometry3d& tip, const Eigen::Isometry3d& target);

/// The fixed orthonormal pair (u1, u2) orthogonal to the unit vector b of the kAxis rows:
/// u1 = the base axis e_k least aligned with b (smallest |b_k|, lowest k on ties) made
/// orthogonal to b and normalised, u2 = b x u1.
void axis_basis(const Eigen::Vector3d& b, Eigen::Vector3d& u1, Eigen::Vector3d& u2);

/// The task error e of a tip pose against a target (see the file comment; the kAxis basis is
/// built on the target's axis). Allocation-free.
void task_error(const IkTask& task, const Eigen::Isometry3d& tip, const Eigen::Isometry3d& target, TaskVector& error);

/// Solves one target from one start within the joint limits.
/// \param target the tip pose wanted, in the base frame (only the rows in `task` matter)
/// \param start  n joint positions to start from (clamped / wrapped into the limits first)
/// \param q      out: n joint positions, the last iterate (inside the limits); may alias start
/// \returns kConverged or kUnreachable (the budget ran out or the iteration stalled)
IkStatus solve_ik_from(const Chain& chain, const IkTask& task, const IkSettings& settings,
                       const Eigen::Isometry3d& target, const double* start, double* q, IkScratch& scratch);

/// Solves one target from `starts` (tried in order), then `settings.restarts` deterministic
/// pseudo-random starts inside the limits (ik_random_start(chain, settings.seed, k) for
/// k = 0, 1, ...), and picks among the converged solutions the one closest to `home` (sum of
/// squared joint differences, revolute ones wrapped to (-pi, pi]; ties: the first found).
/// A redundant chain (n > task.rows()) first moves each converged solution along its
/// self-motion toward `home` (settings.nullspace_steps steps q += N (home - q), N = I - J^+ J
/// the projector on the task Jacobian's null space, each re-converged; a step that fails or does
/// not bring q closer is halved), so the rule picks a posture, not an accident of the start.
/// When `first_converged` is true (or home is null) it returns the first converged solution
/// instead (faster; no self-motion).
/// kJointLimit when no start converged inside the limits but an unconstrained run did (the
/// same starts are re-run without limits only after all constrained runs failed).
/// \param starts  start_count pointers to n joint positions each (start_count may be 0)
/// \param home    n joint positions, or null
/// \param q       out: n joint positions. kConverged: the solution picked (inside the limits);
///                kJointLimit: the first unconstrained solution (outside the limits);
///                kUnreachable: the constrained iterate with the smallest task error.
IkStatus solve_ik(const Chain& chain, const IkTask& task, const IkSettings& settings,
                  const Eigen::Isometry3d& target, const double* const* starts, int start_count,
                  const double* home, bool first_converged, double* q, IkScratch& scratch);

/// The distance solve_ik's closest-to-home rule minimises: the sum of squared joint differences,
/// revolute ones wrapped to (-pi, pi].
double ik_home_distance(const Chain& chain, const double* q, const double* home);

/// Moves n joint positions into the joint limits by whole turns, as solve_ik reports angles: a
/// continuous revolute joint (limits spanning 2 pi or more, or infinite) is wrapped into
/// (-pi, pi] when that fits inside its limits, else into [lower, lower + 2 pi); another revolute
/// joint takes the value wrapped to (-pi, pi] or that plus or minus 2 pi that lies within
/// [lower - tolerance, upper + tolerance], clamped onto [lower, upper]. Prismatic joints are only
/// checked. \returns false (q partly changed) when a joint has no such value.
bool ik_shift_into_limits(const Chain& chain, double* q, double tolerance);

/// The `index`-th pseudo-random start of solve_ik's restarts (splitmix64 from `seed` and
/// `index`; identical on every platform): each joint uniform in [lower, upper], (-pi, pi] for
/// an unlimited revolute joint, [-reach, reach] for an unlimited prismatic one.
/// \param q out: n joint positions
void ik_random_start(const Chain& chain, std::uint64_t seed, int index, double* q);

/// The task Jacobian: the rows of the geometric Jacobian (omega, v) that `task` matches, for a
/// tip frame at `tip` and a target with the same axis: orientation rows first (kFull: omega;
/// kAxis: omega projected on (u1, u2) = axis_basis of the tip's `axis`), then v. At a target
/// equal to `tip`, de/dq = -out for e = task_error. Allocation-free.
void task_jacobian(const IkTask& task, const Eigen::Isometry3d& tip, const TaskJointMatrix& geometric,
                   TaskJointMatrix& out);

}  // namespace hapsyn::plugins
