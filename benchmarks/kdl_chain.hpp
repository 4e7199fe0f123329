#pragma once
// KDL's view of a serial_chain Chain, for the benchmarks that measure our IK against KDL's.
#include <chain.hpp>

#include <Eigen/Geometry>
#include <kdl/chain.hpp>

namespace hapsyn::bench {

inline KDL::Frame to_kdl(const Eigen::Isometry3d& t) {
  const Eigen::Matrix3d& r = t.linear();
  return KDL::Frame(KDL::Rotation(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)),
                    KDL::Vector(t.translation().x(), t.translation().y(), t.translation().z()));
}

// KDL's chain of a Chain: a fixed segment O_1, then per joint a segment rotating (sliding) about
// (along) its axis whose tip is the next joint's origin (T_tip for the last).
inline KDL::Chain to_kdl(const plugins::Chain& chain) {
  KDL::Chain k;
  k.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), to_kdl(chain.joints[0].origin)));
  for (int i = 0; i < chain.dof(); ++i) {
    const plugins::ChainJoint& j = chain.joints[static_cast<std::size_t>(i)];
    const Eigen::Isometry3d next = i + 1 < chain.dof() ? chain.joints[static_cast<std::size_t>(i) + 1].origin : chain.tip;
    const KDL::Vector axis(j.axis.x(), j.axis.y(), j.axis.z());
    const auto type = j.type == plugins::ChainJointType::kRevolute ? KDL::Joint::RotAxis : KDL::Joint::TransAxis;
    k.addSegment(KDL::Segment(KDL::Joint(j.name, KDL::Vector::Zero(), axis, type), to_kdl(next)));
  }
  return k;
}

}  // namespace hapsyn::bench
