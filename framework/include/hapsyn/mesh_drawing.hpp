#pragma once
/// \file
/// An optional drawing interface a MechanismModel may also implement: the mesh files of its links
/// (a URDF's STL / COLLADA visuals) and where they are at a sample's configuration, for viewers
/// (`hapsyn view`). It is not part of MechanismModel (no plugin API change): a viewer asks for
/// it with `dynamic_cast<const MeshDrawing*>(model)` and, without it, draws the polylines of
/// MechanismModel::segments alone.
///
/// Contract for an implementer (a MechanismModel that also derives from MeshDrawing):
/// - mesh_visuals() answers for the configuration that solve() picks for the sample, the same
///   one MechanismModel::segments() draws; it is empty when segments() is (an unreachable sample,
///   or one solve() finds only outside the joint limits).
/// - Each MeshVisual::file is an absolute path to a regular file the mechanism resolved and
///   checked at load (a file that could not be resolved is left out with a warning then, never
///   an error: mesh_warnings() says why); only ".stl" (binary or ASCII STL) and ".dae"
///   (COLLADA) files are listed. Links and files should be named in UTF-8 (a viewer writes
///   them into JSON and leaves out, with a warning, a visual whose names are not).
/// - Called once per picture, outside the per-sample loop, with a scratch from
///   Mechanism::make_scratch: may allocate; const and thread-safe like solve().
#include <hapsyn/mechanism.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace hapsyn {

/// One mesh of a mechanism's drawing at one configuration.
struct MeshVisual {
  std::string link;  ///< the link (rigid body) that carries it, for a legend
  std::string file;  ///< absolute path of the mesh file (.stl or .dae), resolved at load
  /// The mesh file's frame in the frame of the scene's poses [m]: a point p of the file (after
  /// `scale`) is drawn at pose * p. For a URDF: the link frame at the configuration times the
  /// visual's `<origin>`.
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  /// Per-axis scale of the file's coordinates (URDF `<mesh scale>`; 1 1 1 when not given). Note
  /// that a COLLADA file's own `<unit>` applies before it.
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();
};

/// The meshes of a mechanism model at a sample's configuration (see the file comment).
class MeshDrawing {
 public:
  MeshDrawing() = default;
  MeshDrawing(const MeshDrawing&) = delete;
  MeshDrawing& operator=(const MeshDrawing&) = delete;
  virtual ~MeshDrawing();  // out of line (framework library): one typeinfo for dynamic_cast
  /// The meshes at the configuration solve() picks for sample `sample` (an index) of `scene`;
  /// empty when MechanismModel::segments() is empty for it. May allocate.
  virtual std::vector<MeshVisual> mesh_visuals(const SampleSet& scene, int sample, MechanismScratch& scratch) const = 0;
  /// One line per visual the mechanism's file has but mesh_visuals() leaves out (a file not
  /// found, another format, a primitive shape), naming the link and the file; found at load,
  /// printed by the viewer (a study that is only run stays quiet). Default: none.
  virtual std::vector<std::string> mesh_warnings() const;
};

}  // namespace hapsyn
