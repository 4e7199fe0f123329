#include "haptic6r.hpp"

#include <hapsyn/data_file.hpp>

#include <hapsyn/error.hpp>
#include <hapsyn/fast_math.hpp>
#include <hapsyn/multiversion.hpp>

#include <boost/filesystem.hpp>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

namespace hapsyn::plugins {

namespace {

constexpr const char* kName = "haptic6r";
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
// acos/asin arguments this far past +-1 are rounding at the reach boundary, not a miss.
constexpr double kBoundaryTolerance = 1e-12;

namespace fs = boost::filesystem;

std::string show(const Json& v) { return v.dump(); }

// Into [-pi, pi). IK angles are sums of a few atan2 values (|angle| < 6 pi), so the common
// case is one comparison; floor() instead of fmod() keeps the per-sample loop cheap.
inline double wrap(double angle) {
  if (angle >= -kPi && angle < kPi) return angle;
  double r = angle - 2.0 * kPi * std::floor((angle + kPi) / (2.0 * kPi));
  if (r >= kPi) r -= 2.0 * kPi;
  if (r < -kPi) r += 2.0 * kPi;
  return r;
}

inline double norm2(double x, double y) { return std::sqrt(x * x + y * y); }

// Rotation of one DH row from cos/sin of its angle (no trigonometric call).
inline void dh_rotation(double ct, double st, double ca, double sa, Eigen::Matrix3d& rot) {
  rot << ct, -st * ca, st * sa, st, ct * ca, -ct * sa, 0.0, sa, ca;
}

Json read_json_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(kName, path + ": cannot be read");
  try {
    return Json::parse(in);
  } catch (const std::exception& e) {
    throw Error(kName, path + ": not valid JSON (" + e.what() + ")");
  }
}

double number_at(const Json& doc, const std::string& file, const std::string& path, const Json& v,
                 double lower, double upper, bool lower_open = false) {
  if (!v.is_number()) throw Error(kName, file + ": " + path + " = " + show(v) + ": must be a number");
  const double x = v.get<double>();
  if (!std::isfinite(x) || x < lower || (lower_open && x == lower) || x > upper) {
    throw Error(kName, file + ": " + path + " = " + show(v) + ": must be in " + (lower_open ? "(" : "[") +
                           std::to_string(lower) + ", " + std::to_string(upper) + "]");
  }
  (void)doc;
  return x;
}

LinkRef parse_length(const Json& v, const std::string& file, const std::string& path) {
  LinkRef r;
  if (v.is_number()) {
    r.value = v.get<double>();
    if (!std::isfinite(r.value)) throw Error(kName, file + ": " + path + " = " + show(v) + ": must be finite");
    return r;
  }
  if (v.is_string()) {
    std::string s = v.get<std::string>();
    if (!s.empty() && s[0] == '-') {
      r.factor = -1.0;
      s = s.substr(1);
    }
    if (s.size() == 2 && s[0] == 'l' && s[1] >= '1' && s[1] <= '5') {
      r.link = s[1] - '1';
      return r;
    }
  }
  throw Error(kName, file + ": " + path + " = " + show(v) + ": must be a number [m] or a link name l1..l5, optionally negated");
}

// Double rows of the DH structure the closed-form IK serves.
bool same_ref(const LinkRef& r, int link, double factor) {
  if (link < 0) return r.link < 0 && r.value == 0.0;
  return r.link == link && r.factor == factor;
}

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

Vector6d degrees_option(const Json& options, const char* key, const Vector6d& fallback) {
  if (!options.contains(key)) return fallback;
  const Json& v = options[key];
  if (!v.is_array() || v.size() != 6) throw Error(kName, std::string("options.") + key + " = " + show(v) + ": must be an array of 6 angles [deg]");
  Vector6d out;
  for (int i = 0; i < 6; ++i) {
    if (!v[static_cast<std::size_t>(i)].is_number() || !std::isfinite(v[static_cast<std::size_t>(i)].get<double>())) {
      throw Error(kName, std::string("options.") + key + "[" + std::to_string(i) + "] = " + show(v[static_cast<std::size_t>(i)]) + ": must be a finite number [deg]");
    }
    out(i) = v[static_cast<std::size_t>(i)].get<double>() * kDeg;
  }
  return out;
}

double positive_option(const Json& options, const char* key, double fallback, bool allow_zero) {
  if (!options.contains(key)) return fallback;
  const Json& v = options[key];
  if (!v.is_number() || !std::isfinite(v.get<double>()) || v.get<double>() < 0.0 || (!allow_zero && v.get<double>() == 0.0)) {
    throw Error(kName, std::string("options.") + key + " = " + show(v) + (allow_zero ? ": must be a finite number >= 0" : ": must be a finite number > 0"));
  }
  return v.get<double>();
}


}  // namespace

// ---------------------------------------------------------------- data files ----

double ActuatorTable::max_velocity(int size, int code) const {
  return motor_speed[static_cast<std::size_t>(size - 1)] / gear_ratios[static_cast<std::size_t>(code - 1)];
}

double ActuatorTable::max_torque(int size, int code) const {
  const std::size_t s = static_cast<std::size_t>(size - 1);
  return std::min(motor_torque[s] * gear_ratios[static_cast<std::size_t>(code - 1)] * gear_efficiency, gear_torque[s]);
}

std::string resolve_haptic6r_file(const std::string& option_name, const std::string& value) {
  return find_data_file(kName, option_name, value);
}

