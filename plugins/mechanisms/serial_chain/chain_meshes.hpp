#pragma once
/// \file
/// The mesh visuals of a URDF chain, for viewers (hapsyn/mesh_drawing.hpp): which links' <visual>
/// <mesh> files are drawn, where each sits relative to the chain's frames, and how a URDF's mesh
/// file name is resolved to a file. Read once at load by ChainTemplate::from_urdf; a visual that
/// cannot be drawn is left out with a warning, never an error (the study must still run).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// One drawable mesh of a chain: the frame of the link that carries it is the frame of moving
/// joint `body` (chain.hpp's joint frame, after its motion; the base frame for -1) times the
/// origins of the fixed joints of the base -> tip path between that frame and the link (design
/// parameters "<joint>:x..yaw", in path order), times `offset`.
struct ChainMeshVisual {
  std::string link;   ///< the link whose <visual> it is
  std::string file;   ///< absolute path of an existing .stl or .dae file
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();  ///< <mesh scale>
  int body = -1;      ///< the moving joint whose frame carries the link (-1: the base)
  /// Index of the "<joint>:x" parameter (then y, z, roll, pitch, yaw) of each fixed path joint
  /// from body's frame to the link, in order.
  std::vector<int> path_origins;
  /// The fixed joints off the path (as the file writes them) from the last path link to the
  /// link, then the visual's <origin>.
  Eigen::Isometry3d offset = Eigen::Isometry3d::Identity();
};

/// The mesh visuals of a chain file and why the others are not drawn.
struct ChainMeshes {
  std::vector<ChainMeshVisual> visuals;
  /// One line per visual left out: "<urdf>: link \"L\" visual mesh \"F\": <why>".
  std::vector<std::string> warnings;
};

/// Where a URDF mesh file name points: `path` (absolute, an existing regular file) or, when it
/// cannot be resolved, `problem` (why, naming what was searched).
struct MeshFileLookup {
  std::string path;
  std::string problem;
};

/// Resolves a URDF <mesh filename>: an absolute path; "file://" + a path (absolute, or relative
/// to the URDF's folder); "package://NAME/rest": rest inside a folder NAME, searched as the URDF's
/// folder or one of its ancestors named NAME, or a folder NAME inside one of them, then inside
/// each entry of `ros_package_path` (':'-separated, as ROS_PACKAGE_PATH; may be empty) or that
/// entry itself when named NAME; any other text: a path relative to the URDF's folder. Other
/// URI schemes ("http://", "model://") are a problem. Does not check the format.
MeshFileLookup resolve_mesh_file(const std::string& filename, const std::string& urdf_path,
                                 const std::string& ros_package_path);

/// Whether a mesh file name is in a format viewers draw: ".stl" or ".dae" (any case).
bool drawable_mesh_format(const std::string& filename);

/// The visual's pose in its body's frame (see ChainMeshVisual) for the chain's parameter values.
Eigen::Isometry3d mesh_pose_in_body(const ChainMeshVisual& visual, const double* values);

}  // namespace hapsyn::plugins
