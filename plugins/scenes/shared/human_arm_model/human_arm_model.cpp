// The human arm model shared by the human_arm and motion scenes: the arm file, the arm's
// kinematics and closed-form IK, the ellipsoid axes. The human_arm scene (orientation set, lattice,
// options, cache, build()) lives in plugins/scenes/human_arm/.
#include "human_arm_model.hpp"

#include <hapsyn/data_file.hpp>
#include <hapsyn/json_text.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/read_file.hpp>

#include <Eigen/Cholesky>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace hapsyn::plugins {
namespace {

constexpr const char* kName = "human_arm";
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
// acos arguments up to this far beyond +-1 are rounding (a target exactly at the reach
// boundary gives 1 + a few ulp); further out the target is unreachable.
constexpr double kAcosTolerance = 1e-10;
// Below this a direction is treated as lying on a rotation axis (a degenerate branch).
constexpr double kAxisTolerance = 1e-12;

std::string show(const Json& value) { return render_value(value); }

// ---------------------------------------------------------------- arm file ----

[[noreturn]] void arm_error(const std::string& label, const std::string& path, const Json& value,
                            const std::string& rule) {
  throw Error(kName, label + ": " + path + " = " + show(value) + ": " + rule);
}

const Json& require(const Json& object, const std::string& key, const std::string& label, const std::string& path) {
  const auto it = object.find(key);
  if (it == object.end()) throw Error(kName, label + ": " + path + "." + key + ": missing");
  return *it;
}

double finite_number(const Json& value, const std::string& label, const std::string& path) {
  if (!value.is_number()) arm_error(label, path, value, "must be a number");
  const double x = value.get<double>();
  if (!std::isfinite(x)) arm_error(label, path, value, "must be finite");
  return x;
}

// A length: a number [m] or a segment name, optionally negated ("-l_ua").
double length_value(const Json& value, const HumanArmData& arm, const std::string& label, const std::string& path) {
  if (value.is_string()) {
    std::string name = value.get<std::string>();
    double sign = 1.0;
    if (!name.empty() && name[0] == '-') {
      sign = -1.0;
      name = name.substr(1);
    }
    std::string known;
    for (const auto& s : arm.segments) {
      if (s.first == name) return sign * s.second;
      known += (known.empty() ? "" : ", ") + s.first;
    }
    arm_error(label, path, value, "unknown segment (known: " + known + ")");
  }
  return finite_number(value, label, path);
}

Eigen::Matrix3d rz_rx(double theta, double alpha) {
  const double ct = std::cos(theta), st = std::sin(theta), ca = std::cos(alpha), sa = std::sin(alpha);
  Eigen::Matrix3d R;
  R << ct, -st * ca, st * sa, st, ct * ca, -ct * sa, 0.0, sa, ca;
  return R;
}

Eigen::Matrix3d rx(double alpha) { return Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitX()).toRotationMatrix(); }

double positive_mod(double x, double m) {
  double r = std::fmod(x, m);
  if (r < 0.0) r += m;
  return r;
}

// Maps a DH angle theta to the joint angle q = theta - offset inside [lower, upper], wrapping by
// 2 pi. Within kJointLimitTolerance of a limit the angle is clamped onto it (an exact 80 deg
// limit must not drop a pose over 1 ulp). Up to kSnapTolerance outside, it is clamped too but
// flagged in *snapped: near a singularity that coincides with a limit (q2 = 90 deg) the
// closed form loses digits (acos near 1 turns 1e-16 into 1e-8 rad, an axis-distance division
// amplifies that further), so the caller must verify such a solution by forward kinematics.
constexpr double kSnapTolerance = 1e-4;
bool fit_limit(double theta, double offset, double lower, double upper, double* q, bool* snapped = nullptr) {
  const double base = lower - kSnapTolerance;
  double x = base + positive_mod(theta - offset - base, 2.0 * kPi);
  if (!(x <= upper + kSnapTolerance)) return false;
  const bool outside = x < lower - kJointLimitTolerance || x > upper + kJointLimitTolerance;
  if (outside) {
    if (!snapped) return false;
    *snapped = true;
  }
  *q = std::min(std::max(x, lower), upper);
  return true;
}

// Up to two solutions of acos(c) with sign: {+a, -a}, one when a is 0 or pi; none beyond +-1.
int acos_pair(double c, double out[2]) {
  if (!std::isfinite(c) || std::abs(c) > 1.0 + kAcosTolerance) return 0;
  c = std::min(1.0, std::max(-1.0, c));
  const double a = std::acos(c);
  out[0] = a;
  if (a == 0.0 || a == kPi) return 1;
  out[1] = -a;
  return 2;
}

