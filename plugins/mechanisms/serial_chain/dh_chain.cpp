// ChainTemplate::from_dh_file: a DH or modified-DH table in JSON (format "hapsyn-dh" version 1,
// share/serial_chain/README.md) as a chain template.
//
// Standard DH, T_i = Rz(theta_i + q_i) Tz(d_i) Tx(a_i) Rx(alpha_i): joint frame i is DH frame i-1
// turned by Rz(theta_i) (a rotation about the joint's own axis commutes with its motion), so
// O_i = X_{i-1} Rz(theta_i) with X_i = Tz(d_i) Tx(a_i) Rx(alpha_i), T_tip = X_n (times "tip"), and
// a body given in DH frame i is re-expressed in joint frame i through X_i.
// Modified DH, T_i = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i + q_i) Tz(d_i) (row i holds alpha_{i-1},
// a_{i-1}, theta_i, d_i): Tz(d_i) commutes with Rz, so O_i = Rx Tx Rz(theta_i) Tz(d_i), joint
// frame i IS DH frame i (bodies as given) and T_tip = "tip". A prismatic joint's q adds to d.
#include "chain_template_impl.hpp"

#include <hapsyn/json_text.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/read_file.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstddef>
#include <fstream>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn::plugins {

using namespace serial_chain_detail;

namespace {

// The file's key order is the parameters' order.
using OrderedJson = nlohmann::ordered_json;

constexpr double kPi = 3.14159265358979323846;

// A DH entry (theta, d, a or alpha): sign * values[parameter] * unit (to SI).
struct DhEntry {
  int parameter = -1;
  double sign = 1.0;
  double unit = 1.0;
  double eval(const double* values) const { return sign * values[parameter] * unit; }
};

struct DhRow {
  ChainJoint joint;  // name, type, limits in SI (origin: from the entries)
  DhEntry theta, d, a, alpha;
  std::optional<ChainBody> body;  // in DH frame i, SI
  int mass_parameter = -1;
};

struct DhTable {
  bool modified = false;
  std::vector<DhRow> rows;
  Eigen::Isometry3d tip = Eigen::Isometry3d::Identity();
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  std::optional<FennelMassModel> fennel;
  int mass_scale_parameter = -1;
};

// Reads and checks JSON values, every error naming the file, the JSON path, the value, the rule.
class DhReader {
 public:
  explicit DhReader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& at, const std::string& value, const std::string& rule) const {
    throw Error(kSerialChainName, file_ + ": " + at + " = " + value + ": " + rule);
  }
  [[noreturn]] void fail(const std::string& at, const OrderedJson& v, const std::string& rule) const {
    fail(at, v.dump(), rule);
  }

  static std::string join(const std::string& at, const std::string& key) { return at.empty() ? key : at + "." + key; }

  const OrderedJson& object(const OrderedJson& v, const std::string& at, std::initializer_list<const char*> keys) const {
    if (!v.is_object()) fail(at.empty() ? "(document)" : at, shorten(v), "must be an object");
    std::vector<std::string> allowed(keys.begin(), keys.end());
    for (auto it = v.begin(); it != v.end(); ++it) {
      bool known = false;
      for (const std::string& k : allowed) known = known || k == it.key();
      if (!known) {
        std::string list;
        for (const std::string& k : allowed) list += (list.empty() ? "" : ", ") + k;
        fail(join(at, it.key()), shorten(it.value()), "unknown key" + did_you_mean(it.key(), allowed) + " (known: " + list + ")");
      }
    }
    return v;
  }

  const OrderedJson& required(const OrderedJson& obj, const std::string& at, const char* key) const {
    if (!obj.contains(key)) fail(join(at, key), std::string("(missing)"), "required");
    return obj[key];
  }

  double number(const OrderedJson& v, const std::string& at) const {
    if (!v.is_number()) fail(at, shorten(v), "must be a number");
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(at, v, "must be finite");
    return x;
  }

  double non_negative(const OrderedJson& v, const std::string& at) const {
    const double x = number(v, at);
    if (x < 0.0) fail(at, v, "must be >= 0");
    return x;
  }

  std::string string(const OrderedJson& v, const std::string& at) const {
    if (!v.is_string()) fail(at, shorten(v), "must be a string");
    return v.get<std::string>();
  }

