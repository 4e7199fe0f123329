#include "human_arm.hpp"

#include "shared/human_arm_model/human_figure.hpp"


#include <hapsyn/error.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/parallel.hpp>
#include <hapsyn/read_file.hpp>

#include <Eigen/LU>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <random>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>

namespace hapsyn::plugins {
namespace {

namespace fs = std::filesystem;

constexpr const char* kName = "human_arm";

// Changing the IK, the sampling or the payload layout must change one of these: the cache key
// carries both, so old files are rebuilt instead of trusted.
constexpr std::uint32_t kCacheFormatVersion = 1;
constexpr int kAlgorithmVersion = 1;
constexpr char kCacheMagic[8] = {'H', 'A', 'P', 'S', 'Y', 'N', 'H', 'A'};

std::string show(const Json& value) { return render_value(value); }

constexpr double kPi = 3.14159265358979323846;

double positive_mod(double x, double m) {
  double r = std::fmod(x, m);
  if (r < 0.0) r += m;
  return r;
}

}  // namespace

// ---------------------------------------------------------------- poses ----

std::vector<Eigen::Quaterniond> orientation_set(int n) {
  // Plastic number: the real root of x^3 = x + 1 (the generalized golden ratio for 3 dims).
  constexpr double kPlastic = 1.32471795724474602596;
  const double g1 = 1.0 / kPlastic, g2 = 1.0 / (kPlastic * kPlastic);
  std::vector<Eigen::Quaterniond> set;
  set.reserve(static_cast<std::size_t>(std::max(0, n)));
  for (int i = 0; i < n; ++i) {
    const double u1 = (i + 0.5) / n;
    const double u2 = positive_mod(i * g1, 1.0);
    const double u3 = positive_mod(i * g2, 1.0);
    const double psi = kPi * (u3 - 0.5);  // [-pi/2, pi/2): cos >= 0, the w >= 0 hemisphere
    const double chi = 2.0 * kPi * u2;
    const double r1 = std::sqrt(u1), r2 = std::sqrt(1.0 - u1);
    Eigen::Quaterniond q(r1 * std::cos(psi), r2 * std::sin(chi), r2 * std::cos(chi), r1 * std::sin(psi));
    q.normalize();
    if (q.w() < 0.0) q.w() = 0.0;  // cos(-pi/2) rounding; never negative
    set.push_back(q);
  }
  return set;
}

std::vector<double> lattice_axis(double step, double extent) {
  const int m = static_cast<int>(std::floor(extent / step + 1e-9));
  std::vector<double> axis;
  for (int k = -m; k <= m; ++k) axis.push_back(k * step);
  return axis;
}

// ---------------------------------------------------------------- options ----

namespace {

Eigen::Vector3d vector3(const std::vector<double>& v) { return Eigen::Vector3d(v[0], v[1], v[2]); }

Json vector_json(const Eigen::Vector3d& v) { return Json::array({v(0), v(1), v(2)}); }
Json matrix_json(const Eigen::Matrix3d& C) {
  Json rows = Json::array();
  for (int r = 0; r < 3; ++r) rows.push_back(Json::array({C(r, 0), C(r, 1), C(r, 2)}));
  return rows;
}

}  // namespace

std::string human_arm_lattice_rule(const HumanArmOptions& o) {
  // The lattice size depends on two options together, which no single declaration can bound.
  const double per_axis = 2.0 * std::floor(o.lattice_extent / o.lattice_step + 1e-9) + 1.0;
  if (per_axis <= 401.0) return "";
  return "gives " + show(Json(per_axis)) + " lattice points per axis; at most 401 are allowed (lattice_extent " +
         show(Json(o.lattice_extent)) + ")";
}

HumanArmSceneOptions resolve_human_arm_scene_options(const HumanArmOptions& options) {
  HumanArmSceneOptions o;
  static_cast<HumanArmOptions&>(o) = options;
  o.arm_file = resolve_arm_file(options.arm_file);
  o.x_S_B = vector3(options.x_S_B);
  o.C_S_B = rotation_option(options.C_S_B, "C_S_B", kName);
  o.C_E_P = rotation_option(options.C_E_P, "C_E_P", kName);
  o.x_E_P = vector3(options.x_E_P);
  return o;
}

HumanArmSceneSize human_arm_scene_size(const HumanArmSceneOptions& o, double reach) {
  HumanArmSceneSize size;
  const std::vector<double> axis = lattice_axis(o.lattice_step, o.lattice_extent);
  size.per_axis = static_cast<int>(axis.size());
  // The build's own test (solve_lattice), so the count is exact; per_axis <= 401 keeps it cheap.
  for (double z : axis) {
    for (double y : axis) {
      for (double x : axis) {
        if (Eigen::Vector3d(x, y, z).norm() <= reach * (1.0 + 1e-9)) ++size.points_in_reach;
      }
    }
  }
  // <= 401^3 x 1e6 x 1e4 < 2^63 by the declared ranges.
  size.candidate_poses = size.points_in_reach * o.orientations;
  size.ik_solves = size.candidate_poses * o.joint3_steps;
  return size;
}

void check_human_arm_scene_size(const HumanArmSceneOptions& o, const HumanArmSceneSize& size) {
  const std::string made_of = " candidate poses (" + std::to_string(size.points_in_reach) +
                              " lattice points within the arm's reach, of " + std::to_string(size.per_axis) +
                              "^3 from lattice_step " + show(Json(o.lattice_step)) + " and lattice_extent " +
                              show(Json(o.lattice_extent)) + ", x " + std::to_string(o.orientations) + " orientations)";
  if (size.candidate_poses > o.max_samples) {
    throw Error(kName, "options.max_samples = " + std::to_string(o.max_samples) + ": the scene would try " +
                           std::to_string(size.candidate_poses) + made_of +
                           "; raise lattice_step, lower orientations, or raise max_samples deliberately");
  }
  if (size.ik_solves > o.max_ik_solves) {
    throw Error(kName, "options.max_ik_solves = " + std::to_string(o.max_ik_solves) + ": the scene would do " +
                           std::to_string(size.ik_solves) + " IK solves (" + std::to_string(size.candidate_poses) +
                           made_of + " x " + std::to_string(o.joint3_steps) +
                           " joint3_steps); lower joint3_steps or orientations, raise lattice_step, or raise "
                           "max_ik_solves deliberately");
  }
}

// ---------------------------------------------------------------- scene ----

std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t seed) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  std::uint64_t h = seed;
  for (std::size_t i = 0; i < size; ++i) {
    h ^= bytes[i];
    h *= 1099511628211ULL;
  }
  return h;
}

