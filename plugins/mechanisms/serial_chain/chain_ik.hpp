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

/// Which task-space rows the IK matches (the others are free).
struct IkTask {
  bool position = true;                              ///< match the tip point (3 rows)
  std::array<bool, 3> orientation = {true, true, true};  ///< match the tip's x, y, z axes' rotation rows (omega_x, omega_y, omega_z in the base frame)
  int rows() const;  ///< number of matched rows (1..6)
};

/// Options of the IK (the mechanism declares them as its own options).
struct IkSettings {
  double position_tolerance = 1e-10;     ///< converged when the position error is below [m]
  double orientation_tolerance = 1e-10;  ///< ... and the rotation error below [rad]
  int max_iterations = 100;              ///< per start
  int restarts = 8;                      ///< extra starts after the given ones (deterministic pseudo-random, seeded)
  std::uint64_t seed = 1;                ///< seed of the restarts' starts
  double singular_tolerance = 1e-6;      ///< smallest singular value of the task Jacobian (scaled, see chain_ik.cpp) below which a solution is singular
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
/// When `first_converged` is true it returns the first converged solution instead (faster).
/// kJointLimit when no start converged inside the limits but an unconstrained run did.
IkStatus solve_ik(const Chain& chain, const IkTask& task, const IkSettings& settings,
                  const Eigen::Isometry3d& target, const double* const* starts, int start_count,
                  const double* home, bool first_converged, double* q, IkScratch& scratch);

/// The smallest singular value of the task rows of the Jacobian at the solution, each column
/// scaled as chain_ik.cpp documents (so that metres and radians are comparable); the
/// mechanism classifies a sample singular when it is below settings.singular_tolerance.
double task_singular_value(const Chain& chain, const IkTask& task, const TaskJointMatrix& jacobian);

}  // namespace hapsyn::plugins