Haptic6RDh read_haptic6r_dh(const std::string& path) {
  const Json doc = read_json_file(path);
  Haptic6RDh dh;
  dh.file = path;
  if (!doc.is_object() || doc.value("format", "") != "hapsyn-haptic6r-dh") {
    throw Error(kName, path + ": format = " + (doc.is_object() && doc.contains("format") ? show(doc["format"]) : "(missing)") +
                           ": must be \"hapsyn-haptic6r-dh\"");
  }
  if (!doc.contains("dh") || !doc["dh"].is_array() || doc["dh"].size() != 6) {
    throw Error(kName, path + ": dh = " + (doc.contains("dh") ? show(doc["dh"]) : "(missing)") + ": must be an array of 6 rows");
  }
  for (std::size_t i = 0; i < 6; ++i) {
    const Json& row = doc["dh"][i];
    const std::string at = "dh[" + std::to_string(i) + "]";
    for (const char* key : {"theta_offset", "d", "a", "alpha"}) {
      if (!row.is_object() || !row.contains(key)) throw Error(kName, path + ": " + at + "." + key + ": missing");
    }
    Haptic6RDhRow& r = dh.rows[i];
    r.theta_offset = number_at(doc, path, at + ".theta_offset", row["theta_offset"], -360.0, 360.0) * kDeg;
    r.alpha = number_at(doc, path, at + ".alpha", row["alpha"], -360.0, 360.0) * kDeg;
    r.d = parse_length(row["d"], path, at + ".d");
    r.a = parse_length(row["a"], path, at + ".a");
  }
  // The structure the closed-form IK is derived for (docs/design.md section 4).
  static const int a_link[6] = {0, 1, -1, 3, -1, -1};
  static const int d_link[6] = {-1, -1, 2, -1, -1, 4};
  static const double d_sign[6] = {1, 1, -1, 1, 1, 1};
  static const double alpha_deg[6] = {0, 0, 90, 0, 90, 0};
  for (std::size_t i = 0; i < 6; ++i) {
    const Haptic6RDhRow& r = dh.rows[i];
    if (!same_ref(r.a, a_link[i], 1.0) || !same_ref(r.d, d_link[i], d_sign[i]) ||
        std::abs(r.alpha - alpha_deg[i] * kDeg) > 1e-12) {
      throw Error(kName, path + ": dh[" + std::to_string(i) + "] = " + show(doc["dh"][i]) +
                             ": the closed-form IK serves a = (l1, l2, 0, l4, 0, 0), d = (0, 0, -l3, 0, 0, l5), "
                             "alpha = (0, 0, 90, 0, 90, 0) deg; only theta_offset may differ");
    }
  }
  return dh;
}

ActuatorTable read_actuator_table(const std::string& path) {
  const Json doc = read_json_file(path);
  ActuatorTable t;
  t.file = path;
  if (!doc.is_object() || doc.value("format", "") != "hapsyn-actuator-table") {
    throw Error(kName, path + ": format = " + (doc.is_object() && doc.contains("format") ? show(doc["format"]) : "(missing)") +
                           ": must be \"hapsyn-actuator-table\"");
  }
  if (!doc.contains("gear_ratios") || !doc["gear_ratios"].is_array() || doc["gear_ratios"].size() != 6) {
    throw Error(kName, path + ": gear_ratios = " + (doc.contains("gear_ratios") ? show(doc["gear_ratios"]) : "(missing)") +
                           ": must be an array of 6 ratios (gear codes 1..6)");
  }
  for (std::size_t i = 0; i < 6; ++i) {
    t.gear_ratios[i] = number_at(doc, path, "gear_ratios[" + std::to_string(i) + "]", doc["gear_ratios"][i], 0.0, 1e6, true);
  }
  if (!doc.contains("gear_efficiency")) throw Error(kName, path + ": gear_efficiency: missing");
  t.gear_efficiency = number_at(doc, path, "gear_efficiency", doc["gear_efficiency"], 0.0, 1.0, true);
  if (!doc.contains("sizes") || !doc["sizes"].is_array() || doc["sizes"].size() != 3) {
    throw Error(kName, path + ": sizes = " + (doc.contains("sizes") ? show(doc["sizes"]) : "(missing)") +
                           ": must be an array of 3 entries (sizes 1..3)");
  }
  for (std::size_t i = 0; i < 3; ++i) {
    const Json& s = doc["sizes"][i];
    const std::string at = "sizes[" + std::to_string(i) + "]";
    for (const char* key : {"size", "mass", "motor_speed_rpm", "motor_peak_torque", "gear_peak_torque"}) {
      if (!s.is_object() || !s.contains(key)) throw Error(kName, path + ": " + at + "." + key + ": missing");
    }
    if (!s["size"].is_number_integer() || s["size"].get<int>() != static_cast<int>(i) + 1) {
      throw Error(kName, path + ": " + at + ".size = " + show(s["size"]) + ": must be " + std::to_string(i + 1) + " (sizes in order)");
    }
    t.mass[i] = number_at(doc, path, at + ".mass", s["mass"], 0.0, 1e3);
    t.motor_speed[i] = number_at(doc, path, at + ".motor_speed_rpm", s["motor_speed_rpm"], 0.0, 1e6, true) * 2.0 * kPi / 60.0;
    t.motor_torque[i] = number_at(doc, path, at + ".motor_peak_torque", s["motor_peak_torque"], 0.0, 1e6, true);
    t.gear_torque[i] = number_at(doc, path, at + ".gear_peak_torque", s["gear_peak_torque"], 0.0, 1e6, true);
  }
  return t;
}

