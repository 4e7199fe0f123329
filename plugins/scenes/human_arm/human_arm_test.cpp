// Tests of the human_arm scene: the orientation set (Kolmogorov-Smirnov on the rotation angle),
// the lattice, extremes without NaN, the scene's samples and attributes, the disk cache (hit,
// corrupt, truncated, stale), the arm_file option, option errors, the upright placement and the
// declared schema. The arm model's own tests (arm file, kinematics, IK, ellipsoid axes) are in
// plugins/scenes/shared/human_arm_model/human_arm_model_test.cpp.
#include "human_arm.hpp"
#include "shared/human_arm_model/human_arm_model_testing.hpp"
#include "test_support.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/parallel.hpp>
#include <hapsyn/schema.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <sys/stat.h>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using hapsyn::Json;
using hapsyn::SampleSet;
using namespace hapsyn::plugins;
using namespace hapsyn::plugins::human_arm_testing;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// The scene created as a study creates it: the options validated against the declared schema
// (defaults filled), then the constructor.
std::string registry_error(const Json& options) {
  return hapsyn::test::error_of([&] { hapsyn::test::registry().create_scene("human_arm", options, "scene"); });
}

template <class Fn>
std::string error_of(Fn&& fn) {
  try {
    fn();
  } catch (const hapsyn::Error& e) {
    return e.what();
  }
  return "no error";
}

// The options as the registry hands them over: validated against the declarations, defaults filled.
HumanArmOptions options_of(const Json& options) { return hapsyn::make_options<HumanArmOptions>(options); }

Json small_scene(const fs::path& cache_dir) {
  return Json{{"lattice_step", 0.2},  {"lattice_extent", 0.6},   {"orientations", 40},
              {"joint3_steps", 5},    {"cache_directory", cache_dir.string()}, {"threads", 2}};
}

// Uniform rotations have angle density (1 - cos t) / pi on [0, pi]: CDF (t - sin t) / pi.
double ks_statistic(const std::vector<Eigen::Quaterniond>& set) {
  std::vector<double> angles;
  for (const auto& q : set) angles.push_back(2 * std::acos(std::min(1.0, q.w())));
  std::sort(angles.begin(), angles.end());
  const double n = static_cast<double>(angles.size());
  double D = 0;
  for (std::size_t i = 0; i < angles.size(); ++i) {
    const double F = (angles[i] - std::sin(angles[i])) / kPi;
    D = std::max({D, (i + 1) / n - F, F - i / n});
  }
  return D;
}

TEST(HumanArm, OrientationSetIsUnitHemisphereAndUniformInRotationAngle) {
  for (const int n : {505, 100, 2000}) {
    const std::vector<Eigen::Quaterniond> set = orientation_set(n);
    ASSERT_EQ(static_cast<int>(set.size()), n);
    for (const auto& q : set) {
      EXPECT_NEAR(q.norm(), 1.0, 1e-15);
      EXPECT_GE(q.w(), 0.0);
    }
    // Kolmogorov-Smirnov at 5 %: D < 1.358 / sqrt(n). A deterministic low-discrepancy set
    // should do much better than random; half the critical value is required.
    const double D = ks_statistic(set);
    EXPECT_LT(D, 0.5 * 1.358 / std::sqrt(n)) << "n = " << n << ", D = " << D;
  }
  // The test can fail: a set clustered near the identity is rejected.
  std::vector<Eigen::Quaterniond> biased = orientation_set(505);
  for (auto& q : biased) q = Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * Eigen::AngleAxisd(q).angle(), Eigen::AngleAxisd(q).axis()));
  EXPECT_GT(ks_statistic(biased), 1.358 / std::sqrt(505.0));
}

TEST(HumanArm, OrientationSetCoversSo3WithoutLargeHoles) {
  const std::vector<Eigen::Quaterniond> set = orientation_set(505);
  // Every random rotation has a set member within ~ the covering radius of 505 points
  // (the volume of SO(3) is pi^2: a ball of angle r holds (r - sin r)/pi of it).
  std::mt19937 rng(10);
  double worst = 0;
  for (int t = 0; t < 2000; ++t) {
    const Eigen::Quaterniond r = Eigen::Quaterniond::UnitRandom();
    double nearest = 10;
    for (const auto& q : set) nearest = std::min(nearest, 2 * std::acos(std::min(1.0, std::abs(q.dot(r)))));
    worst = std::max(worst, nearest);
  }
  EXPECT_LT(worst, 0.6);  // ~34 deg; a single point's share of SO(3) is a ball of ~0.31 rad
}

TEST(HumanArm, LatticeIsSymmetricAroundTheShoulder) {
  const std::vector<double> axis = lattice_axis(0.1, 0.7);
  ASSERT_EQ(axis.size(), 15u);
  EXPECT_EQ(axis[7], 0.0);
  for (int k = 0; k < 15; ++k) EXPECT_EQ(axis[k], -axis[14 - k]);
  EXPECT_NEAR(axis.back(), 0.7, 1e-15);
  EXPECT_EQ(lattice_axis(0.3, 0.7).size(), 5u);  // 0, +-0.3, +-0.6
}

