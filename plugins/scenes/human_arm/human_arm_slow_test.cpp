// Slow check (label "slow", not in the default run): the paper-resolution human_arm scene
// (0.1 m lattice over +-0.7 m, 505 orientations, 17 joint-3 steps) builds, every sample is a
// finite reachable pose, and the cached copy loads back bit for bit. Times are measured in
// benchmarks/human_arm_benchmark.cpp, not here.
#include "human_arm.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using hapsyn::Json;
using hapsyn::SampleSet;
using namespace hapsyn::plugins;

TEST(HumanArmSlow, PaperResolutionSceneBuildsAndReloadsFromCache) {
  const fs::path dir = fs::temp_directory_path() / ("hapsyn-human-arm-slow-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const HumanArmScene scene(hapsyn::make_options<HumanArmOptions>(Json{{"cache_directory", dir.string()}}));
  hapsyn::SceneRequest request;
  request.attributes = {"M_v", "M_a"};
  const SampleSet built = scene.build(request);
  EXPECT_EQ(built.info["lattice_points"], 15 * 15 * 15);
  EXPECT_EQ(built.info["poses_tried"], 15 * 15 * 15 * 505);
  ASSERT_GT(built.size(), 10000);
  EXPECT_TRUE(built.poses.allFinite());
  for (const auto& [name, values] : built.attributes) EXPECT_TRUE(values.allFinite()) << name;
  const SampleSet loaded = scene.build(request);
  EXPECT_EQ(loaded.info["from_cache"], true);
  EXPECT_TRUE(loaded.poses == built.poses);
  EXPECT_TRUE(loaded.attributes == built.attributes);
  fs::remove_all(dir);
}

}  // namespace