namespace {

// The scene's samples in compact form: what the cache stores. Poses are recomputed from the
// indices (the same code as a fresh build, so a cached scene equals a built one bit for bit).
struct RawScene {
  std::vector<std::int32_t> lattice, orientation;
  std::vector<double> q, manipulability, mv, ma;  // n*7, n, n*36, n*36
  std::uint64_t size() const { return lattice.size(); }
};

std::string default_cache_directory() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return (fs::path(xdg) / "hapsyn").string();
  if (const char* home = std::getenv("HOME"); home && *home) return (fs::path(home) / ".cache" / "hapsyn").string();
  return "";
}

template <class T>
void put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <class T>
void put_array(std::string& out, const std::vector<T>& values) {
  if (!values.empty()) out.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

// Reads from a byte buffer; every read is bounds-checked so a truncated file is detected.
struct Reader {
  const std::string& bytes;
  std::size_t at = 0;
  template <class T>
  bool get(T* value) {
    if (bytes.size() - at < sizeof(T) || at > bytes.size()) return false;
    std::memcpy(value, bytes.data() + at, sizeof(T));
    at += sizeof(T);
    return true;
  }
  template <class T>
  bool get_array(std::vector<T>* values, std::uint64_t count) {
    if (count > (bytes.size() - at) / sizeof(T)) return false;
    values->resize(count);
    if (count) std::memcpy(values->data(), bytes.data() + at, count * sizeof(T));
    at += count * sizeof(T);
    return true;
  }
};

std::string payload_bytes(const RawScene& raw) {
  std::string payload;
  put_array(payload, raw.lattice);
  put_array(payload, raw.orientation);
  put_array(payload, raw.q);
  put_array(payload, raw.manipulability);
  put_array(payload, raw.mv);
  put_array(payload, raw.ma);
  return payload;
}

// Writes the cache atomically (write_file_atomically). Returns
// "" on success, else why it failed (a failed write never fails the build).
std::string write_cache(const std::string& file, const std::string& key, const RawScene& raw, bool ellipsoids) {
  try {
    const fs::path path(file);
    fs::create_directories(path.parent_path());
    const std::string payload = payload_bytes(raw);
    std::string out;
    out.append(kCacheMagic, sizeof kCacheMagic);
    put(out, kCacheFormatVersion);
    put(out, static_cast<std::uint32_t>(ellipsoids ? 1 : 0));
    put(out, static_cast<std::uint64_t>(key.size()));
    out += key;
    put(out, raw.size());
    put(out, static_cast<std::uint64_t>(payload.size()));
    put(out, fnv1a64(payload.data(), payload.size()));
    put(out, fnv1a64(out.data(), out.size()));  // header checksum
    write_file_atomically(file, {out, payload});
    return "";
  } catch (const std::exception& e) {
    return e.what();
  }
}

std::uint64_t bytes_per_sample(bool ellipsoids) {
  return 2 * sizeof(std::int32_t) + 8 * sizeof(double) + (ellipsoids ? 72 * sizeof(double) : 0);
}

// The largest cache file a scene of at most `samples` samples can have: header, key, payload.
// (samples <= 401^3 x 1e6 candidate poses: no overflow.)
std::uint64_t max_cache_bytes(const std::string& key, long long samples, bool ellipsoids) {
  return 4096 + key.size() + static_cast<std::uint64_t>(samples) * bytes_per_sample(ellipsoids);
}

// The cache file's bytes, or a reason it is not used ("missing", "corrupt: ..."). A cache path
// that exists but is not a regular file (a directory, a FIFO, /dev/zero) is no cache at all and
// can be neither read nor replaced: that is an Error naming it, not a rebuild.
std::string load_cache_bytes(const std::string& file, std::uint64_t max_bytes, std::string* bytes) {
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0) return "missing";
  if (!S_ISREG(st.st_mode)) {
    throw Error(kName, "cache file " + file + " is not a regular file (" +
                           (S_ISDIR(st.st_mode) ? "a directory" : S_ISFIFO(st.st_mode) ? "a FIFO" : "a device or socket") +
                           "); remove it, or set cache_directory or cache = false");
  }
  if (static_cast<std::uint64_t>(st.st_size) > max_bytes) {
    return "corrupt: " + std::to_string(st.st_size) + " bytes, more than the " + std::to_string(max_bytes) +
           " a cache of these options can hold";
  }
  *bytes = read_regular_file(file, kName, "cache file", max_bytes);
  return "";
}

