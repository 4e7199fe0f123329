// Haptic6RModel's block kernel (KERNELS.md sections 14.3 and 14.4): the IK, its selection and the
// classification (haptic6r_ik.hpp), the forward chain, Jacobian, inertia and gravity torque
// (haptic6r_chain.hpp) run once for the block, one sample per lane (the templates at T = Lanes).
#include "haptic6r.hpp"
#include "haptic6r_chain.hpp"
#include "haptic6r_ik.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/accel/lanes.hpp>
#include <hapsyn/accel/multiversion.hpp>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <string>

namespace hapsyn::plugins {

namespace {

constexpr Needs kBlockNeeds = kNeedPose | kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits;

// Entry (r, c) of a QuantityBlock matrix with `cols` columns, as the lanes of one sample each.
// The block's rows are 64-byte aligned arrays of kBlockLanes doubles: the layout of Lanes.
struct BlockMatrix {
  double (*entries)[kBlockLanes];
  int cols;
  [[gnu::always_inline]] Lanes& operator()(int r, int c) const { return reinterpret_cast<Lanes&>(entries[r * cols + c]); }
  [[gnu::always_inline]] Lanes& operator()(int r) const { return reinterpret_cast<Lanes&>(entries[r]); }
};

}  // namespace

bool Haptic6R::solves_blocks(Needs needs) const { return (needs & ~kBlockNeeds) == 0; }

// The block's Jacobian, inertia and gravity torque (those in `needs`) from each lane's DH-angle
// cosines and sines, with the chain kernels of haptic6r_chain.hpp at T = Lanes.
[[gnu::always_inline]] inline void Haptic6RModel::fill_block(const Lanes* cosine, const Lanes* sine, const Lanes& reachable,
                                                            Needs needs, QuantityBlock& out) const {
  if (needs & kNeedActuatorLimits) {
    out.actuator_count = 6;
    for (int j = 0; j < 6; ++j) {
      out.max_velocity[j] = max_velocity_(j);
      out.max_torque[j] = max_torque_(j);
    }
  }
  if (!(needs & (kNeedJacobian | kNeedInertia | kNeedGravity))) return;
  if (needs & kNeedJacobian) out.jacobian_rows = out.jacobian_cols = 6;
  if (needs & kNeedInertia) out.inertia_size = 6;
  if (needs & kNeedGravity) out.gravity_size = 6;
  // The quantities of lanes that are not reachable are never read (QuantityBlock's contract):
  // a block without a reachable lane (a few percent of a human-arm scene) computes none.
  if (!any_nonzero(reachable)) return;
  haptic6r_chain::ChainOf<Lanes> chain;
  haptic6r_chain::chain_from(cosine, sine, d_, a_, chain);
  if (needs & kNeedJacobian) {
    const BlockMatrix jacobian{out.jacobian, 6};
    haptic6r_chain::jacobian_from(chain, jacobian);
  }
  if (needs & (kNeedInertia | kNeedGravity)) {
    const BlockMatrix inertia{out.inertia, 6}, gravity{out.gravity, 1};
    haptic6r_chain::dynamics_from(chain, bodies_, setup_->options.gravity, (needs & kNeedInertia) ? &inertia : nullptr,
                                  (needs & kNeedGravity) ? &gravity : nullptr);
  }
}

HAPSYN_MULTIVERSION_WIDE
void Haptic6RModel::solve_block_impl(const PoseBlock& poses, Needs needs, QuantityBlock& out) const {
  const Lanes zero = Lanes::splat(0.0), one = Lanes::splat(1.0);
  // Lanes past the count, and poses solve() settles before the IK (a non-finite position, a
  // quaternion of norm <= 1e-9 or not finite), take the identity pose: finite arithmetic,
  // status unreachable below.
  static constexpr double kIdentity[7] = {0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0};
  Lanes pose[7];
  if (poses.count == kBlockLanes && poses.dimension == 7) {  // the usual block: a vector load per coordinate
    for (int c = 0; c < 7; ++c) pose[c] = Lanes::load(poses.coordinate[c]);
  } else {
    for (int c = 0; c < 7; ++c) {
      for (int lane = 0; lane < kBlockLanes; ++lane) {
        pose[c].v[lane] = lane < poses.count && c < poses.dimension ? poses.coordinate[c][lane] : kIdentity[c];
      }
    }
  }
  Lanes norm = haptic6r_ik::quaternion_norm(pose);
  const Lanes position_sum = pose[0] + pose[1] + pose[2];
  Lanes ok = where_greater(norm, Lanes::splat(1e-9), one, zero);
  ok = where_equal(norm - norm, zero, ok, zero);  // a finite norm
  ok = where_equal(position_sum - position_sum, zero, ok, zero);  // a finite position
  for (int lane = poses.count; lane < kBlockLanes; ++lane) ok.v[lane] = 0.0;
  for (int c = 0; c < 7; ++c) pose[c] = where_equal(ok, zero, Lanes::splat(kIdentity[c]), pose[c]);
  norm = where_equal(ok, zero, one, norm);
  const haptic6r_ik::IkModel& m = ik_;
  // The branches' angles (13 atan2, 9 square roots and the rotations), then the assembly,
  // selection and classification, all of it for the eight lanes at once (haptic6r_ik.hpp).
  haptic6r_ik::Target<Lanes> target;
  haptic6r_ik::target_of(pose, norm, target);
  haptic6r_ik::Branches<Lanes> branches;
  haptic6r_ik::branch_angles(target, m, branches);
  haptic6r_ik::LaneOutcomes outcome;
  haptic6r_ik::configure_lanes(branches, m, ok, outcome);
  std::memcpy(out.status, outcome.status, sizeof out.status);
  const Lanes(&cosine)[6] = outcome.c;
  const Lanes(&sine)[6] = outcome.s;
  fill_block(cosine, sine, outcome.reachable, needs, out);
}

HAPSYN_MULTIVERSION_WIDE
void Haptic6RModel::quantities_block_impl(const Vector6d* q, int count, Needs needs, QuantityBlock& out) const {
  Lanes theta[6], cosine[6], sine[6];
  for (int lane = 0; lane < kBlockLanes; ++lane) {
    const Vector6d& angles = q[std::min(lane, count - 1)];
    for (std::size_t i = 0; i < 6; ++i) theta[i].v[lane] = angles(static_cast<Eigen::Index>(i)) + offset_[i];
    out.status[lane] = static_cast<std::int32_t>(lane < count ? SampleStatus::kReachable : SampleStatus::kUnreachable);
  }
  for (std::size_t i = 0; i < 6; ++i) sin_cos(theta[i], sine[i], cosine[i]);  // as quantities() does, per lane
  fill_block(cosine, sine, Lanes::splat(1.0), needs, out);  // every lane holds a configuration (count >= 1)
}

void Haptic6RModel::quantities_block(const Vector6d* q, int count, Needs needs, QuantityBlock& out) const {
  if (count < 1 || count > kBlockLanes) {
    throw Error("haptic6r", "quantities_block: count = " + std::to_string(count) + ": must be 1.." + std::to_string(kBlockLanes));
  }
  quantities_block_impl(q, count, needs, out);
}

void Haptic6RModel::solve_block(const PoseBlock& poses, Needs needs, MechanismScratch&, QuantityBlock& out) const {
  solve_block_impl(poses, needs, out);
}

}  // namespace hapsyn::plugins
