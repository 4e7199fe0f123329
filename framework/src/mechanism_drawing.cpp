// The default drawing of a mechanism (MechanismModel::segments): the end effector's point, seen
// from the scene frame's origin.
#include <hapsyn/mechanism.hpp>

#include <algorithm>

namespace hapsyn {

std::vector<Segment> MechanismModel::segments(const SampleSet& scene, int sample, MechanismScratch& scratch) const {
  SampleQuantities q;
  q.scene = &scene;
  q.sample = sample;
  const double* pose = scene.pose(sample);
  solve(pose, kNeedPose, scratch, q);
  if (q.status == SampleStatus::kUnreachable) return {};
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();
  for (int c = 0; c < std::min(3, scene.dimension()); ++c) tip[c] = pose[c];
  return {Segment{"end effector", {Eigen::Vector3d::Zero(), tip}}};
}

}  // namespace hapsyn