double deg_field(const Json& joint, const char* key, const std::string& label, const std::string& path) {
  return finite_number(require(joint, key, label, path), label, path + "." + key) * kDeg;
}

}  // namespace

// ---------------------------------------------------------------- arm data ----

HumanArmData parse_human_arm(const Json& doc, const std::string& label) {
  if (!doc.is_object()) arm_error(label, "(document)", doc, "must be a JSON object");
  HumanArmData arm;
  arm.document = doc;
  if (doc.contains("name")) arm.name = doc["name"].is_string() ? doc["name"].get<std::string>() : doc["name"].dump();
  if (doc.contains("source")) arm.source = doc["source"].is_string() ? doc["source"].get<std::string>() : "";
  arm.side = doc.value("side", std::string("right"));
  if (arm.side != "right" && arm.side != "left") arm_error(label, "side", doc["side"], "must be \"right\" or \"left\"");
  if (doc.contains("units")) {
    const Json& units = doc["units"];
    const std::pair<const char*, const char*> expected[] = {
        {"length", "m"}, {"angle", "deg"}, {"velocity", "deg/s"}, {"acceleration", "deg/s^2"}};
    for (const auto& [key, unit] : expected) {
      if (units.contains(key) && units[key] != unit) {
        arm_error(label, std::string("units.") + key, units[key], std::string("must be \"") + unit + "\"");
      }
    }
  }
  const Json& segments = require(doc, "segments", label, "");
  if (!segments.is_object()) arm_error(label, "segments", segments, "must be an object of lengths [m]");
  for (auto it = segments.begin(); it != segments.end(); ++it) {
    const double length = finite_number(it.value(), label, "segments." + it.key());
    if (!(length > 0.0)) arm_error(label, "segments." + it.key(), it.value(), "must be > 0");
    arm.segments.emplace_back(it.key(), length);
  }
  const Json& dh = require(doc, "dh", label, "");
  if (!dh.is_array() || dh.size() != 7) arm_error(label, "dh", dh, "must be an array of 7 rows");
  for (int i = 0; i < 7; ++i) {
    const std::string path = "dh[" + std::to_string(i) + "]";
    const Json& row = dh[i];
    if (!row.is_object()) arm_error(label, path, row, "must be an object {theta_offset, d, a, alpha}");
    for (auto it = row.begin(); it != row.end(); ++it) {
      if (it.key() != "theta_offset" && it.key() != "d" && it.key() != "a" && it.key() != "alpha") {
        throw Error(kName, label + ": " + path + "." + it.key() + ": unknown key (known: theta_offset, d, a, alpha)");
      }
    }
    DhRow& r = arm.dh[i];
    r.theta_offset = finite_number(require(row, "theta_offset", label, path), label, path + ".theta_offset") * kDeg;
    r.d = length_value(require(row, "d", label, path), arm, label, path + ".d");
    r.a = length_value(require(row, "a", label, path), arm, label, path + ".a");
    r.alpha = finite_number(require(row, "alpha", label, path), label, path + ".alpha") * kDeg;
  }
  const Json& joints = require(doc, "joints", label, "");
  if (!joints.is_array() || joints.size() != 7) arm_error(label, "joints", joints, "must be an array of 7 joints");
  for (int i = 0; i < 7; ++i) {
    const std::string path = "joints[" + std::to_string(i) + "]";
    const Json& joint = joints[i];
    if (!joint.is_object()) arm_error(label, path, joint, "must be an object");
    arm.lower(i) = deg_field(joint, "lower", label, path);
    arm.upper(i) = deg_field(joint, "upper", label, path);
    arm.velocity_max(i) = deg_field(joint, "velocity_max", label, path);
    arm.acceleration_max(i) = deg_field(joint, "acceleration_max", label, path);
    if (!(arm.lower(i) <= arm.upper(i))) {
      arm_error(label, path + ".upper", joint["upper"], "must be >= lower (" + show(joint["lower"]) + ")");
    }
    if (!(arm.velocity_max(i) > 0.0)) arm_error(label, path + ".velocity_max", joint["velocity_max"], "must be > 0");
    if (!(arm.acceleration_max(i) > 0.0)) {
      arm_error(label, path + ".acceleration_max", joint["acceleration_max"], "must be > 0");
    }
  }
  // The closed-form IK needs this structure; say which entry breaks it.
  const auto must_be_zero = [&](int i, const char* key, double value) {
    if (value != 0.0) {
      arm_error(label, "dh[" + std::to_string(i) + "]." + key, dh[i][key],
                "must be 0 (the closed-form IK needs a spherical shoulder at the origin, an elbow on the "
                "upper-arm axis and a spherical wrist)");
    }
  };
  for (int i = 0; i < 6; ++i) must_be_zero(i, "a", arm.dh[i].a);
  for (int i : {0, 1, 3, 5}) must_be_zero(i, "d", arm.dh[i].d);
  for (int i : {2, 4}) {
    if (arm.dh[i].d == 0.0) arm_error(label, "dh[" + std::to_string(i) + "].d", dh[i]["d"], "must be != 0 (a limb length)");
  }
  const auto twist_needed = [&](int i, double value) {
    if (std::abs(value) < 1e-6) {
      arm_error(label, "dh[" + std::to_string(i) + "].alpha", dh[i]["alpha"],
                "sin(alpha) must not be 0 here (adjacent joint axes would be parallel: no closed-form IK)");
    }
  };
  twist_needed(0, std::sin(arm.dh[0].alpha));
  twist_needed(2, std::sin(arm.dh[2].alpha));
  twist_needed(3, std::sin(arm.dh[3].alpha));
  twist_needed(4, std::sin(arm.dh[4].alpha));
  twist_needed(5, std::sin(arm.dh[5].alpha));
  return arm;
}