  std::vector<double> numbers(const OrderedJson& v, const std::string& at, std::size_t size) const {
    if (!v.is_array() || v.size() != size) fail(at, shorten(v), "must be an array of " + std::to_string(size) + " numbers");
    std::vector<double> out;
    for (std::size_t i = 0; i < size; ++i) out.push_back(number(v[i], at + "[" + std::to_string(i) + "]"));
    return out;
  }

  const std::string& file() const { return file_; }

 private:
  // Long values (a whole row, an array) are cut in messages.
  static std::string shorten(const OrderedJson& v) {
    std::string s = v.dump();
    return s.size() > 80 ? s.substr(0, 77) + "..." : s;
  }

  std::string file_;
};

// A DH file is a few kB: a FIFO, a device or a huge file is refused before it is read.
constexpr std::uint64_t kMaxDhFileBytes = 64u << 20;

OrderedJson read_json(const std::string& path) {
  const std::string text = read_regular_file(path, kSerialChainName, "DH file", kMaxDhFileBytes);
  check_json_text(text, path, kSerialChainName);  // nesting and duplicate keys, before a document is built
  try {
    return OrderedJson::parse(text);
  } catch (const std::exception& e) {
    throw Error(kSerialChainName, path + ": not valid JSON (" + e.what() + ")");
  }
}

struct Units {
  double length = 1.0, angle = 1.0;  // to m, to rad
  std::string length_name, angle_name;
};

Units read_units(const DhReader& r, const OrderedJson& doc) {
  const OrderedJson& u = r.object(r.required(doc, "", "units"), "units", {"length", "angle"});
  Units units;
  units.length_name = r.string(r.required(u, "units", "length"), "units.length");
  units.angle_name = r.string(r.required(u, "units", "angle"), "units.angle");
  if (units.length_name == "m") {
    units.length = 1.0;
  } else if (units.length_name == "mm") {
    units.length = 1e-3;
  } else {
    r.fail("units.length", u["length"], "must be \"m\" or \"mm\"");
  }
  if (units.angle_name == "rad") {
    units.angle = 1.0;
  } else if (units.angle_name == "deg") {
    units.angle = kPi / 180.0;
  } else {
    r.fail("units.angle", u["angle"], "must be \"deg\" or \"rad\"");
  }
  return units;
}

// The named lengths ("parameters"), declared first; returns their names.
std::vector<std::string> read_named_lengths(const DhReader& r, const OrderedJson& doc, const Units& units,
                                            std::vector<ChainParameter>& parameters) {
  std::vector<std::string> names;
  if (!doc.contains("parameters")) return names;
  const OrderedJson& p = doc["parameters"];
  if (!p.is_object()) r.fail("parameters", p, "must be an object of named lengths {\"l1\": 0.45, ...}");
  for (auto it = p.begin(); it != p.end(); ++it) {
    const std::string at = "parameters." + it.key();
    if (it.key().empty() || it.key().find(':') != std::string::npos || it.key() == "mass_scale" || it.key()[0] == '-') {
      r.fail("parameters", "\"" + it.key() + "\"", "a named length must be a non-empty name without ':' or a leading '-', other than mass_scale");
    }
    ChainParameter c;
    c.name = it.key();
    c.description = "named length " + it.key() + " of the DH table";
    c.unit = units.length_name;
    c.nominal = r.non_negative(it.value(), at);
    c.hard_lower = 0.0;
    parameters.push_back(c);
    names.push_back(it.key());
  }
  return names;
}

