#include <hapsyn/error.hpp>
#include <hapsyn/scene.hpp>
#include "sample_checks.hpp"

#include <Eigen/LU>

#include <cassert>
#include <cmath>
#include <set>
#include <sstream>
#include <string>

namespace hapsyn {

SampleSet::Corner SampleSet::lower_corner() const {
  if (cached_lower_.size() == poses.cols()) return cached_lower_;
  return poses.colwise().minCoeff().transpose();
}
SampleSet::Corner SampleSet::upper_corner() const {
  if (cached_upper_.size() == poses.cols()) return cached_upper_;
  return poses.colwise().maxCoeff().transpose();
}
void SampleSet::cache_bounds() {
  assert(poses.cols() <= 16 && "SampleSet::Corner holds at most 16 pose coordinates");
  cached_lower_ = poses.colwise().minCoeff().transpose();
  cached_upper_ = poses.colwise().maxCoeff().transpose();
}

Eigen::Matrix3d rotation_option(const std::vector<std::vector<double>>& rows, const std::string& key,
                                const std::string& scene) {
  assert(rows.size() == 3 && rows[0].size() == 3 && rows[1].size() == 3 && rows[2].size() == 3);
  Eigen::Matrix3d c;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) c(r, k) = rows[static_cast<std::size_t>(r)][static_cast<std::size_t>(k)];
  }
  const double orthogonality = (c.transpose() * c - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(orthogonality <= 1e-6) || !(c.determinant() > 0.0)) {
    std::ostringstream s;
    s << "options." << key << " = " << render_value(Json(rows))
      << ": must be a rotation matrix (orthonormal, det +1); max |C^T C - I| = " << orthogonality
      << ", det = " << c.determinant();
    throw Error(scene, s.str());
  }
  return c;
}

const std::vector<std::vector<double>>& upright_shoulder_to_base_rows() {
  static const std::vector<std::vector<double>> rows{{0.0, 0.0, -1.0}, {-1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}};
  return rows;
}

void check_lattice(const SampleSet& samples, const std::string& scene) {
  if (!samples.lattice) return;
  const SampleLattice& l = *samples.lattice;
  const auto refuse = [&](const std::string& why) { throw Error(scene, "lattice: " + why); };
  // At most 2^20 points per axis: n^3 stays far inside long long.
  if (l.per_axis < 1 || l.per_axis > (1 << 20)) {
    refuse("per_axis = " + std::to_string(l.per_axis) + ": must be in [1, 2^20]");
  }
  if (!(l.step > 0.0) || !std::isfinite(l.step)) {
    refuse("step = " + render_value(Json(l.step)) + ": must be finite and > 0");
  }
  const Eigen::Matrix3d& R = l.lattice_to_poses;
  const double orthogonality = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(orthogonality <= 1e-6) || !(R.determinant() > 0.0)) {
    std::ostringstream s;
    s << "lattice_to_poses: must be a rotation matrix (orthonormal, det +1); max |C^T C - I| = " << orthogonality
      << ", det = " << R.determinant();
    refuse(s.str());
  }
  if (l.candidates_per_point < 1) {
    refuse("candidates_per_point = " + std::to_string(l.candidates_per_point) + ": must be >= 1");
  }
  if (l.index_of_sample.size() != static_cast<std::size_t>(samples.size())) {
    refuse("index_of_sample has " + std::to_string(l.index_of_sample.size()) + " entries for " +
           std::to_string(samples.size()) + " samples (one per sample)");
  }
  const long long n = l.per_axis;
  const long long points = n * n * n;
  for (std::size_t i = 0; i < l.index_of_sample.size(); ++i) {
    const long long index = l.index_of_sample[i];
    if (index < 0 || index >= points) {
      refuse("index_of_sample[" + std::to_string(i) + "] = " + std::to_string(index) + ": must be in [0, " +
             std::to_string(points) + ")");
    }
  }
}

