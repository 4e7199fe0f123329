// PoeChain: conversion from local joint frames, forward kinematics, the reversed chain and the
// axis classifier (poe_chain.hpp).
#include "shared/closed_form_ik/poe_chain.hpp"

#include "shared/closed_form_ik/subproblems.hpp"

#include <hapsyn/error.hpp>

#include <cmath>
#include <sstream>

namespace hapsyn::plugins::closed_form_ik {

PoeChain PoeChain::from_local_frames(const std::vector<Eigen::Isometry3d>& origins,
                                     const std::vector<Eigen::Vector3d>& axes, const Eigen::Isometry3d& tip) {
  if (origins.size() != axes.size() || origins.empty() || origins.size() > static_cast<std::size_t>(kMaxJoints)) {
    throw Error("closed_form_ik", std::to_string(origins.size()) + " joint origins and " + std::to_string(axes.size()) +
                                      " axes: need the same number, 1 to " + std::to_string(kMaxJoints));
  }
  PoeChain c;
  c.n = static_cast<int>(origins.size());
  // frame = pose of joint frame i at q = 0 in the base frame; the offsets are differences of its
  // origins, the axes its rotation times the local axes.
  Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  for (int i = 0; i < c.n; ++i) {
    const std::size_t s = static_cast<std::size_t>(i);
    const double length = axes[s].norm();
    if (!(length > 0.0) || !std::isfinite(length)) {
      throw Error("closed_form_ik", "joint " + std::to_string(i + 1) + ": axis has length " + std::to_string(length) +
                                        ": must be finite and > 0");
    }
    frame = frame * origins[s];
    c.h[s] = frame.linear() * axes[s] / length;
    c.p[s] = frame.translation() - previous;
    previous = frame.translation();
  }
  frame = frame * tip;
  c.p[static_cast<std::size_t>(c.n)] = frame.translation() - previous;
  c.r_tool = frame.linear();
  return c;
}

Eigen::Isometry3d PoeChain::forward(const double* q) const {
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = p[0];
  for (int i = 0; i < n; ++i) {
    r = r * rot(h[static_cast<std::size_t>(i)], q[i]);
    t += r * p[static_cast<std::size_t>(i + 1)];
  }
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = r * r_tool;
  pose.translation() = t;
  return pose;
}

void PoeChain::forward_jacobian(const double* q, Eigen::Isometry3d& pose,
                                Eigen::Matrix<double, 6, kMaxJoints>& jacobian) const {
  // Axis i in the base frame is R_0,i-1 h_i, through the point o_i (joint i's origin now).
  std::array<Eigen::Vector3d, kMaxJoints> axis, origin;
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = p[0];
  for (int i = 0; i < n; ++i) {
    const std::size_t s = static_cast<std::size_t>(i);
    axis[s] = r * h[s];
    origin[s] = t;
    r = r * rot(h[s], q[i]);
    t += r * p[s + 1];
  }
  pose = Eigen::Isometry3d::Identity();
  pose.linear() = r * r_tool;
  pose.translation() = t;
  for (int i = 0; i < n; ++i) {
    const std::size_t s = static_cast<std::size_t>(i);
    jacobian.col(i).head<3>() = axis[s];
    jacobian.col(i).tail<3>() = axis[s].cross(t - origin[s]);
  }
}

Eigen::Vector3d PoeChain::joint_point(int i) const {
  Eigen::Vector3d o = Eigen::Vector3d::Zero();
  for (int j = 0; j <= i; ++j) o += p[static_cast<std::size_t>(j)];
  return o;
}

PoeChain PoeChain::reversed() const {
  PoeChain c;
  c.n = n;
  const Eigen::Matrix3d qt = r_tool.transpose();
  for (int i = 0; i < n; ++i) c.h[static_cast<std::size_t>(i)] = -(qt * h[static_cast<std::size_t>(n - 1 - i)]);
  for (int i = 0; i <= n; ++i) c.p[static_cast<std::size_t>(i)] = -(qt * p[static_cast<std::size_t>(n - i)]);
  c.r_tool = qt;
  return c;
}

namespace {

// The point where lines (a, u) and (b, v) meet, if they do (not parallel, closer than tol).
bool meet(const Eigen::Vector3d& a, const Eigen::Vector3d& u, const Eigen::Vector3d& b, const Eigen::Vector3d& v,
          double parallel_tol, double distance_tol, Eigen::Vector3d& point) {
  const Eigen::Vector3d nrm = u.cross(v);
  const double nn = nrm.norm();
  if (nn <= parallel_tol) return false;
  if (std::abs((b - a).dot(nrm)) / nn > distance_tol) return false;
  const double s = (b - a).cross(v).dot(nrm) / (nn * nn);
  const double t = (b - a).cross(u).dot(nrm) / (nn * nn);
  point = 0.5 * ((a + s * u) + (b + t * v));
  return true;
}

void choose_family(ChainGeometry& g) {
  if (g.n != 6) return;
  if (g.spherical_wrist) {
    g.family = IkFamily::kSphericalWrist;
  } else if (g.spherical_shoulder) {
    g.family = IkFamily::kSphericalWrist, g.reversed = true;
  } else if (g.parallel[1] && g.parallel[2]) {
    g.family = IkFamily::kThreeParallel;
  } else if (g.parallel[2] && g.parallel[3]) {
    g.family = IkFamily::kThreeParallel, g.reversed = true;
  } else if (g.parallel[0] && g.parallel[1] && g.parallel[3]) {
    g.family = IkFamily::kScaraPair;
  } else if (g.parallel[3] && g.parallel[4] && g.parallel[1]) {
    g.family = IkFamily::kScaraPair, g.reversed = true;
  } else if (g.intersecting[4]) {
    g.family = IkFamily::kSearch1d;
  } else if (g.intersecting[0]) {
    g.family = IkFamily::kSearch1d, g.reversed = true;
  }
}

}  // namespace

ChainGeometry classify(const PoeChain& chain, double tolerance) {
  ChainGeometry g;
  g.n = chain.n;
  double size = 0.0;
  for (int i = 0; i <= chain.n; ++i) size += chain.p[static_cast<std::size_t>(i)].norm();
  const double distance_tol = tolerance * std::max(size, 1.0);
  for (int i = 0; i + 1 < chain.n; ++i) {
    const std::size_t s = static_cast<std::size_t>(i);
    g.parallel[s] = chain.h[s].cross(chain.h[s + 1]).norm() <= tolerance;
    g.intersecting[s] = meet(chain.joint_point(i), chain.h[s], chain.joint_point(i + 1), chain.h[s + 1], tolerance,
                             distance_tol, g.point[s]);
    if (i >= 1 && g.parallel[s - 1] && g.parallel[s] && g.three_parallel < 0) g.three_parallel = i - 1;
  }
  if (chain.n >= 3) {
    const std::size_t a = static_cast<std::size_t>(chain.n - 3), b = a + 1;
    g.spherical_wrist = g.intersecting[a] && g.intersecting[b] && (g.point[a] - g.point[b]).norm() <= distance_tol;
    g.wrist_point = g.point[a];
    g.spherical_shoulder = g.intersecting[0] && g.intersecting[1] && (g.point[0] - g.point[1]).norm() <= distance_tol;
    g.shoulder_point = g.point[0];
  }
  choose_family(g);
  return g;
}

std::string ChainGeometry::describe() const {
  std::ostringstream out;
  out << n << "R:";
  bool any = false;
  for (int i = 0; i + 1 < n; ++i) {
    const std::size_t s = static_cast<std::size_t>(i);
    if (parallel[s]) out << (any ? ", " : " ") << i + 1 << "||" << i + 2, any = true;
    if (intersecting[s]) out << (any ? ", " : " ") << i + 1 << "x" << i + 2, any = true;
  }
  if (!any) out << " no parallel or intersecting consecutive axes";
  if (three_parallel >= 0) {
    out << "; three parallel axes " << three_parallel + 1 << "-" << three_parallel + 2 << "-" << three_parallel + 3;
  }
  if (spherical_wrist) out << "; spherical wrist";
  if (spherical_shoulder) out << "; spherical shoulder";
  out << "; family: ";
  switch (family) {
    case IkFamily::kSphericalWrist:
      out << (reversed ? "spherical shoulder (spherical wrist of the reversed chain)" : "spherical wrist");
      break;
    case IkFamily::kThreeParallel:
      out << (reversed ? "three parallel axes 3-4-5 (UR type, reversed chain)" : "three parallel axes 2-3-4 (UR type)");
      break;
    case IkFamily::kScaraPair:
      out << (reversed ? "three parallel axes 4-5-6 and 2||3 (haptic 6R type, reversed chain)"
                       : "three parallel axes 1-2-3 and 4||5 (haptic 6R type)");
      break;
    case IkFamily::kSearch1d:
      out << (reversed ? "1-D search over joint 6 (axes 1x2 intersect)" : "1-D search over joint 1 (axes 5x6 intersect)");
      break;
    case IkFamily::kUnsupported:
      out << (n == 6 ? "none (general 6R: needs a 2-D search, not implemented)" : "none (closed forms are for 6R)");
      break;
  }
  return out.str();
}

}  // namespace hapsyn::plugins::closed_form_ik
