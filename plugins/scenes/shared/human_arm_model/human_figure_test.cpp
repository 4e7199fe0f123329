#include "shared/human_arm_model/human_figure.hpp"

#include "shared/human_arm_model/human_arm_model_testing.hpp"

#include <gtest/gtest.h>

#include <random>

namespace hapsyn::plugins {
namespace {

using human_arm_testing::arm;
using human_arm_testing::arm_document;

// The segment lengths as the arm file states them, read from the JSON (not through the model).
double segment(const std::string& name) { return arm_document()["segments"][name].get<double>(); }

Vector7d random_in_limits(std::mt19937& rng) {
  Vector7d q;
  for (int j = 0; j < 7; ++j) {
    std::uniform_real_distribution<double> u(arm().data().lower(j), arm().data().upper(j));
    q(j) = u(rng);
  }
  return q;
}

TEST(HumanFigure, ArmPointsAreSpacedByTheArmFilesSegments) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 500; ++trial) {
    const Vector7d q = random_in_limits(rng);
    const ArmPoints p = arm_points(arm(), q);
    EXPECT_LT(p[0].norm(), 1e-15);
    EXPECT_NEAR((p[1] - p[0]).norm(), segment("l_ua"), 1e-12);
    EXPECT_NEAR((p[2] - p[1]).norm(), segment("l_la"), 1e-12);
    EXPECT_NEAR((p[3] - p[2]).norm(), segment("l_p"), 1e-12);
    // The palm is the forward kinematics' (a second formulation: frame by frame against the
    // product of the transforms).
    EXPECT_LT((p[3] - arm().forward(q).translation()).norm(), 1e-12);
  }
}

TEST(HumanFigure, TheArmAtRestHangsDownFromTheShoulder) {
  // At q = 0 the arm hangs along -y_S, y_S being up: each point straight below the last.
  const ArmPoints p = arm_points(arm(), Vector7d::Zero());
  for (int k = 1; k < 3; ++k) {
    EXPECT_LT(p[k].y(), p[k - 1].y() - 0.2);
    EXPECT_NEAR(p[k].x(), 0.0, 1e-12);
    EXPECT_NEAR(p[k].z(), 0.0, 1e-12);
  }
  EXPECT_NEAR(p[2].y(), -(segment("l_ua") + segment("l_la")), 1e-12);
  EXPECT_LT(p[3].y(), p[2].y());
}

TEST(HumanFigure, TheBodyStandsUprightOnTheMedialSideOfTheArm) {
  const HumanBodyProxy body = body_proxy(arm());
  // Upper arm 0.186 of body height.
  EXPECT_NEAR(body.height, segment("l_ua") / 0.186, 1e-12);
  ASSERT_EQ(body.lines.size(), 3u);
  const Eigen::Vector3d other_shoulder = body.lines[0][1];
  // A right arm: the other shoulder lies at -x_S (x_S lateral), level with this one.
  EXPECT_LT(other_shoulder.x(), -0.3);
  EXPECT_NEAR(other_shoulder.y(), 0.0, 1e-15);
  // The hips below the shoulders, the head above them: the user stands upright in S.
  for (std::size_t k = 1; k + 1 < body.lines[1].size(); ++k) EXPECT_LT(body.lines[1][k].y(), -0.4);
  EXPECT_GT(body.head_centre.y() - body.head_radius, 0.0);
  EXPECT_NEAR(body.head_centre.x(), 0.5 * other_shoulder.x(), 1e-12);
}

TEST(HumanFigure, ALeftArmsBodyIsTheMirrorImage) {
  Json doc = arm_document();
  doc["side"] = "left";
  const HumanArm left(parse_human_arm(doc, "left.json"));
  const HumanBodyProxy right_body = body_proxy(arm()), left_body = body_proxy(left);
  ASSERT_EQ(left_body.lines.size(), right_body.lines.size());
  for (std::size_t l = 0; l < left_body.lines.size(); ++l) {
    for (std::size_t k = 0; k < left_body.lines[l].size(); ++k) {
      const Eigen::Vector3d mirrored(-right_body.lines[l][k].x(), right_body.lines[l][k].y(), right_body.lines[l][k].z());
      EXPECT_LT((left_body.lines[l][k] - mirrored).norm(), 1e-15);
    }
  }
}

}  // namespace
}  // namespace hapsyn::plugins