void check_groups(const SampleSet& samples, const std::string& scene) {
  std::set<std::string> names;
  for (std::size_t k = 0; k < samples.groups.size(); ++k) {
    const SampleGrouping& g = samples.groups[k];
    const std::string where = "groups[" + std::to_string(k) + "]";
    const auto refuse = [&](const std::string& why) { throw Error(scene, where + why); };
    if (g.name.empty()) refuse(".name is empty: every grouping needs a name");
    if (!names.insert(g.name).second) refuse(".name = \"" + g.name + "\": two groupings have this name");
    if (g.labels.empty()) refuse(" ('" + g.name + "') has no labels");
    std::set<std::string> labels;
    for (std::size_t i = 0; i < g.labels.size(); ++i) {
      if (g.labels[i].empty()) refuse(".labels[" + std::to_string(i) + "] is empty");
      if (!labels.insert(g.labels[i]).second) {
        refuse(".labels[" + std::to_string(i) + "] = \"" + g.labels[i] + "\": listed twice");
      }
    }
    if (g.of_sample.size() != static_cast<std::size_t>(samples.size())) {
      refuse(".of_sample has " + std::to_string(g.of_sample.size()) + " entries for " +
             std::to_string(samples.size()) + " samples (one per sample)");
    }
    for (std::size_t i = 0; i < g.of_sample.size(); ++i) {
      if (g.of_sample[i] < 0 || g.of_sample[i] >= static_cast<int>(g.labels.size())) {
        refuse(".of_sample[" + std::to_string(i) + "] = " + std::to_string(g.of_sample[i]) + ": must be in [0, " +
               std::to_string(g.labels.size()) + ")");
      }
    }
  }
}

void check_finite_samples(const SampleSet& samples, const std::string& scene) {
  const auto refuse = [&](Eigen::Index row, const std::string& column, double value, const char* what) {
    throw Error(scene, "sample " + std::to_string(row) + ": " + column + " = " + render_value(Json(value)) +
                           ": every " + what + " must be finite (are the scene's options beyond the range of doubles?)");
  };
  for (Eigen::Index i = 0; i < samples.poses.rows(); ++i) {
    for (Eigen::Index c = 0; c < samples.poses.cols(); ++c) {
      if (std::isfinite(samples.poses(i, c))) continue;
      const std::size_t k = static_cast<std::size_t>(c);
      refuse(i, k < samples.coordinates.size() ? samples.coordinates[k] : "column " + std::to_string(c),
             samples.poses(i, c), "pose coordinate");
    }
  }
  for (const auto& [name, values] : samples.attributes) {
    for (Eigen::Index i = 0; i < values.rows(); ++i) {
      for (Eigen::Index c = 0; c < values.cols(); ++c) {
        if (!std::isfinite(values(i, c))) refuse(i, name + "[" + std::to_string(c) + "]", values(i, c), "attribute value");
      }
    }
  }
}

void check_weights(const SampleSet& samples, const std::string& component) {
  const std::vector<double>& w = samples.weights;
  if (w.empty()) return;
  const auto refuse = [&](const std::string& why) { throw Error(component, "scene: weights" + why); };
  if (w.size() != static_cast<std::size_t>(samples.size())) {
    refuse(" has " + std::to_string(w.size()) + " entries for " + std::to_string(samples.size()) +
           " samples (one per sample, or none for equal weights)");
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < w.size(); ++i) {
    if (!(w[i] >= 0.0) || !std::isfinite(w[i])) {
      refuse("[" + std::to_string(i) + "] = " + render_value(Json(w[i])) + ": must be finite and >= 0");
    }
    sum += w[i];
  }
  // Finite weights can still overflow their sum; N / W must be a usable finite factor.
  if (!(sum > 0.0) || !std::isfinite(sum)) {
    refuse(" sum to " + render_value(Json(sum)) + ": the sum must be finite and > 0 (at least one weight > 0)");
  }
}

std::vector<double> orientation_option(const std::vector<double>& orientation, int dimension, const std::string& scene) {
  if (orientation.empty()) return {};
  const std::string shown = "options.orientation = " + Json(orientation).dump();
  if (orientation.size() != 4) throw Error(scene, shown + ": must be empty or 4 numbers [qw, qx, qy, qz]");
  if (dimension != 3) throw Error(scene, shown + ": needs dimension 3 (a full pose is x, y, z, qw, qx, qy, qz)");
  double norm = 0.0;
  for (double q : orientation) norm += q * q;
  norm = std::sqrt(norm);
  if (!(std::abs(norm - 1.0) <= 1e-6)) {
    throw Error(scene, shown + ": must be a unit quaternion (norm " + Json(norm).dump() + " differs from 1 by more than 1e-6)");
  }
  std::vector<double> out;
  for (double q : orientation) out.push_back(q / norm);
  return out;
}

}  // namespace hapsyn