TEST(HumanArm, PointsAtAndBeyondReachGiveNoNaN) {
  const std::vector<double> grid = arm().joint3_grid(17);
  const std::vector<Eigen::Quaterniond> set = orientation_set(505);
  Vector7d q;
  double m;
  // Fully stretched (q4 = 0, the elbow's lower limit): the palm exactly at the reach boundary.
  Vector7d stretched = Vector7d::Zero();
  stretched(3) = 0.0;
  const Eigen::Isometry3d T = arm().forward(stretched);
  ASSERT_TRUE(arm().best(T.linear(), T.translation(), grid, &q, &m));
  EXPECT_TRUE(std::isfinite(m));
  EXPECT_TRUE(q.allFinite());
  // Slightly beyond it along the arm: unreachable, not NaN.
  const Eigen::Vector3d beyond = T.translation() * 1.001;
  EXPECT_FALSE(arm().best(T.linear(), beyond, grid, &q, &m));
  // Far lattice points (corners of the 0.7 m cube), the shoulder itself and a point on axis 1.
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.7, 0.7, 0.7), Eigen::Vector3d(0.0, 0.0, 0.0),
                                   Eigen::Vector3d(0.0, 0.0, 0.3), Eigen::Vector3d(0.677, 0.0, 0.0)}) {
    for (const auto& r : set) {
      ArmIkSolution s[8];
      for (double q3 : grid) {
        const int n = arm().solve(r.toRotationMatrix(), p, q3, s);
        for (int i = 0; i < n; ++i) ASSERT_TRUE(s[i].q.allFinite());
      }
      if (arm().best(r.toRotationMatrix(), p, grid, &q, &m)) {
        ASSERT_TRUE(q.allFinite());
        ASSERT_TRUE(std::isfinite(m));
      }
    }
  }
}

// ------------------------------------------------------------------------- scene ----

TEST(HumanArm, SceneSamplesAreConsistentReachablePoses) {
  const fs::path dir = temp_dir("consistent");
  Json options = small_scene(dir);
  options["cache"] = false;
  const HumanArmScene scene(options_of(options));
  const SampleSet set = scene.build({});
  ASSERT_GT(set.size(), 100);
  EXPECT_EQ(set.coordinates, (std::vector<std::string>{"x", "y", "z", "qw", "qx", "qy", "qz"}));
  EXPECT_EQ(set.info["n_reach"], set.size());
  EXPECT_EQ(set.info["lattice_points"], 7 * 7 * 7);
  EXPECT_EQ(set.info["poses_tried"], 7 * 7 * 7 * 40);
  EXPECT_EQ(set.info["from_cache"], false);
  EXPECT_EQ(set.info["cache_status"], "off");
  EXPECT_EQ(set.attributes.count("M_v"), 0u);
  EXPECT_EQ(set.attributes.count("M_a"), 0u);
  const auto& shoulder = set.attributes.at("shoulder_pose");
  const auto& hq = set.attributes.at("human_q");
  const auto& manip = set.attributes.at("manipulability");
  const HumanArmSceneOptions& o = scene.options();
  for (int i = 0; i < set.size(); ++i) {
    const Eigen::Vector3d p = shoulder.row(i).head<3>().transpose();
    const Eigen::Quaterniond r(shoulder(i, 3), shoulder(i, 4), shoulder(i, 5), shoulder(i, 6));
    const Vector7d q = hq.row(i).transpose();
    const Eigen::Isometry3d T = arm().forward(q);
    ASSERT_LT((T.translation() - p).norm(), 1e-9) << i;
    ASSERT_LT(rotation_distance(T.linear(), r.toRotationMatrix()), 1e-9) << i;
    ASSERT_EQ(manip(i, 0), arm().manipulability(q));
    // The pose in B: T_S^B T_P^S T_E^P.
    const Eigen::Vector3d xb = o.x_S_B + o.C_S_B * p;
    const Eigen::Matrix3d Cb = o.C_S_B * r.toRotationMatrix() * o.C_E_P;
    const Eigen::Quaterniond qb(set.poses(i, 3), set.poses(i, 4), set.poses(i, 5), set.poses(i, 6));
    ASSERT_LT((set.poses.row(i).head<3>().transpose() - xb).norm(), 1e-12);
    ASSERT_LT(rotation_distance(qb.toRotationMatrix(), Cb), 1e-12);
    ASSERT_GE(qb.w(), 0.0);
    ASSERT_TRUE(set.poses.row(i).allFinite());
  }
  fs::remove_all(dir);
}

TEST(HumanArm, ArmPointsDrawTheUserHoldingEachSampleUpright) {
  const fs::path dir = temp_dir("figure");
  Json options = small_scene(dir);
  options["cache"] = false;
  options["x_E_P"] = {0.0, 0.0, 0.0};
  const HumanArmScene scene(options_of(options));
  const SampleSet set = scene.build({});
  const HumanArmSceneOptions& o = scene.options();
  const auto& points = set.attributes.at("arm_points");
  ASSERT_EQ(points.cols(), 12);
  for (int i = 0; i < set.size(); ++i) {
    // The shoulder is the scene's x_S_B; with x_E^P = 0 the palm is the sample's position.
    ASSERT_LT((points.row(i).head<3>().transpose() - o.x_S_B).norm(), 1e-15) << i;
    ASSERT_LT((points.row(i).tail<3>() - set.poses.row(i).head<3>()).norm(), 1e-12) << i;
  }
  // The body in B: gravity is -z_B, so the head is above the shoulder and the hips below it.
  const Json& figure = set.info.at("figure");
  EXPECT_EQ(figure["arm_attribute"], "arm_points");
  const double shoulder_z = o.x_S_B.z();
  EXPECT_GT(figure["head_centre"][2].get<double>() - figure["head_radius"].get<double>(), shoulder_z);
  const Json& torso = figure["body_lines"][1];
  EXPECT_LT(torso[1][2].get<double>(), shoulder_z - 0.4);
  EXPECT_LT(torso[2][2].get<double>(), shoulder_z - 0.4);
  fs::remove_all(dir);
}