// Reads a cache file. Returns "" and fills raw when it is intact and made for `key`; else the
// reason it is not used ("missing", "corrupt: ...", "stale: ..."). `max_samples`: the candidate
// poses of these options, which no intact cache exceeds; a larger file is not even read.
std::string read_cache(const std::string& file, const std::string& key, bool ellipsoids, int lattice_points,
                       int orientations, long long max_samples, RawScene* raw) {
  std::string bytes;
  if (std::string why = load_cache_bytes(file, max_cache_bytes(key, max_samples, ellipsoids), &bytes); !why.empty()) {
    return why;
  }
  Reader r{bytes};
  char magic[8];
  if (!r.get(&magic) || std::memcmp(magic, kCacheMagic, sizeof magic) != 0) return "corrupt: not a human_arm cache file";
  std::uint32_t version = 0, flags = 0;
  if (!r.get(&version)) return "corrupt: truncated header";
  if (version != kCacheFormatVersion) return "stale: format version " + std::to_string(version);
  std::uint64_t key_size = 0;
  if (!r.get(&flags) || !r.get(&key_size) || key_size > bytes.size() - r.at) return "corrupt: truncated header";
  const std::string stored_key = bytes.substr(r.at, key_size);
  r.at += key_size;
  std::uint64_t n = 0, payload_size = 0, payload_sum = 0, header_sum = 0;
  if (!r.get(&n) || !r.get(&payload_size) || !r.get(&payload_sum)) return "corrupt: truncated header";
  const std::size_t header_end = r.at;
  if (!r.get(&header_sum) || header_sum != fnv1a64(bytes.data(), header_end)) return "corrupt: header checksum";
  if (stored_key != key || (flags != 0) != ellipsoids) return "stale: made for other options or another arm file";
  const std::uint64_t per_sample = bytes_per_sample(ellipsoids);
  if (n > static_cast<std::uint64_t>(max_samples) || payload_size != n * per_sample) return "corrupt: payload size";
  if (bytes.size() - r.at != payload_size) return "corrupt: truncated or oversized payload";
  if (fnv1a64(bytes.data() + r.at, payload_size) != payload_sum) return "corrupt: payload checksum";
  RawScene s;
  if (!r.get_array(&s.lattice, n) || !r.get_array(&s.orientation, n) || !r.get_array(&s.q, n * 7) ||
      !r.get_array(&s.manipulability, n) || !r.get_array(&s.mv, ellipsoids ? n * 36 : 0) ||
      !r.get_array(&s.ma, ellipsoids ? n * 36 : 0)) {
    return "corrupt: truncated payload";
  }
  for (std::uint64_t i = 0; i < n; ++i) {
    if (s.lattice[i] < 0 || s.lattice[i] >= lattice_points || s.orientation[i] < 0 || s.orientation[i] >= orientations) {
      return "corrupt: sample index out of range";
    }
  }
  for (const auto* v : {&s.q, &s.manipulability, &s.mv, &s.ma}) {
    for (double x : *v) {
      if (!std::isfinite(x)) return "corrupt: non-finite value";
    }
  }
  *raw = std::move(s);
  return "";
}

}  // namespace

