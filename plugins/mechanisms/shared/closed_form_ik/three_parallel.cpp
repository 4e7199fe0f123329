// The 6R with axes 2, 3, 4 parallel (UR type; six_r_ik.hpp): (q1, q5) by SP6, q6 and
// q2 + q3 + q4 by SP1, q3 by SP3, q2 by SP1.
#include "shared/closed_form_ik/angles.hpp"
#include "shared/closed_form_ik/families.hpp"
#include "shared/closed_form_ik/subproblems.hpp"

#include <cmath>

namespace hapsyn::plugins::closed_form_ik::detail {

void three_parallel_candidates(const PoeChain& c, const Eigen::Isometry3d& target, IkScratch& s) {
  const auto& h = c.h;
  const auto& p = c.p;
  const Eigen::Vector3d& k = h[1];  // the common axis (h3, h4 = +-k)
  const Eigen::Matrix3d r06 = target.linear() * c.r_tool.transpose();
  const Eigen::Vector3d v = target.translation() - p[0] - r06 * p[6];
  // k^T R(h, q) = k^T for rotations about the parallel axes, so with R_1^T R_06 = R_234 R_5 R_6:
  //   k . R(h1, -q1) R_06 h6 = k . R(h5, q5) h6,
  //   k . R(h1, -q1) v = k . (p_12 + p_23 + p_34 + p_45) + k . R(h5, q5) p_56      (SP6).
  const Angles2 t15 = sp6({k, -k, k, -k}, {h[0], h[4], h[0], h[4]}, {r06 * h[5], h[5], v, p[5]}, 0.0,
                          k.dot(p[1] + p[2] + p[3] + p[4]));
  const Eigen::Vector3d ortho = k.unitOrthogonal();
  for (int i = 0; i < t15.count; ++i) {
    const std::size_t a = static_cast<std::size_t>(i);
    const double q1 = -t15.theta1[a], q5 = t15.theta2[a];
    const Eigen::Matrix3d r1t = rot(h[0], q1).transpose();
    const Eigen::Matrix3d rr = r1t * r06;  // R_234 R_5 R_6
    const Eigen::Matrix3d r5 = rot(h[4], q5);
    // k^T R_5 R_6 = k^T rr: R(h6, -q6) (R_5^T k) = rr^T k (SP1). (The rotations below are built
    // from the subproblems' own sine and cosine: no sin/cos of the angles again.)
    const Angles1 t6 = sp1(r5.transpose() * k, rr.transpose() * k, h[5]);
    const double q6 = -t6.theta[0];
    const Eigen::Matrix3d r234 = rr * rot(h[5], -t6.sine[0], t6.cosine[0]).transpose() * r5.transpose();
    const double q234 = sp1(ortho, r234 * ortho, k).theta[0];
    // p_12 + R_2 (p_23 + R_3 p_34) = R_1^T v - R_234 (p_45 + R_5 p_56) =: d.
    const Eigen::Vector3d d = r1t * v - r234 * (p[4] + r5 * p[5]) - p[1];
    const Angles1 t3 = sp3(p[3], -p[2], h[2], d.norm());
    for (int j = 0; j < t3.count; ++j) {
      const std::size_t b = static_cast<std::size_t>(j);
      const double q3 = t3.theta[b];
      const double q2 = sp1(p[2] + rot(h[2], t3.sine[b], t3.cosine[b]) * p[3], d, h[1]).theta[0];
      // h3, h4 may point against k: their angles enter q234 with the sign of h . k.
      const double q4 = (q234 - q2 - std::copysign(1.0, h[2].dot(k)) * q3) * std::copysign(1.0, h[3].dot(k));
      Vector6d q;
      q << q1, q2, q3, remainder_two_pi(q4), q5, q6;
      push(s, q);
    }
  }
}

}  // namespace hapsyn::plugins::closed_form_ik::detail