HumanArmData load_human_arm(const std::string& path) {
  // A FIFO, a device or a huge file is refused before it is read (an arm file is a few kB).
  const std::string text = read_regular_file(path, kName, "arm file", kHumanArmMaxArmFileBytes);
  const Json doc = parse_json_text(text, path, kName);
  HumanArmData arm = parse_human_arm(doc, path);
  arm.file = path;
  return arm;
}

std::string resolve_arm_file(const std::string& option) {
  // An empty option means the default, the shipped right arm.
  return find_data_file(kName, "arm_file", option.empty() ? kHumanArmDefaultArmFile : option);
}

// ---------------------------------------------------------------- kinematics ----

HumanArm::HumanArm(HumanArmData data) : data_(std::move(data)) {
  const DhRow& last = data_.dh[6];
  palm_offset_ = rx(-last.alpha) * Eigen::Vector3d(last.a, 0.0, last.d);
  reach_ = std::abs(data_.dh[2].d) + std::abs(data_.dh[4].d) + palm_offset_.norm();
}

Eigen::Isometry3d HumanArm::forward(const Vector7d& q) const {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < 7; ++i) {
    const DhRow& r = data_.dh[i];
    const double theta = q(i) + r.theta_offset;
    p += R * Eigen::Vector3d(r.a * std::cos(theta), r.a * std::sin(theta), r.d);
    R = R * rz_rx(theta, r.alpha);
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = p;
  return T;
}

std::array<Eigen::Vector3d, 8> HumanArm::frame_origins(const Vector7d& q) const {
  std::array<Eigen::Vector3d, 8> origins;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  origins[0].setZero();
  for (int i = 0; i < 7; ++i) {
    const DhRow& r = data_.dh[i];
    const double theta = q(i) + r.theta_offset;
    origins[i + 1] = origins[i] + R * Eigen::Vector3d(r.a * std::cos(theta), r.a * std::sin(theta), r.d);
    R = R * rz_rx(theta, r.alpha);
  }
  return origins;
}

Matrix67d HumanArm::jacobian(const Vector7d& q) const {
  // Joint i turns about z_{i-1} through o_{i-1} (standard DH): collect them, then the palm.
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 3, 7> z, o;
  for (int i = 0; i < 7; ++i) {
    z.col(i) = R.col(2);
    o.col(i) = p;
    const DhRow& r = data_.dh[i];
    const double theta = q(i) + r.theta_offset;
    p += R * Eigen::Vector3d(r.a * std::cos(theta), r.a * std::sin(theta), r.d);
    R = R * rz_rx(theta, r.alpha);
  }
  Matrix67d J;
  for (int i = 0; i < 7; ++i) {
    J.block<3, 1>(0, i) = z.col(i);
    J.block<3, 1>(3, i) = z.col(i).cross(p - o.col(i));
  }
  return J;
}

double HumanArm::manipulability(const Vector7d& q) const {
  const Matrix67d J = jacobian(q);
  const Matrix6d JJt = J * J.transpose();
  // LDLT of the symmetric positive semi-definite J J^T: det = prod(D); tiny negative pivots are
  // rounding at a singularity, so the product is clamped to 0 rather than giving NaN.
  const Eigen::LDLT<Matrix6d> ldlt(JJt);
  double det = 1.0;
  for (int i = 0; i < 6; ++i) det *= std::max(0.0, ldlt.vectorD()(i));
  return std::sqrt(std::max(0.0, det));
}

