// The default drawing of a mechanism (MechanismModel::segments): a line from the scene frame's
// origin to the end effector, none for an unreachable sample.
#include <hapsyn/mechanism.hpp>

#include <gtest/gtest.h>

namespace {

using hapsyn::SampleQuantities;
using hapsyn::SampleStatus;

// Reaches every sample within 1 m of the origin; records the scene and sample solve() was given.
class DiscModel final : public hapsyn::MechanismModel {
 public:
  mutable const hapsyn::SampleSet* seen_scene = nullptr;
  mutable int seen_sample = -1;
  void solve(const double* pose, hapsyn::Needs, hapsyn::MechanismScratch&, SampleQuantities& out) const override {
    seen_scene = out.scene;
    seen_sample = out.sample;
    out.status = pose[0] * pose[0] + pose[1] * pose[1] <= 1.0 ? SampleStatus::kReachable : SampleStatus::kUnreachable;
  }
};

}  // namespace

TEST(MechanismDrawing, DefaultDrawsTheOriginToTheEndEffector) {
  hapsyn::SampleSet scene;
  scene.poses.resize(2, 2);
  scene.poses << 0.3, -0.4, 2.0, 0.0;
  const DiscModel model;
  hapsyn::MechanismScratch scratch;
  const std::vector<hapsyn::Segment> drawn = model.segments(scene, 0, scratch);
  ASSERT_EQ(drawn.size(), 1u);
  EXPECT_EQ(drawn[0].name, "end effector");
  ASSERT_EQ(drawn[0].points.size(), 2u);
  EXPECT_EQ(drawn[0].points[0], Eigen::Vector3d::Zero());
  EXPECT_EQ(drawn[0].points[1], Eigen::Vector3d(0.3, -0.4, 0.0));  // a missing z is 0
  EXPECT_EQ(model.seen_scene, &scene);  // solve() is told the scene and the sample
  EXPECT_EQ(model.seen_sample, 0);
}

TEST(MechanismDrawing, DefaultDrawsNothingForAnUnreachableSample) {
  hapsyn::SampleSet scene;
  scene.poses.resize(2, 3);
  scene.poses << 0.1, 0.2, 0.3, 2.0, 0.0, 0.0;
  const DiscModel model;
  hapsyn::MechanismScratch scratch;
  EXPECT_TRUE(model.segments(scene, 1, scratch).empty());
  const std::vector<hapsyn::Segment> drawn = model.segments(scene, 0, scratch);
  ASSERT_EQ(drawn.size(), 1u);
  EXPECT_EQ(drawn[0].points[1], Eigen::Vector3d(0.1, 0.2, 0.3));
}