HumanArmScene::HumanArmScene(const HumanArmOptions& options)
    : options_(resolve_human_arm_scene_options(options)),
      arm_(load_human_arm(options_.arm_file)),
      size_(human_arm_scene_size(options_, arm_.reach())) {
  check_human_arm_scene_size(options_, size_);
}

std::string HumanArmScene::cache_key(bool ellipsoids) const {
  const HumanArmSceneOptions& o = options_;
  // Everything the samples depend on, and nothing else (threads and the cache location do not
  // change the result).
  const Json key = {{"scene", "human_arm"},
                    {"format_version", kCacheFormatVersion},
                    {"algorithm_version", kAlgorithmVersion},
                    {"arm", arm_.data().document},
                    {"lattice_step", o.lattice_step},
                    {"lattice_extent", o.lattice_extent},
                    {"orientations", o.orientations},
                    {"joint3_steps", o.joint3_steps},
                    {"x_S_B", vector_json(o.x_S_B)},
                    {"C_S_B", matrix_json(o.C_S_B)},
                    {"C_E_P", matrix_json(o.C_E_P)},
                    {"x_E_P", vector_json(o.x_E_P)},
                    {"ellipsoids", ellipsoids}};
  return key.dump();
}

std::string HumanArmScene::cache_file(bool ellipsoids) const {
  if (!options_.cache) return "";
  const std::string dir = options_.cache_directory.empty() ? default_cache_directory() : options_.cache_directory;
  if (dir.empty()) return "";
  const std::string key = cache_key(ellipsoids);
  char name[64];
  std::snprintf(name, sizeof name, "human_arm-%016llx.bin",
                static_cast<unsigned long long>(fnv1a64(key.data(), key.size())));
  return (fs::path(dir) / name).string();
}