Haptic6ROptions Haptic6ROptions::from_json(const Json& options_in) {
  const Json options = options_in.is_null() ? Json::object() : options_in;
  if (!options.is_object()) throw Error(kName, "options = " + show(options) + ": must be an object");
  static const std::vector<std::string> kKeys = {
      "dh_file", "actuator_file", "selection", "home", "joint_lower", "joint_upper", "singularity_tolerance",
      "link_density", "tube_outer_diameter", "tube_wall", "ee_mass", "ee_diameter", "ee_length",
      "motor_mass_factor", "gravity"};
  for (auto it = options.begin(); it != options.end(); ++it) {
    if (std::find(kKeys.begin(), kKeys.end(), it.key()) == kKeys.end()) {
      throw Error(kName, "options." + it.key() + ": unknown option");
    }
  }
  Haptic6ROptions o;
  const auto string_option = [&](const char* key, const std::string& fallback) {
    if (!options.contains(key)) return fallback;
    if (!options[key].is_string()) throw Error(kName, std::string("options.") + key + " = " + show(options[key]) + ": must be a string");
    return options[key].get<std::string>();
  };
  o.dh = read_haptic6r_dh(resolve_haptic6r_file("dh_file", string_option("dh_file", "haptic6r/fennel2022_dh.json")));
  o.actuators = read_actuator_table(
      resolve_haptic6r_file("actuator_file", string_option("actuator_file", "haptic6r/actuators_assumed.json")));
  o.selection = string_option("selection", "closest_to_home");
  if (o.selection != "closest_to_home" && o.selection != "elbow_left" && o.selection != "elbow_right") {
    throw Error(kName, "options.selection = " + show(Json(o.selection)) +
                           ": must be \"closest_to_home\", \"elbow_left\" or \"elbow_right\"");
  }
  Vector6d home_deg, lower_deg, upper_deg;
  home_deg << 0, 90, 0, 90, 90, 0;
  lower_deg << -180, -180, -180, 0, -180, -180;
  upper_deg << 180, 180, 180, 180, 180, 180;
  o.home = degrees_option(options, "home", home_deg * kDeg);
  o.joint_lower = degrees_option(options, "joint_lower", lower_deg * kDeg);
  o.joint_upper = degrees_option(options, "joint_upper", upper_deg * kDeg);
  for (int i = 0; i < 6; ++i) {
    if (!(o.joint_upper(i) >= o.joint_lower(i)) || o.joint_upper(i) - o.joint_lower(i) > 2.0 * kPi + 1e-12) {
      throw Error(kName, "options.joint_upper[" + std::to_string(i) + "] = " + std::to_string(o.joint_upper(i) / kDeg) +
                             ": must be >= joint_lower[" + std::to_string(i) + "] (" + std::to_string(o.joint_lower(i) / kDeg) +
                             ") and span at most 360 deg");
    }
  }
  o.singularity_tolerance = positive_option(options, "singularity_tolerance", 1e-4, true);
  if (o.singularity_tolerance >= 1.0) throw Error(kName, "options.singularity_tolerance = " + show(options["singularity_tolerance"]) + ": must be < 1");
  o.link_density = positive_option(options, "link_density", 4.0, true);
  o.tube_outer_diameter = positive_option(options, "tube_outer_diameter", 0.1, true);
  o.tube_wall = positive_option(options, "tube_wall", 0.002, true);
  if (2.0 * o.tube_wall > o.tube_outer_diameter) {
    throw Error(kName, "options.tube_wall = " + std::to_string(o.tube_wall) + ": must be <= tube_outer_diameter / 2 (" +
                           std::to_string(o.tube_outer_diameter / 2) + ")");
  }
  o.ee_mass = positive_option(options, "ee_mass", 0.5, true);
  o.ee_diameter = positive_option(options, "ee_diameter", 0.1, true);
  o.ee_length = positive_option(options, "ee_length", 0.05, true);
  o.motor_mass_factor = positive_option(options, "motor_mass_factor", 1.2, true);
  o.gravity = positive_option(options, "gravity", 9.81, true);
  return o;
}

// ---------------------------------------------------------------- model ----

void Haptic6RModel::rebuild(const double* design, const Haptic6ROptions& options) {
  options_ = &options;
  selection_ = options.selection == "elbow_left" ? 1 : options.selection == "elbow_right" ? 2 : 0;
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
    max_velocity_(i) = options.actuators.max_velocity(size[static_cast<std::size_t>(i)], code[static_cast<std::size_t>(i)]);
    max_torque_(i) = options.actuators.max_torque(size[static_cast<std::size_t>(i)], code[static_cast<std::size_t>(i)]);
  }
  for (std::size_t i = 0; i < 6; ++i) {
    const Haptic6RDhRow& row = options.dh.rows[i];
    d_[i] = row.d.eval(l_.data());
    a_[i] = row.a.eval(l_.data());
    offset_[i] = row.theta_offset;
    ca_[i] = std::cos(row.alpha);
    sa_[i] = std::sin(row.alpha);
    // Exact zeros for the right angles, so that FK and IK agree to the last bit.
    if (std::abs(ca_[i]) < 1e-15) ca_[i] = 0.0;
    if (std::abs(sa_[i]) < 1e-15) sa_[i] = 0.0;
  }
  // Mass model, each body in its own DH frame.
  const double ro = 0.5 * options.tube_outer_diameter, ri = ro - options.tube_wall;
  const double tube_r2 = ro * ro + ri * ri;
  for (std::size_t i = 0; i < 6; ++i) {
    Haptic6RBody& b = bodies_[i];
    b = Haptic6RBody{};
    // The previous origin o_{i-1} in frame i is -(a, d sin(alpha), d cos(alpha)).
    const Eigen::Vector3d prev(-a_[i], -d_[i] * sa_[i], -d_[i] * ca_[i]);
    const double length = prev.norm();
    if (length > 0.0 && options.link_density > 0.0) {
      const double m = options.link_density * length;
      const Eigen::Vector3d axis = prev / length;
      add_part(b, m, 0.5 * prev, cylinder_inertia(m, axis, 0.5 * tube_r2, m * (3.0 * tube_r2 + length * length) / 12.0));
    }
    if (i < 5) {  // motor i+2 (1-based) sits at this frame's origin, on joint i+2's axis
      const double m = options.motor_mass_factor * options.actuators.mass[static_cast<std::size_t>(size[i + 1] - 1)];
      add_part(b, m, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero());
    } else {
      const double m = options.ee_mass, r = 0.5 * options.ee_diameter, h = options.ee_length;
      add_part(b, m, Eigen::Vector3d::Zero(),
               cylinder_inertia(m, Eigen::Vector3d::UnitZ(), 0.5 * r * r, m * (3.0 * r * r + h * h) / 12.0));
    }
  }
}