// theta, d, a or alpha of a row: a number (its own parameter "<joint>:<key>") or, for d and a,
// a named length "l1" / "-l1".
DhEntry read_entry(const DhReader& r, const OrderedJson& row, const std::string& at, const std::string& joint,
                   const char* key, bool is_length, const Units& units, const std::vector<std::string>& named,
                   std::vector<ChainParameter>& parameters) {
  const OrderedJson& v = r.required(row, at, key);
  const std::string here = DhReader::join(at, key);
  DhEntry e;
  e.unit = is_length ? units.length : units.angle;
  if (v.is_string() && is_length) {
    std::string name = v.get<std::string>();
    if (!name.empty() && name[0] == '-') {
      e.sign = -1.0;
      name = name.substr(1);
    }
    for (std::size_t i = 0; i < named.size(); ++i) {
      if (named[i] == name) e.parameter = static_cast<int>(i);  // named lengths come first
    }
    if (e.parameter < 0) {
      std::string list;
      for (const std::string& n : named) list += (list.empty() ? "" : ", ") + n;
      r.fail(here, v, "no such named length in \"parameters\"" + did_you_mean(name, named) + " (named: " +
                          (list.empty() ? "none" : list) + ")");
    }
    return e;
  }
  if (!v.is_number()) {
    r.fail(here, v, is_length ? "must be a number or a named length (\"l1\" or \"-l1\")" : "must be a number");
  }
  ChainParameter c;
  c.name = joint + ":" + key;
  c.description = std::string("DH ") + key + " of joint " + joint;
  c.unit = is_length ? units.length_name : units.angle_name;
  c.nominal = r.number(v, here);
  if (is_length && c.nominal > 0.0) c.hard_lower = 0.0;
  if (is_length && c.nominal < 0.0) c.hard_upper = 0.0;
  e.parameter = static_cast<int>(parameters.size());
  parameters.push_back(c);
  return e;
}

ChainBody read_body(const DhReader& r, const OrderedJson& v, const std::string& at) {
  r.object(v, at, {"mass", "com", "inertia"});
  ChainBody b;
  b.mass = r.non_negative(r.required(v, at, "mass"), at + ".mass");
  const std::vector<double> c = r.numbers(r.required(v, at, "com"), at + ".com", 3);
  b.com = Eigen::Vector3d(c[0], c[1], c[2]);
  const std::vector<double> i = r.numbers(r.required(v, at, "inertia"), at + ".inertia", 6);
  b.inertia << i[0], i[1], i[2], i[1], i[3], i[4], i[2], i[4], i[5];
  for (int k = 0; k < 3; ++k) {
    if (b.inertia(k, k) < 0.0) r.fail(at + ".inertia", v["inertia"], "the moments ixx, iyy, izz must be >= 0");
  }
  if (const std::string why = inertia_implausibility(b.inertia); !why.empty()) {
    r.fail(at + ".inertia", v["inertia"], why + ": no rigid body has this inertia");
  }
  return b;
}

// A row's type, limits (in SI) and name.
ChainJoint read_joint(const DhReader& r, const OrderedJson& row, const std::string& at, const Units& units) {
  ChainJoint j;
  j.name = r.string(r.required(row, at, "joint"), at + ".joint");
  if (j.name.empty() || j.name.find(':') != std::string::npos) {
    r.fail(at + ".joint", row["joint"], "must be a non-empty name without ':'");
  }
  const std::string type = row.contains("type") ? r.string(row["type"], at + ".type") : "revolute";
  if (type == "prismatic") {
    j.type = ChainJointType::kPrismatic;
  } else if (type != "revolute") {
    r.fail(at + ".type", row["type"], "must be \"revolute\" or \"prismatic\"");
  }
  const double unit = j.type == ChainJointType::kRevolute ? units.angle : units.length;
  if (row.contains("lower")) j.lower = r.number(row["lower"], at + ".lower") * unit;
  if (row.contains("upper")) j.upper = r.number(row["upper"], at + ".upper") * unit;
  if (j.lower > j.upper) r.fail(at + ".lower", row["lower"], "must be <= upper (" + row["upper"].dump() + ")");
  if (row.contains("max_velocity")) j.max_velocity = r.non_negative(row["max_velocity"], at + ".max_velocity") * unit;
  if (row.contains("max_effort")) j.max_effort = r.non_negative(row["max_effort"], at + ".max_effort");
  return j;
}