namespace {

// The lattice and orientation set of a build: shared by the solve and the assembly steps.
struct LatticeGeometry {
  std::vector<double> axis;
  int per_axis = 0;
  int points = 0;
  std::vector<Eigen::Quaterniond> rotations;
  Eigen::Vector3d point(int index) const {
    return Eigen::Vector3d(axis[index % per_axis], axis[(index / per_axis) % per_axis],
                           axis[index / (per_axis * per_axis)]);
  }
};

struct AttributeWish {
  bool mv = false, ma = false;
  bool ellipsoids() const { return mv || ma; }
};

AttributeWish requested_attributes(const SceneRequest& request) {
  AttributeWish wish;
  for (const std::string& a : request.attributes) {
    if (a == "M_v") {
      wish.mv = true;
    } else if (a == "M_a") {
      wish.ma = true;
    } else if (a != "shoulder_pose" && a != "human_q" && a != "manipulability" && a != "lattice_index" &&
               a != "arm_points") {
      throw Error(kName, "per-sample attribute '" + a +
                             "' requested: this scene provides shoulder_pose, human_q, manipulability, lattice_index, "
                             "arm_points, M_v, M_a");
    }
  }
  return wish;
}

// The reachable poses of one lattice point: every orientation the arm reaches there, with its
// best joint-3 solution and (on request) its velocity and acceleration ellipsoid axes in B.
void solve_lattice_point(const HumanArm& arm, const HumanArmSceneOptions& o, const std::vector<Eigen::Matrix3d>& matrices,
                         const std::vector<double>& grid, bool ellipsoids, int index, const Eigen::Vector3d& p,
                         RawScene& out) {
  Vector7d q;
  double m = 0.0;
  for (int k = 0; k < o.orientations; ++k) {
    if (!arm.best(matrices[k], p, grid, &q, &m)) continue;
    out.lattice.push_back(static_cast<std::int32_t>(index));
    out.orientation.push_back(k);
    out.q.insert(out.q.end(), q.data(), q.data() + 7);
    out.manipulability.push_back(m);
    if (!ellipsoids) continue;
    Matrix67d J = arm.jacobian(q);
    // Twist of E rather than P when x_E^P != 0: v_E = v_P + omega x r, r = C_P^S x_E^P.
    const Eigen::Vector3d r = matrices[k] * o.x_E_P;
    for (int c = 0; c < 7; ++c) J.block<3, 1>(3, c) += J.block<3, 1>(0, c).cross(r);
    // Then rotate both halves into B: blockdiag(C_S^B, C_S^B) M^S, as eq. (12) does.
    for (const auto& [scale, target] : {std::pair{&arm.data().velocity_max, &out.mv},
                                        std::pair{&arm.data().acceleration_max, &out.ma}}) {
      Matrix6d M = ellipsoid_axes(J, *scale);
      M.topRows<3>() = (o.C_S_B * M.topRows<3>()).eval();
      M.bottomRows<3>() = (o.C_S_B * M.bottomRows<3>()).eval();
      const Eigen::Matrix<double, 6, 6, Eigen::RowMajor> row_major = M;
      target->insert(target->end(), row_major.data(), row_major.data() + 36);
    }
  }
}

// "human_arm: building the reachable poses: P% of N, ~L s left" on `out`, at most every 2 s
// (the first after 2 s, so a quick build prints nothing); silent when `out` is null. Called from
// the build's worker threads: one of them prints, the others never wait for it.
class BuildProgress {
 public:
  BuildProgress(std::ostream* out, long long total) : out_(out), total_(total) {}
  void add(long long poses) {
    if (!out_) return;
    const long long done = done_ += poses;
    std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < std::chrono::seconds(2) || done <= 0 || total_ <= 0) return;
    last_ = now;
    const double fraction = std::min(1.0, static_cast<double>(done) / static_cast<double>(total_));
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    char line[160];
    std::snprintf(line, sizeof line, "human_arm: building the reachable poses: %.0f%% of %lld, ~%.0f s left\n",
                  100.0 * fraction, total_, elapsed * (1.0 - fraction) / fraction);
    *out_ << line << std::flush;
  }

 private:
  std::ostream* out_;
  long long total_;
  std::atomic<long long> done_{0};
  std::mutex mutex_;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_ = start_;
};

// The build's thread count: the scene's own option, else what the run grants, else every core.
int build_threads(const HumanArmSceneOptions& o, const SceneRequest& request) {
  if (o.threads > 0) return o.threads;
  return request.threads > 0 ? request.threads : hardware_threads();
}