Eigen::Vector4d Haptic6RModel::dh_row(int i) const {
  const std::size_t k = static_cast<std::size_t>(i);
  return Eigen::Vector4d(offset_[k], d_[k], a_[k], std::atan2(sa_[k], ca_[k]));
}

namespace {
// The chain's DH frames in B as plain scalars (axes x, y, z and origin o of frame i = 0..6).
// Plain arrays, not Eigen 3-vectors: the per-sample kernels below are scalar code with many
// live values, and Eigen's 2-wide packing of 3-vectors spilled halves to the stack and read
// them back as pairs (store-forwarding stalls that cost more than the arithmetic).
struct Chain {
  double x[7][3], y[7][3], z[7][3], o[7][3];
};

// R_{i+1} = R_i Rz(theta) Rx(alpha) column by column, o_{i+1} = o_i + R_i (a ct, a st, d):
// 24 multiplications per joint instead of a 3x3 product.
[[gnu::always_inline]] inline void chain_from(const JointTrig& trig, const std::array<double, 6>& d, const std::array<double, 6>& a,
                const std::array<double, 6>& ca, const std::array<double, 6>& sa, Chain& c) {
  for (int r = 0; r < 3; ++r) {
    c.x[0][r] = r == 0 ? 1.0 : 0.0;
    c.y[0][r] = r == 1 ? 1.0 : 0.0;
    c.z[0][r] = r == 2 ? 1.0 : 0.0;
    c.o[0][r] = 0.0;
  }
  for (std::size_t i = 0; i < 6; ++i) {
    const double ct = trig.c[i], st = trig.s[i];
    for (int r = 0; r < 3; ++r) {
      const double xr = c.x[i][r], yr = c.y[i][r], zr = c.z[i][r];
      const double x_new = ct * xr + st * yr;
      const double u = ct * yr - st * xr;
      c.x[i + 1][r] = x_new;
      c.y[i + 1][r] = ca[i] * u + sa[i] * zr;
      c.z[i + 1][r] = ca[i] * zr - sa[i] * u;
      c.o[i + 1][r] = c.o[i][r] + a[i] * x_new + d[i] * zr;
    }
  }
}

[[gnu::always_inline]] inline void chain_from(const Vector6d& q, const std::array<double, 6>& offset, const std::array<double, 6>& d,
                const std::array<double, 6>& a, const std::array<double, 6>& ca, const std::array<double, 6>& sa,
                Chain& c) {
  JointTrig trig;
  for (std::size_t i = 0; i < 6; ++i) {
    const double theta = q(static_cast<Eigen::Index>(i)) + offset[i];
    fast::sin_cos(theta, trig.s[i], trig.c[i]);
  }
  chain_from(trig, d, a, ca, sa, c);
}

// Geometric Jacobian of E, column i = (z_i, z_i x (p - o_i)), written into `j` (6 x 6).
template <typename Matrix>
[[gnu::always_inline]] inline void jacobian_from(const Chain& c, Matrix& j) {
  const double* p = c.o[6];
  for (int i = 0; i < 6; ++i) {
    const double* z = c.z[i];
    const double rx = p[0] - c.o[i][0], ry = p[1] - c.o[i][1], rz = p[2] - c.o[i][2];
    j(0, i) = z[0];
    j(1, i) = z[1];
    j(2, i) = z[2];
    j(3, i) = z[1] * rz - z[2] * ry;
    j(4, i) = z[2] * rx - z[0] * rz;
    j(5, i) = z[0] * ry - z[1] * rx;
  }
}

Matrix6d jacobian_from(const Chain& c) {
  Matrix6d j;
  jacobian_from(c, j);
  return j;
}

// Composite rigid bodies in B, accumulated about the base origin so that adding a body needs no
// division or centre-of-mass shift: composite j (bodies j..5) has mass M, first moment h = M c
// and inertia K about the origin (symmetric: six numbers). A unit rate of joint j (axis z_j
// through o_j) gives it the linear momentum P = z_j x (h - M o_j) and the angular momentum about
// the origin L = K z_j - h x (z_j x o_j); then H_ij = z_i . (L - o_i x P) = z_i . L - (z_i x o_i) . P
// for i <= j, and the holding torque tau_j = z_j . ((h - M o_j) x g e_z).
template <typename InertiaMatrix, typename GravityVector>
[[gnu::always_inline]] inline void dynamics_from(const Chain& c, const std::array<Haptic6RBody, 6>& bodies, double g, InertiaMatrix* inertia,
                   GravityVector* gravity) {
  double mass = 0.0;
  double h[3] = {0.0, 0.0, 0.0};
  double kxx = 0.0, kyy = 0.0, kzz = 0.0, kxy = 0.0, kxz = 0.0, kyz = 0.0;
  double arm[6][3];  // z_i x o_i
  for (int i = 0; i < 6; ++i) {
    const double *z = c.z[i], *o = c.o[i];
    arm[i][0] = z[1] * o[2] - z[2] * o[1];
    arm[i][1] = z[2] * o[0] - z[0] * o[2];
    arm[i][2] = z[0] * o[1] - z[1] * o[0];
  }
  for (int j = 5; j >= 0; --j) {
    const Haptic6RBody& b = bodies[static_cast<std::size_t>(j)];
    if (b.mass > 0.0) {
      const int f = j + 1;  // body j lives in DH frame j + 1
      const double *X = c.x[f], *Y = c.y[f], *Z = c.z[f];
      const double lx = b.com.x(), ly = b.com.y(), lz = b.com.z();
      double com[3];
      for (int r = 0; r < 3; ++r) com[r] = c.o[f][r] + X[r] * lx + Y[r] * ly + Z[r] * lz;
      // R I R^T with I the body's inertia about its centre of mass in its frame: A = R I, then
      // K_ab = sum_k A_ak R_bk (only the six distinct entries).
      const Eigen::Matrix3d& in = b.inertia;
      double A[3][3];  // A[r][k]
      if (in(0, 1) == 0.0 && in(0, 2) == 0.0 && in(1, 2) == 0.0) {
        // Principal axes along the frame's (every body of the docs/design.md model): A = R diag(I).
        for (int r = 0; r < 3; ++r) {
          A[r][0] = X[r] * in(0, 0);
          A[r][1] = Y[r] * in(1, 1);
          A[r][2] = Z[r] * in(2, 2);
        }
      } else {
        for (int r = 0; r < 3; ++r) {
          for (int k = 0; k < 3; ++k) A[r][k] = X[r] * in(0, k) + Y[r] * in(1, k) + Z[r] * in(2, k);
        }
      }
      kxx += A[0][0] * X[0] + A[0][1] * Y[0] + A[0][2] * Z[0];
      kyy += A[1][0] * X[1] + A[1][1] * Y[1] + A[1][2] * Z[1];
      kzz += A[2][0] * X[2] + A[2][1] * Y[2] + A[2][2] * Z[2];
      kxy += A[0][0] * X[1] + A[0][1] * Y[1] + A[0][2] * Z[1];
      kxz += A[0][0] * X[2] + A[0][1] * Y[2] + A[0][2] * Z[2];
      kyz += A[1][0] * X[2] + A[1][1] * Y[2] + A[1][2] * Z[2];
      // Point mass at com about the origin: m (|c|^2 1 - c c^T).
      const double mx = b.mass * com[0], my = b.mass * com[1], mz = b.mass * com[2];
      kxx += my * com[1] + mz * com[2];
      kyy += mx * com[0] + mz * com[2];
      kzz += mx * com[0] + my * com[1];
      kxy -= mx * com[1];
      kxz -= mx * com[2];
      kyz -= my * com[2];
      h[0] += mx;
      h[1] += my;
      h[2] += mz;
      mass += b.mass;
    }
    const double *zj = c.z[j], *oj = c.o[j];
    const double lever[3] = {h[0] - mass * oj[0], h[1] - mass * oj[1], h[2] - mass * oj[2]};  // M (c - o_j)
    if (inertia) {
      const double momentum[3] = {zj[1] * lever[2] - zj[2] * lever[1], zj[2] * lever[0] - zj[0] * lever[2],
                                  zj[0] * lever[1] - zj[1] * lever[0]};
      const double* aj = arm[j];
      const double angular[3] = {kxx * zj[0] + kxy * zj[1] + kxz * zj[2] - (h[1] * aj[2] - h[2] * aj[1]),
                                 kxy * zj[0] + kyy * zj[1] + kyz * zj[2] - (h[2] * aj[0] - h[0] * aj[2]),
                                 kxz * zj[0] + kyz * zj[1] + kzz * zj[2] - (h[0] * aj[1] - h[1] * aj[0])};
      for (int i = 0; i <= j; ++i) {
        const double *zi = c.z[i], *ai = arm[i];
        const double value = zi[0] * angular[0] + zi[1] * angular[1] + zi[2] * angular[2] -
                             (ai[0] * momentum[0] + ai[1] * momentum[1] + ai[2] * momentum[2]);
        (*inertia)(i, j) = value;
        (*inertia)(j, i) = value;
      }
    }
    // lever x e_z = (lever_y, -lever_x, 0).
    if (gravity) (*gravity)(j) = g * (zj[0] * lever[1] - zj[1] * lever[0]);
  }
}
}  // namespace