TEST(HumanArm, SceneDoesNotDependOnTheThreadCount) {
  const fs::path dir = temp_dir("threads");
  Json options = small_scene(dir);
  options["cache"] = false;
  options["threads"] = 1;
  const SampleSet one = HumanArmScene(options_of(options)).build({});
  options["threads"] = 3;
  const SampleSet three = HumanArmScene(options_of(options)).build({});
  EXPECT_TRUE(one.poses == three.poses);
  EXPECT_TRUE(one.attributes == three.attributes);
  fs::remove_all(dir);
}

TEST(HumanArm, EllipsoidsAreBuiltOnlyWhenRequestedAndExpressedInTheBaseFrame) {
  const fs::path dir = temp_dir("ellipsoids");
  Json options = small_scene(dir);
  options["cache"] = false;
  options["x_E_P"] = {0.0, 0.0, 0.05};  // a non-zero offset: M is the twist of E, not P
  const HumanArmScene scene(options_of(options));
  hapsyn::SceneRequest request;
  request.attributes = {"M_v"};
  const SampleSet only_v = scene.build(request);
  EXPECT_EQ(only_v.attributes.count("M_v"), 1u);
  EXPECT_EQ(only_v.attributes.count("M_a"), 0u);
  request.attributes = {"M_v", "M_a"};
  const SampleSet set = scene.build(request);
  const HumanArmSceneOptions& o = scene.options();
  const HumanArmData& d = arm().data();
  for (int i = 0; i < set.size(); i += 7) {
    const Vector7d q = set.attributes.at("human_q").row(i).transpose();
    // Reference: the Jacobian of the point E in B, by finite differences of T_E^B.
    Matrix67d J;
    const auto pose_b = [&](const Vector7d& qq) {
      const Eigen::Isometry3d T = arm().forward(qq);
      Eigen::Isometry3d E;
      E.linear() = o.C_S_B * T.linear();
      E.translation() = o.x_S_B + o.C_S_B * (T.translation() + T.linear() * o.x_E_P);
      return E;
    };
    for (int j = 0; j < 7; ++j) {
      Vector7d qp = q, qm = q;
      qp(j) += 1e-6;
      qm(j) -= 1e-6;
      const Eigen::Isometry3d Tp = pose_b(qp), Tm = pose_b(qm);
      const Eigen::AngleAxisd w(Tp.linear() * Tm.linear().transpose());
      J.block<3, 1>(0, j) = w.axis() * w.angle() / 2e-6;
      J.block<3, 1>(3, j) = (Tp.translation() - Tm.translation()) / 2e-6;
    }
    for (const auto& [name, scale] : {std::pair{"M_v", &d.velocity_max}, std::pair{"M_a", &d.acceleration_max}}) {
      const Eigen::Matrix<double, 6, 6, Eigen::RowMajor> M =
          Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(set.attributes.at(name).row(i).data());
      const Matrix67d Js = J * scale->asDiagonal();
      const Matrix6d expected = Js * Js.transpose();
      EXPECT_LT((M * M.transpose() - expected).norm(), 1e-6 * expected.norm()) << name << " sample " << i;
    }
  }
  fs::remove_all(dir);
}

TEST(HumanArm, RefusesUnknownAttributes) {
  const fs::path dir = temp_dir("attr");
  Json options = small_scene(dir);
  options["cache"] = false;
  hapsyn::SceneRequest request;
  request.attributes = {"force_axes"};
  EXPECT_EQ(error_of([&] { HumanArmScene(options_of(options)).build(request); }),
            "human_arm: per-sample attribute 'force_axes' requested: this scene provides shoulder_pose, human_q, "
            "manipulability, lattice_index, arm_points, M_v, M_a");
  fs::remove_all(dir);
}

// ------------------------------------------------------------------------- cache ----

bool same_samples(const SampleSet& a, const SampleSet& b) {
  return a.poses.rows() == b.poses.rows() && a.poses == b.poses && a.attributes == b.attributes;
}

TEST(HumanArm, CacheIsWrittenAtomicallyAndLoadsBitForBit) {
  const fs::path dir = temp_dir("cache");
  const HumanArmScene scene(options_of(small_scene(dir)));
  hapsyn::SceneRequest request;
  request.attributes = {"M_v", "M_a"};
  const SampleSet built = scene.build(request);
  EXPECT_EQ(built.info["from_cache"], false);
  EXPECT_EQ(built.info["cache_status"], "miss: built");
  const std::string file = built.info["cache_file"];
  EXPECT_EQ(file, scene.cache_file(true));
  ASSERT_TRUE(fs::exists(file));
  int entries = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    ++entries;
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
  }
  EXPECT_EQ(entries, 1);
  const SampleSet loaded = scene.build(request);
  EXPECT_EQ(loaded.info["from_cache"], true);
  EXPECT_EQ(loaded.info["cache_status"], "hit");
  EXPECT_TRUE(same_samples(built, loaded));
  // A request without the ellipsoids is another cache entry (they are not built for it).
  const SampleSet plain = scene.build({});
  EXPECT_EQ(plain.info["from_cache"], false);
  EXPECT_NE(plain.info["cache_file"], file);
  fs::remove_all(dir);
}