std::vector<double> HumanArm::joint3_grid(int steps) const {
  const double lo = data_.lower(2), hi = data_.upper(2);
  std::vector<double> grid;
  if (steps <= 1) return {0.5 * (lo + hi)};
  for (int k = 0; k < steps; ++k) {
    // Both ends exactly on the limits (no accumulated rounding).
    grid.push_back(k == steps - 1 ? hi : lo + (hi - lo) * k / (steps - 1));
  }
  return grid;
}

int HumanArm::solve(const Eigen::Matrix3d& R, const Eigen::Vector3d& p, double q3, ArmIkSolution out[8]) const {
  const auto& dh = data_.dh;
  const Vector7d& lo = data_.lower;
  const Vector7d& hi = data_.upper;
  const double d3 = dh[2].d, d5 = dh[4].d;
  const Eigen::Vector3d w = p - R * palm_offset_;  // wrist centre in S

  // Elbow: |w|^2 = d3^2 + d5^2 + 2 d3 d5 (cos a3 cos a4 - sin a3 sin a4 cos theta4), independent of q3.
  const double sa3 = std::sin(dh[2].alpha), ca3 = std::cos(dh[2].alpha);
  const double sa4 = std::sin(dh[3].alpha), ca4 = std::cos(dh[3].alpha);
  const double k = (w.squaredNorm() - d3 * d3 - d5 * d5) / (2.0 * d3 * d5);
  double theta4s[2];
  const int n4 = acos_pair((ca3 * ca4 - k) / (sa3 * sa4), theta4s);

  double q3_fit;
  if (!fit_limit(q3 + dh[2].theta_offset, dh[2].theta_offset, lo(2), hi(2), &q3_fit)) return 0;
  const double theta3 = q3_fit + dh[2].theta_offset;
  const Eigen::Matrix3d R23 = rz_rx(theta3, dh[2].alpha);
  const double sa1 = std::sin(dh[0].alpha), ca1 = std::cos(dh[0].alpha);
  const double sa5 = std::sin(dh[4].alpha), ca5 = std::cos(dh[4].alpha);
  const double sa6 = std::sin(dh[5].alpha), ca6 = std::cos(dh[5].alpha);
  const Eigen::Matrix3d R_palm = R * rx(-dh[6].alpha);

  int count = 0;
  for (int i4 = 0; i4 < n4; ++i4) {
    Vector7d q;
    q(2) = q3_fit;
    bool snap4 = false;
    if (!fit_limit(theta4s[i4], dh[3].theta_offset, lo(3), hi(3), &q(3), &snap4)) continue;
    const double theta4 = q(3) + dh[3].theta_offset;
    const Eigen::Matrix3d R34 = rz_rx(theta4, dh[3].alpha);
    const Eigen::Vector3d v2 = Eigen::Vector3d(0.0, 0.0, d3) + d5 * (R23 * R34.col(2));
    const Eigen::Vector3d u = rx(dh[1].alpha) * v2;

    // Shoulder: w = Rz(theta1) Rx(alpha1) Rz(theta2) u; the z row fixes theta2, the rest theta1.
    const double rho = std::hypot(u.x(), u.y());
    double theta2s[2];
    int n2;
    if (rho < kAxisTolerance) {
      // u on axis 2: theta2 is free (degenerate); take the middle of the joint-2 range.
      if (std::abs(w.z() - ca1 * u.z()) > 1e-9) continue;
      theta2s[0] = 0.5 * (lo(1) + hi(1)) + dh[1].theta_offset;
      n2 = 1;
    } else {
      double a[2];
      n2 = acos_pair((w.z() - ca1 * u.z()) / (sa1 * rho), a);
      const double phi = std::atan2(u.x(), u.y());
      for (int j = 0; j < n2; ++j) theta2s[j] = phi + a[j];
    }
    for (int i2 = 0; i2 < n2; ++i2) {
      bool snap2 = snap4;
      if (!fit_limit(theta2s[i2], dh[1].theta_offset, lo(1), hi(1), &q(1), &snap2)) continue;
      const double theta2 = q(1) + dh[1].theta_offset;
      const Eigen::Vector3d m = rx(dh[0].alpha) * (Eigen::AngleAxisd(theta2, Eigen::Vector3d::UnitZ()) * u);
      double theta1;
      if (std::hypot(w.x(), w.y()) < kAxisTolerance && std::hypot(m.x(), m.y()) < kAxisTolerance) {
        theta1 = 0.5 * (lo(0) + hi(0)) + dh[0].theta_offset;  // wrist centre on axis 1: free
      } else {
        theta1 = std::atan2(w.y(), w.x()) - std::atan2(m.y(), m.x());
      }
      if (!fit_limit(theta1, dh[0].theta_offset, lo(0), hi(0), &q(0), &snap2)) continue;
      const double theta1f = q(0) + dh[0].theta_offset;
      const Eigen::Matrix3d R02 = rz_rx(theta1f, dh[0].alpha) * rz_rx(theta2, dh[1].alpha);
      const Eigen::Matrix3d R04 = R02 * R23 * R34;
      // Wrist: R' = R04^T R Rx(-alpha7) = Rz(theta5) Rx(alpha5) Rz(theta6) Rx(alpha6) Rz(theta7).
      const Eigen::Matrix3d Rw = R04.transpose() * R_palm;
      const Eigen::Vector3d r = Rw.col(2);
      double theta6s[2];
      const int n6 = acos_pair((ca5 * ca6 - r.z()) / (sa5 * sa6), theta6s);
      for (int i6 = 0; i6 < n6; ++i6) {
        bool snap6 = snap2;
        if (!fit_limit(theta6s[i6], dh[5].theta_offset, lo(5), hi(5), &q(5), &snap6)) continue;
        const double theta6 = q(5) + dh[5].theta_offset;
        const Eigen::Vector3d n = rx(dh[4].alpha) * (rz_rx(theta6, dh[5].alpha).col(2));
        double theta5;
        if (std::hypot(r.x(), r.y()) < kAxisTolerance || std::hypot(n.x(), n.y()) < kAxisTolerance) {
          theta5 = 0.5 * (lo(4) + hi(4)) + dh[4].theta_offset;  // wrist singular: theta5 free
        } else {
          theta5 = std::atan2(r.y(), r.x()) - std::atan2(n.y(), n.x());
        }
        if (!fit_limit(theta5, dh[4].theta_offset, lo(4), hi(4), &q(4), &snap6)) continue;
        const double theta5f = q(4) + dh[4].theta_offset;
        const Eigen::Matrix3d G = (rz_rx(theta5f, dh[4].alpha) * rz_rx(theta6, dh[5].alpha)).transpose() * Rw;
        const double theta7 = std::atan2(G(1, 0), G(0, 0));
        if (!fit_limit(theta7, dh[6].theta_offset, lo(6), hi(6), &q(6), &snap6)) continue;
        if (snap6) {
          // A clamped angle is kept only when the clamped configuration still reaches the pose.
          const Eigen::Isometry3d T = forward(q);
          if (!((T.translation() - p).norm() <= 1e-9 && (T.linear() - R).cwiseAbs().maxCoeff() <= 1e-9)) continue;
        }
        out[count++].q = q;
      }
    }
  }
  return count;
}

