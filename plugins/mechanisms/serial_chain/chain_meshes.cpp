// A URDF's mesh file names resolved to files, and a mesh's pose in its body's frame.
#include "chain_meshes.hpp"

#include "chain_template_impl.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <system_error>

namespace hapsyn::plugins {
namespace {

namespace fs = std::filesystem;

bool starts_with(const std::string& s, const std::string& prefix) { return s.compare(0, prefix.size(), prefix) == 0; }

bool regular_file(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

bool directory(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

// An absolute, lexically normal path (no file system access beyond the current directory).
std::string absolute_path(const fs::path& p) {
  std::error_code ec;
  const fs::path a = fs::absolute(p, ec);
  return (ec ? p : a).lexically_normal().string();
}

fs::path urdf_folder(const std::string& urdf_path) { return fs::path(absolute_path(urdf_path)).parent_path(); }

MeshFileLookup existing(const fs::path& p, const std::string& what) {
  const std::string shown = absolute_path(p);
  if (regular_file(p)) return {shown, ""};
  return {"", "no such file (" + what + shown + ")"};
}

// The folders a package named `name` may be: the URDF's folder and its ancestors named so, or a
// folder `name` inside one of them; then the ROS_PACKAGE_PATH entries (or a folder inside them).
std::vector<fs::path> package_candidates(const std::string& name, const std::string& urdf_path,
                                         const std::string& ros_package_path) {
  std::vector<fs::path> out;
  for (fs::path d = urdf_folder(urdf_path);; d = d.parent_path()) {
    if (d.filename() == name) out.push_back(d);
    out.push_back(d / name);
    if (d == d.parent_path() || d.empty()) break;
  }
  std::size_t start = 0;
  while (start <= ros_package_path.size()) {
    const std::size_t end = std::min(ros_package_path.find(':', start), ros_package_path.size());
    const fs::path entry = ros_package_path.substr(start, end - start);
    if (!entry.empty()) {
      if (entry.filename() == name) out.push_back(entry);
      out.push_back(entry / name);
    }
    start = end + 1;
  }
  return out;
}

MeshFileLookup resolve_package(const std::string& rest, const std::string& urdf_path, const std::string& ros_package_path) {
  const std::size_t slash = rest.find('/');
  const std::string name = rest.substr(0, slash);
  const std::string inside = slash == std::string::npos ? "" : rest.substr(slash + 1);
  if (name.empty() || inside.empty()) return {"", "a package:// URI must be package://NAME/PATH"};
  std::vector<std::string> packages;
  for (const fs::path& folder : package_candidates(name, urdf_path, ros_package_path)) {
    if (!directory(folder)) continue;
    const std::string shown = absolute_path(folder);
    if (std::find(packages.begin(), packages.end(), shown) != packages.end()) continue;
    packages.push_back(shown);
    if (regular_file(folder / inside)) return {absolute_path(folder / inside), ""};
  }
  if (packages.empty()) {
    return {"", "package \"" + name + "\" not found (searched the URDF's folder and its ancestors" +
                    (ros_package_path.empty() ? std::string(", ROS_PACKAGE_PATH not set)") : ", and ROS_PACKAGE_PATH)")};
  }
  std::string list;
  for (const std::string& p : packages) list += (list.empty() ? "" : ", ") + p;
  return {"", "no file " + inside + " in package \"" + name + "\" (" + list + ")"};
}

}  // namespace

MeshFileLookup resolve_mesh_file(const std::string& filename, const std::string& urdf_path,
                                 const std::string& ros_package_path) {
  if (filename.empty()) return {"", "an empty file name"};
  if (starts_with(filename, "package://")) return resolve_package(filename.substr(10), urdf_path, ros_package_path);
  std::string path = filename;
  if (starts_with(filename, "file://")) {
    path = filename.substr(7);
  } else if (const std::size_t scheme = filename.find("://"); scheme != std::string::npos) {
    return {"", "URI scheme \"" + filename.substr(0, scheme) + "://\" not supported (absolute or relative paths, "
                "file:// and package:// are)"};
  }
  const fs::path p(path);
  if (p.is_absolute()) return existing(p, "");
  return existing(urdf_folder(urdf_path) / p, "relative to the URDF's folder: ");
}

bool drawable_mesh_format(const std::string& filename) {
  std::string extension = fs::path(filename).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".stl" || extension == ".dae";
}

Eigen::Isometry3d mesh_pose_in_body(const ChainMeshVisual& visual, const double* values) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (const int k : visual.path_origins) {
    const double* o = values + k;
    pose = pose * serial_chain_detail::xyz_rpy_pose(Eigen::Vector3d(o[0], o[1], o[2]), o[3], o[4], o[5]);
  }
  return pose * visual.offset;
}

}  // namespace hapsyn::plugins
