// ChainClosedFormIk (chain_closed_form_ik.hpp): the closed_form_ik engine with the chain's joint
// limits and the selection rules.
#include "chain_closed_form_ik.hpp"

#include "shared/closed_form_ik/angles.hpp"

#include <algorithm>
#include <cmath>
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

const closed_form_ik::IkSolutions& ChainClosedFormIk::all_solutions(const Eigen::Isometry3d& target,
                                                                   ClosedFormScratch& scratch) const {
  engine_.solve(target, scratch.engine, scratch.solutions);
  return scratch.solutions;
}

IkStatus ChainClosedFormIk::solve_from_all(const Chain& chain, const Eigen::Isometry3d& target, const double* home,
                                           bool first_found, double* q, ClosedFormScratch& scratch) const {
  const closed_form_ik::IkSolutions& all = all_solutions(target, scratch);
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

bool ChainClosedFormIk::polished(const Eigen::Isometry3d& target, const ClosedFormScratch& scratch, int i,
                                 closed_form_ik::Vector6d& out) const {
  out = scratch.engine.candidate[static_cast<std::size_t>(i)];
  if (!engine_.polish(target, out)) return false;
  for (int k = 0; k < 6; ++k) out(k) = closed_form_ik::remainder_two_pi(out(k));  // as the engine's solve() wraps
  return true;
}

IkStatus ChainClosedFormIk::solve(const Chain& chain, const Eigen::Isometry3d& target, const double* home,
                                  bool first_found, double* q, ClosedFormScratch& scratch) const {
  constexpr double kRankTolerance = 1e-6;  // [rad] a raw candidate this far outside a limit may polish into it
  engine_.candidates(target, scratch.engine);
  const int count = scratch.engine.count;
  const bool by_distance = !first_found && home != nullptr;
  // The ranking: closest_to_home, the candidates inside the limits (insertion sort, stable: ties
  // keep the engine's order); first_found, every candidate in the engine's order.
  int ranked = 0;
  closed_form_ik::Vector6d c;
  for (int i = 0; i < count; ++i) {
    scratch.failed[static_cast<std::size_t>(i)] = false;
    double key = 0.0;
    if (by_distance) {
      c = scratch.engine.candidate[static_cast<std::size_t>(i)];
      if (!ik_shift_into_limits(chain, c.data(), kRankTolerance)) continue;
      key = ik_home_distance(chain, c.data(), home);
    }
    int j = ranked++;
    for (; j > 0 && scratch.key[static_cast<std::size_t>(j - 1)] > key; --j) {
      scratch.key[static_cast<std::size_t>(j)] = scratch.key[static_cast<std::size_t>(j - 1)];
      scratch.order[static_cast<std::size_t>(j)] = scratch.order[static_cast<std::size_t>(j - 1)];
    }
    scratch.key[static_cast<std::size_t>(j)] = key;
    scratch.order[static_cast<std::size_t>(j)] = i;
  }
  for (int r = 0; r < ranked; ++r) {
    const int i = scratch.order[static_cast<std::size_t>(r)];
    if (!polished(target, scratch, i, c)) {
      scratch.failed[static_cast<std::size_t>(i)] = true;
      continue;
    }
    if (!ik_shift_into_limits(chain, c.data(), kClosedFormLimitTolerance)) continue;
    if (by_distance && r + 1 < ranked &&
        ik_home_distance(chain, c.data(), home) > scratch.key[static_cast<std::size_t>(r + 1)] + 1e-9) {
      return solve_from_all(chain, target, home, first_found, q, scratch);  // the polish moved it: rank them all
    }
    std::copy_n(c.data(), 6, q);
    return IkStatus::kConverged;
  }
  // Nothing inside the limits: is there a solution at all? (The engine's order, as its solve().)
  for (int i = 0; i < count; ++i) {
    if (scratch.failed[static_cast<std::size_t>(i)] || !polished(target, scratch, i, c)) continue;
    std::copy_n(c.data(), 6, q);
    return IkStatus::kJointLimit;
  }
  return IkStatus::kUnreachable;
}

}  // namespace hapsyn::plugins
