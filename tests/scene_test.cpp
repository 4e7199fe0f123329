// The lattice contract of a scene (SampleSet::lattice): what the framework checks, and
// human_arm's declaration against its own per-sample lattice_index attribute.
#include "test_support.hpp"

#include <hapsyn/scene.hpp>
#include <hapsyn/internal/scene_export.hpp>

#include <boost/filesystem.hpp>

#include <sstream>

#include <unistd.h>

using hapsyn::Json;
using hapsyn::SampleLattice;
using hapsyn::SampleSet;
using hapsyn::test::error_of;
using hapsyn::test::registry;

namespace {
// Three samples on a 3 x 3 x 3 lattice.
SampleSet lattice_scene() {
  SampleSet set;
  set.coordinates = {"x", "y", "z"};
  set.poses = SampleSet::RowMatrix::Zero(3, 3);
  SampleLattice lattice;
  lattice.per_axis = 3;
  lattice.step = 0.5;
  lattice.index_of_sample = {0, 13, 13};
  lattice.candidates_per_point = 2;
  set.lattice = lattice;
  return set;
}
}  // namespace

TEST(SceneLattice, AConsistentDeclarationOrNoneIsAccepted) {
  EXPECT_EQ(error_of([] { hapsyn::check_lattice(lattice_scene(), "toy"); }), "(no error)");
  SampleSet plain = lattice_scene();
  plain.lattice.reset();
  EXPECT_EQ(error_of([&] { hapsyn::check_lattice(plain, "toy"); }), "(no error)");
}

TEST(SceneLattice, EachBrokenRuleIsRefusedNamingTheScene) {
  SampleSet s = lattice_scene();
  s.lattice->per_axis = 0;
  EXPECT_EQ(error_of([&] { hapsyn::check_lattice(s, "toy"); }), "toy: lattice: per_axis = 0: must be in [1, 2^20]");
  s = lattice_scene();
  s.lattice->step = 0.0;
  EXPECT_EQ(error_of([&] { hapsyn::check_lattice(s, "toy"); }), "toy: lattice: step = 0.0: must be finite and > 0");
  s = lattice_scene();
  s.lattice->candidates_per_point = 0;
  EXPECT_EQ(error_of([&] { hapsyn::check_lattice(s, "toy"); }), "toy: lattice: candidates_per_point = 0: must be >= 1");
  s = lattice_scene();
  s.lattice->index_of_sample.pop_back();
  EXPECT_EQ(error_of([&] { hapsyn::check_lattice(s, "toy"); }),
            "toy: lattice: index_of_sample has 2 entries for 3 samples (one per sample)");
  s = lattice_scene();
  s.lattice->index_of_sample[1] = 27;
  EXPECT_EQ(error_of([&] { hapsyn::check_lattice(s, "toy"); }),
            "toy: lattice: index_of_sample[1] = 27: must be in [0, 27)");
}

TEST(SceneLattice, DensityCountsSamplesPerPointOverCandidates) {
  const auto dir = boost::filesystem::temp_directory_path() / ("hapsyn-scene-test-" + std::to_string(::getpid()));
  hapsyn::plot_lattice_density(lattice_scene(), dir.string());
  EXPECT_TRUE(boost::filesystem::exists(dir / "density_slices.dat"));
  EXPECT_TRUE(boost::filesystem::exists(dir / "density_slices.gp"));
  boost::filesystem::remove_all(dir);
  SampleSet plain = lattice_scene();
  plain.lattice.reset();
  EXPECT_NE(error_of([&] { hapsyn::plot_lattice_density(plain, dir.string()); }).find("declares no SampleLattice"),
            std::string::npos);
}

TEST(SceneLattice, HumanArmDeclaresItsLatticeAsItsLatticeIndexAttribute) {
  const Json doc = {{"scene",
                     {{"plugin", "human_arm"},
                      {"options", {{"lattice_step", 0.35}, {"orientations", 20}, {"joint3_steps", 5}, {"cache", false}}}}}};
  const hapsyn::BuiltScene built = hapsyn::build_scene_alone(doc, registry(), 2, {});
  const SampleSet& set = built.samples;
  ASSERT_GT(set.size(), 0);
  ASSERT_TRUE(set.lattice.has_value());
  EXPECT_EQ(set.lattice->per_axis, set.info["lattice_per_axis"].get<int>());
  EXPECT_EQ(set.lattice->step, set.info["lattice_step"].get<double>());
  EXPECT_EQ(set.lattice->candidates_per_point, set.info["orientations"].get<int>());
  EXPECT_EQ(set.lattice->candidates, "orientations");
  const auto& index = set.attributes.at("lattice_index");
  ASSERT_EQ(set.lattice->index_of_sample.size(), static_cast<std::size_t>(set.size()));
  for (int i = 0; i < set.size(); ++i) {
    EXPECT_EQ(set.lattice->index_of_sample[static_cast<std::size_t>(i)], static_cast<long long>(index(i, 0))) << i;
  }
}

// ---- Per-sample weights: the central check and the exported CSV ------------------------------

TEST(SceneWeights, CheckWeightsNamesTheComponentAndTheRule) {
  SampleSet s = lattice_scene();
  EXPECT_EQ(error_of([&] { hapsyn::check_weights(s, "toy"); }), "(no error)");  // none: all 1
  s.weights = {0.0, 2.0, 0.5};
  EXPECT_EQ(error_of([&] { hapsyn::check_weights(s, "toy"); }), "(no error)");  // a zero weight is allowed
  s.weights = {1.0, -1e-300, 1.0};
  EXPECT_EQ(error_of([&] { hapsyn::check_weights(s, "toy"); }), "toy: scene: weights[1] = -1e-300: must be finite and >= 0");
  s.weights = {1.0};
  EXPECT_EQ(error_of([&] { hapsyn::check_weights(s, "toy"); }),
            "toy: scene: weights has 1 entries for 3 samples (one per sample, or none for equal weights)");
}

TEST(SceneWeights, SceneCsvEndsWithAWeightColumnWhenWeightsArePresent) {
  SampleSet s;
  s.coordinates = {"x", "y"};
  s.poses = SampleSet::RowMatrix::Zero(2, 2);
  s.poses(1, 0) = 0.5;
  EXPECT_EQ(hapsyn::scene_csv(s), "x,y\n0,0\n0.5,0\n");
  s.weights = {0.25, 3.0};
  EXPECT_EQ(hapsyn::scene_csv(s), "x,y,weight\n0,0,0.25\n0.5,0,3\n");
}

// The run's grants to a scene build (issue 20): a default request grants nothing, so a scene
// built without the loader's settings behaves as before (every core, no progress output).
TEST(Scene, DefaultRequestStatesNoThreadsAndNoProgressStream) {
  const hapsyn::SceneRequest request;
  EXPECT_TRUE(request.attributes.empty());
  EXPECT_EQ(request.threads, 0);
  EXPECT_EQ(request.progress, nullptr);
}

TEST(Scene, PluginScenesReceiveTheRequestThreadsAndProgressThroughTheRegistry) {
  // human_arm through the plugin boundary: the fields added after `attributes` arrive intact.
  const auto scene = registry().create_scene(
      "human_arm", Json{{"lattice_step", 0.2}, {"orientations", 20}, {"joint3_steps", 3}, {"cache", false}}, "scene");
  hapsyn::SceneRequest request;
  request.threads = 1;
  std::ostringstream progress;
  request.progress = &progress;
  const SampleSet set = scene->build(request);
  EXPECT_GT(set.size(), 0);
  EXPECT_EQ(progress.str(), "");  // a build well under 2 s prints nothing
}
