#pragma once
// The mesh files `hapsyn view` draws for a mechanism that has them (hapsyn/mesh_drawing.hpp):
// each distinct file read once at start, within size limits, and served on a fixed route
// "/api/mesh/K"; no request ever names a path.
#include <hapsyn/json.hpp>
#include <hapsyn/mechanism.hpp>

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace hapsyn_cli {

/// The largest mesh file served, and the most bytes of mesh files in all [bytes].
struct MeshLimits {
  std::uint64_t per_file = 32u << 20;
  std::uint64_t total = 128u << 20;
};

/// One served mesh file: its route ("/api/mesh/K"), content type and bytes.
struct MeshFile {
  std::string route;
  std::string content_type;
  std::string bytes;
};

/// What the page draws of the meshes, and the files behind it.
struct ViewMeshes {
  /// /api/study "meshes": [{link, name (the file's name, no folder), route, format ("stl" or
  /// "dae"), pose (4 x 4 rows: the mesh frame in the scene frame), scale [sx, sy, sz]}].
  hapsyn::Json list = hapsyn::Json::array();
  std::vector<MeshFile> files;  ///< files[K] is served at "/api/mesh/K"
};

/// The meshes of `mechanism` at `design`, drawn at sample `sample` of `scene` (none for -1, for a
/// model that is no MeshDrawing, or one that lists none there). Prints the mechanism's
/// mesh_warnings() and a warning for each file refused here, "hapsyn view: warning: ...", to
/// `warnings` (null: quiet): a file that cannot be read, or one over limits.per_file, or one that
/// would take the total over limits.total, is left out (its meshes are not listed).
ViewMeshes load_view_meshes(const hapsyn::Mechanism& mechanism, const double* design, const hapsyn::SampleSet& scene,
                            int sample, const MeshLimits& limits, std::ostream* warnings);

}  // namespace hapsyn_cli