void Haptic6RModel::frames(const Vector6d& q, std::array<Eigen::Isometry3d, 7>& out) const {
  Chain c;
  chain_from(q, offset_, d_, a_, ca_, sa_, c);
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
  chain_from(q, offset_, d_, a_, ca_, sa_, c);
  return jacobian_from(c);
}

void Haptic6RModel::dynamics(const Vector6d& q, Matrix6d* inertia, Vector6d* gravity) const {
  Chain c;
  chain_from(q, offset_, d_, a_, ca_, sa_, c);
  dynamics_from(c, bodies_, options_->gravity, inertia, gravity);
}

HAPSYN_MULTIVERSION
void Haptic6RModel::quantities_impl(const Vector6d& q, Matrix6d* jacobian, Matrix6d* inertia, Vector6d* gravity) const {
  Chain c;
  chain_from(q, offset_, d_, a_, ca_, sa_, c);
  if (jacobian) *jacobian = jacobian_from(c);
  if (inertia || gravity) dynamics_from(c, bodies_, options_->gravity, inertia, gravity);
}

HAPSYN_MULTIVERSION
int Haptic6RModel::inverse_kinematics_impl(const Eigen::Isometry3d& target, std::array<Vector6d, 8>& solutions,
                                           std::array<JointTrig, 8>* trig) const {
  const double L1 = a_[0], L2 = a_[1], L3 = -d_[2], L4 = a_[3], L5 = d_[5];
  const Eigen::Matrix3d& rot = target.linear();
  const Eigen::Vector3d approach = rot.col(2);
  const Eigen::Vector3d w = target.translation() - L5 * approach;
  // Axis of joints 4 and 5: horizontal and perpendicular to the roll axis.
  Eigen::Vector3d hz(-approach.y(), approach.x(), 0.0);
  double n = hz.norm();
  if (n < 1e-12) {
    // Wrist axis vertical: h is free (a singular family); take the one normal to x_E so that
    // the solution stays finite and deterministic.
    hz = Eigen::Vector3d(-rot(1, 0), rot(0, 0), 0.0);
    n = hz.norm();
    if (n < 1e-12) return 0;  // not a rotation
  }
  hz /= n;
  double s4 = (w.z() + L3) / L4;
  if (std::abs(s4) > 1.0 + kBoundaryTolerance) return 0;
  s4 = std::clamp(s4, -1.0, 1.0);
  const double c4_abs = std::sqrt(std::max(0.0, 1.0 - s4 * s4));

  // The eight branches (h sign, theta4 branch, elbow) share most of their work: flipping h
  // flips x3 = e_z x h (yaw + pi), and the wrist centre o = w - L4 cos(theta4) x3 depends only
  // on the product of the two signs, so the planar 2R solve (three atan2) is done for two
  // points only; rotations are built from the cosines and sines at hand, not from angles.
  struct Planar {
    bool valid = false;
    double c2 = 0.0, theta2 = 0.0, phi = 0.0, beta = 0.0;  // theta1 = phi -+ beta, theta2 = +-theta2
    double s2 = 0.0, cos_phi = 1.0, sin_phi = 0.0, cos_beta = 1.0, sin_beta = 0.0;
  };
  std::array<Planar, 2> planar;
  for (int k = 0; k < 2; ++k) {
    const double c4x3 = (k == 0 ? c4_abs : -c4_abs) * L4;  // L4 c4 times the sign of x3
    const double ox = w.x() + c4x3 * hz.y(), oy = w.y() - c4x3 * hz.x();  // x3 = (-h_y, h_x, 0)
    double c2 = (ox * ox + oy * oy - L1 * L1 - L2 * L2) / (2.0 * L1 * L2);
    if (std::abs(c2) > 1.0 + kBoundaryTolerance) continue;
    c2 = std::clamp(c2, -1.0, 1.0);
    const double s2_abs = std::sqrt(std::max(0.0, 1.0 - c2 * c2));
    Planar& p = planar[static_cast<std::size_t>(k)];
    p.valid = true;
    p.c2 = c2;
    p.theta2 = fast::atan2(s2_abs, c2);
    p.phi = fast::atan2(oy, ox);
    p.beta = fast::atan2(L2 * s2_abs, L1 + L2 * c2);
    if (trig) {  // the same angles as cosines and sines, for the chosen solution's frames
      p.s2 = s2_abs;
      // Lengths of order 1 m: sqrt(x^2 + y^2) cannot overflow, and is several times cheaper than hypot.
      const double ro = norm2(ox, oy), rb = norm2(L1 + L2 * c2, L2 * s2_abs);
      if (ro > 0.0) {
        p.cos_phi = ox / ro;
        p.sin_phi = oy / ro;
      }
      if (rb > 0.0) {
        p.cos_beta = (L1 + L2 * c2) / rb;
        p.sin_beta = L2 * s2_abs / rb;
      }
    }
  }
  const double yaw0 = fast::atan2(hz.x(), -hz.y());
  const double theta4_branch[2] = {fast::atan2(s4, c4_abs), fast::atan2(s4, -c4_abs)};
  // Wrist angles for h = +hz. Flipping h and the theta4 branch together turns R_04 into
  // R_04 Rx(pi) (x3 -> -x3, cos theta4 -> -cos theta4), which maps theta5 -> pi - theta5 and
  // theta6 -> theta6 + pi: the h = -hz branches reuse these (two atan2 pairs instead of four).
  double wrist5[2] = {0.0, 0.0}, wrist6[2] = {0.0, 0.0};
  double cos5[2] = {1.0, 1.0}, sin5[2] = {0.0, 0.0}, cos6[2] = {1.0, 1.0}, sin6[2] = {0.0, 0.0};
  const Eigen::Vector3d x_e = rot.col(0);
  {
    Eigen::Matrix3d r3;
    dh_rotation(-hz.y(), hz.x(), ca_[2], sa_[2], r3);
    for (int b4 = 0; b4 < 2; ++b4) {
      if (!planar[static_cast<std::size_t>(b4)].valid) continue;  // used by (+hz, b4) and (-hz, 1 - b4) only
      Eigen::Matrix3d r4, r5;
      dh_rotation(b4 == 0 ? c4_abs : -c4_abs, s4, ca_[3], sa_[3], r4);
      const Eigen::Matrix3d r04 = r3 * r4;
      const Eigen::Vector3d a4 = r04.transpose() * approach;
      // z_5 in frame 4 is Rz(theta5) (0, -sin alpha5, cos alpha5) = (sin theta5, -cos theta5, 0).
      wrist5[b4] = fast::atan2(a4.x(), -a4.y());
      const double n5 = norm2(a4.x(), a4.y());  // 1 up to rounding: the approach is normal to h
      cos5[b4] = n5 > 0.0 ? -a4.y() / n5 : 1.0;
      sin5[b4] = n5 > 0.0 ? a4.x() / n5 : 0.0;
      dh_rotation(cos5[b4], sin5[b4], ca_[4], sa_[4], r5);
      // theta6 from x_E in frame 5: (x_5 . x_E, y_5 . x_E).
      const Eigen::Vector3d x5 = r04 * r5.col(0), y5 = r04 * r5.col(1);
      wrist6[b4] = fast::atan2(y5.dot(x_e), x5.dot(x_e));
      const double n6 = norm2(y5.dot(x_e), x5.dot(x_e));
      if (n6 > 0.0) {
        cos6[b4] = x5.dot(x_e) / n6;
        sin6[b4] = y5.dot(x_e) / n6;
      }
    }
  }
  int count = 0;
  for (int hs = 0; hs < 2; ++hs) {
    const double yaw = hs == 0 ? yaw0 : yaw0 + kPi;
    for (int b4 = 0; b4 < 2; ++b4) {
      const Planar& p = planar[static_cast<std::size_t>(hs ^ b4)];
      if (!p.valid) continue;
      const double theta5 = hs == 0 ? wrist5[b4] : kPi - wrist5[1 - b4];
      const double theta6 = hs == 0 ? wrist6[b4] : wrist6[1 - b4] + kPi;
      for (int b2 = 0; b2 < 2; ++b2) {
        const double theta2 = b2 == 0 ? p.theta2 : -p.theta2;
        const double theta1 = b2 == 0 ? p.phi - p.beta : p.phi + p.beta;
        const double theta3 = yaw - theta1 - theta2;
        Vector6d& q = solutions[static_cast<std::size_t>(count++)];
        q << theta1, theta2, theta3, theta4_branch[b4], theta5, theta6;
        for (int i = 0; i < 6; ++i) q(i) = wrap(q(i) - offset_[static_cast<std::size_t>(i)]);
        if (trig) {
          // cos/sin of the DH angles by angle-sum identities on the vectors they came from.
          JointTrig& t = (*trig)[static_cast<std::size_t>(count - 1)];
          const double sb = b2 == 0 ? -p.sin_beta : p.sin_beta;  // theta1 = phi + (-+beta)
          t.c[0] = p.cos_phi * p.cos_beta - p.sin_phi * sb;
          t.s[0] = p.sin_phi * p.cos_beta + p.cos_phi * sb;
          t.c[1] = p.c2;
          t.s[1] = b2 == 0 ? p.s2 : -p.s2;
          const double c12 = t.c[0] * t.c[1] - t.s[0] * t.s[1], s12 = t.s[0] * t.c[1] + t.c[0] * t.s[1];
          const double sign = hs == 0 ? 1.0 : -1.0;
          const double cy = -sign * hz.y(), sy = sign * hz.x();  // the yaw: x3 = e_z x h
          t.c[2] = cy * c12 + sy * s12;  // theta3 = yaw - (theta1 + theta2)
          t.s[2] = sy * c12 - cy * s12;
          t.c[3] = b4 == 0 ? c4_abs : -c4_abs;
          t.s[3] = s4;
          t.c[4] = hs == 0 ? cos5[b4] : -cos5[1 - b4];  // pi - theta5
          t.s[4] = hs == 0 ? sin5[b4] : sin5[1 - b4];
          t.c[5] = hs == 0 ? cos6[b4] : -cos6[1 - b4];  // theta6 + pi
          t.s[5] = hs == 0 ? sin6[b4] : -sin6[1 - b4];
        }
      }
    }
  }
  return count;
}

