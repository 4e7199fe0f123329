#pragma once
// What `hapsyn view` shows of one study, computed once at start: the study's design, the
// mechanism drawn at one of its samples, and the samples with every metric's local values. The
// server (http_server.hpp) only hands these documents out.
#include "view_meshes.hpp"

#include <hapsyn/internal/registry.hpp>
#include <hapsyn/json.hpp>

#include <memory>
#include <ostream>
#include <string>

namespace hapsyn_cli {

struct ViewSource;

/// The two JSON documents of the page's API.
struct ViewData {
  std::string name;     ///< the study's name
  hapsyn::Json study;   ///< /api/study: name, plugins, design, drawn sample, segments, gravity
  hapsyn::Json samples; ///< /api/samples: positions, status, local-value columns with units
  hapsyn::Json result;  ///< /api/result: front, statistics (runs, history), batch (result_views.hpp)
  /// The study and its design, kept for the virtual prototype (replay_data.hpp).
  std::shared_ptr<const ViewSource> source;
  ViewMeshes meshes;    ///< the mesh files of the drawn design (study["meshes"] lists them)
};

/// Loads a problem file, a result directory (one holding result.json) or a sweep's or
/// comparison's directory (result_views.hpp find_batch: one of its runs) and computes its
/// ViewData (/api/study also carries the human of a scene that models one: view_figure.hpp).
/// The design: a result's best design (result.json "best.design"); for a problem file, every
/// fixed component's value and the midpoint of every free one's bounds (rounded for integer
/// variables), which is the design `hapsyn run` evaluates for an evaluate-solver
/// study. The local values: the result's samples.csv when it has one, else the design evaluated
/// at every sample as `hapsyn run` does for samples.csv (record_samples). The drawn sample:
/// the reachable one nearest the reachable samples' centroid (none drawn when no sample is).
/// The meshes: load_view_meshes at the drawn sample (default MeshLimits).
/// \param progress where progress lines and the meshes' warnings go (null: quiet)
/// \throws hapsyn::Error("view", ...) for a path that is neither, a result without a best
///         design, a samples.csv that does not match the scene; the loader's errors otherwise.
ViewData load_view_data(const std::string& path, const hapsyn::Registry& registry, std::ostream* progress);

}  // namespace hapsyn_cli
