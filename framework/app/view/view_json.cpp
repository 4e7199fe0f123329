#include "view_json.hpp"

#include <algorithm>

namespace hapsyn_cli {

hapsyn::Json segments_json(const std::vector<hapsyn::Segment>& segments) {
  hapsyn::Json out = hapsyn::Json::array();
  for (const hapsyn::Segment& segment : segments) {
    hapsyn::Json points = hapsyn::Json::array();
    for (const Eigen::Vector3d& p : segment.points) points.push_back({p.x(), p.y(), p.z()});
    out.push_back({{"name", segment.name}, {"points", points}});
  }
  return out;
}

Eigen::Vector3d sample_position(const hapsyn::SampleSet& samples, int i) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int c = 0; c < std::min(3, samples.dimension()); ++c) p[c] = samples.pose(i)[c];
  return p;
}

}  // namespace hapsyn_cli
