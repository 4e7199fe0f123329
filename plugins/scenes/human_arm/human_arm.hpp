#pragma once
/// \file
/// The scene of palm poses the 7-DOF human arm of Fennel et al. (IEEE ToH 2022, section V) can
/// reach: the orientation set, the position lattice, the scene's options, the scene and its disk
/// cache. The arm itself (arm file, kinematics, IK, ellipsoid axes) is the shared model
/// "shared/human_arm_model/human_arm_model.hpp".
///
/// Frames: S is the shoulder (DH frame 0), P the palm (DH frame 7), B the manipulator base and E
/// its end effector. Twists are ordered (omega, v). Angles are in rad, lengths in m, joint
/// velocities in rad/s, joint accelerations in rad/s^2 (the arm file holds degrees; they are
/// converted once on load).
#include "shared/human_arm_model/human_arm_model.hpp"

#include <hapsyn/json.hpp>
#include <hapsyn/options.hpp>
#include <hapsyn/scene.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// The orientation set: n unit quaternions (w, x, y, z) with w >= 0, near-uniform on SO(3).
/// A generalized Fibonacci grid in [0,1)^3, u_i = ((i + 1/2)/n, frac(i/phi), frac(i/phi^2)) with
/// phi the plastic number (the real root of x^3 = x + 1), mapped to the hemisphere by the
/// volume-preserving (constant Jacobian determinant) Hopf map
/// q = (sqrt(u1) cos(pi (u3 - 1/2)), sqrt(1 - u1) sin(2 pi u2), sqrt(1 - u1) cos(2 pi u2),
///      sqrt(u1) sin(pi (u3 - 1/2))).
std::vector<Eigen::Quaterniond> orientation_set(int n);

/// Lattice coordinates along one axis: k * step for k = -m..m, m = floor(extent/step + 1e-9).
std::vector<double> lattice_axis(double step, double extent);

/// Default of the max_samples option: 50 million candidate poses (about 30 GB of samples with
/// the ellipsoids; the paper's scene tries about 0.7 million).
constexpr long long kHumanArmMaxSamples = 50000000;
/// Default of the max_ik_solves option: 1e9 solves (minutes on a few cores; the paper's scene
/// needs about 11 million).
constexpr long long kHumanArmMaxIkSolves = 1000000000;

struct HumanArmOptions;
/// The rule relating lattice_step and lattice_extent: "" when they give at most 401 lattice points
/// per axis, else what is wrong.
std::string human_arm_lattice_rule(const HumanArmOptions& o);

/// The options of the human_arm scene as a problem file gives them, declared once
/// (`hapsyn describe human_arm`). Shapes, ranges, types and the lattice size are checked by the
/// framework from these declarations; HumanArmScene's constructor checks the rest (see
/// resolve_human_arm_scene_options).
struct HumanArmOptions {
  std::string arm_file;                     ///< as given; resolved by resolve_arm_file
  double lattice_step{};                    ///< [m], > 0
  double lattice_extent{};                  ///< [m], >= 0: cube of +-extent around the shoulder
  int orientations{};                       ///< [1, 1000000]
  int joint3_steps{};                       ///< [1, 10000]
  std::vector<double> x_S_B;                ///< 3: shoulder position in B [m]
  std::vector<std::vector<double>> C_S_B;   ///< 3 rows of 3: rotation S -> B (default: upright user)
  std::vector<std::vector<double>> C_E_P;   ///< 3 rows of 3: rotation E -> P
  std::vector<double> x_E_P;                ///< 3: end-effector position in P [m]
  bool cache{};
  std::string cache_directory;              ///< "" = $XDG_CACHE_HOME/hapsyn or ~/.cache/hapsyn
  int threads{};                            ///< [0, 4096], 0 = the run's --threads, else all cores
  long long max_samples{};                  ///< >= 1: cap on the candidate poses (kHumanArmMaxSamples)
  long long max_ik_solves{};                ///< >= 1: cap on the IK solves (kHumanArmMaxIkSolves)

