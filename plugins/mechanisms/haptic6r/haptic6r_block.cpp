// Haptic6RModel's block kernel (KERNELS.md sections 14.3 and 14.4): the IK, its selection and the
// classification (haptic6r_ik.hpp), the forward chain, Jacobian, inertia and gravity torque
// (haptic6r_chain.hpp) run once for the block, one sample per lane (the templates at T = a lanes
// type), compiled once per instruction set (hapsyn/accel/vector_dispatch.hpp).
#include "haptic6r.hpp"
#include "haptic6r_chain.hpp"
#include "haptic6r_ik.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/accel/lanes.hpp>
#include <hapsyn/accel/vector_dispatch.hpp>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <string>

namespace hapsyn::plugins {

namespace {

constexpr Needs kBlockNeeds = kNeedPose | kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits;

// Entry (r, c) of a QuantityBlock matrix with `cols` columns, as the lanes of one sample each.
// The block's rows are 64-byte aligned arrays of kBlockLanes doubles: the layout of every lanes type.
template <class L>
struct BlockMatrix {
  double (*entries)[kBlockLanes];
  int cols;
  [[gnu::always_inline]] L& operator()(int r, int c) const { return reinterpret_cast<L&>(entries[r * cols + c]); }
  [[gnu::always_inline]] L& operator()(int r) const { return reinterpret_cast<L&>(entries[r]); }
};

}  // namespace

bool Haptic6R::solves_blocks(Needs needs) const { return (needs & ~kBlockNeeds) == 0; }

// The block's Jacobian, inertia and gravity torque (those in `needs`) from each lane's DH-angle
// cosines and sines, with the chain kernels of haptic6r_chain.hpp at T = L.
template <class L>
[[gnu::always_inline]] inline void Haptic6RModel::fill_block(const L* cosine, const L* sine, const L& reachable, Needs needs,
                                                            QuantityBlock& out) const {
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
  haptic6r_chain::ChainOf<L> chain;
  haptic6r_chain::chain_from(cosine, sine, d_, a_, chain);
  if (needs & kNeedJacobian) {
    const BlockMatrix<L> jacobian{out.jacobian, 6};
    haptic6r_chain::jacobian_from(chain, jacobian);
  }
  if (needs & (kNeedInertia | kNeedGravity)) {
    const BlockMatrix<L> inertia{out.inertia, 6}, gravity{out.gravity, 1};
    haptic6r_chain::dynamics_from(chain, bodies_, setup_->options.gravity, (needs & kNeedInertia) ? &inertia : nullptr,
                                  (needs & kNeedGravity) ? &gravity : nullptr);
  }
}

template <class L>
[[gnu::always_inline]] inline void Haptic6RModel::solve_block_lanes(const PoseBlock& poses, Needs needs,
                                                                   QuantityBlock& out) const {
  const L zero = L::splat(0.0), one = L::splat(1.0);
  // L past the count, and poses solve() settles before the IK (a non-finite position, a
  // quaternion of norm <= 1e-9 or not finite), take the identity pose: finite arithmetic,
  // status unreachable below.
  static constexpr double kIdentity[7] = {0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0};
  L pose[7];
  if (poses.count == kBlockLanes && poses.dimension == 7) {  // the usual block: a vector load per coordinate
    for (int c = 0; c < 7; ++c) pose[c] = L::load(poses.coordinate[c]);
  } else {
    for (int c = 0; c < 7; ++c) {
      for (int lane = 0; lane < kBlockLanes; ++lane) {
        pose[c].set(lane, lane < poses.count && c < poses.dimension ? poses.coordinate[c][lane] : kIdentity[c]);
      }
    }
  }
  L norm = haptic6r_ik::quaternion_norm(pose);
  const L position_sum = pose[0] + pose[1] + pose[2];
  L ok = where_greater(norm, L::splat(1e-9), one, zero);
  ok = where_equal(norm - norm, zero, ok, zero);  // a finite norm
  ok = where_equal(position_sum - position_sum, zero, ok, zero);  // a finite position
  for (int lane = poses.count; lane < kBlockLanes; ++lane) ok.set(lane, 0.0);
  for (int c = 0; c < 7; ++c) pose[c] = where_equal(ok, zero, L::splat(kIdentity[c]), pose[c]);
  norm = where_equal(ok, zero, one, norm);
  const haptic6r_ik::IkModel& m = ik_;
  // The branches' angles (13 atan2, 9 square roots and the rotations), then the assembly,
  // selection and classification, all of it for the eight lanes at once (haptic6r_ik.hpp).
  haptic6r_ik::Target<L> target;
  haptic6r_ik::target_of(pose, norm, target);
  haptic6r_ik::Branches<L> branches;
  haptic6r_ik::branch_angles(target, m, branches);
  haptic6r_ik::LaneOutcomes<L> outcome;
  haptic6r_ik::configure_lanes(branches, m, ok, outcome);
  std::memcpy(out.status, outcome.status, sizeof out.status);
  const L(&cosine)[6] = outcome.c;
  const L(&sine)[6] = outcome.s;
  fill_block(cosine, sine, outcome.reachable, needs, out);
}

template <class L>
[[gnu::always_inline]] inline void Haptic6RModel::quantities_block_lanes(const Vector6d* q, int count, Needs needs,
                                                                        QuantityBlock& out) const {
  L theta[6], cosine[6], sine[6];
  for (int lane = 0; lane < kBlockLanes; ++lane) {
    const Vector6d& angles = q[std::min(lane, count - 1)];
    for (std::size_t i = 0; i < 6; ++i) theta[i].set(lane, angles(static_cast<Eigen::Index>(i)) + offset_[i]);
    out.status[lane] = static_cast<std::int32_t>(lane < count ? SampleStatus::kReachable : SampleStatus::kUnreachable);
  }
  for (std::size_t i = 0; i < 6; ++i) sin_cos(theta[i], sine[i], cosine[i]);  // as quantities() does, per lane
  fill_block(cosine, sine, L::splat(1.0), needs, out);  // every lane holds a configuration (count >= 1)
}

void Haptic6RModel::quantities_block(const Vector6d* q, int count, Needs needs, QuantityBlock& out) const {
  if (count < 1 || count > kBlockLanes) {
    throw Error("haptic6r", "quantities_block: count = " + std::to_string(count) + ": must be 1.." + std::to_string(kBlockLanes));
  }
  with_vector_lanes([&](auto tag) HAPSYN_KERNEL_BODY {
    quantities_block_lanes<typename decltype(tag)::type>(q, count, needs, out);
  });
}

void Haptic6RModel::solve_block(const PoseBlock& poses, Needs needs, MechanismScratch&, QuantityBlock& out) const {
  with_vector_lanes([&](auto tag) HAPSYN_KERNEL_BODY {
    solve_block_lanes<typename decltype(tag)::type>(poses, needs, out);
  });
}

}  // namespace hapsyn::plugins
