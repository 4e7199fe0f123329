// Forward kinematics and the geometric Jacobian of a Chain (chain.hpp).
#include "chain.hpp"

#include <Eigen/LU>
#include <Eigen/SVD>

#include <cassert>

namespace hapsyn::plugins {

namespace {

// The motion of joint j at position x: a rotation about, or a translation along, its axis.
Eigen::Isometry3d joint_motion(const ChainJoint& j, double x) {
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  if (j.type == ChainJointType::kRevolute) {
    m.linear() = Eigen::AngleAxisd(x, j.axis).toRotationMatrix();
  } else {
    m.translation() = x * j.axis;
  }
  return m;
}

}  // namespace

void chain_frames(const Chain& chain, const double* q, ChainFrames& out) {
  assert(chain.dof() >= 1 && chain.dof() <= kMaxChainJoints);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int i = 0; i < chain.dof(); ++i) {
    const ChainJoint& j = chain.joints[static_cast<std::size_t>(i)];
    t = t * j.origin * joint_motion(j, q[i]);
    out.joint[static_cast<std::size_t>(i)] = t;
  }
  out.tip = t * chain.tip;
}

void chain_jacobian(const Chain& chain, const ChainFrames& frames, TaskJointMatrix& jacobian) {
  const int n = chain.dof();
  jacobian.resize(6, n);
  const Eigen::Vector3d p = frames.tip.translation();
  for (int i = 0; i < n; ++i) {
    const ChainJoint& j = chain.joints[static_cast<std::size_t>(i)];
    const Eigen::Isometry3d& f = frames.joint[static_cast<std::size_t>(i)];
    const Eigen::Vector3d z = f.linear() * j.axis;
    if (j.type == ChainJointType::kRevolute) {
      jacobian.col(i).head<3>() = z;
      jacobian.col(i).tail<3>() = z.cross(p - f.translation());
    } else {
      jacobian.col(i).head<3>().setZero();
      jacobian.col(i).tail<3>() = z;
    }
  }
}

// sigma_max <= |J|_F and sigma_min >= 1 / |J^-1|_F, so |J|_F |J^-1|_F tolerance < 1 proves the
// answer at the cost of an LU (the margin 1e-6 covers the inverse's rounding, about cond(J) 1e-16
// relative). Near a singularity the bound is loose or the inverse not finite, and the SVD decides;
// so the answer is always the SVD's, and the SVD (a fifth of a coverage evaluation) runs rarely.
bool chain_well_conditioned(const TaskJointMatrix& jacobian, double tolerance) {
  if (jacobian.rows() == 6 && jacobian.cols() == 6) {
    const Eigen::Matrix<double, 6, 6> square = jacobian;
    const Eigen::Matrix<double, 6, 6> inverse = square.partialPivLu().inverse();
    if (square.norm() * inverse.norm() * tolerance * (1.0 + 1e-6) < 1.0) return true;  // false for NaN
  }
  const Eigen::JacobiSVD<TaskJointMatrix> svd(jacobian);
  const auto& sigma = svd.singularValues();
  return sigma(sigma.size() - 1) > tolerance * sigma(0);
}

}  // namespace hapsyn::plugins