void expect_rebuilt(const HumanArmScene& scene, const SampleSet& reference, const std::string& reason) {
  const SampleSet again = scene.build({});
  EXPECT_EQ(again.info["from_cache"], false);
  EXPECT_EQ(again.info["cache_status"], "rebuilt (" + reason + ")");
  EXPECT_TRUE(same_samples(reference, again));
  // And the rebuilt file is good again.
  EXPECT_EQ(scene.build({}).info["cache_status"], "hit");
}

TEST(HumanArm, CorruptCacheIsDetectedAndRebuilt) {
  const fs::path dir = temp_dir("corrupt");
  const HumanArmScene scene(options_of(small_scene(dir)));
  const SampleSet reference = scene.build({});
  const std::string file = reference.info["cache_file"];
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(-9, std::ios::end);  // inside the manipulability payload
    char c;
    f.read(&c, 1);
    f.seekp(-9, std::ios::end);
    c = static_cast<char>(c ^ 0x10);
    f.write(&c, 1);
  }
  expect_rebuilt(scene, reference, "corrupt: payload checksum");
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(0);
    f.write("XXXX", 4);
  }
  expect_rebuilt(scene, reference, "corrupt: not a human_arm cache file");
  fs::remove_all(dir);
}

// Issue 53, cause 8: a cache edited by hand with its checksums recomputed was trusted (J 1.437
// instead of 2.647). A few lattice points are solved again on load and must agree.
TEST(HumanArm, ForgedCacheWithValidChecksumsIsCaughtBySpotChecks) {
  const fs::path dir = temp_dir("forged");
  const HumanArmScene scene(options_of(small_scene(dir)));
  const SampleSet reference = scene.build({});
  const std::string file = reference.info["cache_file"];
  std::string pristine;
  {
    std::ifstream in(file, std::ios::binary);
    pristine.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  // magic 8, version 4, flags 4, key size 8, key, n 8, payload size 8, payload sum 8, header sum 8.
  std::uint64_t key_size = 0, n = 0;
  std::memcpy(&key_size, pristine.data() + 16, 8);
  const std::size_t counts = 24 + key_size;
  std::memcpy(&n, pristine.data() + counts, 8);
  const std::size_t header = counts + 32;
  ASSERT_GT(n, 10u);
  const auto forge = [&](std::uint64_t samples, const std::string& payload) {
    std::string bytes = pristine.substr(0, header);
    const std::uint64_t size = payload.size(), sum = hapsyn::plugins::fnv1a64(payload.data(), payload.size());
    std::memcpy(&bytes[counts], &samples, 8);
    std::memcpy(&bytes[counts + 8], &size, 8);
    std::memcpy(&bytes[counts + 16], &sum, 8);
    const std::uint64_t header_sum = hapsyn::plugins::fnv1a64(bytes.data(), counts + 24);
    std::memcpy(&bytes[counts + 24], &header_sum, 8);
    std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes << payload;
  };
  // Every manipulability halved: the payload is lattice, orientation (int32 each), q (7 doubles),
  // manipulability (1 double) per sample.
  std::string payload = pristine.substr(header);
  for (std::uint64_t i = 0; i < n; ++i) {
    double m = 0;
    const std::size_t at = n * 8 + n * 56 + i * 8;
    std::memcpy(&m, &payload[at], 8);
    m *= 0.5;
    std::memcpy(&payload[at], &m, 8);
  }
  forge(n, payload);
  const SampleSet halved = scene.build({});
  EXPECT_EQ(halved.info["from_cache"], false);
  EXPECT_EQ(halved.info["cache_status"].get<std::string>().rfind("rebuilt (corrupt: its samples at lattice point ", 0), 0u)
      << halved.info["cache_status"];
  EXPECT_TRUE(same_samples(reference, halved));
  // No samples at all: the points within reach that have some are missing.
  forge(0, "");
  const SampleSet emptied = scene.build({});
  EXPECT_EQ(emptied.info["from_cache"], false) << emptied.info["cache_status"];
  EXPECT_TRUE(same_samples(reference, emptied));
  EXPECT_EQ(scene.build({}).info["cache_status"], "hit");
  fs::remove_all(dir);
}

TEST(HumanArm, TruncatedCacheIsDetectedAndRebuilt) {
  const fs::path dir = temp_dir("truncated");
  const HumanArmScene scene(options_of(small_scene(dir)));
  const SampleSet reference = scene.build({});
  const std::string file = reference.info["cache_file"];
  fs::resize_file(file, fs::file_size(file) - 100);
  expect_rebuilt(scene, reference, "corrupt: truncated or oversized payload");
  fs::resize_file(file, 30);
  expect_rebuilt(scene, reference, "corrupt: truncated header");
  fs::resize_file(file, 0);
  expect_rebuilt(scene, reference, "corrupt: not a human_arm cache file");
  fs::remove_all(dir);
}

TEST(HumanArm, StaleCacheIsDetectedAndRebuilt) {
  const fs::path dir = temp_dir("stale");
  Json options = small_scene(dir);
  const HumanArmScene a(options_of(options));
  const SampleSet built_a = a.build({});
  options["joint3_steps"] = 3;
  const HumanArmScene b(options_of(options));
  EXPECT_NE(a.cache_file(false), b.cache_file(false));
  EXPECT_NE(a.cache_key(false), b.cache_key(false));
  // A's file placed under B's name (a hash collision, or a file copied by hand) is not trusted.
  fs::copy_file(a.cache_file(false), b.cache_file(false));
  const SampleSet built_b = b.build({});
  EXPECT_EQ(built_b.info["cache_status"], "rebuilt (stale: made for other options or another arm file)");
  EXPECT_EQ(b.build({}).info["cache_status"], "hit");
  // The key changes with the arm file's content, not only its name.
  const fs::path arm_copy = dir / "arm.json";
  Json doc = arm_document();
  doc["segments"]["l_p"] = 0.1;
  std::ofstream(arm_copy) << doc.dump(2);
  options["arm_file"] = arm_copy.string();
  options["joint3_steps"] = 5;
  const HumanArmScene c(options_of(options));
  EXPECT_NE(c.cache_file(false), a.cache_file(false));
  // Thread count and cache location are not part of the key.
  Json other = small_scene(dir);
  other["threads"] = 1;
  EXPECT_EQ(HumanArmScene(options_of(other)).cache_key(false), a.cache_key(false));
  fs::remove_all(dir);
}

TEST(HumanArm, UnwritableCacheDirectoryDoesNotFailTheBuild) {
  const fs::path dir = temp_dir("unwritable");
  const fs::path blocker = dir / "file";
  std::ofstream(blocker) << "x";
  Json options = small_scene(blocker / "sub");  // a directory below a regular file
  const SampleSet set = HumanArmScene(options_of(options)).build({});
  EXPECT_GT(set.size(), 0);
  EXPECT_NE(set.info["cache_status"].get<std::string>().find("cache not written"), std::string::npos)
      << set.info["cache_status"];
  fs::remove_all(dir);
}

TEST(HumanArm, UnreadableOrMalformedArmFilesAreRefused) {
  const fs::path dir = temp_dir("armfiles");
  const std::string missing = (dir / "missing.json").string();
  EXPECT_EQ(error_of([&] { load_human_arm(missing); }),
            "human_arm: cannot read arm file " + missing + ": No such file or directory");
  const fs::path broken = dir / "broken.json";
  std::ofstream(broken) << "{ \"dh\": [ }";
  EXPECT_EQ(error_of([&] { load_human_arm(broken.string()); }),
            "human_arm: " + broken.string() + ":1:11: malformed JSON: unexpected '}'; expected '[', '{', or a literal");
  // Issue 53, cause 5: nesting that would overflow the stack of the parser is refused before it.
  const fs::path deep = dir / "deep.json";
  std::ofstream(deep) << "{\"dh\": " << std::string(200000, '[') << std::string(200000, ']') << "}";
  EXPECT_EQ(error_of([&] { load_human_arm(deep.string()); }).rfind("human_arm: " + deep.string() +
                                                                   ":1:263: nesting deeper than 256 levels", 0), 0u);
  EXPECT_EQ(error_of([&] { HumanArmScene(options_of(Json{{"arm_file", missing}})); }),
            "human_arm: options.arm_file = \"" + missing + "\": no such file");
  const std::string relative_error = error_of([&] { HumanArmScene(options_of(Json{{"arm_file", "nowhere/arm.json"}})); });
  EXPECT_EQ(relative_error.rfind("human_arm: options.arm_file = \"nowhere/arm.json\": no such file (tried ", 0), 0u);
  // A relative path resolves against the share directory too.
  EXPECT_EQ(HumanArmScene(options_of(Json{{"arm_file", "human_arm/fennel2022_right_arm.json"}, {"cache", false}})).options().arm_file,
            fs::path(kArmFile).lexically_normal().string());
  fs::remove_all(dir);
}

// ------------------------------------------------------ the user is upright ----

// Gravity in the manipulator base B, as the mechanisms pull (haptic6r, serial_chain: -z_B).
const Eigen::Vector3d kGravityInBase(0.0, 0.0, -1.0);

// The unit direction from the shoulder to the palm in B for the arm at q, placed by C_S_B.
Eigen::Vector3d palm_direction_in_base(const HumanArm& a, const Eigen::Matrix3d& C_S_B, const Vector7d& q) {
  return (C_S_B * a.forward(q).translation()).normalized();
}

// The physical sanity of a placement: the arm model's rest pose (q = 0, the arm straight along
// the body) points along gravity; forward flexion (joint 2) and abduction (joint 1) by 90 deg
// are horizontal, the flexed arm points where the user faces (+x_B) and the abducted arm to the
// user's own side (right: -y_B, left: +y_B). A user lying on their side fails every line.
void expect_upright(const HumanArm& a, const Eigen::Matrix3d& C_S_B, const std::string& label) {
  const double sign = a.data().side == "left" ? -1.0 : 1.0;  // the left arm's angles are mirrored
  const Vector7d rest = Vector7d::Zero();
  Vector7d flexed = rest, abducted = rest;
  flexed(1) = sign * 90.0 * kDeg;
  abducted(0) = sign * 90.0 * kDeg;
  const Eigen::Vector3d down = palm_direction_in_base(a, C_S_B, rest);
  const Eigen::Vector3d forward = palm_direction_in_base(a, C_S_B, flexed);
  const Eigen::Vector3d sideways = palm_direction_in_base(a, C_S_B, abducted);
  EXPECT_GT(down.dot(kGravityInBase), 1.0 - 1e-12) << label << ": the rest arm points along " << down.transpose();
  EXPECT_NEAR(forward.z(), 0.0, 1e-12) << label << ": flexion is not horizontal: " << forward.transpose();
  EXPECT_GT(forward.x(), 1.0 - 1e-12) << label << ": flexion does not point to +x_B: " << forward.transpose();
  EXPECT_NEAR(sideways.z(), 0.0, 1e-12) << label << ": abduction is not horizontal: " << sideways.transpose();
  EXPECT_GT(-sign * sideways.y(), 1.0 - 1e-12) << label << ": abduction points to " << sideways.transpose();
}

TEST(HumanArm, DefaultPlacementSeatsTheUserUpright) {
  const Eigen::Matrix3d C = resolve_human_arm_scene_options(hapsyn::default_options<HumanArmOptions>()).C_S_B;
  expect_upright(arm(), C, "right arm");
  const HumanArm left(load_human_arm(HAPSYN_SOURCE_DIR "/share/human_arm/fennel2022_left_arm.json"));
  expect_upright(left, C, "left arm");
  // The check can fail: the paper's printed matrix taken as S -> B lays the user on their side.
  Eigen::Matrix3d lying;
  lying << 0, -1, 0, 0, 0, 1, -1, 0, 0;
  EXPECT_LT(palm_direction_in_base(arm(), lying, Vector7d::Zero()).dot(kGravityInBase), 0.5);
  EXPECT_EQ(C, lying.transpose());
}

TEST(HumanArm, EveryShippedHumanStudySeatsTheUserUpright) {
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(HAPSYN_SOURCE_DIR "/problems")) {
    if (entry.path().extension() != ".json") continue;
    std::ifstream in(entry.path());
    const Json problem = Json::parse(in);
    const std::string plugin = problem.at("scene").at("plugin");
    if (plugin != "human_arm" && plugin != "motion") continue;
    const Json given = problem.at("scene").value("options", Json::object());
    const Json options = hapsyn::validate_and_fill(hapsyn::test::registry().find(plugin).schema, given, "scene.options");
    const Eigen::Matrix3d C = hapsyn::rotation_option(options.at("C_S_B").get<std::vector<std::vector<double>>>(),
                                                      "C_S_B", plugin);
    // A motion study's recordings are of the arm the right arm file models (RightArm, RightHand).
    const std::string arm_file = plugin == "human_arm" ? resolve_arm_file(options.at("arm_file").get<std::string>()) : kArmFile;
    expect_upright(HumanArm(load_human_arm(arm_file)), C, entry.path().filename().string());
    ++checked;
  }
  EXPECT_GE(checked, 7) << "the shipped human-arm and motion studies";
}