int Haptic6RModel::select(const std::array<Vector6d, 8>& solutions, int count) const {
  const Haptic6ROptions& o = *options_;
  int best = -1;
  double best_distance = std::numeric_limits<double>::infinity();
  for (int k = 0; k < count; ++k) {
    const Vector6d& q = solutions[static_cast<std::size_t>(k)];
    bool inside = true;
    for (int i = 0; i < 6 && inside; ++i) {
      if (q(i) >= o.joint_lower(i) && q(i) <= o.joint_upper(i)) continue;  // the common case
      // The representative of q_i in [lower, lower + 2 pi) must not exceed upper (with tolerance).
      double v = q(i);
      while (v < o.joint_lower(i) - kHaptic6RAngleTolerance) v += 2.0 * kPi;
      while (v > o.joint_lower(i) + 2.0 * kPi - kHaptic6RAngleTolerance) v -= 2.0 * kPi;
      if (v < o.joint_lower(i) - kHaptic6RAngleTolerance) v += 2.0 * kPi;
      inside = v <= o.joint_upper(i) + kHaptic6RAngleTolerance;
    }
    if (!inside) continue;
    if (selection_ == 1 && q(1) < -kHaptic6RAngleTolerance) continue;
    if (selection_ == 2 && q(1) > kHaptic6RAngleTolerance) continue;
    double distance = 0.0;
    for (int i = 0; i < 6; ++i) {
      const double e = wrap(q(i) - o.home(i));
      distance += e * e;
    }
    if (distance < best_distance) {
      best_distance = distance;
      best = k;
    }
  }
  return best;
}

