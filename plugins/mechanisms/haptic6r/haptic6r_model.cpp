// Haptic6RModel::rebuild: a design vector (l, s, r) into the DH lengths, the actuator limits and
// the mass model of docs/design.md section 4, each body in its own DH frame.
#include "haptic6r.hpp"

#include <hapsyn/error.hpp>

#include <cmath>
#include <cstddef>
#include <sstream>

namespace hapsyn::plugins {

namespace {

constexpr const char* kName = "haptic6r";

Eigen::Matrix3d parallel_axis(const Eigen::Vector3d& r) {
  return r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose();
}

// Adds a body part (mass m, com c, inertia I about c) to an accumulated body.
void add_part(Haptic6RBody& body, double m, const Eigen::Vector3d& c, const Eigen::Matrix3d& inertia) {
  if (m <= 0.0) return;
  const double total = body.mass + m;
  const Eigen::Vector3d com = (body.mass * body.com + m * c) / total;
  body.inertia = body.inertia + body.mass * parallel_axis(body.com - com) + inertia + m * parallel_axis(c - com);
  body.com = com;
  body.mass = total;
}

Eigen::Matrix3d cylinder_inertia(double m, const Eigen::Vector3d& axis, double r_sq_sum_half, double transverse) {
  // axial m * r_sq_sum_half, transverse `transverse` about the centre.
  return m * r_sq_sum_half * axis * axis.transpose() + transverse * (Eigen::Matrix3d::Identity() - axis * axis.transpose());
}

}  // namespace

void Haptic6RModel::rebuild(const double* design, const Haptic6RSetup& setup) {
  setup_ = &setup;
  for (int i = 0; i < 5; ++i) {
    const double l = design[i];
    if (!std::isfinite(l) || l <= 0.0) {
      std::ostringstream m;
      m << "design l[" << i << "] = " << l << ": must be a finite length > 0 [m]";
      throw Error(kName, m.str());
    }
    l_[static_cast<std::size_t>(i)] = l;
  }
  std::array<int, 6> size{}, code{};
  for (int i = 0; i < 6; ++i) {
    const double s = design[5 + i], r = design[11 + i];
    if (!(s >= 0.5 && s < 3.5) || !(r >= 0.5 && r < 6.5)) {
      std::ostringstream m;
      m << "design s[" << i << "] = " << s << ", r[" << i << "] = " << r << ": sizes must be in {1, 2, 3}, gear codes in {1..6}";
      throw Error(kName, m.str());
    }
    size[static_cast<std::size_t>(i)] = static_cast<int>(std::lround(s));
    code[static_cast<std::size_t>(i)] = static_cast<int>(std::lround(r));
    max_velocity_(i) = setup.actuators.max_velocity(size[static_cast<std::size_t>(i)], code[static_cast<std::size_t>(i)]);
    max_torque_(i) = setup.actuators.max_torque(size[static_cast<std::size_t>(i)], code[static_cast<std::size_t>(i)]);
  }
  for (std::size_t i = 0; i < 6; ++i) {
    const Haptic6RDhRow& row = setup.dh.rows[i];
    d_[i] = row.d.eval(l_.data());
    a_[i] = row.a.eval(l_.data());
    offset_[i] = row.theta_offset;
    ca_[i] = std::cos(row.alpha);
    sa_[i] = std::sin(row.alpha);
    // Exact zeros for the right angles, so that FK and IK agree to the last bit.
    if (std::abs(ca_[i]) < 1e-15) ca_[i] = 0.0;
    if (std::abs(sa_[i]) < 1e-15) sa_[i] = 0.0;
  }
  ik_model(ik_);  // after d_, a_, offset_, ca_, sa_: the IK reads these once per design
  // Mass model, each body in its own DH frame.
  const double ro = 0.5 * setup.options.tube_outer_diameter, ri = ro - setup.options.tube_wall;
  const double tube_r2 = ro * ro + ri * ri;
  for (std::size_t i = 0; i < 6; ++i) {
    Haptic6RBody& b = bodies_[i];
    b = Haptic6RBody{};
    // The previous origin o_{i-1} in frame i is -(a, d sin(alpha), d cos(alpha)).
    const Eigen::Vector3d prev(-a_[i], -d_[i] * sa_[i], -d_[i] * ca_[i]);
    const double length = prev.norm();
    if (length > 0.0 && setup.options.link_density > 0.0) {
      const double m = setup.options.link_density * length;
      const Eigen::Vector3d axis = prev / length;
      add_part(b, m, 0.5 * prev, cylinder_inertia(m, axis, 0.5 * tube_r2, m * (3.0 * tube_r2 + length * length) / 12.0));
    }
    if (i < 5) {  // motor i+2 (1-based) sits at this frame's origin, on joint i+2's axis
      const double m = setup.options.motor_mass_factor * setup.actuators.mass[static_cast<std::size_t>(size[i + 1] - 1)];
      add_part(b, m, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero());
    } else {
      const double m = setup.options.ee_mass, r = 0.5 * setup.options.ee_diameter, h = setup.options.ee_length;
      add_part(b, m, Eigen::Vector3d::Zero(),
               cylinder_inertia(m, Eigen::Vector3d::UnitZ(), 0.5 * r * r, m * (3.0 * r * r + h * h) / 12.0));
    }
  }
}

std::vector<Segment> Haptic6RModel::segments(const SampleSet& scene, int sample, MechanismScratch& /*scratch*/) const {
  Vector6d q;
  JointTrig trig;
  const SampleStatus status = configuration(scene.pose(sample), q, trig);
  if (status != SampleStatus::kReachable && status != SampleStatus::kSingular) return {};
  std::array<Eigen::Isometry3d, 7> frame;
  frames(q, frame);
  Segment links{"links", {frame[0].translation()}};
  for (std::size_t i = 1; i < 7; ++i) {
    // DH row i: d along z_{i-1} first, then a along x_i; a zero length adds no point.
    const Eigen::Vector3d corner = frame[i - 1].translation() + d_[i - 1] * frame[i - 1].linear().col(2);
    for (const Eigen::Vector3d& p : {corner, Eigen::Vector3d(frame[i].translation())}) {
      if ((p - links.points.back()).norm() > 1e-12) links.points.push_back(p);
    }
  }
  return {links};
}

Eigen::Vector4d Haptic6RModel::dh_row(int i) const {
  const std::size_t k = static_cast<std::size_t>(i);
  return Eigen::Vector4d(offset_[k], d_[k], a_[k], std::atan2(sa_[k], ca_[k]));
}

}  // namespace hapsyn::plugins