TEST(HumanArm, OptionErrorsNameTheOptionTheValueAndTheRule) {
  // The declared rules, checked by the framework when a study creates the scene.
  EXPECT_EQ(registry_error(Json{{"lattice_stp", 0.1}}),
            "problem: scene.options.lattice_stp: unknown key (did you mean 'lattice_step'?); known keys: C_E_P, C_S_B, "
            "arm_file, cache, cache_directory, joint3_steps, lattice_extent, lattice_step, max_ik_solves, max_samples, "
            "orientations, threads, x_E_P, "
            "x_S_B");
  EXPECT_EQ(registry_error(Json{{"lattice_step", 0.0}}), "problem: scene.options.lattice_step = 0.0: must be > 0");
  EXPECT_EQ(registry_error(Json{{"orientations", 0}}), "problem: scene.options.orientations = 0: must be >= 1");
  EXPECT_EQ(registry_error(Json{{"joint3_steps", 2.5}}), "problem: scene.options.joint3_steps = 2.5: must be an integer");
  EXPECT_EQ(registry_error(Json{{"x_S_B", {0.0, 1.0}}}),
            "problem: scene.options.x_S_B = [0.0,1.0]: must have at least 3 items");
  EXPECT_EQ(registry_error(Json{{"cache", "yes"}}), "problem: scene.options.cache = \"yes\": must be a boolean");
  // The declared rule relating lattice_step and lattice_extent, checked when the options are filled.
  EXPECT_EQ(error_of([] { HumanArmScene(options_of(Json{{"lattice_step", 0.001}})); }),
            "problem: options.lattice_step = 0.001: gives 1401.0 lattice points per axis; at most 401 are allowed "
            "(lattice_extent 0.7)");
  // What the declarations cannot express (a rotation), checked by the constructor.
  const std::string rotation = error_of([] {
    HumanArmScene(options_of(Json{{"C_S_B", {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, -1.0}}}}));
  });
  EXPECT_EQ(rotation.rfind("human_arm: options.C_S_B = [[1.0,0.0,0.0],[0.0,1.0,0.0],[0.0,0.0,-1.0]]: must be a "
                           "rotation matrix (orthonormal, det +1)",
                           0),
            0u)
      << rotation;
  // Through a study, the constructor's message is kept under the options' path.
  EXPECT_EQ(registry_error(Json{{"lattice_step", 0.001}}),
            "problem: scene.options: human_arm: options.lattice_step = 0.001: gives 1401.0 lattice points per axis; at "
            "most 401 are allowed (lattice_extent 0.7)");
}

