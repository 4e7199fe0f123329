// The spherical-wrist 6R (six_r_ik.hpp): wrist centre by SP5, wrist angles by SP2 and SP1.
#include "shared/closed_form_ik/families.hpp"
#include "shared/closed_form_ik/subproblems.hpp"

namespace hapsyn::plugins::closed_form_ik::detail {

void spherical_wrist_candidates(const PoeChain& c, const Eigen::Vector3d& wrist, const Eigen::Isometry3d& target,
                                IkScratch& s) {
  const auto& h = c.h;
  const auto& p = c.p;
  // Rotations about axes through the wrist point leave it fixed, so the wrist point now is
  // p_0T - R_06 (tool point - wrist point at q = 0) and depends on q1..q3 only:
  //   R(h1, -q1) (p_w - p_01) - p_12 = R(h2, q2) (p_23 + R(h3, q3) (w - o_3))   (SP5).
  const Eigen::Matrix3d r06 = target.linear() * c.r_tool.transpose();
  const Eigen::Vector3d tool0 = c.joint_point(5) + p[6];
  const Eigen::Vector3d pw = target.translation() - r06 * (tool0 - wrist);
  const Angles3 arm = sp5(-p[1], pw - p[0], p[2], wrist - c.joint_point(2), h[0], h[1], h[2]);
  for (int i = 0; i < arm.count; ++i) {
    const std::size_t a = static_cast<std::size_t>(i);
    Vector6d q;
    q << -arm.theta1[a], arm.theta2[a], arm.theta3[a], 0, 0, 0;
    const Eigen::Matrix3d r36 = (rot(h[0], q(0)) * rot(h[1], q(1)) * rot(h[2], q(2))).transpose() * r06;
    // R(h4, -q4) (R_36 h6) = R(h5, q5) h6 (SP2), then R(h6, q6) h5 = (R_4 R_5)^T R_36 h5 (SP1).
    const Angles2 wrist45 = sp2(r36 * h[5], h[5], h[3], h[4]);
    for (int j = 0; j < wrist45.count; ++j) {
      const std::size_t b = static_cast<std::size_t>(j);
      q(3) = -wrist45.theta1[b];
      q(4) = wrist45.theta2[b];
      const Eigen::Matrix3d r45 = rot(h[3], q(3)) * rot(h[4], q(4));
      q(5) = sp1(h[4], r45.transpose() * r36 * h[4], h[5]).theta[0];
      push(s, q);
    }
  }
}

}  // namespace hapsyn::plugins::closed_form_ik::detail
