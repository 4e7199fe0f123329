#pragma once
// Small conversions the view's documents share (study, result, live frames).
#include <hapsyn/json.hpp>
#include <hapsyn/mechanism.hpp>
#include <hapsyn/scene.hpp>

#include <Eigen/Core>

#include <vector>

namespace hapsyn_cli {

/// A drawing as JSON: [{"name", "points": [[x, y, z], ...]}, ...] (the scene frame, m).
hapsyn::Json segments_json(const std::vector<hapsyn::Segment>& segments);

/// Sample i's position: its pose's first three coordinates, missing ones 0 (a planar scene).
Eigen::Vector3d sample_position(const hapsyn::SampleSet& samples, int i);

}  // namespace hapsyn_cli