// Every lattice point in parallel, merged in lattice order (so the result does not depend on
// the thread count).
RawScene solve_lattice(const HumanArm& arm, const HumanArmSceneOptions& o, const LatticeGeometry& g, bool ellipsoids,
                       int threads, BuildProgress& progress) {
  const std::vector<double> grid = arm.joint3_grid(o.joint3_steps);
  std::vector<Eigen::Matrix3d> matrices(g.rotations.size());
  for (std::size_t i = 0; i < g.rotations.size(); ++i) matrices[i] = g.rotations[i].toRotationMatrix();
  std::vector<RawScene> per_point(static_cast<std::size_t>(g.points));
  // Lattice points far from the shoulder cost nothing; near ones cost a full orientation
  // sweep: dynamic scheduling balances them.
  parallel_for_dynamic(g.points, threads, 1, [&](long long index, int) {
    const Eigen::Vector3d p = g.point(static_cast<int>(index));
    if (p.norm() > arm.reach() * (1.0 + 1e-9)) return;
    solve_lattice_point(arm, o, matrices, grid, ellipsoids, static_cast<int>(index), p,
                        per_point[static_cast<std::size_t>(index)]);
    progress.add(o.orientations);
  });
  RawScene raw;
  for (RawScene& s : per_point) {
    raw.lattice.insert(raw.lattice.end(), s.lattice.begin(), s.lattice.end());
    raw.orientation.insert(raw.orientation.end(), s.orientation.begin(), s.orientation.end());
    raw.q.insert(raw.q.end(), s.q.begin(), s.q.end());
    raw.manipulability.insert(raw.manipulability.end(), s.manipulability.begin(), s.manipulability.end());
    raw.mv.insert(raw.mv.end(), s.mv.begin(), s.mv.end());
    raw.ma.insert(raw.ma.end(), s.ma.begin(), s.ma.end());
    s = RawScene();
  }
  return raw;
}

// Lattice points a loaded cache is checked at: re-solved and compared with its samples there.
constexpr int kCacheSpotChecks = 8;

// The spot check of a loaded cache: a checksum only proves the file is what some writer wrote,
// and a file edited by hand with the checksums recomputed was once trusted (J 1.437 instead of
// 2.647). kCacheSpotChecks lattice points within reach (chosen from the file's own checksum, so
// that every cache is checked at other points) and as many holding samples are solved again with
// the builder's own code; their samples must be the cache's. Returns "" or "corrupt: ...".
std::string spot_check(const RawScene& cached, const HumanArm& arm, const HumanArmSceneOptions& o,
                       const LatticeGeometry& g, bool ellipsoids, std::uint64_t seed) {
  if (!std::is_sorted(cached.lattice.begin(), cached.lattice.end())) return "corrupt: samples out of lattice order";
  std::vector<int> within_reach;
  for (int i = 0; i < g.points; ++i) {
    if (g.point(i).norm() <= arm.reach() * (1.0 + 1e-9)) within_reach.push_back(i);
  }
  if (within_reach.empty()) return "";
  std::uint64_t state = seed;
  const auto draw = [&](std::size_t n) {  // splitmix64
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return static_cast<std::size_t>((z ^ (z >> 31)) % n);
  };
  std::vector<int> points;
  for (int k = 0; k < kCacheSpotChecks; ++k) {
    points.push_back(within_reach[draw(within_reach.size())]);
    if (cached.size() > 0) points.push_back(cached.lattice[draw(cached.size())]);
  }
  const std::vector<double> grid = arm.joint3_grid(o.joint3_steps);
  std::vector<Eigen::Matrix3d> matrices(g.rotations.size());
  for (std::size_t i = 0; i < g.rotations.size(); ++i) matrices[i] = g.rotations[i].toRotationMatrix();
  for (const int point : points) {
    RawScene fresh;
    solve_lattice_point(arm, o, matrices, grid, ellipsoids, point, g.point(point), fresh);
    const auto [begin, end] = std::equal_range(cached.lattice.begin(), cached.lattice.end(), point);
    const std::size_t first = static_cast<std::size_t>(begin - cached.lattice.begin());
    const std::size_t count = static_cast<std::size_t>(end - begin);
    // Within 1e-9: another build of the same code may round differently in the last bits.
    const auto same = [](const double* a, const double* b, std::size_t n) {
      for (std::size_t i = 0; i < n; ++i) {
        if (!(std::abs(a[i] - b[i]) <= 1e-9 * (1.0 + std::abs(b[i])))) return false;
      }
      return true;
    };
    const std::size_t m = ellipsoids ? 36 : 0;
    const bool agrees =
        fresh.size() == count &&
        std::equal(fresh.orientation.begin(), fresh.orientation.end(), cached.orientation.begin() + first) &&
        same(fresh.q.data(), cached.q.data() + 7 * first, 7 * count) &&
        same(fresh.manipulability.data(), cached.manipulability.data() + first, count) &&
        same(fresh.mv.data(), cached.mv.data() + m * first, m * count) &&
        same(fresh.ma.data(), cached.ma.data() + m * first, m * count);
    if (!agrees) {
      return "corrupt: its samples at lattice point " + std::to_string(point) + " differ from a fresh solve (spot check)";
    }
  }
  return "";
}