std::vector<DhRow> read_rows(const DhReader& r, const OrderedJson& doc, const Units& units,
                             const std::vector<std::string>& named, std::vector<ChainParameter>& parameters) {
  const OrderedJson& rows = r.required(doc, "", "joints");
  if (!rows.is_array() || rows.empty() || rows.size() > static_cast<std::size_t>(kMaxChainJoints)) {
    r.fail("joints", rows.is_array() ? std::to_string(rows.size()) + " rows" : rows.dump(),
           "must be an array of 1 to " + std::to_string(kMaxChainJoints) + " rows");
  }
  std::vector<DhRow> out;
  std::vector<std::string> names;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::string at = "joints[" + std::to_string(i) + "]";
    const OrderedJson& row = r.object(rows[i], at, {"joint", "type", "theta", "d", "a", "alpha", "lower", "upper",
                                                   "max_velocity", "max_effort", "body", "notes"});
    DhRow d;
    d.joint = read_joint(r, row, at, units);
    for (const std::string& n : names) {
      if (n == d.joint.name) r.fail(at + ".joint", row["joint"], "joint names must be unique");
    }
    names.push_back(d.joint.name);
    d.theta = read_entry(r, row, at, d.joint.name, "theta", false, units, named, parameters);
    d.d = read_entry(r, row, at, d.joint.name, "d", true, units, named, parameters);
    d.a = read_entry(r, row, at, d.joint.name, "a", true, units, named, parameters);
    d.alpha = read_entry(r, row, at, d.joint.name, "alpha", false, units, named, parameters);
    if (row.contains("body")) {
      d.body = read_body(r, row["body"], at + ".body");
      ChainParameter c;
      c.name = d.joint.name + ":mass";
      c.description = "mass of the body moving with joint " + d.joint.name + " (its inertia scales with it)";
      c.unit = "kg";
      c.nominal = d.body->mass;
      c.hard_lower = 0.0;
      if (c.nominal > 0.0) {
        d.mass_parameter = static_cast<int>(parameters.size());
        parameters.push_back(c);
      }
    }
    out.push_back(d);
  }
  return out;
}

FennelMassModel read_fennel(const DhReader& r, const OrderedJson& v, std::size_t n) {
  const std::string at = "mass_model";
  r.object(v, at, {"kind", "motor_mass", "motor_mass_factor", "link_density", "tube_outer_diameter", "tube_wall",
                   "ee_mass", "ee_diameter", "ee_length", "notes"});
  const OrderedJson& kind = r.required(v, at, "kind");
  if (kind != "fennel") r.fail(at + ".kind", kind, "must be \"fennel\"");
  FennelMassModel m;
  m.motor_mass = r.numbers(r.required(v, at, "motor_mass"), at + ".motor_mass", n);
  for (std::size_t i = 0; i < n; ++i) {
    if (m.motor_mass[i] < 0.0) r.fail(at + ".motor_mass[" + std::to_string(i) + "]", v["motor_mass"][i], "must be >= 0");
  }
  const struct {
    const char* key;
    double* value;
  } scalars[] = {{"motor_mass_factor", &m.motor_mass_factor}, {"link_density", &m.link_density},
                 {"tube_outer_diameter", &m.tube_outer_diameter}, {"tube_wall", &m.tube_wall},
                 {"ee_mass", &m.ee_mass}, {"ee_diameter", &m.ee_diameter}, {"ee_length", &m.ee_length}};
  for (const auto& s : scalars) {
    if (v.contains(s.key)) *s.value = r.non_negative(v[s.key], at + "." + s.key);
  }
  if (m.tube_wall > 0.5 * m.tube_outer_diameter) {
    r.fail(at + ".tube_wall", show_number(m.tube_wall), "must be <= tube_outer_diameter / 2");
  }
  return m;
}

Eigen::Isometry3d read_tip(const DhReader& r, const OrderedJson& v, const Units& units) {
  r.object(v, "tip", {"xyz", "rpy"});
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero(), rpy = Eigen::Vector3d::Zero();
  if (v.contains("xyz")) {
    const std::vector<double> x = r.numbers(v["xyz"], "tip.xyz", 3);
    xyz = Eigen::Vector3d(x[0], x[1], x[2]) * units.length;
  }
  if (v.contains("rpy")) {
    const std::vector<double> a = r.numbers(v["rpy"], "tip.rpy", 3);
    rpy = Eigen::Vector3d(a[0], a[1], a[2]) * units.angle;
  }
  return xyz_rpy_pose(xyz, rpy.x(), rpy.y(), rpy.z());
}

