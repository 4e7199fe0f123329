// Tests of the actuator-table format (hapsyn/actuator_table.hpp): the shipped table's limits, and
// every error of the reader with its message (file, JSON path, value, rule; the caller's
// component).
#include "test_support.hpp"

#include <hapsyn/actuator_table.hpp>
#include <hapsyn/data_file.hpp>

#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <unistd.h>

using hapsyn::ActuatorTable;
using hapsyn::Json;
using hapsyn::read_actuator_table;
using hapsyn::test::expect_error;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A valid table (the shipped one's figures) that each error test breaks in one place.
Json valid_table() {
  Json sizes = Json::array();
  sizes.push_back({{"size", 1}, {"mass", 0.9}, {"motor_speed_rpm", 6000}, {"motor_peak_torque", 0.25}, {"gear_peak_torque", 30}});
  sizes.push_back({{"size", 2}, {"mass", 1.6}, {"motor_speed_rpm", 5000}, {"motor_peak_torque", 0.6}, {"gear_peak_torque", 70}});
  sizes.push_back({{"size", 3}, {"mass", 2.5}, {"motor_speed_rpm", 4000}, {"motor_peak_torque", 1.2}, {"gear_peak_torque", 150}});
  return {{"format", "hapsyn-actuator-table"},
          {"gear_ratios", {30, 50, 80, 100, 120, 160}},
          {"gear_efficiency", 0.8},
          {"sizes", sizes}};
}

// `text` written to a file of its own; returns the path.
std::string write_table(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/actuator_table_test_" + std::to_string(::getpid()) + "_" + name;
  std::ofstream(path) << text;
  return path;
}

ActuatorTable read(const std::string& name, const Json& table) {
  return read_actuator_table(write_table(name, table.dump()), "some_plugin");
}

}  // namespace

TEST(ActuatorTable, ShippedTableGivesTheLimitsOfItsModel) {
  const std::string file = hapsyn::find_data_file("test", "actuator_file", "haptic6r/actuators_assumed.json");
  const ActuatorTable t = read_actuator_table(file, "test");
  EXPECT_EQ(t.file, file);
  EXPECT_EQ(t.gear_ratios[1], 50.0);
  EXPECT_EQ(t.gear_efficiency, 0.8);
  EXPECT_EQ(t.mass[2], 2.5);
  EXPECT_NEAR(t.motor_speed[0], 6000 * 2 * kPi / 60, 1e-12) << "rpm to rad/s";
  EXPECT_NEAR(t.max_velocity(3, 2), 4000 * 2 * kPi / 60 / 50, 1e-12);
  EXPECT_NEAR(t.max_torque(3, 2), 1.2 * 50 * 0.8, 1e-12);
  EXPECT_NEAR(t.max_torque(1, 6), 30.0, 1e-12) << "capped by the gear's peak torque";
}

TEST(ActuatorTable, ValidTableIsReadAsWritten) {
  const ActuatorTable t = read("valid.json", valid_table());
  EXPECT_EQ(t.gear_ratios[5], 160.0);
  EXPECT_EQ(t.mass[1], 1.6);
  EXPECT_EQ(t.motor_torque[2], 1.2);
  EXPECT_EQ(t.gear_torque[0], 30.0);
}

// (Moved from haptic6r_test: the reader names its caller's component.)
TEST(ActuatorTable, DataFilesThatAreNotRegularFilesAreRefusedWithoutBlocking) {
  expect_error([] { read_actuator_table("/tmp", "haptic6r"); }, {"haptic6r: data file /tmp is not a regular file (a directory)"});
  expect_error([] { read_actuator_table("/nonexistent/actuators.json", "haptic6r"); },
               {"haptic6r: cannot read data file /nonexistent/actuators.json: No such file or directory"});
}

TEST(ActuatorTable, ErrorMessagesNameTheFileThePathTheValueAndTheRule) {
  const std::string bad_json = write_table("bad_json.json", "{\"format\": ");
  expect_error([&] { read_actuator_table(bad_json, "some_plugin"); }, {"some_plugin", "bad_json.json"});
  Json t = valid_table();
  t["format"] = "hapsyn-haptic6r-dh";
  expect_error([&] { read("format.json", t); },
               {"some_plugin: ", "format.json: format = \"hapsyn-haptic6r-dh\": must be \"hapsyn-actuator-table\""});
  t = valid_table();
  t.erase("format");
  expect_error([&] { read("no_format.json", t); }, {"no_format.json: format = (missing)"});
  t = valid_table();
  t.erase("gear_ratios");
  expect_error([&] { read("no_ratios.json", t); }, {"gear_ratios = (missing): must be an array of 6 ratios (gear codes 1..6)"});
  t = valid_table();
  t["gear_ratios"] = {30, 50};
  expect_error([&] { read("few_ratios.json", t); }, {"gear_ratios = [30,50]: must be an array of 6 ratios"});
  t = valid_table();
  t["gear_ratios"][2] = -80;
  expect_error([&] { read("bad_act.json", t); }, {"bad_act.json", "gear_ratios[2] = -80: must be in (0.000000, 1000000.000000]"});
  t = valid_table();
  t["gear_ratios"][0] = "thirty";
  expect_error([&] { read("text_ratio.json", t); }, {"gear_ratios[0] = \"thirty\": must be a number"});
  t = valid_table();
  t.erase("gear_efficiency");
  expect_error([&] { read("no_efficiency.json", t); }, {"no_efficiency.json: gear_efficiency: missing"});
  t = valid_table();
  t["gear_efficiency"] = 1.5;
  expect_error([&] { read("efficiency.json", t); }, {"gear_efficiency = 1.5: must be in (0.000000, 1.000000]"});
  t = valid_table();
  t["sizes"] = Json::array();
  expect_error([&] { read("no_sizes.json", t); }, {"sizes = []: must be an array of 3 entries (sizes 1..3)"});
  t = valid_table();
  t["sizes"][1].erase("gear_peak_torque");
  expect_error([&] { read("size_key.json", t); }, {"size_key.json: sizes[1].gear_peak_torque: missing"});
  t = valid_table();
  t["sizes"][2]["size"] = 1;
  expect_error([&] { read("size_order.json", t); }, {"sizes[2].size = 1: must be 3 (sizes in order)"});
  t = valid_table();
  t["sizes"][0]["mass"] = 2000;
  expect_error([&] { read("mass.json", t); }, {"sizes[0].mass = 2000: must be in [0.000000, 1000.000000]"});
  t = valid_table();
  t["sizes"][0]["motor_speed_rpm"] = 0;
  expect_error([&] { read("speed.json", t); }, {"sizes[0].motor_speed_rpm = 0: must be in (0.000000, 1000000.000000]"});
  t = valid_table();
  t["sizes"][1]["motor_peak_torque"] = -1;
  expect_error([&] { read("motor_torque.json", t); }, {"sizes[1].motor_peak_torque = -1: must be in (0.000000"});
  t = valid_table();
  t["sizes"][2]["gear_peak_torque"] = 2e6;
  expect_error([&] { read("gear_torque.json", t); }, {"sizes[2].gear_peak_torque = 2000000.0: must be in (0.000000"});
}
