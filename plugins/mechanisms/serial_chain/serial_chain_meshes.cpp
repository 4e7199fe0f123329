// SerialChainModel::mesh_visuals (hapsyn/mesh_drawing.hpp): a URDF's meshes at the configuration
// segments() draws, in the scene frame.
#include "serial_chain.hpp"

namespace hapsyn::plugins {

std::vector<MeshVisual> SerialChainModel::mesh_visuals(const SampleSet& scene, int sample, MechanismScratch& scratch) const {
  const std::vector<ChainMeshVisual>& visuals = setup_->chain_template.meshes().visuals;
  if (visuals.empty()) return {};
  ChainFrames frames;
  if (!drawn_frames(scene, sample, scratch, frames)) return {};
  const Eigen::Isometry3d scene_from_base = setup_->base_from_scene.inverse();
  std::vector<MeshVisual> out;
  for (const ChainMeshVisual& v : visuals) {
    const Eigen::Isometry3d body =
        v.body < 0 ? Eigen::Isometry3d::Identity() : frames.joint[static_cast<std::size_t>(v.body)];
    out.push_back({v.link, v.file, scene_from_base * body * mesh_pose_in_body(v, mesh_parameters_.data()), v.scale});
  }
  return out;
}

std::vector<std::string> SerialChainModel::mesh_warnings() const { return setup_->chain_template.meshes().warnings; }

}  // namespace hapsyn::plugins
