#pragma once
/// \file
/// The actuator-table format (format "hapsyn-actuator-table", e.g.
/// share/haptic6r/actuators_assumed.json): three actuator sizes (motor + gear module) and six
/// gear codes, from which a joint's velocity and torque limits and its motor mass follow. Read by
/// the mechanisms that choose actuators per joint (haptic6r, serial_chain).
///
/// The file: {"format": "hapsyn-actuator-table", "gear_ratios": [6 ratios > 0, gear codes
/// 1..6], "gear_efficiency": (0, 1], "sizes": [3 entries, sizes 1..3 in order: {"size",
/// "mass" [kg], "motor_speed_rpm" [1/min], "motor_peak_torque" [N m], "gear_peak_torque" [N m]}]};
/// other keys (name, source, units, ...) are documentation and are not read.
#include <array>
#include <string>

namespace hapsyn {

/// An actuator table as read from its file, in SI units.
struct ActuatorTable {
  std::string file;
  std::array<double, 6> gear_ratios{};   ///< per gear code 1..6 [-]
  double gear_efficiency = 1.0;          ///< [-]
  std::array<double, 3> mass{};          ///< per size 1..3 [kg]
  std::array<double, 3> motor_speed{};   ///< [rad/s]
  std::array<double, 3> motor_torque{};  ///< motor peak torque [N m]
  std::array<double, 3> gear_torque{};   ///< gear peak torque [N m]
  /// qdot_max(s, r) = motor_speed(s) / gear_ratios(r) [rad/s] for size 1..3 and code 1..6
  /// (unchecked).
  double max_velocity(int size, int code) const;
  /// tau_max(s, r) = min(motor_torque(s) gear_ratios(r) gear_efficiency, gear_torque(s)) [N m]
  /// (unchecked).
  double max_torque(int size, int code) const;
};

/// Reads and checks an actuator table file (a regular file of at most 64 MiB).
/// \param path       the file (already resolved, e.g. by find_data_file)
/// \param component  who reads it, the prefix of its errors (the plugin: "haptic6r")
/// \throws Error(component, "<file>: <json path> = <value>: <rule>") for a file of another
///         format, a missing key, or a value out of its range (e.g. "gear_ratios[2] = -80: must
///         be in (0.000000, 1000000.000000]"); Error(component, "cannot read data file <file>:
///         ...") / "data file <file> is not a regular file (...)" when it cannot be read.
ActuatorTable read_actuator_table(const std::string& path, const std::string& component);

}  // namespace hapsyn
