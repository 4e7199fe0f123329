// ChainTemplate's file-independent part (lookup, instantiate) and the helpers the readers share;
// the readers are urdf_chain.cpp and dh_chain.cpp, the mass model fennel_mass_model.cpp.
#include "chain_template_impl.hpp"

#include <Eigen/Eigenvalues>

#include <hapsyn/data_file.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace hapsyn::plugins {

using namespace serial_chain_detail;

int ChainTemplate::find(const std::string& name) const {
  for (std::size_t i = 0; i < parameters_.size(); ++i) {
    if (parameters_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

const ChainMeshes& ChainTemplate::meshes() const {
  static const ChainMeshes none;
  return impl_ ? impl_->meshes : none;
}

const std::vector<ChainFoldedLinks>& ChainTemplate::folded_links() const {
  static const std::vector<ChainFoldedLinks> none;
  return impl_ ? impl_->folded_links : none;
}

const std::vector<std::string>& ChainTemplate::links_on_base() const {
  static const std::vector<std::string> none;
  return impl_ ? impl_->links_on_base : none;
}

int ChainTemplate::dof() const { return impl_ ? impl_->dof : 0; }

const FennelMassModel* ChainTemplate::fennel_mass_model() const {
  return impl_ && impl_->fennel ? &*impl_->fennel : nullptr;
}

void ChainTemplate::instantiate(const double* values, const double* motor_mass, Chain& out) const {
  assert(impl_ && impl_->build);
  impl_->build(values, motor_mass, out);
  assert(out.dof() == impl_->dof && out.bodies.size() == out.joints.size());
}

std::string resolve_serial_chain_file(const std::string& option_name, const std::string& value) {
  return find_data_file(kSerialChainName, option_name, value);
}

namespace serial_chain_detail {

std::string inertia_implausibility(const Eigen::Matrix3d& inertia) {
  if (!inertia.allFinite()) return "its entries must be finite";
  const Eigen::Vector3d moments = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(inertia, Eigen::EigenvaluesOnly).eigenvalues();
  const double tolerance = 1e-6 * moments.cwiseAbs().sum();
  // Six digits: eigenvalues carry rounding the file's numbers do not have.
  char shown_moments[96];
  std::snprintf(shown_moments, sizeof shown_moments, "(%.6g, %.6g, %.6g)", moments(0), moments(1), moments(2));
  const std::string shown = std::string("its principal moments ") + shown_moments;
  if (moments(0) < -tolerance) return shown + " must be >= 0 (positive semi-definite)";
  // Sorted ascending: the largest is the only one that can exceed the sum of the others.
  if (moments(2) > moments(0) + moments(1) + tolerance) {
    return shown + " break the triangle inequality: the largest may not exceed the sum of the other two";
  }
  return "";
}

Eigen::Matrix3d rpy_rotation(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Isometry3d xyz_rpy_pose(const Eigen::Vector3d& xyz, double roll, double pitch, double yaw) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = rpy_rotation(roll, pitch, yaw);
  t.translation() = xyz;
  return t;
}

Eigen::Matrix3d parallel_axis(double m, const Eigen::Vector3d& r) {
  return m * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
}

void add_part(ChainBody& body, double m, const Eigen::Vector3d& c, const Eigen::Matrix3d& inertia) {
  // A massless part adds only its rotational inertia (the com would be 0/0 on an empty body).
  if (m <= 0.0) {
    body.inertia += inertia;
    return;
  }
  const double total = body.mass + m;
  const Eigen::Vector3d com = (body.mass * body.com + m * c) / total;
  body.inertia = body.inertia + parallel_axis(body.mass, body.com - com) + inertia + parallel_axis(m, c - com);
  body.com = com;
  body.mass = total;
}

ChainBody transformed(const ChainBody& body, const Eigen::Isometry3d& pose) {
  ChainBody b;
  b.mass = body.mass;
  b.com = pose * body.com;
  b.inertia = pose.linear() * body.inertia * pose.linear().transpose();
  return b;
}

void scale_body(ChainBody& body, double factor) {
  body.mass *= factor;
  body.inertia *= factor;
}

namespace {

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

}  // namespace

ChainParameter mass_scale_parameter() {
  ChainParameter scale;
  scale.name = "mass_scale";
  scale.description = "factor on every mass and inertia of the chain";
  scale.nominal = 1.0;
  scale.hard_lower = 0.0;
  return scale;
}

std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates) {
  const std::size_t limit = std::max<std::size_t>(2, name.size() / 3);
  const std::string* best = nullptr;
  std::size_t best_distance = limit + 1;
  for (const std::string& c : candidates) {
    const std::size_t d = edit_distance(name, c);
    if (d < best_distance) {
      best_distance = d;
      best = &c;
    }
  }
  return best ? ", did you mean \"" + *best + "\"?" : "";
}

std::string show_number(double x) {
  char buffer[32];
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(buffer, sizeof buffer, "%.*g", precision, x);
    if (std::strtod(buffer, nullptr) == x || !std::isfinite(x)) break;
  }
  return buffer;
}

}  // namespace serial_chain_detail

}  // namespace hapsyn::plugins
