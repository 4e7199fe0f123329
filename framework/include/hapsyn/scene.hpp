#pragma once
/// \file
/// Scenes: the finite set of task-space samples a mechanism must serve. A scene never depends
/// on the design; it is built once per study.
#include <hapsyn/json.hpp>

#include <Eigen/Core>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn {

/// The declaration of a scene whose samples sit on the points of a cubic lattice, several
/// samples per point (human_arm: the reachable orientations at each position). It is the only
/// lattice knowledge the framework has: a scene that fills SampleSet::lattice gets
///  - maps.csv / position maps grouped by lattice point (one row per point that holds samples,
///    with a `lattice_index` column), and map_<objective>.png drawn as lattice slices;
///  - `hapsyn scene --plot`: the density (samples at a point / candidates_per_point) as slices.
/// Without it, samples are grouped by equal x, y, z coordinates and `scene --plot` refuses.
///
/// Geometry: point (ix, iy, iz), each in [0, per_axis), has the index ix + n (iy + n iz)
/// (n = per_axis; x varies fastest) and lies at ((ix - h) step, (iy - h) step, (iz - h) step),
/// h = (n - 1) / 2, in the scene's own lattice frame (human_arm: the shoulder frame S), which
/// need not be the frame of SampleSet::poses: `lattice_to_poses` rotates one into the other, and
/// the plots slice by height along the vertical z of the poses' frame.
///
/// The framework checks the declaration after Scene::build (check_lattice) and refuses a scene
/// that breaks it.
struct SampleLattice {
  int per_axis = 0;    ///< n >= 1: points per axis (n^3 points)
  double step = 0.0;   ///< > 0: spacing of neighbouring points [SampleSet::unit]
  /// One entry per sample (SampleSet::size() entries): the index in [0, n^3) of its point.
  std::vector<long long> index_of_sample;
  /// How many candidate samples each point was tried with (human_arm: the orientation set's
  /// size), >= 1; the density plot shows samples at a point / candidates_per_point.
  int candidates_per_point = 1;
  /// What a candidate is, for plot titles (human_arm: "orientations").
  std::string candidates = "samples";
  /// Rotation from the lattice frame to the frame of SampleSet::poses (human_arm: C_S^B), a
  /// rotation matrix. The maps slice the lattice along the vertical z of the poses' frame (the
  /// heights of the base frame B, where gravity points along -z) when it maps lattice axes onto
  /// pose axes; otherwise along the lattice axis closest to that vertical.
  Eigen::Matrix3d lattice_to_poses = Eigen::Matrix3d::Identity();
  /// What the lattice is centred on, for plot labels ("height above <origin>"; human_arm: "the
  /// shoulder").
  std::string origin = "the lattice centre";
  /// The lattice frame's name, for axis labels (human_arm: "S").
  std::string frame = "L";
};

/// A partition of a scene's samples into labelled groups (the recording, the subject, the
/// activity a sample comes from). For a scene that declares groupings, `hapsyn run` reports
/// every objective per group (each group's samples reduced and combined as the whole scene is),
/// with the mean and standard deviation across the groups (result.json "groups", groups.csv).
/// Checked centrally by check_groups after Scene::build.
struct SampleGrouping {
  std::string name;                 ///< what a group is, e.g. "subject"; unique within a scene
  std::vector<std::string> labels;  ///< the groups' names, distinct, e.g. {"S01", "S02"}
  std::vector<int> of_sample;       ///< per sample: its group, an index into labels
};

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
  /// Optional per-sample weights [-]: empty means every weight is 1; otherwise one entry per
  /// sample, finite, >= 0, with a positive sum (checked centrally by check_weights when the
  /// Problem is made). Averaging metrics then give weighted means: the evaluator multiplies every
  /// Reduction::kSum local value of sample i by w_i N / W (N samples, W the sum of the weights),
  /// so a combine() that divides sums by the sample count, or by another sum-reduced count,
  /// yields sum_i w_i v_i / sum_i w_i without knowing about weights. Min/max reductions ignore
  /// the weights: a worst case is a worst case. Equal weights (all the same value) are exactly
  /// the unweighted study. On a subset of the samples (culling, a chunk), a combine()
  /// that divides by another sum-reduced local (coverage, mean_isotropy) still gives the
  /// subset's weighted mean; one that divides by the sample count gives it scaled by the
  /// scene's mean weight over the subset's mean weight. Position maps (hapsyn/internal/maps.hpp) weight
  /// each position's samples by their own weights.
  std::vector<double> weights;
  /// What the scene reports about itself (e.g. build time, cache file, counts); copied into
  /// result.json under "scene" and printed by `hapsyn scene`.
  Json info = Json::object();
  /// Groupings of the samples (see SampleGrouping), coarse or fine in any order; usually empty.
  std::vector<SampleGrouping> groups;
  /// Set by scenes whose samples sit on a cubic lattice (see SampleLattice); empty otherwise.
  std::optional<SampleLattice> lattice;

  int size() const { return static_cast<int>(poses.rows()); }
  int dimension() const { return static_cast<int>(poses.cols()); }
  const double* pose(int i) const { return poses.data() + static_cast<Eigen::Index>(i) * poses.cols(); }
  /// Componentwise minimum / maximum over all samples (the scene's bounding box). O(1) once
  /// cache_bounds() ran (the framework calls it after Scene::build), else a scan.
  Corner lower_corner() const;
  Corner upper_corner() const;
  /// Minimum / maximum of pose coordinate `k` (0 <= k < dimension()) over all samples, in the
  /// coordinate's unit. O(1) and copy-free once cache_bounds() ran, else a scan: what per-design
  /// constraints call (a Corner copy costs more than the constraint).
  double min_coordinate(int k) const {
    return cached_lower_.size() == poses.cols() ? cached_lower_[k] : poses.col(k).minCoeff();
  }
  double max_coordinate(int k) const {
    return cached_upper_.size() == poses.cols() ? cached_upper_[k] : poses.col(k).maxCoeff();
  }
  /// Computes the bounding box once, so that per-design constraints need not scan the samples.
  void cache_bounds();

 private:
  Corner cached_lower_, cached_upper_;
};

