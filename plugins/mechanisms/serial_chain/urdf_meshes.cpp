// The mesh visuals of a URDF chain (urdf_meshes.hpp): which links are carried by which frame,
// and each visual checked once at load.
#ifdef HAPSYN_HAVE_URDFDOM
#include "urdf_meshes.hpp"

#include "chain_template_impl.hpp"

#include <hapsyn/read_file.hpp>

#include <set>

namespace hapsyn::plugins {
namespace {

const char* primitive_name(int type) {
  switch (type) {
    case urdf::Geometry::BOX: return "box";
    case urdf::Geometry::CYLINDER: return "cylinder";
    case urdf::Geometry::SPHERE: return "sphere";
    default: return "geometry";
  }
}

Eigen::Isometry3d pose_of(const urdf::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  t.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized().toRotationMatrix();
  return t;
}

class Collector {
 public:
  Collector(const std::string& urdf_path, const urdf::ModelInterface& model, const std::set<std::string>& on_path,
            const std::map<std::string, std::array<double, 6>>& origins, const std::string& ros_package_path)
      : urdf_path_(urdf_path), model_(model), on_path_(on_path), origins_(origins), ros_package_path_(ros_package_path) {}

  // The link's visuals, then those of the links fixed to it off the path.
  void link(const urdf::Link& link, const ChainMeshVisual& frame) {
    for (const urdf::VisualSharedPtr& visual : link.visual_array) {
      if (visual && visual->geometry) add(link.name, *visual, frame);
    }
    for (const urdf::JointSharedPtr& joint : link.child_joints) {
      if (joint->type != urdf::Joint::FIXED || on_path_.count(joint->child_link_name)) continue;
      const urdf::LinkConstSharedPtr child = model_.getLink(joint->child_link_name);
      if (!child) continue;
      ChainMeshVisual below = frame;
      const auto o = origins_.find(joint->name);
      if (o != origins_.end()) {
        const auto& v = o->second;
        below.offset = frame.offset * serial_chain_detail::xyz_rpy_pose(Eigen::Vector3d(v[0], v[1], v[2]), v[3], v[4], v[5]);
      }
      this->link(*child, below);
    }
  }

  ChainMeshes out;

 private:
  void add(const std::string& link, const urdf::Visual& visual, const ChainMeshVisual& frame) {
    const std::string at = urdf_path_ + ": link \"" + link + "\" visual ";
    if (visual.geometry->type != urdf::Geometry::MESH) {
      out.warnings.push_back(at + primitive_name(visual.geometry->type) +
                             ": a primitive shape, not drawn (only .stl and .dae meshes are)");
      return;
    }
    const auto& mesh = static_cast<const urdf::Mesh&>(*visual.geometry);
    const std::string named = at + "mesh \"" + mesh.filename + "\": ";
    if (!drawable_mesh_format(mesh.filename)) {
      out.warnings.push_back(named + "not drawn (only .stl and .dae files are)");
      return;
    }
    const MeshFileLookup found = resolve_mesh_file(mesh.filename, urdf_path_, ros_package_path_);
    if (found.path.empty()) {
      out.warnings.push_back(named + found.problem + "; not drawn");
      return;
    }
    // The view lists link and file names in JSON, which must be UTF-8 (a path on Linux need not be).
    if (invalid_utf8_at(link) != std::string::npos || invalid_utf8_at(found.path) != std::string::npos) {
      out.warnings.push_back(urdf_path_ + ": link " + shown_bytes(link) + " visual mesh " + shown_bytes(mesh.filename) +
                             ": the link's or the file's name is not UTF-8; not drawn");
      return;
    }
    ChainMeshVisual v = frame;
    v.link = link;
    v.file = found.path;
    v.scale = Eigen::Vector3d(mesh.scale.x, mesh.scale.y, mesh.scale.z);
    v.offset = frame.offset * pose_of(visual.origin);
    out.visuals.push_back(std::move(v));
  }

  const std::string& urdf_path_;
  const urdf::ModelInterface& model_;
  const std::set<std::string>& on_path_;
  const std::map<std::string, std::array<double, 6>>& origins_;
  const std::string& ros_package_path_;
};

}  // namespace

ChainMeshes collect_urdf_meshes(const std::string& urdf_path, const urdf::ModelInterface& model,
                                const urdf::LinkConstSharedPtr& base, const std::vector<UrdfPathJoint>& path,
                                const std::map<std::string, std::array<double, 6>>& origins,
                                const std::string& ros_package_path) {
  std::set<std::string> on_path{base->name};
  for (const UrdfPathJoint& j : path) on_path.insert(j.joint->child_link_name);
  Collector collect(urdf_path, model, on_path, origins, ros_package_path);
  ChainMeshVisual frame;  // the base's
  collect.link(*base, frame);
  for (const UrdfPathJoint& j : path) {
    if (j.moving) {
      ++frame.body;
      frame.path_origins.clear();
    } else {
      frame.path_origins.push_back(j.origin_parameter);
    }
    if (const urdf::LinkConstSharedPtr child = model.getLink(j.joint->child_link_name)) collect.link(*child, frame);
  }
  return std::move(collect.out);
}

}  // namespace hapsyn::plugins
#endif  // HAPSYN_HAVE_URDFDOM
