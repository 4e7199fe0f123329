// The redundant joint of a 7R chain for the closed form (chain_closed_form_ik.hpp): the 6R left
// when it is locked, its grid, whether locking it leaves a closed form, the automatic choice.
#include "chain_closed_form_ik.hpp"
#include "number_text.hpp"

#include <Eigen/SVD>
#include <cmath>

namespace hapsyn::plugins {

bool generic_full_rank(const closed_form_ik::PoeChain& c) {
  constexpr double kConfigurations[2][6] = {{0.4, 0.9, -0.7, 1.1, -0.5, 0.8}, {-1.3, 0.35, 1.7, -0.45, 1.2, -2.1}};
  for (const auto& q : kConfigurations) {
    Eigen::Isometry3d pose;
    Eigen::Matrix<double, 6, closed_form_ik::kMaxJoints> jacobian;
    c.forward_jacobian(q, pose, jacobian);
    const Eigen::JacobiSVD<Eigen::Matrix<double, 6, 6>> svd(jacobian.leftCols<6>());
    if (svd.singularValues()(5) > 1e-6 * svd.singularValues()(0)) return true;
  }
  return false;
}


closed_form_ik::PoeChain locked_poe_chain(const Chain& chain, int k, double value) {
  std::vector<Eigen::Isometry3d> origins;
  std::vector<Eigen::Vector3d> axes;
  Eigen::Isometry3d carried = Eigen::Isometry3d::Identity();  // O_k Rot(a_k, value), waiting for the next origin
  for (int i = 0; i < chain.dof(); ++i) {
    const ChainJoint& j = chain.joints[static_cast<std::size_t>(i)];
    if (i == k) {
      carried = j.origin * Eigen::AngleAxisd(value, j.axis.normalized());
      continue;
    }
    origins.push_back(carried * j.origin);
    axes.push_back(j.axis);
    carried = Eigen::Isometry3d::Identity();
  }
  return closed_form_ik::PoeChain::from_local_frames(origins, axes, carried * chain.tip);
}

std::vector<double> redundant_grid(const ChainJoint& joint, int steps) {
  std::vector<double> grid(static_cast<std::size_t>(steps));
  const bool full_turn = !std::isfinite(joint.lower) || !std::isfinite(joint.upper) || joint.upper - joint.lower >= 2.0 * M_PI;
  const double lower = full_turn ? -M_PI : joint.lower;
  const double step = full_turn ? 2.0 * M_PI / steps : (joint.upper - joint.lower) / (steps - 1);
  for (int i = 0; i < steps; ++i) grid[static_cast<std::size_t>(i)] = lower + step * i;
  if (!full_turn) grid.back() = joint.upper;  // exactly the limit, not lower + (steps - 1) step
  return grid;
}

std::string redundant_joint_unsuitability(const Chain& chain, int k, closed_form_ik::ChainGeometry* geometry) {
  const std::string joint = "locking joint " + std::to_string(k + 1) + " (" + chain.joints[static_cast<std::size_t>(k)].name + ")";
  for (const double value : {0.0, 1.0, -2.0, M_SQRT2}) {
    const closed_form_ik::PoeChain locked = locked_poe_chain(chain, k, value);
    const closed_form_ik::ChainGeometry g = closed_form_ik::classify(locked);
    if (value == 0.0 && geometry != nullptr) *geometry = g;
    if (g.family == closed_form_ik::IkFamily::kUnsupported) {
      return joint + " at " + number_text(value) + " rad leaves a 6R without a closed-form family (" + g.describe() + ")";
    }
    if (!generic_full_rank(locked)) {
      return joint + " at " + number_text(value) + " rad leaves a 6R whose Jacobian is rank-deficient everywhere (a self-motion remains; " +
             g.describe() + ")";
    }
  }
  return "";
}

int choose_redundant_joint(const Chain& chain) {
  if (chain.dof() != 7) return -1;
  constexpr int kOrder[7] = {3, 2, 4, 1, 5, 0, 6};  // 0-based: the middle outward, the shoulder side first
  for (const bool search_allowed : {false, true}) {
    for (const int k : kOrder) {
      closed_form_ik::ChainGeometry g;
      if (!redundant_joint_unsuitability(chain, k, &g).empty()) continue;
      if (search_allowed || g.family != closed_form_ik::IkFamily::kSearch1d) return k;
    }
  }
  return -1;
}

}  // namespace hapsyn::plugins