// The samples (end-effector poses in B) and their attributes from the solved lattice.
SampleSet assemble_samples(const HumanArm& arm, const RawScene& raw, const HumanArmSceneOptions& o,
                           const LatticeGeometry& g, const AttributeWish& wish) {
  SampleSet set;
  set.coordinates = {"x", "y", "z", "qw", "qx", "qy", "qz"};
  set.unit = "m";
  const Eigen::Index n = static_cast<Eigen::Index>(raw.size());
  set.poses.resize(n, 7);
  SampleSet::RowMatrix shoulder(n, 7), human_q(n, 7), manip(n, 1), lattice_index(n, 1), arm_points_in_b(n, 12);
  const Eigen::Quaterniond q_S_B(o.C_S_B), q_E_P(o.C_E_P);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d p = g.point(raw.lattice[i]);
    const Eigen::Quaterniond& r = g.rotations[static_cast<std::size_t>(raw.orientation[i])];
    shoulder.row(i) << p(0), p(1), p(2), r.w(), r.x(), r.y(), r.z();
    // T_E^B = T_S^B T_P^S T_E^P.
    const Eigen::Vector3d x = o.x_S_B + o.C_S_B * (p + r.toRotationMatrix() * o.x_E_P);
    Eigen::Quaterniond qb = (q_S_B * r * q_E_P).normalized();
    if (qb.w() < 0.0) qb.coeffs() = -qb.coeffs();
    set.poses.row(i) << x(0), x(1), x(2), qb.w(), qb.x(), qb.y(), qb.z();
    for (int j = 0; j < 7; ++j) human_q(i, j) = raw.q[static_cast<std::size_t>(i) * 7 + j];
    const ArmPoints points = arm_points(arm, human_q.row(i).transpose());
    for (int k = 0; k < 4; ++k) arm_points_in_b.row(i).segment<3>(3 * k) = (o.x_S_B + o.C_S_B * points[k]).transpose();
    manip(i, 0) = raw.manipulability[static_cast<std::size_t>(i)];
    lattice_index(i, 0) = raw.lattice[static_cast<std::size_t>(i)];
  }
  set.attributes["shoulder_pose"] = std::move(shoulder);
  set.attributes["human_q"] = std::move(human_q);
  set.attributes["manipulability"] = std::move(manip);
  set.attributes["lattice_index"] = std::move(lattice_index);
  // Cheap (one forward pass per sample, after the solve or the cache), so always there, like
  // human_q: viewers draw the arm with it.
  set.attributes["arm_points"] = std::move(arm_points_in_b);
  const auto matrix_attribute = [&](const std::vector<double>& values) {
    SampleSet::RowMatrix M(n, 36);
    if (n > 0) std::memcpy(M.data(), values.data(), values.size() * sizeof(double));
    return M;
  };
  if (wish.mv) set.attributes["M_v"] = matrix_attribute(raw.mv);
  if (wish.ma) set.attributes["M_a"] = matrix_attribute(raw.ma);
  // The lattice declaration the framework's maps and plots use (the lattice frame is S, the
  // poses' frame B).
  SampleLattice lattice;
  lattice.per_axis = g.per_axis;
  lattice.step = o.lattice_step;
  lattice.index_of_sample.assign(raw.lattice.begin(), raw.lattice.end());
  lattice.candidates_per_point = o.orientations;
  lattice.candidates = "orientations";
  lattice.lattice_to_poses = o.C_S_B;
  lattice.origin = "the shoulder";
  lattice.frame = "S";
  set.lattice = std::move(lattice);
  return set;
}

