#include "human_arm.hpp"

#include <hapsyn/data_file.hpp>

#include <hapsyn/error.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/parallel.hpp>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SVD>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <unistd.h>

namespace hapsyn::plugins {
namespace {

namespace fs = std::filesystem;

constexpr const char* kName = "human_arm";
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
// acos arguments up to this far beyond +-1 are rounding (a target exactly at the reach
// boundary gives 1 + a few ulp); further out the target is unreachable.
constexpr double kAcosTolerance = 1e-10;
// Below this a direction is treated as lying on a rotation axis (a degenerate branch).
constexpr double kAxisTolerance = 1e-12;

// Changing the IK, the sampling or the payload layout must change one of these: the cache key
// carries both, so old files are rebuilt instead of trusted.
constexpr std::uint32_t kCacheFormatVersion = 1;
constexpr int kAlgorithmVersion = 1;
constexpr char kCacheMagic[8] = {'H', 'A', 'P', 'S', 'Y', 'N', 'H', 'A'};

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
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(kName, path + ": cannot be read");
  std::stringstream buffer;
  buffer << in.rdbuf();
  Json doc;
  try {
    doc = Json::parse(buffer.str());
  } catch (const Json::parse_error& e) {
    throw Error(kName, path + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  HumanArmData arm = parse_human_arm(doc, path);
  arm.file = path;
  return arm;
}

std::string resolve_arm_file(const std::string& option) {
  // An empty option means the shipped right arm.
  return find_data_file(kName, "arm_file", option.empty() ? "human_arm/fennel2022_right_arm.json" : option);
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

std::vector<Eigen::Quaterniond> orientation_set(int n) {
  // Plastic number: the real root of x^3 = x + 1 (the generalized golden ratio for 3 dims).
  constexpr double kPlastic = 1.32471795724474602596;
  const double g1 = 1.0 / kPlastic, g2 = 1.0 / (kPlastic * kPlastic);
  std::vector<Eigen::Quaterniond> set;
  set.reserve(static_cast<std::size_t>(std::max(0, n)));
  for (int i = 0; i < n; ++i) {
    const double u1 = (i + 0.5) / n;
    const double u2 = positive_mod(i * g1, 1.0);
    const double u3 = positive_mod(i * g2, 1.0);
    const double psi = kPi * (u3 - 0.5);  // [-pi/2, pi/2): cos >= 0, the w >= 0 hemisphere
    const double chi = 2.0 * kPi * u2;
    const double r1 = std::sqrt(u1), r2 = std::sqrt(1.0 - u1);
    Eigen::Quaterniond q(r1 * std::cos(psi), r2 * std::sin(chi), r2 * std::cos(chi), r1 * std::sin(psi));
    q.normalize();
    if (q.w() < 0.0) q.w() = 0.0;  // cos(-pi/2) rounding; never negative
    set.push_back(q);
  }
  return set;
}

std::vector<double> lattice_axis(double step, double extent) {
  const int m = static_cast<int>(std::floor(extent / step + 1e-9));
  std::vector<double> axis;
  for (int k = -m; k <= m; ++k) axis.push_back(k * step);
  return axis;
}

// ---------------------------------------------------------------- options ----

namespace {

const std::vector<std::string> kOptionNames = {"arm_file", "lattice_step", "lattice_extent", "orientations",
                                               "joint3_steps", "x_S_B", "C_S_B", "C_E_P", "x_E_P",
                                               "cache", "cache_directory", "threads"};

double option_number(const Json& options, const char* key, double fallback, bool positive) {
  const auto it = options.find(key);
  if (it == options.end()) return fallback;
  if (!it->is_number()) throw Error(kName, std::string("options.") + key + " = " + show(*it) + ": must be a number");
  const double v = it->get<double>();
  if (!std::isfinite(v)) throw Error(kName, std::string("options.") + key + " = " + show(*it) + ": must be finite");
  if (positive && !(v > 0.0)) throw Error(kName, std::string("options.") + key + " = " + show(*it) + ": must be > 0");
  return v;
}

int option_int(const Json& options, const char* key, int fallback, int lower, int upper) {
  const auto it = options.find(key);
  if (it == options.end()) return fallback;
  if (!it->is_number_integer()) {
    throw Error(kName, std::string("options.") + key + " = " + show(*it) + ": must be an integer");
  }
  const long long v = it->get<long long>();
  if (v < lower || v > upper) {
    throw Error(kName, std::string("options.") + key + " = " + show(*it) + ": must be in [" + std::to_string(lower) +
                           ", " + std::to_string(upper) + "]");
  }
  return static_cast<int>(v);
}

Eigen::Vector3d option_vector(const Json& options, const char* key, const Eigen::Vector3d& fallback) {
  const auto it = options.find(key);
  if (it == options.end()) return fallback;
  if (!it->is_array() || it->size() != 3) {
    throw Error(kName, std::string("options.") + key + " = " + show(*it) + ": must be an array of 3 numbers [m]");
  }
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    const Json& x = (*it)[i];
    if (!x.is_number() || !std::isfinite(x.get<double>())) {
      throw Error(kName, std::string("options.") + key + " = " + show(*it) + ": must be an array of 3 finite numbers");
    }
    v(i) = x.get<double>();
  }
  return v;
}

Eigen::Matrix3d option_rotation(const Json& options, const char* key, const Eigen::Matrix3d& fallback) {
  const auto it = options.find(key);
  if (it == options.end()) return fallback;
  const std::string rule = ": must be a 3x3 rotation matrix given as 3 rows of 3 numbers";
  if (!it->is_array() || it->size() != 3) throw Error(kName, std::string("options.") + key + " = " + show(*it) + rule);
  Eigen::Matrix3d C;
  for (int r = 0; r < 3; ++r) {
    const Json& row = (*it)[r];
    if (!row.is_array() || row.size() != 3) throw Error(kName, std::string("options.") + key + " = " + show(*it) + rule);
    for (int c = 0; c < 3; ++c) {
      if (!row[c].is_number() || !std::isfinite(row[c].get<double>())) {
        throw Error(kName, std::string("options.") + key + " = " + show(*it) + rule);
      }
      C(r, c) = row[c].get<double>();
    }
  }
  const double orthogonality = (C.transpose() * C - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(orthogonality <= 1e-6) || !(C.determinant() > 0.0)) {
    std::ostringstream s;
    s << "options." << key << " = " << show(*it) << ": must be a rotation matrix (orthonormal, det +1); max |C^T C - I| = "
      << orthogonality << ", det = " << C.determinant();
    throw Error(kName, s.str());
  }
  return C;
}

Eigen::Matrix3d paper_C_S_B() {
  Eigen::Matrix3d C;
  C << 0, -1, 0, 0, 0, 1, -1, 0, 0;
  return C;
}

Eigen::Matrix3d paper_C_E_P() {
  Eigen::Matrix3d C;
  C << 0, 0, 1, 0, -1, 0, 1, 0, 0;
  return C;
}

Json vector_json(const Eigen::Vector3d& v) { return Json::array({v(0), v(1), v(2)}); }
Json matrix_json(const Eigen::Matrix3d& C) {
  Json rows = Json::array();
  for (int r = 0; r < 3; ++r) rows.push_back(Json::array({C(r, 0), C(r, 1), C(r, 2)}));
  return rows;
}

}  // namespace

HumanArmSceneOptions parse_human_arm_scene_options(const Json& options) {
  HumanArmSceneOptions o;
  o.C_S_B = paper_C_S_B();
  o.C_E_P = paper_C_E_P();
  if (!options.is_null() && !options.is_object()) throw Error(kName, "options = " + show(options) + ": must be an object");
  const Json opts = options.is_null() ? Json::object() : options;
  for (auto it = opts.begin(); it != opts.end(); ++it) {
    if (std::find(kOptionNames.begin(), kOptionNames.end(), it.key()) == kOptionNames.end()) {
      std::string known;
      for (const auto& k : kOptionNames) known += (known.empty() ? "" : ", ") + k;
      throw Error(kName, "options." + it.key() + ": unknown option (known: " + known + ")");
    }
  }
  std::string arm_option;
  if (opts.contains("arm_file")) {
    if (!opts["arm_file"].is_string()) throw Error(kName, "options.arm_file = " + show(opts["arm_file"]) + ": must be a string");
    arm_option = opts["arm_file"].get<std::string>();
  }
  o.arm_file = resolve_arm_file(arm_option);
  o.lattice_step = option_number(opts, "lattice_step", o.lattice_step, true);
  o.lattice_extent = option_number(opts, "lattice_extent", o.lattice_extent, false);
  if (o.lattice_extent < 0.0) {
    throw Error(kName, "options.lattice_extent = " + show(opts["lattice_extent"]) + ": must be >= 0");
  }
  const double per_axis = 2.0 * std::floor(o.lattice_extent / o.lattice_step + 1e-9) + 1.0;
  if (per_axis > 401.0) {
    throw Error(kName, "options.lattice_step = " + show(Json(o.lattice_step)) + ": gives " + show(Json(per_axis)) +
                           " lattice points per axis; at most 401 are allowed (lattice_extent " +
                           show(Json(o.lattice_extent)) + ")");
  }
  o.orientations = option_int(opts, "orientations", o.orientations, 1, 1000000);
  o.joint3_steps = option_int(opts, "joint3_steps", o.joint3_steps, 1, 10000);
  o.x_S_B = option_vector(opts, "x_S_B", o.x_S_B);
  o.x_E_P = option_vector(opts, "x_E_P", o.x_E_P);
  o.C_S_B = option_rotation(opts, "C_S_B", o.C_S_B);
  o.C_E_P = option_rotation(opts, "C_E_P", o.C_E_P);
  if (opts.contains("cache")) {
    if (!opts["cache"].is_boolean()) throw Error(kName, "options.cache = " + show(opts["cache"]) + ": must be true or false");
    o.cache = opts["cache"].get<bool>();
  }
  if (opts.contains("cache_directory")) {
    if (!opts["cache_directory"].is_string()) {
      throw Error(kName, "options.cache_directory = " + show(opts["cache_directory"]) + ": must be a string");
    }
    o.cache_directory = opts["cache_directory"].get<std::string>();
  }
  o.threads = option_int(opts, "threads", o.threads, 0, 4096);
  return o;
}

// ---------------------------------------------------------------- scene ----

std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t seed) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  std::uint64_t h = seed;
  for (std::size_t i = 0; i < size; ++i) {
    h ^= bytes[i];
    h *= 1099511628211ULL;
  }
  return h;
}

namespace {

// The scene's samples in compact form: what the cache stores. Poses are recomputed from the
// indices (the same code as a fresh build, so a cached scene equals a built one bit for bit).
struct RawScene {
  std::vector<std::int32_t> lattice, orientation;
  std::vector<double> q, manipulability, mv, ma;  // n*7, n, n*36, n*36
  std::uint64_t size() const { return lattice.size(); }
};

std::string default_cache_directory() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return (fs::path(xdg) / "hapsyn").string();
  if (const char* home = std::getenv("HOME"); home && *home) return (fs::path(home) / ".cache" / "hapsyn").string();
  return "";
}

template <class T>
void put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <class T>
void put_array(std::string& out, const std::vector<T>& values) {
  if (!values.empty()) out.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

// Reads from a byte buffer; every read is bounds-checked so a truncated file is detected.
struct Reader {
  const std::string& bytes;
  std::size_t at = 0;
  template <class T>
  bool get(T* value) {
    if (bytes.size() - at < sizeof(T) || at > bytes.size()) return false;
    std::memcpy(value, bytes.data() + at, sizeof(T));
    at += sizeof(T);
    return true;
  }
  template <class T>
  bool get_array(std::vector<T>* values, std::uint64_t count) {
    if (count > (bytes.size() - at) / sizeof(T)) return false;
    values->resize(count);
    if (count) std::memcpy(values->data(), bytes.data() + at, count * sizeof(T));
    at += count * sizeof(T);
    return true;
  }
};

std::string payload_bytes(const RawScene& raw) {
  std::string payload;
  put_array(payload, raw.lattice);
  put_array(payload, raw.orientation);
  put_array(payload, raw.q);
  put_array(payload, raw.manipulability);
  put_array(payload, raw.mv);
  put_array(payload, raw.ma);
  return payload;
}

// Writes the cache atomically (write_file_atomically). Returns
// "" on success, else why it failed (a failed write never fails the build).
std::string write_cache(const std::string& file, const std::string& key, const RawScene& raw, bool ellipsoids) {
  try {
    const fs::path path(file);
    fs::create_directories(path.parent_path());
    const std::string payload = payload_bytes(raw);
    std::string out;
    out.append(kCacheMagic, sizeof kCacheMagic);
    put(out, kCacheFormatVersion);
    put(out, static_cast<std::uint32_t>(ellipsoids ? 1 : 0));
    put(out, static_cast<std::uint64_t>(key.size()));
    out += key;
    put(out, raw.size());
    put(out, static_cast<std::uint64_t>(payload.size()));
    put(out, fnv1a64(payload.data(), payload.size()));
    put(out, fnv1a64(out.data(), out.size()));  // header checksum
    write_file_atomically(file, {out, payload});
    return "";
  } catch (const std::exception& e) {
    return e.what();
  }
}

// Reads a cache file. Returns "" and fills raw when it is intact and made for `key`; else the
// reason it is not used ("missing", "corrupt: ...", "stale: ...").
std::string read_cache(const std::string& file, const std::string& key, bool ellipsoids, int lattice_points,
                       int orientations, RawScene* raw) {
  std::ifstream f(file, std::ios::binary);
  if (!f) return "missing";
  std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  Reader r{bytes};
  char magic[8];
  if (!r.get(&magic) || std::memcmp(magic, kCacheMagic, sizeof magic) != 0) return "corrupt: not a human_arm cache file";
  std::uint32_t version = 0, flags = 0;
  if (!r.get(&version)) return "corrupt: truncated header";
  if (version != kCacheFormatVersion) return "stale: format version " + std::to_string(version);
  std::uint64_t key_size = 0;
  if (!r.get(&flags) || !r.get(&key_size) || key_size > bytes.size() - r.at) return "corrupt: truncated header";
  const std::string stored_key = bytes.substr(r.at, key_size);
  r.at += key_size;
  std::uint64_t n = 0, payload_size = 0, payload_sum = 0, header_sum = 0;
  if (!r.get(&n) || !r.get(&payload_size) || !r.get(&payload_sum)) return "corrupt: truncated header";
  const std::size_t header_end = r.at;
  if (!r.get(&header_sum) || header_sum != fnv1a64(bytes.data(), header_end)) return "corrupt: header checksum";
  if (stored_key != key || (flags != 0) != ellipsoids) return "stale: made for other options or another arm file";
  const std::uint64_t per_sample = 2 * sizeof(std::int32_t) + 8 * sizeof(double) + (ellipsoids ? 72 * sizeof(double) : 0);
  if (n > (std::uint64_t(1) << 40) || payload_size != n * per_sample) return "corrupt: payload size";
  if (bytes.size() - r.at != payload_size) return "corrupt: truncated or oversized payload";
  if (fnv1a64(bytes.data() + r.at, payload_size) != payload_sum) return "corrupt: payload checksum";
  RawScene s;
  if (!r.get_array(&s.lattice, n) || !r.get_array(&s.orientation, n) || !r.get_array(&s.q, n * 7) ||
      !r.get_array(&s.manipulability, n) || !r.get_array(&s.mv, ellipsoids ? n * 36 : 0) ||
      !r.get_array(&s.ma, ellipsoids ? n * 36 : 0)) {
    return "corrupt: truncated payload";
  }
  for (std::uint64_t i = 0; i < n; ++i) {
    if (s.lattice[i] < 0 || s.lattice[i] >= lattice_points || s.orientation[i] < 0 || s.orientation[i] >= orientations) {
      return "corrupt: sample index out of range";
    }
  }
  for (const auto* v : {&s.q, &s.manipulability, &s.mv, &s.ma}) {
    for (double x : *v) {
      if (!std::isfinite(x)) return "corrupt: non-finite value";
    }
  }
  *raw = std::move(s);
  return "";
}

}  // namespace

HumanArmScene::HumanArmScene(const Json& options)
    : options_(parse_human_arm_scene_options(options)), arm_(load_human_arm(options_.arm_file)) {}

std::string HumanArmScene::cache_key(bool ellipsoids) const {
  const HumanArmSceneOptions& o = options_;
  // Everything the samples depend on, and nothing else (threads and the cache location do not
  // change the result).
  const Json key = {{"scene", "human_arm"},
                    {"format_version", kCacheFormatVersion},
                    {"algorithm_version", kAlgorithmVersion},
                    {"arm", arm_.data().document},
                    {"lattice_step", o.lattice_step},
                    {"lattice_extent", o.lattice_extent},
                    {"orientations", o.orientations},
                    {"joint3_steps", o.joint3_steps},
                    {"x_S_B", vector_json(o.x_S_B)},
                    {"C_S_B", matrix_json(o.C_S_B)},
                    {"C_E_P", matrix_json(o.C_E_P)},
                    {"x_E_P", vector_json(o.x_E_P)},
                    {"ellipsoids", ellipsoids}};
  return key.dump();
}

std::string HumanArmScene::cache_file(bool ellipsoids) const {
  if (!options_.cache) return "";
  const std::string dir = options_.cache_directory.empty() ? default_cache_directory() : options_.cache_directory;
  if (dir.empty()) return "";
  const std::string key = cache_key(ellipsoids);
  char name[64];
  std::snprintf(name, sizeof name, "human_arm-%016llx.bin",
                static_cast<unsigned long long>(fnv1a64(key.data(), key.size())));
  return (fs::path(dir) / name).string();
}

SampleSet HumanArmScene::build(const SceneRequest& request) const {
  const auto start = std::chrono::steady_clock::now();
  bool want_mv = false, want_ma = false;
  for (const std::string& a : request.attributes) {
    if (a == "M_v") {
      want_mv = true;
    } else if (a == "M_a") {
      want_ma = true;
    } else if (a != "shoulder_pose" && a != "human_q" && a != "manipulability" && a != "lattice_index") {
      throw Error(kName, "per-sample attribute '" + a +
                             "' requested: this scene provides shoulder_pose, human_q, manipulability, lattice_index, "
                             "M_v, M_a");
    }
  }
  const bool ellipsoids = want_mv || want_ma;
  const HumanArmSceneOptions& o = options_;
  const std::vector<double> axis = lattice_axis(o.lattice_step, o.lattice_extent);
  const int n_axis = static_cast<int>(axis.size());
  const int n_lattice = n_axis * n_axis * n_axis;
  const std::vector<Eigen::Quaterniond> rotations = orientation_set(o.orientations);
  const auto lattice_point = [&](int index) {
    return Eigen::Vector3d(axis[index % n_axis], axis[(index / n_axis) % n_axis], axis[index / (n_axis * n_axis)]);
  };

  Json info = Json::object();
  const std::string file = cache_file(ellipsoids);
  const std::string key = file.empty() ? std::string() : cache_key(ellipsoids);
  RawScene raw;
  bool from_cache = false;
  std::string cache_status = o.cache ? (file.empty() ? "off: no cache directory ($XDG_CACHE_HOME and $HOME unset)" : "")
                                     : "off";
  if (!file.empty()) {
    const std::string why = read_cache(file, key, ellipsoids, n_lattice, o.orientations, &raw);
    if (why.empty()) {
      from_cache = true;
      cache_status = "hit";
    } else {
      cache_status = why == "missing" ? "miss: built" : "rebuilt (" + why + ")";
    }
  }
  if (!from_cache) {
    const std::vector<double> grid = arm_.joint3_grid(o.joint3_steps);
    std::vector<Eigen::Matrix3d> matrices(rotations.size());
    for (std::size_t i = 0; i < rotations.size(); ++i) matrices[i] = rotations[i].toRotationMatrix();
    std::vector<RawScene> per_point(static_cast<std::size_t>(n_lattice));
    const int threads = o.threads > 0 ? o.threads : hardware_threads();
    // Lattice points far from the shoulder cost nothing; near ones cost a full orientation
    // sweep: dynamic scheduling balances them.
    parallel_for_dynamic(n_lattice, threads, 1, [&](long long index, int) {
      const Eigen::Vector3d p = lattice_point(static_cast<int>(index));
      if (p.norm() > arm_.reach() * (1.0 + 1e-9)) return;
      RawScene& out = per_point[static_cast<std::size_t>(index)];
      Vector7d q;
      double m = 0.0;
      for (int k = 0; k < o.orientations; ++k) {
        if (!arm_.best(matrices[k], p, grid, &q, &m)) continue;
        out.lattice.push_back(static_cast<std::int32_t>(index));
        out.orientation.push_back(k);
        out.q.insert(out.q.end(), q.data(), q.data() + 7);
        out.manipulability.push_back(m);
        if (ellipsoids) {
          Matrix67d J = arm_.jacobian(q);
          // Twist of E rather than P when x_E^P != 0: v_E = v_P + omega x r, r = C_P^S x_E^P.
          const Eigen::Vector3d r = matrices[k] * o.x_E_P;
          for (int c = 0; c < 7; ++c) J.block<3, 1>(3, c) += J.block<3, 1>(0, c).cross(r);
          // Then rotate both halves into B: blockdiag(C_S^B, C_S^B) M^S, as eq. (12) does.
          for (const auto& [scale, target] : {std::pair{&arm_.data().velocity_max, &out.mv},
                                              std::pair{&arm_.data().acceleration_max, &out.ma}}) {
            Matrix6d M = ellipsoid_axes(J, *scale);
            M.topRows<3>() = (o.C_S_B * M.topRows<3>()).eval();
            M.bottomRows<3>() = (o.C_S_B * M.bottomRows<3>()).eval();
            const Eigen::Matrix<double, 6, 6, Eigen::RowMajor> row_major = M;
            target->insert(target->end(), row_major.data(), row_major.data() + 36);
          }
        }
      }
    });
    for (RawScene& s : per_point) {
      raw.lattice.insert(raw.lattice.end(), s.lattice.begin(), s.lattice.end());
      raw.orientation.insert(raw.orientation.end(), s.orientation.begin(), s.orientation.end());
      raw.q.insert(raw.q.end(), s.q.begin(), s.q.end());
      raw.manipulability.insert(raw.manipulability.end(), s.manipulability.begin(), s.manipulability.end());
      raw.mv.insert(raw.mv.end(), s.mv.begin(), s.mv.end());
      raw.ma.insert(raw.ma.end(), s.ma.begin(), s.ma.end());
      s = RawScene();
    }
    if (!file.empty()) {
      const std::string failure = write_cache(file, key, raw, ellipsoids);
      if (!failure.empty()) cache_status += "; cache not written: " + failure;
    }
  }

  SampleSet set;
  set.coordinates = {"x", "y", "z", "qw", "qx", "qy", "qz"};
  set.unit = "m";
  const Eigen::Index n = static_cast<Eigen::Index>(raw.size());
  set.poses.resize(n, 7);
  SampleSet::RowMatrix shoulder(n, 7), human_q(n, 7), manip(n, 1), lattice_index(n, 1);
  const Eigen::Quaterniond q_S_B(o.C_S_B), q_E_P(o.C_E_P);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d p = lattice_point(raw.lattice[i]);
    const Eigen::Quaterniond& r = rotations[static_cast<std::size_t>(raw.orientation[i])];
    shoulder.row(i) << p(0), p(1), p(2), r.w(), r.x(), r.y(), r.z();
    // T_E^B = T_S^B T_P^S T_E^P.
    const Eigen::Vector3d x = o.x_S_B + o.C_S_B * (p + r.toRotationMatrix() * o.x_E_P);
    Eigen::Quaterniond qb = (q_S_B * r * q_E_P).normalized();
    if (qb.w() < 0.0) qb.coeffs() = -qb.coeffs();
    set.poses.row(i) << x(0), x(1), x(2), qb.w(), qb.x(), qb.y(), qb.z();
    for (int j = 0; j < 7; ++j) human_q(i, j) = raw.q[static_cast<std::size_t>(i) * 7 + j];
    manip(i, 0) = raw.manipulability[static_cast<std::size_t>(i)];
    lattice_index(i, 0) = raw.lattice[static_cast<std::size_t>(i)];
  }
  set.attributes["shoulder_pose"] = std::move(shoulder);
  set.attributes["human_q"] = std::move(human_q);
  set.attributes["manipulability"] = std::move(manip);
  set.attributes["lattice_index"] = std::move(lattice_index);
  const auto matrix_attribute = [&](const std::vector<double>& values) {
    SampleSet::RowMatrix M(n, 36);
    if (n > 0) std::memcpy(M.data(), values.data(), values.size() * sizeof(double));
    return M;
  };
  if (want_mv) set.attributes["M_v"] = matrix_attribute(raw.mv);
  if (want_ma) set.attributes["M_a"] = matrix_attribute(raw.ma);
  // The lattice declaration the framework's maps and plots use (the lattice frame is S).
  SampleLattice lattice;
  lattice.per_axis = n_axis;
  lattice.step = o.lattice_step;
  lattice.index_of_sample.assign(raw.lattice.begin(), raw.lattice.end());
  lattice.candidates_per_point = o.orientations;
  lattice.candidates = "orientations";
  set.lattice = std::move(lattice);

  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  info["n_reach"] = static_cast<long long>(n);
  info["lattice_points"] = n_lattice;
  info["lattice_per_axis"] = n_axis;
  info["lattice_step"] = o.lattice_step;
  info["lattice_extent"] = o.lattice_extent;
  info["orientations"] = o.orientations;
  info["joint3_steps"] = o.joint3_steps;
  info["poses_tried"] = static_cast<long long>(n_lattice) * o.orientations;
  info["build_time_s"] = seconds;
  info["cache_file"] = file;
  info["cache_status"] = cache_status;
  info["from_cache"] = from_cache;
  info["arm_file"] = o.arm_file;
  set.info = std::move(info);
  return set;
}

}  // namespace hapsyn::plugins
