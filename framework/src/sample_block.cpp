// The default block path of a mechanism: model.solve() per lane. The evaluator takes the block
// path only when MechanismAcceleration::solves_blocks() says a real kernel exists; this default serves
// callers that use solve_block() directly (tests, plugins that forward to it).
#include <hapsyn/accel/mechanism_acceleration.hpp>

#include <cassert>

namespace hapsyn {
namespace {

template <typename Matrix>
void store_lane(const Matrix& m, int lane, double (*block)[kBlockLanes], int& rows, int& cols) {
  rows = static_cast<int>(m.rows());
  cols = static_cast<int>(m.cols());
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) block[r * cols + c][lane] = m(r, c);
  }
}

}  // namespace

void MechanismAcceleration::solve_block(const MechanismModel& model, const PoseBlock& poses, Needs needs,
                                        MechanismScratch& scratch, QuantityBlock& out) const {
  SampleQuantities q;
  double pose[kBlockMaxCoordinates];
  for (int lane = 0; lane < poses.count; ++lane) {
    for (int c = 0; c < poses.dimension; ++c) pose[c] = poses.coordinate[c][lane];
    model.solve(pose, needs, scratch, q);
    out.status[lane] = static_cast<std::int32_t>(q.status);
    if (q.status != SampleStatus::kReachable) continue;
    int square = 0;
    if (needs & kNeedJacobian) store_lane(q.jacobian, lane, out.jacobian, out.jacobian_rows, out.jacobian_cols);
    if (needs & kNeedInertia) store_lane(q.inertia, lane, out.inertia, out.inertia_size, square);
    if (needs & kNeedEffectiveMass) {
      store_lane(q.effective_mass, lane, out.effective_mass, out.effective_mass_size, square);
    }
    // The block holds at most kMaxTask joints of gravity and limits: a larger arm cannot use it.
    if (needs & kNeedGravity) {
      assert(q.gravity.size() <= kMaxTask);
      store_lane(q.gravity, lane, out.gravity, out.gravity_size, square);
    }
    if (needs & kNeedActuatorLimits) {
      assert(q.max_velocity.size() <= kMaxTask && q.max_torque.size() == q.max_velocity.size());
      out.actuator_count = static_cast<int>(q.max_velocity.size());
      for (int j = 0; j < out.actuator_count; ++j) {
        out.max_velocity[j] = q.max_velocity(j);
        out.max_torque[j] = q.max_torque(j);
      }
    }
  }
  for (int lane = poses.count; lane < kBlockLanes; ++lane) out.status[lane] = static_cast<std::int32_t>(SampleStatus::kUnreachable);
}

}  // namespace hapsyn
