// The actuator-table format: read and checked with messages naming the file, the JSON path, the
// value and the rule (the reader's caller names the component).
#include <hapsyn/actuator_table.hpp>

#include <hapsyn/error.hpp>
#include <hapsyn/json_text.hpp>
#include <hapsyn/read_file.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace hapsyn {

namespace {

constexpr double kPi = 3.14159265358979323846;

// A data file is a few kB: a FIFO, a device or a huge file is refused before it is read.
constexpr std::uint64_t kMaxDataFileBytes = 64u << 20;

// The reader's context: the component its errors name and the file.
struct Reader {
  const std::string& component;
  const std::string& file;

  [[noreturn]] void fail(const std::string& message) const { throw Error(component, file + ": " + message); }

  // The number at `path`, within [lower, upper] ((lower, upper] when lower_open).
  double number(const std::string& path, const Json& v, double lower, double upper, bool lower_open = false) const {
    if (!v.is_number()) fail(path + " = " + v.dump() + ": must be a number");
    const double x = v.get<double>();
    if (!std::isfinite(x) || x < lower || (lower_open && x == lower) || x > upper) {
      fail(path + " = " + v.dump() + ": must be in " + (lower_open ? "(" : "[") + std::to_string(lower) + ", " +
           std::to_string(upper) + "]");
    }
    return x;
  }

  // The array at `key` of `size` entries, else an error naming what it must hold.
  const Json& array(const Json& doc, const char* key, std::size_t size, const std::string& rule) const {
    if (!doc.contains(key) || !doc[key].is_array() || doc[key].size() != size) {
      fail(std::string(key) + " = " + (doc.contains(key) ? doc[key].dump() : "(missing)") + ": " + rule);
    }
    return doc[key];
  }
};

void read_size(const Reader& r, const Json& s, std::size_t i, ActuatorTable& t) {
  const std::string at = "sizes[" + std::to_string(i) + "]";
  for (const char* key : {"size", "mass", "motor_speed_rpm", "motor_peak_torque", "gear_peak_torque"}) {
    if (!s.is_object() || !s.contains(key)) r.fail(at + "." + key + ": missing");
  }
  if (!s["size"].is_number_integer() || s["size"].get<int>() != static_cast<int>(i) + 1) {
    r.fail(at + ".size = " + s["size"].dump() + ": must be " + std::to_string(i + 1) + " (sizes in order)");
  }
  t.mass[i] = r.number(at + ".mass", s["mass"], 0.0, 1e3);
  t.motor_speed[i] = r.number(at + ".motor_speed_rpm", s["motor_speed_rpm"], 0.0, 1e6, true) * 2.0 * kPi / 60.0;
  t.motor_torque[i] = r.number(at + ".motor_peak_torque", s["motor_peak_torque"], 0.0, 1e6, true);
  t.gear_torque[i] = r.number(at + ".gear_peak_torque", s["gear_peak_torque"], 0.0, 1e6, true);
}

}  // namespace

double ActuatorTable::max_velocity(int size, int code) const {
  return motor_speed[static_cast<std::size_t>(size - 1)] / gear_ratios[static_cast<std::size_t>(code - 1)];
}

double ActuatorTable::max_torque(int size, int code) const {
  const std::size_t s = static_cast<std::size_t>(size - 1);
  return std::min(motor_torque[s] * gear_ratios[static_cast<std::size_t>(code - 1)] * gear_efficiency, gear_torque[s]);
}

ActuatorTable read_actuator_table(const std::string& path, const std::string& component) {
  const std::string text = read_regular_file(path, component, "data file", kMaxDataFileBytes);
  const Json doc = parse_json_text(text, path, component.c_str());
  const Reader r{component, path};
  ActuatorTable t;
  t.file = path;
  if (!doc.is_object() || doc.value("format", "") != "hapsyn-actuator-table") {
    r.fail(std::string("format = ") + (doc.is_object() && doc.contains("format") ? doc["format"].dump() : "(missing)") +
           ": must be \"hapsyn-actuator-table\"");
  }
  const Json& ratios = r.array(doc, "gear_ratios", 6, "must be an array of 6 ratios (gear codes 1..6)");
  for (std::size_t i = 0; i < 6; ++i) {
    t.gear_ratios[i] = r.number("gear_ratios[" + std::to_string(i) + "]", ratios[i], 0.0, 1e6, true);
  }
  if (!doc.contains("gear_efficiency")) r.fail("gear_efficiency: missing");
  t.gear_efficiency = r.number("gear_efficiency", doc["gear_efficiency"], 0.0, 1.0, true);
  const Json& sizes = r.array(doc, "sizes", 3, "must be an array of 3 entries (sizes 1..3)");
  for (std::size_t i = 0; i < 3; ++i) read_size(r, sizes[i], i, t);
  return t;
}

}  // namespace hapsyn
