// The haptic6r data file: the DH table (share/haptic6r/), read and checked with messages naming
// the file, the JSON path, the value and the rule. (The actuator table's format is the
// framework's: hapsyn/actuator_table.hpp.)
#include "haptic6r.hpp"

#include <hapsyn/json_text.hpp>
#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/read_file.hpp>

#include <cmath>
#include <fstream>
#include <string>

namespace hapsyn::plugins {

namespace {

constexpr const char* kName = "haptic6r";
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

std::string show(const Json& v) { return v.dump(); }

// A data file is a few kB: a FIFO, a device or a huge file is refused before it is read.
constexpr std::uint64_t kMaxDataFileBytes = 64u << 20;

Json read_json_file(const std::string& path) {
  const std::string text = read_regular_file(path, kName, "data file", kMaxDataFileBytes);
  return parse_json_text(text, path, kName);
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

}  // namespace

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
    // Within 1e-12 rad is the structure's angle: the kinematics (haptic6r_chain.hpp) and the
    // IK assume it exactly.
    dh.rows[i].alpha = alpha_deg[i] * kDeg;
  }
  return dh;
}

}  // namespace hapsyn::plugins
