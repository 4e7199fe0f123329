#pragma once
/// \file
/// Scenes: the finite set of task-space samples a mechanism must serve. A scene never depends
/// on the design; it is built once per study.
#include <hapsyn/json.hpp>

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

namespace hapsyn {

/// The samples of a scene. Each sample is a row of `poses` (e.g. (x, y) [m] for a planar
/// scene), optionally with named per-sample attributes (e.g. the human's ellipsoid axes).
struct SampleSet {
  /// A point of the pose space (fixed capacity: returned by value without heap allocation).
  using Corner = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 16, 1>;
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  std::vector<std::string> coordinates;  ///< names of the pose columns, e.g. {"x", "y"}
  std::string unit = "m";                ///< unit of the position columns
  RowMatrix poses;                       ///< one sample per row
  std::map<std::string, RowMatrix> attributes;  ///< per-sample extras, one row per sample
  /// What the scene reports about itself (e.g. build time, cache file, counts); copied into
  /// result.json under "scene" and printed by `hapsyn scene`.
  Json info = Json::object();

  int size() const { return static_cast<int>(poses.rows()); }
  int dimension() const { return static_cast<int>(poses.cols()); }
  const double* pose(int i) const { return poses.data() + static_cast<Eigen::Index>(i) * poses.cols(); }
  /// Componentwise minimum / maximum over all samples (the scene's bounding box). O(1) once
  /// cache_bounds() ran (the framework calls it after Scene::build), else a scan.
  Corner lower_corner() const;
  Corner upper_corner() const;
  /// Computes the bounding box once, so that per-design constraints need not scan the samples.
  void cache_bounds();

 private:
  Corner cached_lower_, cached_upper_;
};

/// What the scene must provide, derived from the study's metrics (e.g. the human ellipsoids
/// are built only when a metric needs them).
struct SceneRequest {
  std::vector<std::string> attributes;  ///< attribute names some metric requires
};

/// Scene plugin. Thread safety: build() is called once, from one thread.
class Scene {
 public:
  virtual ~Scene() = default;
  /// Builds the samples. Throws hapsyn::Error for unusable options.
  virtual SampleSet build(const SceneRequest& request) const = 0;
};

}  // namespace hapsyn
