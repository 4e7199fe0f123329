#pragma once
// Checks of a scene's output made by the framework after Scene::build, beyond those in
// hapsyn/scene.hpp that plugins may call themselves.
#include <hapsyn/scene.hpp>

#include <string>

namespace hapsyn {

/// Every pose coordinate and attribute value is finite (a scene's options at the edge of the
/// doubles, a box centred at 1.7e308, once gave samples at inf that were exported and used).
/// \throws Error(scene, "sample I: COORDINATE = inf: every pose coordinate must be finite ...").
void check_finite_samples(const SampleSet& samples, const std::string& scene);

}  // namespace hapsyn
