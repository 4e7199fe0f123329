// ClosedFormIk6R (six_r_ik.hpp): family dispatch, Newton polish, limits and duplicates.
#include "shared/closed_form_ik/six_r_ik.hpp"

#include "shared/closed_form_ik/angles.hpp"
#include "shared/closed_form_ik/families.hpp"

#include <hapsyn/error.hpp>

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace hapsyn::plugins::closed_form_ik {

ClosedFormIk6R::ClosedFormIk6R(const PoeChain& chain, const IkOptions& options)
    : chain_(chain), options_(options) {
  if (chain.n != 6) {
    throw Error("closed_form_ik", "chain has " + std::to_string(chain.n) + " joints: the closed-form solvers are for 6R");
  }
  if (options.search_samples < 8) {
    throw Error("closed_form_ik", "search_samples = " + std::to_string(options.search_samples) + ": must be >= 8");
  }
  if (options.newton_steps < 0 || !(options.accept_tolerance > 0.0)) {
    throw Error("closed_form_ik", "newton_steps = " + std::to_string(options.newton_steps) + ", accept_tolerance = " +
                                      std::to_string(options.accept_tolerance) + ": must be >= 0 and > 0");
  }
  if (!(options.polish_radius >= options.accept_tolerance)) {
    std::ostringstream message;
    message << "polish_radius = " << options.polish_radius << ": must be >= accept_tolerance ("
            << options.accept_tolerance << ")";
    throw Error("closed_form_ik", message.str());
  }
  if (options.use_limits) {
    for (int i = 0; i < 6; ++i) {
      const std::size_t s = static_cast<std::size_t>(i);
      if (!(options.lower[s] <= options.upper[s])) {
        throw Error("closed_form_ik", "joint " + std::to_string(i + 1) + " limits [" + std::to_string(options.lower[s]) +
                                          ", " + std::to_string(options.upper[s]) + "]: need lower <= upper");
      }
    }
  }
  geometry_ = classify(chain, options.geometry_tolerance);
  if (geometry_.family == IkFamily::kUnsupported) {
    throw Error("closed_form_ik", "no closed-form decomposition for this chain (" + geometry_.describe() + ")");
  }
  work_ = geometry_.reversed ? chain.reversed() : chain;
  // The 1-D search's candidates at folds are only as close as its last interval halving: Newton
  // brings them in from much farther than the exact families' answers.
  polish_radius_ = geometry_.family == IkFamily::kSearch1d ? std::numeric_limits<double>::infinity() : options.polish_radius;
  const ChainGeometry work_geometry = classify(work_, options.geometry_tolerance);
  point_ = geometry_.family == IkFamily::kSphericalWrist ? work_geometry.wrist_point : work_geometry.point[4];
}

void ClosedFormIk6R::candidates(const Eigen::Isometry3d& target, IkScratch& scratch) const {
  scratch.count = 0;
  const Eigen::Isometry3d work_target = geometry_.reversed ? target.inverse() : target;
  switch (geometry_.family) {
    case IkFamily::kSphericalWrist:
      detail::spherical_wrist_candidates(work_, point_, work_target, scratch);
      break;
    case IkFamily::kThreeParallel:
      detail::three_parallel_candidates(work_, work_target, scratch);
      break;
    case IkFamily::kScaraPair:
      detail::scara_pair_candidates(work_, work_target, scratch);
      break;
    case IkFamily::kSearch1d:
      detail::search_1d_candidates(work_, point_, work_target, options_.search_samples, scratch);
      break;
    case IkFamily::kUnsupported:
      break;
  }
  if (geometry_.reversed) {
    for (int i = 0; i < scratch.count; ++i) {
      scratch.candidate[static_cast<std::size_t>(i)] = scratch.candidate[static_cast<std::size_t>(i)].reverse().eval();
    }
  }
}

namespace {

// The pose error of `pose` against `target`: the rotation vector of R_target R^T and the
// position difference; returns the larger of their norms [rad or m].
double pose_error(const Eigen::Isometry3d& target, const Eigen::Isometry3d& pose, Vector6d& error) {
  const Eigen::AngleAxisd rotation(target.linear() * pose.linear().transpose());
  error.head<3>() = rotation.angle() * rotation.axis();
  error.tail<3>() = target.translation() - pose.translation();
  return std::max(error.head<3>().norm(), error.tail<3>().norm());
}

}  // namespace

// Newton steps on the pose error, then the test against accept_tolerance. The first error comes
// from the forward kinematics alone: the subproblems' exact candidates already reproduce the
// pose to about 1e-14, so most need no step (and no Jacobian). Their least-squares answers for
// branches that do not reach the pose miss it by far more than polish_radius and are dropped
// unpolished (Newton from there ran all its steps, often diverging, for nothing); the 1-D search
// family, whose candidates are approximate, polishes every one.
bool ClosedFormIk6R::polish(const Eigen::Isometry3d& target, Vector6d& q) const {
  Eigen::Isometry3d pose = chain_.forward(q.data());
  Eigen::Matrix<double, 6, kMaxJoints> jacobian;
  Vector6d error;
  for (int step = 0;; ++step) {
    const double worst = pose_error(target, pose, error);
    if (step >= options_.newton_steps || worst <= 1e-4 * options_.accept_tolerance) {
      return worst <= options_.accept_tolerance;
    }
    if (step == 0 && !(worst <= polish_radius_)) return false;
    chain_.forward_jacobian(q.data(), pose, jacobian);
    const Eigen::Matrix<double, 6, 6> j6 = jacobian.leftCols<6>();
    q += j6.partialPivLu().solve(error);
    pose = chain_.forward(q.data());
  }
}

bool ClosedFormIk6R::wrap_into_limits(Vector6d& q) const {
  constexpr double kTwoPi = 2 * M_PI;
  for (int i = 0; i < 6; ++i) {
    q(i) = remainder_two_pi(q(i));
    if (!options_.use_limits) continue;
    const double lo = options_.lower[static_cast<std::size_t>(i)], hi = options_.upper[static_cast<std::size_t>(i)];
    const double shifted = q(i) + kTwoPi * std::ceil((lo - q(i)) / kTwoPi - 1e-12);
    if (shifted > hi + 1e-12) return false;
    q(i) = std::max(shifted, lo);
  }
  return true;
}

void ClosedFormIk6R::solve(const Eigen::Isometry3d& target, IkScratch& scratch, IkSolutions& out) const {
  candidates(target, scratch);
  out.count = 0;
  out.candidates = scratch.count;
  for (int i = 0; i < scratch.count && out.count < kMaxSolutions; ++i) {
    Vector6d q = scratch.candidate[static_cast<std::size_t>(i)];
    if (!polish(target, q) || !wrap_into_limits(q)) continue;
    bool duplicate = false;
    for (int j = 0; j < out.count && !duplicate; ++j) {
      const Vector6d& other = out.q[static_cast<std::size_t>(j)];
      double worst = 0.0;
      for (int k = 0; k < 6; ++k) worst = std::max(worst, std::abs(remainder_two_pi(q(k) - other(k))));
      duplicate = worst <= 1e-9;
    }
    if (!duplicate) out.q[static_cast<std::size_t>(out.count++)] = q;
  }
}

}  // namespace hapsyn::plugins::closed_form_ik