TEST(HumanArm, DeclaredSchemaIsValidAndItsDefaultsAreThePapers) {
  // The schema the plugin exports (what `hapsyn describe` prints) is the declarations'.
  const Json schema = hapsyn::test::registry().find("human_arm").schema;
  EXPECT_EQ(schema, hapsyn::options_schema<HumanArmOptions>());
  EXPECT_NO_THROW(hapsyn::check_schema(schema, "human_arm"));
  const HumanArmSceneOptions defaults = resolve_human_arm_scene_options(hapsyn::default_options<HumanArmOptions>());
  EXPECT_EQ(defaults.arm_file, fs::path(kArmFile).lexically_normal().string());
  EXPECT_EQ(resolve_arm_file(""), defaults.arm_file);  // "" is the declared default
  EXPECT_EQ(defaults.lattice_step, 0.1);
  EXPECT_EQ(defaults.lattice_extent, 0.7);
  EXPECT_EQ(defaults.orientations, 505);
  EXPECT_EQ(defaults.joint3_steps, 17);
  EXPECT_EQ(defaults.x_S_B, Eigen::Vector3d(0, 0, -0.61));
  Eigen::Matrix3d C_S_B, C_E_P;
  C_S_B << 0, 0, -1, -1, 0, 0, 0, 1, 0;  // the transpose of the paper's printed C_S^B: an upright user
  C_E_P << 0, 0, 1, 0, -1, 0, 1, 0, 0;
  EXPECT_EQ(defaults.C_S_B, C_S_B);
  EXPECT_EQ(defaults.C_E_P, C_E_P);
  EXPECT_EQ(defaults.x_E_P, Eigen::Vector3d::Zero());
  EXPECT_TRUE(defaults.cache);
  EXPECT_EQ(defaults.cache_directory, "");
  EXPECT_EQ(defaults.threads, 0);
  EXPECT_EQ(defaults.max_samples, 50000000);
  EXPECT_EQ(defaults.max_ik_solves, 1000000000);
  for (const char* key : {"lattice_step", "lattice_extent", "x_S_B", "x_E_P"}) {
    EXPECT_EQ(schema.at("properties").at(key).at("unit"), "m") << key;
  }
  EXPECT_THROW(hapsyn::validate_and_fill(schema, Json{{"orientations", -1}}, "scene.options"), hapsyn::Error);
}

