// ChainClosedFormIk (chain_closed_form_ik.hpp): the closed_form_ik engine with the chain's joint
// limits and the selection rules.
#include "chain_closed_form_ik.hpp"

#include <algorithm>
#include <limits>
#include <vector>

namespace hapsyn::plugins {

std::string closed_form_applicability(const Chain& chain, const IkTask& task) {
  if (chain.dof() != 6) {
    return std::to_string(chain.dof()) + " moving joints (the closed form is for 6 revolute joints)";
  }
  for (const ChainJoint& j : chain.joints) {
    if (j.type != ChainJointType::kRevolute) return "joint " + j.name + " is prismatic (the closed form is for 6 revolute joints)";
  }
  if (!task.position || task.orientation != IkTask::Orientation::kFull) return "the task is not the full pose (the closed form needs it)";
  return "";
}

closed_form_ik::PoeChain poe_chain_of(const Chain& chain) {
  std::vector<Eigen::Isometry3d> origins;
  std::vector<Eigen::Vector3d> axes;
  for (const ChainJoint& j : chain.joints) {
    origins.push_back(j.origin);
    axes.push_back(j.axis);
  }
  return closed_form_ik::PoeChain::from_local_frames(origins, axes, chain.tip);
}

ChainClosedFormIk::ChainClosedFormIk(const Chain& chain) : engine_(poe_chain_of(chain)) {}

IkStatus ChainClosedFormIk::solve(const Chain& chain, const Eigen::Isometry3d& target, const double* home,
                                  bool first_found, double* q, ClosedFormScratch& scratch) const {
  closed_form_ik::IkSolutions& all = scratch.solutions;
  engine_.solve(target, scratch.engine, all);
  if (all.count == 0) return IkStatus::kUnreachable;
  double closest = std::numeric_limits<double>::infinity();
  bool found = false;
  for (int k = 0; k < all.count; ++k) {
    closed_form_ik::Vector6d candidate = all.q[static_cast<std::size_t>(k)];
    if (!ik_shift_into_limits(chain, candidate.data(), kClosedFormLimitTolerance)) continue;
    const double distance = first_found || home == nullptr ? 0.0 : ik_home_distance(chain, candidate.data(), home);
    if (distance < closest) {
      closest = distance;
      std::copy_n(candidate.data(), 6, q);
      found = true;
      if (first_found || home == nullptr) break;
    }
  }
  if (found) return IkStatus::kConverged;
  std::copy_n(all.q[0].data(), 6, q);
  return IkStatus::kJointLimit;
}

}  // namespace hapsyn::plugins
