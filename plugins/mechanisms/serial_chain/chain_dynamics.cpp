// Joint-space inertia and gravity torque of a Chain (chain.hpp) by composite rigid bodies.
//
// Everything is accumulated in the base frame about the base origin, so that adding a body needs
// no division and no shift of a centre of mass: the composite C_j (bodies j..n) has mass M, first
// moment h = M c and rotational inertia K about the base origin. A unit rate of joint j is the
// twist S_j = (omega, v0) (v0: the velocity of the point at the base origin): (z_j, o_j x z_j)
// for a revolute joint with world axis z_j through o_j, (0, z_j) for a prismatic one. C_j's
// momentum under S_j is P = M v0 + omega x h (linear) and L = K omega + h x v0 (angular, about
// the origin), and H_ij = S_i . (L, P) for i <= j:
//   revolute i:  z_i . (L - o_i x P),   prismatic i:  z_i . P.
// The holding torque against gravity g is the negated generalized force of the weights of C_j:
//   revolute j:  -z_j . ((h - M o_j) x g),   prismatic j:  -z_j . (M g).
// O(n^2) after one O(n) sweep from the tip; no allocation (the matrices have fixed capacity).
// chain_world_joints / chain_world_bodies hand the same axes and bodies to hapsyn/chain_motion.hpp
// for the velocity terms.
#include "chain.hpp"

#include <array>
#include <cassert>
#include <cstddef>

namespace hapsyn::plugins {

namespace {

// The composite of the bodies from the tip down to the current one, about the base origin.
struct Composite {
  double mass = 0.0;
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();  // h = sum m c
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  // K about the base origin

  void add(const ChainBody& body, const Eigen::Isometry3d& frame) {
    if (body.mass == 0.0 && body.inertia.isZero(0.0)) return;
    const Eigen::Vector3d c = frame * body.com;
    const Eigen::Matrix3d& r = frame.linear();
    inertia += r * body.inertia * r.transpose() +
               body.mass * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
    moment += body.mass * c;
    mass += body.mass;
  }
};

// Joint j's world axis and a point on it.
struct WorldAxis {
  Eigen::Vector3d z, o;
  bool revolute;
};

WorldAxis world_axis(const Chain& chain, const ChainFrames& frames, int j) {
  const ChainJoint& joint = chain.joints[static_cast<std::size_t>(j)];
  const Eigen::Isometry3d& f = frames.joint[static_cast<std::size_t>(j)];
  return {f.linear() * joint.axis, f.translation(), joint.type == ChainJointType::kRevolute};
}

// The generalized force of joint i for the wrench (L about the origin, P).
double generalized_force(const WorldAxis& a, const Eigen::Vector3d& angular, const Eigen::Vector3d& linear) {
  return a.revolute ? a.z.dot(angular - a.o.cross(linear)) : a.z.dot(linear);
}

}  // namespace

void chain_inertia(const Chain& chain, const ChainFrames& frames, JointMatrix& inertia) {
  const int n = chain.dof();
  assert(n >= 1 && n <= kMaxChainJoints && chain.bodies.size() == chain.joints.size());
  inertia.resize(n, n);
  std::array<WorldAxis, kMaxChainJoints> axes;
  for (int j = 0; j < n; ++j) axes[static_cast<std::size_t>(j)] = world_axis(chain, frames, j);
  Composite c;
  for (int j = n - 1; j >= 0; --j) {
    c.add(chain.bodies[static_cast<std::size_t>(j)], frames.joint[static_cast<std::size_t>(j)]);
    const WorldAxis& a = axes[static_cast<std::size_t>(j)];
    const Eigen::Vector3d omega = a.revolute ? a.z : Eigen::Vector3d::Zero();
    const Eigen::Vector3d v0 = a.revolute ? Eigen::Vector3d(a.o.cross(a.z)) : a.z;
    const Eigen::Vector3d linear = c.mass * v0 + omega.cross(c.moment);
    const Eigen::Vector3d angular = c.inertia * omega + c.moment.cross(v0);
    for (int i = 0; i <= j; ++i) {
      const double value = generalized_force(axes[static_cast<std::size_t>(i)], angular, linear);
      inertia(i, j) = value;
      inertia(j, i) = value;
    }
  }
}

void chain_gravity(const Chain& chain, const ChainFrames& frames, JointVector& gravity) {
  const int n = chain.dof();
  assert(n >= 1 && n <= kMaxChainJoints && chain.bodies.size() == chain.joints.size());
  gravity.resize(n);
  double mass = 0.0;
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  for (int j = n - 1; j >= 0; --j) {
    const ChainBody& b = chain.bodies[static_cast<std::size_t>(j)];
    mass += b.mass;
    moment += b.mass * (frames.joint[static_cast<std::size_t>(j)] * b.com);
    const WorldAxis a = world_axis(chain, frames, j);
    const Eigen::Vector3d weight = mass * chain.gravity;
    gravity(j) = a.revolute ? -a.z.dot((moment - mass * a.o).cross(chain.gravity)) : -a.z.dot(weight);
  }
}

void chain_world_joints(const Chain& chain, const ChainFrames& frames, WorldJoint* out) {
  for (int i = 0; i < chain.dof(); ++i) {
    // On a revolute axis the origin is any point of it; for a prismatic joint it moves with the
    // body, as chain_motion.hpp wants.
    const WorldAxis a = world_axis(chain, frames, i);
    out[i].axis = a.z;
    out[i].origin = a.o;
    out[i].prismatic = !a.revolute;
  }
}

void chain_world_bodies(const Chain& chain, const ChainFrames& frames, WorldBody* out) {
  for (int i = 0; i < chain.dof(); ++i) {
    const ChainBody& b = chain.bodies[static_cast<std::size_t>(i)];
    const Eigen::Isometry3d& f = frames.joint[static_cast<std::size_t>(i)];
    out[i].mass = b.mass;
    out[i].com = f * b.com;
    out[i].inertia = f.linear() * b.inertia * f.linear().transpose();
  }
}

}  // namespace hapsyn::plugins
