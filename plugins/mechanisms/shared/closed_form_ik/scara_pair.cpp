// The 6R with axes 1, 2, 3 parallel and axes 4, 5 parallel (the haptic 6R / SCARA-with-wrist
// type; six_r_ik.hpp): q4 + q5 by SP4, q4 by SP4, q6 and q1 + q2 + q3 by SP1, q2 by SP3, q1 by SP1.
#include "shared/closed_form_ik/angles.hpp"
#include "shared/closed_form_ik/families.hpp"
#include "shared/closed_form_ik/subproblems.hpp"

#include <cmath>

namespace hapsyn::plugins::closed_form_ik::detail {

void scara_pair_candidates(const PoeChain& c, const Eigen::Isometry3d& target, IkScratch& s) {
  const auto& h = c.h;
  const auto& p = c.p;
  const Eigen::Vector3d& k = h[0];  // axes 2, 3 = +-k
  const Eigen::Vector3d& m = h[3];  // axis 5 = +-m
  const double s2 = std::copysign(1.0, h[1].dot(k)), s3 = std::copysign(1.0, h[2].dot(k));
  const double s5 = std::copysign(1.0, h[4].dot(m));
  const Eigen::Matrix3d r06 = target.linear() * c.r_tool.transpose();
  // k^T R(k, .) = k^T, so with R_06 = R(k, q123) R(m, q45) R_6 (q45 = q4 + s5 q5):
  //   k . R(m, q45) h6 = k . R_06 h6                                          (SP4: q45)
  //   k . R(m, q4) p_45 = k . (p_0T - p_01 - R_06 p_6T - p_12 - p_23 - p_34) - k . R(m, q45) p_56  (SP4: q4)
  const Eigen::Vector3d v = target.translation() - p[0] - r06 * p[6];
  const Angles1 t45 = sp4(k, h[5], m, k.dot(r06 * h[5]));
  for (int i = 0; i < t45.count; ++i) {
    const double q45 = t45.theta[static_cast<std::size_t>(i)];
    const Eigen::Matrix3d r45 = rot(m, q45);
    const Angles1 t4 = sp4(k, p[4], m, k.dot(v - p[1] - p[2] - p[3] - r45 * p[5]));
    // R_6^T (R_45^T k) = R_06^T k (SP1 gives -q6); then R(k, q123) = R_06 R_6^T R_45^T.
    const double q6 = -sp1(r45.transpose() * k, r06.transpose() * k, h[5]).theta[0];
    const Eigen::Matrix3d r123 = r06 * rot(h[5], q6).transpose() * r45.transpose();
    const Eigen::Vector3d ortho = k.unitOrthogonal();
    const double q123 = sp1(ortho, r123 * ortho, k).theta[0];
    for (int j = 0; j < t4.count; ++j) {
      const double q4 = t4.theta[static_cast<std::size_t>(j)];
      const double q5 = s5 * (q45 - q4);
      // R(k, q1) (p_12 + R(h2, q2) p_23) = p_0T - p_01 - R_06 p_6T - R_123 (p_34 + R_4 p_45 + R_45 p_56) =: d.
      const Eigen::Vector3d d = v - r123 * (p[3] + rot(m, q4) * p[4] + r45 * p[5]);
      const Angles1 t2 = sp3(p[2], -p[1], h[1], d.norm());
      for (int l = 0; l < t2.count; ++l) {
        const double q2 = t2.theta[static_cast<std::size_t>(l)];
        const double q1 = sp1(p[1] + rot(h[1], q2) * p[2], d, k).theta[0];
        const double q3 = s3 * (q123 - q1 - s2 * q2);
        Vector6d q;
        q << q1, q2, remainder_two_pi(q3), q4, remainder_two_pi(q5), q6;
        push(s, q);
      }
    }
  }
}

}  // namespace hapsyn::plugins::closed_form_ik::detail
