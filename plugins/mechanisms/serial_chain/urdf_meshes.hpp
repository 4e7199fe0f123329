#pragma once
/// \file
/// Private to the serial_chain model (urdf_chain.cpp): a URDF's drawable mesh visuals along the
/// base -> tip path (chain_meshes.hpp), read from urdfdom's model. Only with urdfdom.
#include "chain_meshes.hpp"

#include <urdf_model/model.h>

#include <array>
#include <map>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// One joint of the base -> tip path, base first.
struct UrdfPathJoint {
  urdf::JointConstSharedPtr joint;
  bool moving = false;
  int origin_parameter = -1;  ///< index of its "<joint>:x" parameter
};

/// The <visual> elements of the links the chain carries: base_link, each path joint's child link,
/// and every link hanging from one of them through fixed joints only (a gripper, a stylus, a
/// cover); each path link rides on the last moving joint before it (the base before the first).
/// Meshes (.stl, .dae) that resolve (resolve_mesh_file, with `ros_package_path`) are drawn;
/// every other visual (another format, a file not found, a box / cylinder / sphere) gives one
/// warning line "<urdf>: link \"L\" visual ...: why; not drawn". \param origins every joint's
/// <origin> as written (x, y, z, roll, pitch, yaw).
ChainMeshes collect_urdf_meshes(const std::string& urdf_path, const urdf::ModelInterface& model,
                                const urdf::LinkConstSharedPtr& base, const std::vector<UrdfPathJoint>& path,
                                const std::map<std::string, std::array<double, 6>>& origins,
                                const std::string& ros_package_path);

}  // namespace hapsyn::plugins