namespace {
// Brings q_i to the representative inside [lower, upper] (select() checked it exists).
void into_limits(Vector6d& q, const Haptic6ROptions& o) {
  for (int i = 0; i < 6; ++i) {
    double v = q(i);
    while (v < o.joint_lower(i) - kHaptic6RAngleTolerance) v += 2.0 * kPi;
    while (v > o.joint_upper(i) + kHaptic6RAngleTolerance) v -= 2.0 * kPi;
    q(i) = std::clamp(v, o.joint_lower(i), o.joint_upper(i));
  }
}
}  // namespace

HAPSYN_MULTIVERSION
void Haptic6RModel::solve_sample(const double* pose, Needs needs, SampleQuantities& out) const {
  out.q.resize(6);
  Eigen::Quaterniond quat(pose[3], pose[4], pose[5], pose[6]);
  const double qn = quat.norm();
  if (!(qn > 1e-9) || !std::isfinite(qn) || !std::isfinite(pose[0] + pose[1] + pose[2])) {
    out.status = SampleStatus::kUnreachable;
    out.q.setZero();
    return;
  }
  quat.coeffs() /= qn;
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
  target.linear() = quat.toRotationMatrix();
  target.translation() = Eigen::Vector3d(pose[0], pose[1], pose[2]);
  std::array<Vector6d, 8> solutions;
  std::array<JointTrig, 8> trig;
  const int count = inverse_kinematics_impl(target, solutions, &trig);
  if (count == 0) {
    out.status = SampleStatus::kUnreachable;
    out.q.setZero();
    return;
  }
  const int chosen = select(solutions, count);
  if (chosen < 0) {
    out.status = SampleStatus::kInvalid;
    out.q = solutions[0];
    return;
  }
  Vector6d q = solutions[static_cast<std::size_t>(chosen)];
  into_limits(q, *options_);
  out.q = q;
  const double tol = options_->singularity_tolerance;
  const Eigen::Vector3d& approach = target.linear().col(2);
  const double wrist = norm2(approach.x(), approach.y());
  const JointTrig& chosen_trig = trig[static_cast<std::size_t>(chosen)];
  const double sin2 = chosen_trig.s[1];
  const double cos4 = chosen_trig.c[3];  // l4 vertical when cos(theta4) = 0
  if (std::abs(sin2) < tol || std::abs(cos4) < tol || wrist < tol) {
    out.status = SampleStatus::kSingular;
    return;
  }
  out.status = SampleStatus::kReachable;
  if (needs & (kNeedJacobian | kNeedInertia | kNeedGravity)) {
    Chain f;
    chain_from(trig[static_cast<std::size_t>(chosen)], d_, a_, ca_, sa_, f);
    if (needs & kNeedJacobian) {
      out.jacobian.resize(6, 6);
      jacobian_from(f, out.jacobian);
    }
    if (needs & (kNeedInertia | kNeedGravity)) {
      // Straight into the fixed-capacity outputs: no 6x6 temporaries to copy.
      if (needs & kNeedInertia) out.inertia.resize(6, 6);
      if (needs & kNeedGravity) out.gravity.resize(6);
      dynamics_from(f, bodies_, options_->gravity, (needs & kNeedInertia) ? &out.inertia : nullptr,
                    (needs & kNeedGravity) ? &out.gravity : nullptr);
    }
  }
  if (needs & kNeedActuatorLimits) {
    out.max_velocity = max_velocity_;
    out.max_torque = max_torque_;
  }
}