// ------------------------------------------------------- trustworthy runs (issue 20) ----

TEST(HumanArm, SceneOfBillionsOfPosesIsRefusedBeforeItIsBuilt) {
  // 281^3 lattice points, of which those within reach times 505 orientations: billions.
  const std::string fine = error_of([] { HumanArmScene(options_of(Json{{"lattice_step", 0.005}, {"cache", false}})); });
  EXPECT_EQ(fine.rfind("human_arm: options.max_samples = 50000000: the scene would try ", 0), 0u) << fine;
  for (const char* part : {"lattice points within the arm's reach, of 281^3 from lattice_step 0.005 and lattice_extent 0.7",
                           "x 505 orientations", "raise max_samples deliberately"}) {
    EXPECT_NE(fine.find(part), std::string::npos) << fine;
  }
  const std::string many = error_of([] {
    HumanArmScene(options_of(Json{{"orientations", 1000000}, {"joint3_steps", 10000}, {"cache", false}}));
  });
  EXPECT_NE(many.find("x 1000000 orientations"), std::string::npos) << many;
  // Within max_samples but too many IK solves.
  const std::string solves = error_of([] {
    HumanArmScene(options_of(Json{{"orientations", 20000}, {"joint3_steps", 10000}, {"cache", false}}));
  });
  EXPECT_EQ(solves.rfind("human_arm: options.max_ik_solves = 1000000000: the scene would do ", 0), 0u) << solves;
  EXPECT_NE(solves.find("x 10000 joint3_steps"), std::string::npos) << solves;
}

TEST(HumanArm, SceneSizeCountsTheLatticePointsItWillSolve) {
  const HumanArmSceneOptions o = resolve_human_arm_scene_options(options_of(Json{{"cache", false}}));
  const HumanArmSceneSize size = human_arm_scene_size(o, arm().reach());
  EXPECT_EQ(size.per_axis, 15);
  EXPECT_GT(size.points_in_reach, 0);
  EXPECT_LT(size.points_in_reach, 15 * 15 * 15);
  EXPECT_EQ(size.candidate_poses, size.points_in_reach * 505);
  EXPECT_EQ(size.ik_solves, size.candidate_poses * 17);
  // The cap is an option: a user who means it can raise (or lower) it.
  const std::string lowered = error_of([] { HumanArmScene(options_of(Json{{"max_samples", 1000}, {"cache", false}})); });
  EXPECT_NE(lowered.find("options.max_samples = 1000: the scene would try " + std::to_string(size.candidate_poses)),
            std::string::npos)
      << lowered;
  const fs::path dir = temp_dir("size");
  Json options = small_scene(dir);
  options["cache"] = false;
  const SampleSet set = HumanArmScene(options_of(options)).build({});
  EXPECT_LE(set.size(), set.info["candidate_poses"].get<long long>());
  fs::remove_all(dir);
}

TEST(HumanArm, CachePathThatIsNotARegularFileIsAClearError) {
  const fs::path dir = temp_dir("cachedir");
  const HumanArmScene scene(options_of(small_scene(dir)));
  const std::string file = scene.cache_file(false);
  fs::create_directories(file);
  EXPECT_EQ(error_of([&] { scene.build({}); }), "human_arm: cache file " + file +
                                                    " is not a regular file (a directory); remove it, or set "
                                                    "cache_directory or cache = false");
  fs::remove_all(file);
  ASSERT_EQ(::mkfifo(file.c_str(), 0600), 0);
  EXPECT_EQ(error_of([&] { scene.build({}); }), "human_arm: cache file " + file +
                                                    " is not a regular file (a FIFO); remove it, or set "
                                                    "cache_directory or cache = false");
  fs::remove(file);
  fs::create_symlink("/dev/zero", file);
  EXPECT_NE(error_of([&] { scene.build({}); }).find("is not a regular file (a device or socket)"), std::string::npos);
  fs::remove_all(dir);
}

