#pragma once
/// \file
/// A scene on its own (`hapsyn scene`): built from a problem file's "scene" section without
/// the rest of the study, exported as CSV, and, for a scene that declares a SampleLattice,
/// its density drawn as lattice slices.
#include <hapsyn/json.hpp>
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/scene.hpp>

#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace hapsyn {

/// A scene built alone.
struct BuiltScene {
  std::string plugin;        ///< the scene plugin's name
  SampleSet samples;         ///< as Scene::build returned it (lattice checked)
  double build_time_s = 0.0; ///< wall time of Scene::build
};

/// Builds the "scene" section ({"plugin", "options"}) of a problem document; every other
/// section is ignored. The lattice declaration, if any, is checked (check_lattice), and so are
/// the weights, if any (check_weights, naming the scene plugin).
/// \param threads    when given, the build's threads (SceneRequest::threads; a scene's own
///                   `threads` option above 0 wins)
/// \param attributes per-sample attributes to request (SceneRequest::attributes)
/// \param progress   progress lines of a long build (SceneRequest::progress), null: quiet
/// \throws Error("problem", "scene ...") for a missing or malformed section, the registry's
///         and the scene's errors for unknown plugins, bad options or attributes.
BuiltScene build_scene_alone(const Json& problem, const Registry& registry, std::optional<int> threads,
                             const std::vector<std::string>& attributes, std::ostream* progress = nullptr);

/// The samples as CSV: the pose columns (SampleSet::coordinates), then every attribute in
/// alphabetical order, flattened as name[i] (name alone for a single column), then a `weight`
/// column when the scene has SampleSet::weights; numbers in their
/// shortest exact form (they read back as the same doubles).
std::string scene_csv(const SampleSet& samples);

/// The density of a lattice scene: per lattice point, its samples / candidates_per_point
/// (human_arm: reachable orientations / orientations tried), written by plot_lattice_slices as
/// `<directory>/density_slices.{dat,gp,png}` (the directory is created).
/// \return run_gnuplot's message: empty when the picture was rendered, else why not (the data
///         and script are written regardless).
/// \throws Error("scene", ...) when the samples declare no lattice; Error("output") when a file
///         cannot be written.
std::string plot_lattice_density(const SampleSet& samples, const std::string& directory);

}  // namespace hapsyn