// The public entry points call the multiversioned bodies (defined above: clang refuses to
// multiversion a function already called, and other translation units must see plain symbols).
int Haptic6RModel::inverse_kinematics(const Eigen::Isometry3d& target, std::array<Vector6d, 8>& solutions,
                                      std::array<JointTrig, 8>* trig) const {
  return inverse_kinematics_impl(target, solutions, trig);
}

void Haptic6RModel::quantities(const Vector6d& q, Matrix6d* jacobian, Matrix6d* inertia, Vector6d* gravity) const {
  quantities_impl(q, jacobian, inertia, gravity);
}

void Haptic6RModel::solve(const double* pose, Needs needs, MechanismScratch&, SampleQuantities& out) const {
  solve_sample(pose, needs, out);
}

// ---------------------------------------------------------------- plugin ----

namespace {
struct Haptic6RScratch final : MechanismScratch {
  Haptic6RModel model;
};
}  // namespace

Haptic6R::Haptic6R(const Json& options) : options_(Haptic6ROptions::from_json(options)) {}

std::unique_ptr<const MechanismModel> Haptic6R::build(const double* design) const {
  auto model = std::make_unique<Haptic6RModel>();
  model->rebuild(design, options_);
  return model;
}

const MechanismModel* Haptic6R::build_in(const double* design, MechanismScratch& scratch) const {
  auto* s = dynamic_cast<Haptic6RScratch*>(&scratch);
  if (!s) return nullptr;
  s->model.rebuild(design, options_);
  return &s->model;
}

std::unique_ptr<MechanismScratch> Haptic6R::make_scratch() const { return std::make_unique<Haptic6RScratch>(); }

std::vector<VariableDecl> Haptic6R::variables() const {
  VariableDecl l{"l", "link lengths l1..l5 (SCARA links, vertical drop, vertical-SCARA link, wrist to end effector)", "m", 5,
                 false, {0.3, 0.3, 0.3, 0.3, 0.12}, {1.0, 1.0, 1.5, 1.0, 0.3}, {0.001}, {10.0}};
  VariableDecl s{"s", "joint sizes (1 smallest .. 3 largest), s_i >= s_{i+1}", "", 6, true, {3, 3, 1, 1, 1, 1}, {3}, {1}, {3}};
  VariableDecl r{"r", "gear codes (index into the actuator table's gear_ratios)", "", 6, true, {1}, {6}, {1}, {6}};
  return {l, s, r};
}

std::vector<ConstraintDecl> Haptic6R::constraints() const {
  std::vector<ConstraintDecl> c;
  for (int i = 1; i <= 5; ++i) {
    c.push_back({"s_monotone_" + std::to_string(i),
                 "s" + std::to_string(i) + " >= s" + std::to_string(i + 1) + ": g = s" + std::to_string(i + 1) + " - s" +
                     std::to_string(i) + " <= 0"});
  }
  return c;
}

void Haptic6R::evaluate_constraints(const double* design, const SampleSet&, double* g) const {
  for (int i = 0; i < 5; ++i) g[i] = design[5 + i + 1] - design[5 + i];
}

void Haptic6R::check_scene(const SampleSet& scene) const {
  if (scene.dimension() != 7) {
    throw Error(kName, "scene: samples have " + std::to_string(scene.dimension()) +
                           " coordinates; haptic6r serves end-effector poses (x, y, z, qw, qx, qy, qz) [m]");
  }
}

Needs Haptic6R::provides() const { return kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits; }

}  // namespace hapsyn::plugins
