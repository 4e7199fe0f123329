#pragma once
// Test support shared by the arm model's tests and the human_arm scene's: the shipped arm file,
// its model, small numeric and file helpers. Header-only, for tests (hapsyn_add_test puts tests/
// on the include path for test_support.hpp).
#include "human_arm_model.hpp"

#include <hapsyn/json.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace hapsyn::plugins::human_arm_testing {

/// The shipped right arm of Fennel et al.
inline const std::string kArmFile = HAPSYN_SOURCE_DIR "/share/human_arm/fennel2022_right_arm.json";

/// The model of kArmFile, loaded once.
inline const HumanArm& arm() {
  static const HumanArm a(load_human_arm(kArmFile));
  return a;
}

/// kArmFile as a JSON document (for tests that edit it).
inline Json arm_document() {
  std::ifstream in(kArmFile);
  return Json::parse(in);
}

/// The largest entry-wise difference of two rotation matrices.
inline double rotation_distance(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  return (A - B).cwiseAbs().maxCoeff();
}

/// An empty folder of this process under the system's temporary folder.
inline std::filesystem::path temp_dir(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("hapsyn-human-arm-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace hapsyn::plugins::human_arm_testing
