// The Fennel 2022 mass model (chain_template.hpp, FennelMassModel) on a Chain: the same parts as
// Haptic6RModel::rebuild (plugins/mechanisms/haptic6r/haptic6r_model.cpp), placed by the chain's
// joint origins instead of DH rows, each body in its joint frame.
#include "chain_template_impl.hpp"

#include <cassert>
#include <cstddef>

namespace hapsyn::plugins::serial_chain_detail {

namespace {

// A solid or hollow cylinder's inertia about its centre: axial m * axial_r2, transverse
// `transverse`, axis the unit `axis`.
Eigen::Matrix3d cylinder_inertia(double m, const Eigen::Vector3d& axis, double axial_r2, double transverse) {
  const Eigen::Matrix3d along = axis * axis.transpose();
  return m * axial_r2 * along + transverse * (Eigen::Matrix3d::Identity() - along);
}

// A thin-walled tube from the body frame's origin to `end` (in the body frame).
void add_tube(const FennelMassModel& model, const Eigen::Vector3d& end, ChainBody& body) {
  const double length = end.norm();
  if (length <= 0.0 || model.link_density <= 0.0) return;  // a zero-length link has no tube
  const double ro = 0.5 * model.tube_outer_diameter, ri = ro - model.tube_wall;
  const double r2 = ro * ro + ri * ri;
  const double m = model.link_density * length;
  add_part(body, m, 0.5 * end, cylinder_inertia(m, end / length, 0.5 * r2, m * (3.0 * r2 + length * length) / 12.0));
}

// The end effector: a solid cylinder centred at the tip, axis along the tip's z.
void add_end_effector(const FennelMassModel& model, const Eigen::Isometry3d& tip, ChainBody& body) {
  const double m = model.ee_mass, r = 0.5 * model.ee_diameter, h = model.ee_length;
  add_part(body, m, tip.translation(),
           cylinder_inertia(m, tip.linear().col(2), 0.5 * r * r, m * (3.0 * r * r + h * h) / 12.0));
}

}  // namespace

void apply_fennel_mass_model(const FennelMassModel& model, const double* motor_mass, Chain& chain) {
  const std::size_t n = chain.joints.size();
  assert(n >= 1 && motor_mass);
  chain.bodies.assign(n, ChainBody{});
  for (std::size_t i = 0; i < n; ++i) {
    ChainBody& body = chain.bodies[i];
    // Joint i+1's frame origin at q = 0 (a prismatic joint's travel does not stretch the tube),
    // or the tip after the last joint.
    const Eigen::Vector3d end = i + 1 < n ? Eigen::Vector3d(chain.joints[i + 1].origin.translation())
                                          : Eigen::Vector3d(chain.tip.translation());
    add_tube(model, end, body);
    if (i + 1 < n) {
      // Motor i+1 sits on joint i+1's origin, carried by the body before it (motor 0 by the base).
      add_part(body, model.motor_mass_factor * motor_mass[i + 1], end, Eigen::Matrix3d::Zero());
    } else {
      add_end_effector(model, chain.tip, body);
    }
  }
}

}  // namespace hapsyn::plugins::serial_chain_detail