bool HumanArm::best(const Eigen::Matrix3d& R, const Eigen::Vector3d& p, const std::vector<double>& q3_grid,
                    Vector7d* q, double* manipulability_out) const {
  // Cheap reject before any joint-3 value: the wrist centre must be within the limb lengths.
  const Eigen::Vector3d w = p - R * palm_offset_;
  const double limb = std::abs(data_.dh[2].d) + std::abs(data_.dh[4].d);
  if (w.norm() > limb * (1.0 + 1e-9)) return false;
  bool found = false;
  double best_value = -1.0;
  ArmIkSolution solutions[8];
  for (const double q3 : q3_grid) {
    const int n = solve(R, p, q3, solutions);
    for (int i = 0; i < n; ++i) {
      const double m = manipulability(solutions[i].q);
      if (m > best_value) {
        best_value = m;
        *q = solutions[i].q;
        found = true;
      }
    }
  }
  if (found) *manipulability_out = best_value;
  return found;
}

Matrix6d ellipsoid_axes(const Matrix67d& J, const Vector7d& scale) {
  const Matrix67d Js = J * scale.asDiagonal();
  const Eigen::JacobiSVD<Matrix67d> svd(Js, Eigen::ComputeFullU);
  Matrix6d M = svd.matrixU() * svd.singularValues().asDiagonal();
  for (int c = 0; c < 6; ++c) {
    Eigen::Index at;
    M.col(c).cwiseAbs().maxCoeff(&at);
    if (M(at, c) < 0.0) M.col(c) = -M.col(c);
  }
  return M;
}

}  // namespace hapsyn::plugins
