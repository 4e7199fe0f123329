// ChainClosedFormIk (chain_closed_form_ik.hpp): the closed_form_ik engine with the chain's joint
// limits and the selection rules.
#include "chain_closed_form_ik.hpp"
#include "number_text.hpp"

#include "shared/closed_form_ik/angles.hpp"

#include <hapsyn/error.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace hapsyn::plugins {

std::string closed_form_applicability(const Chain& chain, const IkTask& task) {
  if (chain.dof() != 6 && chain.dof() != 7) {
    return std::to_string(chain.dof()) + " moving joints (the closed form is for 6 or 7 revolute joints)";
  }
  for (const ChainJoint& j : chain.joints) {
    if (j.type != ChainJointType::kRevolute) return "joint " + j.name + " is prismatic (the closed form is for 6 or 7 revolute joints)";
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

ChainClosedFormIk::ChainClosedFormIk(const Chain& chain, const RedundantJointSettings& redundancy) {
  if (chain.dof() != 7) {
    engines_.emplace_back(poe_chain_of(chain));
    return;
  }
  if (redundancy.steps < 2 || redundancy.steps > kMaxRedundantSteps) {
    throw Error("closed_form_ik", "redundant joint steps = " + std::to_string(redundancy.steps) + ": must be in 2.." +
                                      std::to_string(kMaxRedundantSteps));
  }
  redundant_ = redundancy.joint >= 0 ? redundancy.joint : choose_redundant_joint(chain);
  if (redundant_ < 0 || redundant_ >= 7) {
    std::string why;
    for (int k = 0; k < 7; ++k) why += (why.empty() ? "" : "; ") + redundant_joint_unsuitability(chain, k);
    throw Error("closed_form_ik", "7R: no joint whose locking leaves a 6R with a closed form (" + why + ")");
  }
  const std::string why_not = redundant_joint_unsuitability(chain, redundant_);
  if (!why_not.empty()) throw Error("closed_form_ik", "7R: " + why_not);
  grid_ = redundant_grid(chain.joints[static_cast<std::size_t>(redundant_)], redundancy.steps);
  engines_.reserve(grid_.size());
  const std::string joint = "7R: locking joint " + std::to_string(redundant_ + 1) + " (" +
                            chain.joints[static_cast<std::size_t>(redundant_)].name + ") at its grid value ";
  for (const double value : grid_) {
    const closed_form_ik::PoeChain locked = locked_poe_chain(chain, redundant_, value);
    try {
      engines_.emplace_back(locked);
    } catch (const Error& e) {
      throw Error("closed_form_ik", joint + number_text(value) + " rad: " + std::string(e.what()).substr(e.component().size() + 2));
    }
    if (!generic_full_rank(locked)) {
      throw Error("closed_form_ik", joint + number_text(value) + " rad leaves a 6R whose Jacobian is rank-deficient everywhere (a "
                                    "self-motion remains; " + engines_.back().geometry().describe() + ")");
    }
  }
}

const closed_form_ik::IkSolutions& ChainClosedFormIk::all_solutions(const Eigen::Isometry3d& target,
                                                                   ClosedFormScratch& scratch) const {
  if (redundant_ >= 0) throw Error("closed_form_ik", "all_solutions() is for 6R chains (a 7R chain's: every_solution())");
  engine().solve(target, scratch.engine, scratch.solutions);
  return scratch.solutions;
}

template <class F>
void ChainClosedFormIk::for_each_redundant(const Eigen::Isometry3d& target, ClosedFormScratch& scratch, int g, F&& f) const {
  std::array<double, 7> q{};
  const std::size_t at = static_cast<std::size_t>(g);
  engines_[at].solve(target, scratch.engine, scratch.solutions);
  for (int s = 0; s < scratch.solutions.count; ++s) {
    const closed_form_ik::Vector6d& six = scratch.solutions.q[static_cast<std::size_t>(s)];
    for (int i = 0, j = 0; i < 7; ++i) q[static_cast<std::size_t>(i)] = i == redundant_ ? grid_[at] : six(j++);
    f(q.data());
  }
}

std::vector<JointVector> ChainClosedFormIk::every_solution(const Eigen::Isometry3d& target, ClosedFormScratch& scratch) const {
  std::vector<JointVector> out;
  if (redundant_ < 0) {
    const closed_form_ik::IkSolutions& all = all_solutions(target, scratch);
    for (int s = 0; s < all.count; ++s) out.emplace_back(all.q[static_cast<std::size_t>(s)]);
    return out;
  }
  for (int g = 0; g < static_cast<int>(grid_.size()); ++g) {
    for_each_redundant(target, scratch, g, [&out](const double* q) { out.emplace_back(Eigen::Map<const Eigen::Matrix<double, 7, 1>>(q)); });
  }
  return out;
}

IkStatus ChainClosedFormIk::solve_redundant(const Chain& chain, const Eigen::Isometry3d& target, const double* home,
                                            bool first_found, double* q, ClosedFormScratch& scratch) const {
  const bool by_distance = !first_found && home != nullptr;
  const int steps = static_cast<int>(grid_.size());
  // The visiting order: closest_to_home, by the grid value's own share of the distance to home,
  // (q_k - home_k)^2, a lower bound of every solution's distance on that value (ties: grid
  // order); otherwise the grid order.
  for (int g = 0; g < steps; ++g) {
    scratch.grid_order[static_cast<std::size_t>(g)] = g;
    scratch.grid_bound[static_cast<std::size_t>(g)] = by_distance ? std::pow(closed_form_ik::remainder_two_pi(grid_[static_cast<std::size_t>(g)] - home[redundant_]), 2) : 0.0;
  }
  if (by_distance) {
    std::sort(scratch.grid_order.begin(), scratch.grid_order.begin() + steps, [&scratch](int a, int b) {
      const double ka = scratch.grid_bound[static_cast<std::size_t>(a)], kb = scratch.grid_bound[static_cast<std::size_t>(b)];
      return ka < kb || (ka == kb && a < b);
    });
  }
  double closest = std::numeric_limits<double>::infinity();
  bool any = false, found = false;
  std::array<double, 7> c{};
  for (int r = 0; r < steps; ++r) {
    const int g = scratch.grid_order[static_cast<std::size_t>(r)];
    // No solution on this grid value (nor on the later ones) can beat the pick.
    if (found && scratch.grid_bound[static_cast<std::size_t>(g)] >= closest) break;
    for_each_redundant(target, scratch, g, [&](const double* solution) {
      if (!any) std::copy_n(solution, 7, scratch.first.begin());
      any = true;
      if (found && !by_distance) return;
      std::copy_n(solution, 7, c.begin());
      if (!ik_shift_into_limits(chain, c.data(), kClosedFormLimitTolerance)) return;
      const double distance = by_distance ? ik_home_distance(chain, c.data(), home) : 0.0;
      if (distance < closest) {  // strictly: ties keep the earlier solution
        closest = distance;
        std::copy_n(c.data(), 7, q);
        found = true;
      }
    });
    if (found && !by_distance) break;  // first_found: the first in-limit one ends the search
  }
  if (found) return IkStatus::kConverged;
  if (!any) return IkStatus::kUnreachable;
  std::copy_n(scratch.first.data(), 7, q);
  return IkStatus::kJointLimit;
}

IkStatus ChainClosedFormIk::solve_from_all(const Chain& chain, const Eigen::Isometry3d& target, const double* home,
                                           bool first_found, double* q, ClosedFormScratch& scratch) const {
  if (redundant_ >= 0) return solve_redundant(chain, target, home, first_found, q, scratch);
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
  if (!engine().polish(target, out)) return false;
  for (int k = 0; k < 6; ++k) out(k) = closed_form_ik::remainder_two_pi(out(k));  // as the engine's solve() wraps
  return true;
}

IkStatus ChainClosedFormIk::solve(const Chain& chain, const Eigen::Isometry3d& target, const double* home,
                                  bool first_found, double* q, ClosedFormScratch& scratch) const {
  if (redundant_ >= 0) return solve_redundant(chain, target, home, first_found, q, scratch);
  constexpr double kRankTolerance = 1e-6;  // [rad] a raw candidate this far outside a limit may polish into it
  engine().candidates(target, scratch.engine);
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
