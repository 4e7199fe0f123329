// Haptic6RModel at a given configuration q: frames, forward kinematics, Jacobian, inertia and
// gravity (the forward-chain kernels of haptic6r_chain.hpp). quantities() is the multiversioned
// entry point; frames(), forward(), jacobian() and dynamics() serve tests and tools.
#include "haptic6r.hpp"
#include "haptic6r_chain.hpp"

#include <hapsyn/accel/multiversion.hpp>

#include <cstddef>

namespace hapsyn::plugins {

using haptic6r_chain::Chain;
using haptic6r_chain::chain_from;
using haptic6r_chain::dynamics_from;

namespace {
// Inlined into its multiversioned caller (hapsyn/accel/multiversion.hpp): out of line it was a
// baseline-only copy and took 14 % of haptic6r_benchmark's BM_OursJacobianInertiaGravitySolve.
[[gnu::always_inline]] inline Matrix6d jacobian_of(const Chain& c) {
  Matrix6d j;
  haptic6r_chain::jacobian_from(c, j);
  return j;
}
}  // namespace

void Haptic6RModel::frames(const Vector6d& q, std::array<Eigen::Isometry3d, 7>& out) const {
  Chain c;
  chain_from(q, offset_, d_, a_, c);
  for (std::size_t i = 0; i < 7; ++i) {
    out[i].setIdentity();
    out[i].linear().col(0) = Eigen::Vector3d(c.x[i][0], c.x[i][1], c.x[i][2]);
    out[i].linear().col(1) = Eigen::Vector3d(c.y[i][0], c.y[i][1], c.y[i][2]);
    out[i].linear().col(2) = Eigen::Vector3d(c.z[i][0], c.z[i][1], c.z[i][2]);
    out[i].translation() = Eigen::Vector3d(c.o[i][0], c.o[i][1], c.o[i][2]);
  }
}

Eigen::Isometry3d Haptic6RModel::forward(const Vector6d& q) const {
  std::array<Eigen::Isometry3d, 7> f;
  frames(q, f);
  return f[6];
}

Matrix6d Haptic6RModel::jacobian(const Vector6d& q) const {
  Chain c;
  chain_from(q, offset_, d_, a_, c);
  return jacobian_of(c);
}

void Haptic6RModel::dynamics(const Vector6d& q, Matrix6d* inertia, Vector6d* gravity) const {
  Chain c;
  chain_from(q, offset_, d_, a_, c);
  dynamics_from(c, bodies_, setup_->options.gravity, inertia, gravity);
}

HAPSYN_MULTIVERSION
void Haptic6RModel::quantities_impl(const Vector6d& q, Matrix6d* jacobian, Matrix6d* inertia, Vector6d* gravity) const {
  Chain c;
  chain_from(q, offset_, d_, a_, c);
  if (jacobian) *jacobian = jacobian_of(c);
  if (inertia || gravity) dynamics_from(c, bodies_, setup_->options.gravity, inertia, gravity);
}

// The public entry point calls the multiversioned body (defined above: clang refuses to
// multiversion a function already called, and other translation units must see a plain symbol).
void Haptic6RModel::quantities(const Vector6d& q, Matrix6d* jacobian, Matrix6d* inertia, Vector6d* gravity) const {
  quantities_impl(q, jacobian, inertia, gravity);
}

}  // namespace hapsyn::plugins
