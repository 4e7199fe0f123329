#pragma once
// The virtual prototype's replay of a motion study (`hapsyn view`, /api/replay): per sample, in
// time order, the mechanism drawn at the configuration its IK picks, the joint values, and per
// joint the rate and the torque against the actuator limits that motion_feasibility checks.
// Computed once at start through the evaluator's per-sample path; the server only hands it out.
#include <hapsyn/json.hpp>
#include <hapsyn/problem.hpp>
#include <hapsyn/quantities.hpp>

#include <Eigen/Core>
#include <string>

namespace hapsyn_cli {

/// "" when `problem` can be replayed: its scene gives every sample a "time" attribute [s] and
/// the demanded motion (the "twist" attribute), as the motion scene does; else why not.
std::string replay_unavailable(const hapsyn::Problem& problem);

/// Per joint of `q` (reachable, with the joint rates, accelerations, inertia, velocity torque,
/// gravity and actuator limits computed): qdot[j] = |qdot_j| / qdot_max_j and
/// tau[j] = |tau_j| / tau_max_j, tau = H qddot + C qdot + g summed as motion_feasibility sums it.
/// Each array holds q.joint_velocity.size() values. No allocation.
void limit_ratios(const hapsyn::SampleQuantities& q, double* qdot, double* tau);

/// The replay document of /api/replay for `full_design` (every design component). Frames are the
/// scene's samples ordered by trajectory (the "trajectory" grouping, in its label order; one
/// trajectory without it), then by time. Flat arrays, frame-major (J = joints):
///   frames, joints, sample[f] (the scene sample), time[f] [s] (from the recording's start),
///   trajectory[f] (index into trajectories), status[f] ("reachable", "unreachable", ...),
///   q[f*J + j] [rad or m], qdot_ratio[f*J + j] = |qdot_j| / qdot_max_j,
///   tau_ratio[f*J + j] = |tau_j| / tau_max_j with tau = H qddot + C qdot + g (the full inverse
///   dynamics, of the quantities the mechanism computed for the evaluator),
///   feasible[f]: 1 when every motion_feasibility per-sample value (`checks`, the samples.csv
///   columns) is 1, 0 when one is 0 or the sample has none (not reachable); null without a
///   motion_feasibility metric;
///   the drawing: polylines of every frame, frame f's are [frame_polylines[f], frame_polylines[f+1])
///   of polyline_sizes/polyline_names, their points consecutive in points (x, y, z [m], to 1 um).
/// q and the ratios are null where a frame is not reachable; the ratios are null throughout
/// (with "ratios_missing" saying why) when the study's metrics do not ask the mechanism for the
/// joint rates and the dynamics (Problem::needs()). An unavailable study gives
/// {"available": false, "reason": replay_unavailable()}.
/// \throws hapsyn::Error as Problem::evaluate (a non-finite quantity from a plugin).
hapsyn::Json replay_json(const hapsyn::Problem& problem, const Eigen::VectorXd& full_design);

}  // namespace hapsyn_cli