/// Checks a scene's SampleLattice declaration against its samples (nothing to check without
/// one). \param samples the scene's samples \param scene the scene plugin, for the error
/// \throws Error("<scene>: lattice: ...") when per_axis < 1, step <= 0 or not finite,
///         candidates_per_point < 1, index_of_sample does not hold one entry per sample, or an
///         index lies outside [0, per_axis^3).
void check_lattice(const SampleSet& samples, const std::string& scene);

/// Checks a scene's groupings (nothing to check without any).
/// \throws Error("<scene>: groups[k] ...") for an empty or repeated name, no labels, a repeated
///         or empty label, of_sample not holding one entry per sample, or an entry outside
///         [0, labels.size()).
void check_groups(const SampleSet& samples, const std::string& scene);

/// Checks a scene's per-sample weights (nothing to check when SampleSet::weights is empty).
/// \param samples the scene's samples
/// \param component the component named in the error (the Problem passes "problem")
/// \throws Error("<component>: scene: weights ...") when there is not one weight per sample,
///         a weight is NaN, infinite or negative ("weights[i] = v: must be finite and >= 0"), or
///         the weights sum to zero.
void check_weights(const SampleSet& samples, const std::string& component);

/// A scene option giving one orientation to every sample (box, disc): empty, or a unit
/// quaternion [qw, qx, qy, qz] whose norm is 1 within 1e-6, returned normalised.
/// \param orientation the option's value; \param dimension the scene's position dimension;
/// \param scene the plugin, for the error
/// \throws Error `("<scene>: options.orientation = ...: <rule>")` for another size, a norm off by
///         more than 1e-6, or dimension != 3 (a pose is x, y, z, qw, qx, qy, qz).
std::vector<double> orientation_option(const std::vector<double>& orientation, int dimension, const std::string& scene);

/// A scene option giving a rotation matrix as 3 rows of 3 (human_arm's C_S_B, motion's
/// recording_rotation): the declarations fix the shape, this checks the rest.
/// \param rows the option's value, \param key the option's name, \param scene the plugin, for
/// the error
/// \throws Error `("<scene>: options.<key> = <rows>: must be a rotation matrix (orthonormal,
///         det +1); max |C^T C - I| = ..., det = ...")` when max |C^T C - I| > 1e-6 or det <= 0.
Eigen::Matrix3d rotation_option(const std::vector<std::vector<double>>& rows, const std::string& key,
                                const std::string& scene);

/// The rotation C_S^B from the human arm model's shoulder frame S to the manipulator base B
/// (x_B = x_S^B + C_S^B x_S) that seats the user upright in front of the device: the arm model's
/// rest pose (q = 0, hanging along -y_S) points along -z_B, the direction of gravity; the user
/// faces +x_B (forward flexion, -z_S, goes to +x_B) and abduction of the right arm (+x_S) to -y_B.
/// It is the transpose of the matrix Fennel et al. print as C_S^B, (0,-1,0; 0,0,1; -1,0,0), which
/// taken as S -> B would lay the user on their side (docs/design.md section 4.3). The default of
/// the human_arm and motion scenes' C_S_B option, as 3 rows.
const std::vector<std::vector<double>>& upright_shoulder_to_base_rows();

/// What the scene must provide, derived from the study's metrics (e.g. the human ellipsoids
/// are built only when a metric needs them).
///
/// It also carries what the run grants the build (the fields after `attributes` were added
/// last, so a plugin built before them still reads `attributes` where it was):
struct SceneRequest {
  std::vector<std::string> attributes;  ///< attribute names some metric requires
  /// Threads the run allows the build (`hapsyn run --threads N`), >= 0; 0 means the run stated
  /// none, and the scene may use every core. A scene's own `threads` option, when it has one
  /// and it is set (> 0), wins over this. The loader fills it.
  int threads = 0;
  /// Where a build that takes long reports how far it is: whole lines, at most one every 2 s,
  /// e.g. "human_arm: building the reachable poses: 40% of 656000, ~12 s left". nullptr: quiet
  /// (tests, --quiet). May be written from the scene's worker threads, never two lines at once.
  std::ostream* progress = nullptr;
};

/// Scene plugin: the one pure virtual is build().
///
/// Life cycle: created once per study (options filled from its declarations, see
/// hapsyn/options.hpp; relations between options that the declarations cannot express are
/// checked by the constructor, throwing hapsyn::Error); build() is then called once, from one
/// thread, after the metrics are known. A scene never depends on the design.
///
/// What the framework checks centrally, so a scene need not: the samples exist and are finite,
/// the weights, when given, are usable (check_weights), a declared lattice is consistent with them (check_lattice), the mechanism serves them
/// (Mechanism::check_scene).
class Scene {
 public:
  virtual ~Scene() = default;
  /// Builds the samples.
  /// \param request what the study's metrics need: build exactly these per-sample attributes
  ///        (each a matrix with one row per sample) and no others (they may be expensive).
  /// \returns poses in the scene frame (SampleSet::coordinates names the columns, unit the
  ///          position unit), the attributes asked for, a SampleLattice when the samples sit on
  ///          one, and `info` for result.json. May use threads of its own and allocate freely.
  /// \throws hapsyn::Error for an attribute it cannot provide or unusable input files.
  virtual SampleSet build(const SceneRequest& request) const = 0;
};

}  // namespace hapsyn
