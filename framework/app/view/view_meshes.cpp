#include "view_meshes.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/mesh_drawing.hpp>
#include <hapsyn/read_file.hpp>

#include <boost/filesystem.hpp>

#include <algorithm>
#include <cctype>
#include <map>

namespace hapsyn_cli {
namespace {

using hapsyn::Json;

std::string format_of(const std::string& file) {
  std::string extension = boost::filesystem::path(file).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension.empty() ? "" : extension.substr(1);
}

Json pose_rows(const Eigen::Isometry3d& pose) {
  Json rows = Json::array();
  const Eigen::Matrix4d m = pose.matrix();
  for (int r = 0; r < 4; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  return rows;
}

// "32 MiB" for whole mebibytes, else the bytes.
std::string show_size(std::uint64_t bytes) {
  return bytes % (1u << 20) == 0 ? std::to_string(bytes >> 20) + " MiB" : std::to_string(bytes) + " bytes";
}

// Reads the distinct files of `visuals` within the limits: file -> route index, -1 when refused.
std::map<std::string, int> read_files(const std::vector<hapsyn::MeshVisual>& visuals, const MeshLimits& limits,
                                      std::vector<MeshFile>& files, std::ostream* warnings) {
  std::map<std::string, int> index;
  std::uint64_t total = 0;
  for (const hapsyn::MeshVisual& v : visuals) {
    if (index.count(v.file)) continue;
    index[v.file] = -1;
    std::string bytes;
    try {
      bytes = hapsyn::read_regular_file(v.file, "view", "mesh file", limits.per_file);
    } catch (const hapsyn::Error& e) {
      if (warnings) *warnings << "hapsyn view: warning: link " << v.link << ": " << e.what() << "; not drawn\n";
      continue;
    }
    if (total + bytes.size() > limits.total) {
      if (warnings) {
        *warnings << "hapsyn view: warning: link " << v.link << ": mesh file " << v.file << ": " << bytes.size() << " bytes would take the meshes over "
                  << show_size(limits.total) << " in all; not drawn\n";
      }
      continue;
    }
    total += bytes.size();
    const std::string format = format_of(v.file);
    index[v.file] = static_cast<int>(files.size());
    files.push_back({"/api/mesh/" + std::to_string(files.size()),
                     format == "dae" ? "model/vnd.collada+xml" : "model/stl", std::move(bytes)});
  }
  return index;
}

}  // namespace

ViewMeshes load_view_meshes(const hapsyn::Mechanism& mechanism, const double* design, const hapsyn::SampleSet& scene,
                            int sample, const MeshLimits& limits, std::ostream* warnings) {
  ViewMeshes out;
  if (sample < 0) return out;
  const auto model = mechanism.build(design);
  const auto* drawing = dynamic_cast<const hapsyn::MeshDrawing*>(model.get());
  if (!drawing) return out;
  if (warnings) {
    for (const std::string& w : drawing->mesh_warnings()) *warnings << "hapsyn view: warning: " << w << "\n";
  }
  const auto scratch = mechanism.make_scratch();
  std::vector<hapsyn::MeshVisual> visuals = drawing->mesh_visuals(scene, sample, *scratch);
  // The list is JSON, which must be UTF-8 (a mechanism's names, a path on Linux, need not be).
  const auto not_utf8 = [&](const hapsyn::MeshVisual& v) {
    if (hapsyn::invalid_utf8_at(v.link) == std::string::npos && hapsyn::invalid_utf8_at(v.file) == std::string::npos) return false;
    if (warnings) {
      *warnings << "hapsyn view: warning: link " << hapsyn::shown_bytes(v.link) << ": mesh file " << hapsyn::shown_bytes(v.file)
                << ": not UTF-8 (the page's documents are JSON); not drawn\n";
    }
    return true;
  };
  visuals.erase(std::remove_if(visuals.begin(), visuals.end(), not_utf8), visuals.end());
  const std::map<std::string, int> index = read_files(visuals, limits, out.files, warnings);
  for (const hapsyn::MeshVisual& v : visuals) {
    const int k = index.at(v.file);
    if (k < 0) continue;
    out.list.push_back({{"link", v.link},
                        {"name", boost::filesystem::path(v.file).filename().string()},
                        {"route", out.files[static_cast<std::size_t>(k)].route},
                        {"format", format_of(v.file)},
                        {"pose", pose_rows(v.pose)},
                        {"scale", {v.scale.x(), v.scale.y(), v.scale.z()}}});
  }
  return out;
}

}  // namespace hapsyn_cli