  static void declare(OptionDeclarations<HumanArmOptions>& d) {
    using O = HumanArmOptions;
    d.describe(
        "Reachable palm poses of the 7-DOF human arm of Fennel et al. 2022 (section V): a position lattice around "
        "the shoulder x a near-uniform orientation set; per pose the closed-form IK with joint 3 on a grid, the "
        "solution of highest manipulability kept, unreachable poses dropped. Samples are the end-effector targets "
        "T_E^B = T_S^B T_P^S T_E^P as (x, y, z, qw, qx, qy, qz) [m]; attributes shoulder_pose, human_q, arm_points, "
        "manipulability, lattice_index, and on request M_v, M_a (6x6 row-major, base frame). Built scenes are "
        "cached on disk.");
    d.add(&O::arm_file, "arm_file", kHumanArmDefaultArmFile,
          "Arm model (JSON, see share/human_arm/README.md): an absolute path, a path relative to the current "
          "directory, or relative to hapsyn's share directory. The default is Table II of the paper.");
    d.add(&O::lattice_step, "lattice_step", 0.1,
          "Spacing of the position lattice (the paper: 0.1 m). Points are k * step, |k * step| <= lattice_extent, "
          "on each axis of the shoulder frame S.")
        .greater_than(0)
        .unit("m");
    d.add(&O::lattice_extent, "lattice_extent", 0.7,
          "Half side of the lattice cube around the shoulder; 0.7 m covers the arm's reach (0.677 m) with 15 points "
          "per axis at 0.1 m.")
        .minimum(0)
        .unit("m");
    d.add(&O::orientations, "orientations", 505,
          "Number of orientations per position (the paper: 505), a generalized Fibonacci grid mapped to the "
          "unit-quaternion hemisphere with constant Jacobian determinant.")
        .range(1, 1000000);
    d.add(&O::joint3_steps, "joint3_steps", 17,
          "Number of equidistant joint-3 values between its limits, both included (17: 10 deg steps over [-80, 80] "
          "deg).")
        .range(1, 10000);
    d.add(&O::x_S_B, "x_S_B", {0.0, 0.0, -0.61},
          "Shoulder position in the manipulator base frame B (the paper: 0.61 m below joint 1).")
        .size(3)
        .unit("m");
    d.add(&O::C_S_B, "C_S_B", upright_shoulder_to_base_rows(),
          "Rotation from the shoulder frame S to B, as 3 rows: x_B = x_S_B + C_S_B x_S. The default seats the user "
          "upright facing +x_B (the rest arm hangs along -z_B, the direction of gravity; abduction goes to -y_B): it "
          "is the transpose of the paper's printed C_S^B = (0,-1,0; 0,0,1; -1,0,0), which read as S -> B would lay the "
          "user on their side (docs/design.md section 4.3).")
        .size(3)
        .row_size(3);
    d.add(&O::C_E_P, "C_E_P", {{0.0, 0.0, 1.0}, {0.0, -1.0, 0.0}, {1.0, 0.0, 0.0}},
          "Rotation from the end-effector frame E to the palm frame P, as 3 rows (the paper's (0,0,1; 0,-1,0; "
          "1,0,0)).")
        .size(3)
        .row_size(3);
    d.add(&O::x_E_P, "x_E_P", {0.0, 0.0, 0.0},
          "End-effector position in the palm frame P (the paper: 0). M_v and M_a are the twists of this point.")
        .size(3)
        .unit("m");
    d.add(&O::cache, "cache", true,
          "Keep built scenes on disk, keyed by a hash of the options and the arm file; a corrupt or stale file is "
          "rebuilt.");
    d.add(&O::cache_directory, "cache_directory", "",
          "Where cached scenes live; \"\" means $XDG_CACHE_HOME/hapsyn, else ~/.cache/hapsyn.");
    d.add(&O::threads, "threads", 0,
          "Threads used to build the scene (0: the run's --threads when given, else all cores). The samples do not "
          "depend on it.")
        .range(0, 4096);
    d.add(&O::max_samples, "max_samples", kHumanArmMaxSamples,
          "Largest number of candidate poses (lattice points within the arm's reach x orientations) the scene may "
          "try; larger scenes are refused before anything is built (a guard against a lattice_step or orientations "
          "that would run for hours and fill memory). Raise it deliberately for a finer scene.")
        .minimum(1);
    d.add(&O::max_ik_solves, "max_ik_solves", kHumanArmMaxIkSolves,
          "Largest number of inverse-kinematics solves (candidate poses x joint3_steps) the build may do; larger "
          "scenes are refused before anything is built.")
        .minimum(1);
    d.rule({"lattice_step", "lattice_extent"}, "at most 401 lattice points per axis (2 floor(extent / step) + 1)",
           &human_arm_lattice_rule);
  }
};