// The human for viewers (hapsyn view, report): the arm's per-sample points are the attribute
// arm_points; the rest of the body is rigid and given once, in B.
Json figure_info(const HumanArm& arm, const HumanArmSceneOptions& o) {
  const HumanBodyProxy body = body_proxy(arm);
  const auto in_b = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d b = o.x_S_B + o.C_S_B * p;
    return Json::array({b.x(), b.y(), b.z()});
  };
  Json lines = Json::array();
  for (const auto& line : body.lines) {
    Json points = Json::array();
    for (const Eigen::Vector3d& p : line) points.push_back(in_b(p));
    lines.push_back(points);
  }
  return {{"arm_attribute", "arm_points"},
          {"arm_joints", {"shoulder", "elbow", "wrist", "palm"}},
          {"body_lines", lines},
          {"head_centre", in_b(body.head_centre)},
          {"head_radius", body.head_radius},
          {"body_height", body.height},
          {"proportions", "Drillis and Contini (Winter, Biomechanics and Motor Control of Human Movement, fig. 4.1), "
                          "scaled by the arm file's upper arm"}};
}

}  // namespace

SampleSet HumanArmScene::build(const SceneRequest& request) const {
  const auto start = std::chrono::steady_clock::now();
  const AttributeWish wish = requested_attributes(request);
  const bool ellipsoids = wish.ellipsoids();
  const HumanArmSceneOptions& o = options_;
  LatticeGeometry g;
  g.axis = lattice_axis(o.lattice_step, o.lattice_extent);
  g.per_axis = static_cast<int>(g.axis.size());
  g.points = g.per_axis * g.per_axis * g.per_axis;
  g.rotations = orientation_set(o.orientations);

  const std::string file = cache_file(ellipsoids);
  const std::string key = file.empty() ? std::string() : cache_key(ellipsoids);
  RawScene raw;
  bool from_cache = false;
  std::string cache_status = o.cache ? (file.empty() ? "off: no cache directory ($XDG_CACHE_HOME and $HOME unset)" : "")
                                     : "off";
  if (!file.empty()) {
    std::string why = read_cache(file, key, ellipsoids, g.points, o.orientations, size_.candidate_poses, &raw);
    if (why.empty()) why = spot_check(raw, arm_, o, g, ellipsoids, fnv1a64(raw.q.data(), raw.q.size() * sizeof(double)));
    if (why.empty()) {
      from_cache = true;
      cache_status = "hit";
    } else {
      cache_status = why == "missing" ? "miss: built" : "rebuilt (" + why + ")";
      // A damaged cache is never trusted; the rebuild replaces it, and the user hears why.
      if (why.rfind("corrupt", 0) == 0) std::cerr << "hapsyn: warning: human_arm: cache file " << file << " " << why << "; rebuilding\n";
    }
  }
  if (!from_cache) {
    BuildProgress progress(request.progress, size_.candidate_poses);
    raw = solve_lattice(arm_, o, g, ellipsoids, build_threads(o, request), progress);
    if (!file.empty()) {
      const std::string failure = write_cache(file, key, raw, ellipsoids);
      if (!failure.empty()) cache_status += "; cache not written: " + failure;
    }
  }

  SampleSet set = assemble_samples(arm_, raw, o, g, wish);
  Json info = Json::object();
  info["n_reach"] = static_cast<long long>(raw.size());
  info["lattice_points"] = g.points;
  info["lattice_per_axis"] = g.per_axis;
  info["lattice_step"] = o.lattice_step;
  info["lattice_extent"] = o.lattice_extent;
  info["orientations"] = o.orientations;
  info["joint3_steps"] = o.joint3_steps;
  info["poses_tried"] = static_cast<long long>(g.points) * o.orientations;
  info["candidate_poses"] = size_.candidate_poses;
  info["build_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  info["cache_file"] = file;
  info["cache_status"] = cache_status;
  info["from_cache"] = from_cache;
  info["arm_file"] = o.arm_file;
  info["figure"] = figure_info(arm_, o);
  set.info = std::move(info);
  return set;
}

}  // namespace hapsyn::plugins
