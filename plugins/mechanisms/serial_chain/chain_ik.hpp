#pragma once
/// \file
/// Numerical inverse kinematics of a Chain (chain.hpp): deterministic (no clock), seeded,
/// iteration-budgeted damped least squares (Levenberg-Marquardt) with joint limits, for full
/// poses, positions, or positions plus some orientation axes.
#include "chain.hpp"

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
};

/// Options of the IK (the mechanism declares them as its own options).
struct IkSettings {
  double position_tolerance = 1e-10;     ///< converged when the position error is below [m]
  double orientation_tolerance = 1e-10;  ///< ... and the rotation error below [rad]
  int max_iterations = 100;              ///< per start
  int restarts = 8;                      ///< extra starts after the given ones (deterministic pseudo-random, seeded)
  std::uint64_t seed = 1;                ///< seed of the restarts' starts
};

/// How one IK ended.
enum class IkStatus : std::uint8_t {
  kConverged,    ///< within the tolerances and the joint limits
  kJointLimit,   ///< the pose is reachable only outside the joint limits
  kUnreachable,  ///< no start converged
};

/// Per-thread scratch of the IK (no allocation per call).
struct IkScratch {
  ChainFrames frames;
  TaskJointMatrix jacobian;
};

/// Solves one target from one start within the joint limits.
/// \param target the tip pose wanted, in the base frame (only the rows in `task` matter)
/// \param start  n joint positions to start from (clamped into the limits first)
/// \param q      out: n joint positions, the last iterate (inside the limits)
/// \returns kConverged or kUnreachable (the budget ran out or the iteration stalled)
IkStatus solve_ik_from(const Chain& chain, const IkTask& task, const IkSettings& settings,
                       const Eigen::Isometry3d& target, const double* start, double* q, IkScratch& scratch);

/// Solves one target from `starts` (tried in order), then `settings.restarts` deterministic
/// pseudo-random starts inside the limits, and picks among the converged solutions the one
/// closest to `home` (sum of squared joint differences, revolute ones wrapped to (-pi, pi]).
/// A redundant chain (n > task.rows()) first moves each converged solution along its
/// self-motion toward `home` (null-space steps, re-converged), so the rule picks a posture,
/// not an accident of the start.
/// When `first_converged` is true it returns the first converged solution instead (faster).
/// kJointLimit when no start converged inside the limits but an unconstrained run did.
IkStatus solve_ik(const Chain& chain, const IkTask& task, const IkSettings& settings,
                  const Eigen::Isometry3d& target, const double* const* starts, int start_count,
                  const double* home, bool first_converged, double* q, IkScratch& scratch);

/// The task Jacobian: the rows of the geometric Jacobian (omega, v) that `task` matches, for a
/// tip frame at `tip` and a target with the same axis: orientation rows first (kFull: omega;
/// kAxis: omega projected on the two directions orthogonal to the tip's `axis`, in a fixed
/// documented basis), then v. Allocation-free.
void task_jacobian(const IkTask& task, const Eigen::Isometry3d& tip, const TaskJointMatrix& geometric,
                   TaskJointMatrix& out);

}  // namespace hapsyn::plugins