/// The options resolved for building (what build() and the cache key read): the declared options
/// with arm_file the resolved absolute path, and the placement as Eigen types, the rotations
/// checked. The placement members hide the declared ones of the same name (HumanArmOptions::x_S_B
/// etc. keep the values as given).
struct HumanArmSceneOptions : HumanArmOptions {
  Eigen::Vector3d x_S_B;  ///< shoulder position in B [m]
  Eigen::Matrix3d C_S_B;  ///< rotation S -> B
  Eigen::Matrix3d C_E_P;  ///< rotation E -> P
  Eigen::Vector3d x_E_P;  ///< end-effector position in P [m]
};

/// How big a human_arm scene is before it is built: what the size caps compare.
struct HumanArmSceneSize {
  int per_axis = 0;                ///< lattice points per axis
  long long points_in_reach = 0;   ///< lattice points within the arm's reach (the others are skipped)
  long long candidate_poses = 0;   ///< points_in_reach x orientations: an upper bound on the samples
  long long ik_solves = 0;         ///< candidate_poses x joint3_steps
};

/// Counts the lattice points the build will solve (those within `reach` [m] of the shoulder) and
/// what follows from them. No overflow: every factor is bounded by the declarations.
HumanArmSceneSize human_arm_scene_size(const HumanArmSceneOptions& options, double reach);

/// \throws Error("human_arm", "options.max_samples = <cap>: the scene would try <n> candidate
///         poses (<points> lattice points within reach (<per_axis>^3 from lattice_step ...,
///         lattice_extent ...) x <orientations> orientations); ...") or the same for
///         max_ik_solves, when a cap is exceeded.
void check_human_arm_scene_size(const HumanArmSceneOptions& options, const HumanArmSceneSize& size);

/// Resolves declared options (already validated against HumanArmOptions::declare) for building.
/// \\throws Error("human_arm", "options.<key> = <value>: <rule>") for what the declarations cannot
///         express: an arm_file that is not found (resolve_arm_file); C_S_B or C_E_P not a
///         rotation (max |C^T C - I| > 1e-6 or det <= 0).
HumanArmSceneOptions resolve_human_arm_scene_options(const HumanArmOptions& options);

/// The human_arm scene: the reachable palm poses of the arm on lattice x orientation set.
///
/// Samples are ordered by lattice point (x fastest, then y, then z, in S) and orientation index.
/// poses row = the end-effector target T_E^B = T_S^B T_P^S T_E^P as (x, y, z, qw, qx, qy, qz)
/// [m] with qw >= 0 (the palm pose in B when C_E^P = I, x_E^P = 0). Attributes: "shoulder_pose"
/// (7: palm position [m] and quaternion in S), "human_q" (7, rad), "manipulability" (1),
/// "lattice_index" (1), and on request "M_v", "M_a" (36 each, row-major 6x6 in B at E).
class HumanArmScene final : public Scene {
 public:
  using Options = HumanArmOptions;
  /// Resolves the options, loads the arm file and checks the scene's size against the caps.
  /// \throws Error("human_arm", ...) as resolve_human_arm_scene_options, load_human_arm and
  ///         check_human_arm_scene_size do.
  explicit HumanArmScene(const HumanArmOptions& options);
  SampleSet build(const SceneRequest& request) const override;

  const HumanArm& arm() const { return arm_; }
  const HumanArmSceneOptions& options() const { return options_; }
  /// The text every cached file must carry to be used: options, arm document, format versions.
  std::string cache_key(bool ellipsoids) const;
  /// The cache file for that key ("" when caching is off or no cache directory is known).
  std::string cache_file(bool ellipsoids) const;

 private:
  HumanArmSceneOptions options_;
  HumanArm arm_;
  HumanArmSceneSize size_;
};

/// 64-bit FNV-1a of bytes (cache file names and payload checksums).
std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t seed = 1469598103934665603ULL);

}  // namespace hapsyn::plugins
