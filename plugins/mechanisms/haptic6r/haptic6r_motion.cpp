// The haptic 6R's joint rates, accelerations and velocity torque for a demanded end-effector
// motion (haptic6r_chain::joint_motion): the chain's DH frames handed to hapsyn/chain_motion.hpp
// in the base frame B, which is also the scene frame of the samples and of their twist.
#include "haptic6r.hpp"
#include "haptic6r_chain.hpp"

#include <hapsyn/chain_motion.hpp>

#include <limits>

namespace hapsyn::plugins::haptic6r_chain {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Eigen::Vector3d vec(const double* v) { return Eigen::Vector3d(v[0], v[1], v[2]); }

// Joint i (0-based) turns about z of DH frame i through its origin.
void world_joints(const Chain& c, WorldJoint* joints) {
  for (int i = 0; i < 6; ++i) {
    joints[i].axis = vec(c.z[i]);
    joints[i].origin = vec(c.o[i]);
    joints[i].prismatic = false;
  }
}

// Body i lives in DH frame i + 1 (with the motor of joint i + 2 at that frame's origin, as in
// dynamics_from): its com and inertia turned into B, so that c comes from the same mass model
// as the composite-rigid-body inertia and the gravity torque.
void world_bodies(const Chain& c, const std::array<Haptic6RBody, 6>& bodies, WorldBody* out) {
  for (int i = 0; i < 6; ++i) {
    const int f = i + 1;
    Eigen::Matrix3d r;
    r.col(0) = vec(c.x[f]);
    r.col(1) = vec(c.y[f]);
    r.col(2) = vec(c.z[f]);
    const Haptic6RBody& b = bodies[static_cast<std::size_t>(i)];
    out[i].mass = b.mass;
    out[i].com = vec(c.o[f]) + r * b.com;
    out[i].inertia = r * b.inertia * r.transpose();
  }
}

}  // namespace

void joint_motion(const Chain& c, const std::array<Haptic6RBody, 6>& bodies, Needs needs, SampleQuantities& out) {
  WorldJoint joints[6];
  world_joints(c, joints);
  out.joint_velocity.resize(6);
  if (!out.twist) {  // outside the evaluator (Problem refuses a scene without the twist)
    out.joint_velocity.setConstant(kNaN);
  } else {
    TaskJointMatrix jacobian(6, 6);
    jacobian_from(c, jacobian);
    JointRateSolver solver;
    solver.compute(jacobian);
    solver.solve(out.twist, out.joint_velocity);
    if (needs & kNeedJointAcceleration) {
      out.joint_acceleration.resize(6);
      if (!out.twist_rate) {
        out.joint_acceleration.setConstant(kNaN);
      } else {
        double rate[6];
        jacobian_rate_times_rate(joints, 6, vec(c.o[6]), out.joint_velocity.data(), rate);
        for (int r = 0; r < 6; ++r) rate[r] = out.twist_rate[r] - rate[r];
        solver.solve(rate, out.joint_acceleration);
      }
    }
  }
  if (needs & kNeedVelocityTorque) {
    WorldBody world[6];
    world_bodies(c, bodies, world);
    out.velocity_torque.resize(6);
    velocity_torque(joints, world, 6, out.joint_velocity.data(), out.velocity_torque.data());
  }
}

}  // namespace hapsyn::plugins::haptic6r_chain