DhTable read_table(const DhReader& r, const OrderedJson& doc, std::vector<ChainParameter>& parameters) {
  r.object(doc, "", {"format", "format_version", "name", "source", "notes", "convention", "units", "parameters",
                     "joints", "tip", "gravity", "mass_model"});
  const OrderedJson& format = r.required(doc, "", "format");
  if (format != "hapsyn-dh") r.fail("format", format, "must be \"hapsyn-dh\"");
  const OrderedJson& version = r.required(doc, "", "format_version");
  if (version != 1) r.fail("format_version", version, "must be 1");
  DhTable t;
  const OrderedJson& convention = r.required(doc, "", "convention");
  if (convention == "modified_dh") {
    t.modified = true;
  } else if (convention != "dh") {
    r.fail("convention", convention, "must be \"dh\" or \"modified_dh\"");
  }
  const Units units = read_units(r, doc);
  const std::vector<std::string> named = read_named_lengths(r, doc, units, parameters);
  t.rows = read_rows(r, doc, units, named, parameters);
  if (doc.contains("tip")) t.tip = read_tip(r, doc["tip"], units);
  if (doc.contains("gravity")) {
    const std::vector<double> g = r.numbers(doc["gravity"], "gravity", 3);
    t.gravity = Eigen::Vector3d(g[0], g[1], g[2]);
  }
  if (doc.contains("mass_model")) {
    t.fennel = read_fennel(r, doc["mass_model"], t.rows.size());
    for (std::size_t i = 0; i < t.rows.size(); ++i) {
      if (t.rows[i].body) {
        r.fail("joints[" + std::to_string(i) + "].body", std::string("{...}"),
               "a row's body and \"mass_model\" exclude each other (the mass model gives every body)");
      }
    }
  }
  t.mass_scale_parameter = static_cast<int>(parameters.size());
  parameters.push_back(mass_scale_parameter());
  return t;
}

Eigen::Isometry3d rot_z(double angle) { return Eigen::Isometry3d(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ())); }
Eigen::Isometry3d rot_x(double angle) { return Eigen::Isometry3d(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX())); }
Eigen::Isometry3d shift(double x, double z) { return Eigen::Isometry3d(Eigen::Translation3d(x, 0.0, z)); }

void build_chain(const DhTable& t, const double* values, const double* motor_mass, Chain& out) {
  out.joints.clear();
  out.bodies.clear();
  out.gravity = t.gravity;
  // Standard DH: X_{i-1} = Tz(d) Tx(a) Rx(alpha) of the previous row, still to be applied.
  Eigen::Isometry3d previous = Eigen::Isometry3d::Identity();
  for (const DhRow& row : t.rows) {
    const double theta = row.theta.eval(values), d = row.d.eval(values), a = row.a.eval(values),
                 alpha = row.alpha.eval(values);
    ChainJoint joint = row.joint;
    joint.axis = Eigen::Vector3d::UnitZ();
    ChainBody body;
    if (row.body) {
      body = *row.body;
      if (row.mass_parameter >= 0) {
        const double m = values[row.mass_parameter];
        body.inertia *= m / body.mass;
        body.mass = m;
      }
    }
    if (t.modified) {
      joint.origin = rot_x(alpha) * shift(a, 0.0) * rot_z(theta) * shift(0.0, d);
    } else {
      joint.origin = previous * rot_z(theta);
      previous = shift(0.0, d) * shift(a, 0.0) * rot_x(alpha);
      body = transformed(body, previous);
    }
    out.joints.push_back(joint);
    out.bodies.push_back(body);
  }
  out.tip = t.modified ? t.tip : previous * t.tip;
  if (t.fennel) apply_fennel_mass_model(*t.fennel, motor_mass ? motor_mass : t.fennel->motor_mass.data(), out);
  const double scale = values[t.mass_scale_parameter];
  for (ChainBody& b : out.bodies) scale_body(b, scale);
}

}  // namespace

ChainTemplate ChainTemplate::from_dh_file(const std::string& path) {
  const DhReader reader(path);
  ChainTemplate t;
  t.source_ = path;
  auto table = std::make_shared<const DhTable>(read_table(reader, read_json(path), t.parameters_));
  auto impl = std::make_shared<Impl>();
  impl->dof = static_cast<int>(table->rows.size());
  impl->fennel = table->fennel;
  impl->build = [table](const double* values, const double* motor_mass, Chain& out) {
    build_chain(*table, values, motor_mass, out);
  };
  t.impl_ = impl;
  return t;
}

}  // namespace hapsyn::plugins