TEST(HumanArm, OversizedCacheIsRebuiltWithAWarningWithoutReadingIt) {
  const fs::path dir = temp_dir("hugecache");
  const HumanArmScene scene(options_of(small_scene(dir)));
  const SampleSet reference = scene.build({});
  const std::string file = reference.info["cache_file"];
  fs::resize_file(file, std::uintmax_t{1} << 40);  // sparse: 1 TiB that must not be read
  testing::internal::CaptureStderr();
  const SampleSet again = scene.build({});
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(again.info["cache_status"].get<std::string>().rfind("rebuilt (corrupt: 1099511627776 bytes, more than the ", 0),
            0u)
      << again.info["cache_status"];
  EXPECT_TRUE(again.poses == reference.poses);
  EXPECT_EQ(err.rfind("hapsyn: warning: human_arm: cache file " + file + " corrupt: 1099511627776 bytes", 0), 0u) << err;
  EXPECT_NE(err.find("; rebuilding"), std::string::npos) << err;
  EXPECT_LT(fs::file_size(file), std::uintmax_t{1} << 20);  // replaced by the rebuilt cache
  fs::remove_all(dir);
}

TEST(HumanArm, DamagedCacheRebuildIsAnnouncedOnStandardError) {
  const fs::path dir = temp_dir("warn");
  const HumanArmScene scene(options_of(small_scene(dir)));
  const std::string file = scene.build({}).info["cache_file"];
  fs::resize_file(file, 30);
  testing::internal::CaptureStderr();
  scene.build({});
  EXPECT_EQ(testing::internal::GetCapturedStderr(),
            "hapsyn: warning: human_arm: cache file " + file + " corrupt: truncated header; rebuilding\n");
  fs::remove_all(dir);
}

TEST(HumanArm, RunThreadsReachTheBuildWhenTheSceneSetsNone) {
  const fs::path dir = temp_dir("runthreads");
  Json options = small_scene(dir);
  options["cache"] = false;
  options["threads"] = 0;
  hapsyn::SceneRequest one;
  one.threads = 1;
  const SampleSet a = HumanArmScene(options_of(options)).build(one);
  hapsyn::SceneRequest four;
  four.threads = 4;
  const SampleSet b = HumanArmScene(options_of(options)).build(four);
  EXPECT_TRUE(a.poses == b.poses);
  // With one thread granted, the build never starts a second one: the seam refuses any start,
  // so a build that tried would print the shortfall warning.
  hapsyn::set_thread_start_limit_for_testing(0);
  testing::internal::CaptureStderr();
  const SampleSet c = HumanArmScene(options_of(options)).build(one);
  const std::string quiet = testing::internal::GetCapturedStderr();
  testing::internal::CaptureStderr();
  HumanArmScene(options_of(options)).build(four);
  const std::string tried = testing::internal::GetCapturedStderr();
  hapsyn::set_thread_start_limit_for_testing(-1);
  EXPECT_EQ(quiet, "");
  EXPECT_NE(tried.find("could only start 1 of 4 threads"), std::string::npos) << tried;
  EXPECT_TRUE(a.poses == c.poses);
  // The scene's own option wins over the run's.
  options["threads"] = 2;
  hapsyn::set_thread_start_limit_for_testing(0);
  testing::internal::CaptureStderr();
  HumanArmScene(options_of(options)).build(one);
  const std::string own = testing::internal::GetCapturedStderr();
  hapsyn::set_thread_start_limit_for_testing(-1);
  EXPECT_NE(own.find("could only start 1 of 2 threads"), std::string::npos) << own;
  fs::remove_all(dir);
}

TEST(HumanArm, SlowBuildReportsProgressOnTheRequestStreamAndIsQuietWithout) {
  const fs::path dir = temp_dir("progress");
  Json options = small_scene(dir);
  options["cache"] = false;
  options["threads"] = 1;
  options["lattice_step"] = 0.1;
  options["orientations"] = 1000;  // about 5 s on one thread: long enough for a progress line
  options["joint3_steps"] = 9;
  const HumanArmScene scene(options_of(options));
  std::ostringstream progress;
  hapsyn::SceneRequest request;
  request.progress = &progress;
  testing::internal::CaptureStderr();
  testing::internal::CaptureStdout();
  const auto start = std::chrono::steady_clock::now();
  const SampleSet set = scene.build(request);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(testing::internal::GetCapturedStdout(), "");
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  const std::string text = progress.str();
  const std::string total = std::to_string(set.info["candidate_poses"].get<long long>());
  std::istringstream lines(text);
  int count = 0;
  for (std::string line; std::getline(lines, line); ++count) {
    EXPECT_EQ(line.rfind("human_arm: building the reachable poses: ", 0), 0u) << line;
    EXPECT_NE(line.find("% of " + total + ", ~"), std::string::npos) << line;
    EXPECT_EQ(line.substr(line.size() - 7), " s left") << line;
  }
  EXPECT_LE(count, static_cast<int>(seconds / 2.0) + 1) << text;  // at most one line every 2 s
  if (seconds > 4.5) {
    EXPECT_GE(count, 1) << "a " << seconds << " s build printed nothing";
  }
  // Without a stream: nothing anywhere.
  testing::internal::CaptureStderr();
  testing::internal::CaptureStdout();
  scene.build({});
  EXPECT_EQ(testing::internal::GetCapturedStdout(), "");
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  fs::remove_all(dir);
}

}  // namespace
