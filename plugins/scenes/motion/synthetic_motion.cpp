// Synthetic arm motion: keyframed activities of daily living on the Fennel 2022 arm, sampled with
// noise and written as hapsyn-motion CSV and BVH (see synthetic_motion.hpp).
#include "synthetic_motion.hpp"

#include <hapsyn/error.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace hapsyn::plugins::motion {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
constexpr double kPeakVelocity = 1.875;                   // max of 30 s^2 (1 - s)^2
constexpr double kPeakAcceleration = 5.773502691896258;   // 10 / sqrt(3), max |60 s - 180 s^2 + 120 s^3|

[[noreturn]] void fail(const std::string& message) { throw Error("motion", message); }

// ------------------------------------------------------------------ random numbers ----

// splitmix64 (Steele, Lea, Flood 2014): tiny, fast, and the same sequence everywhere, unlike the
// standard distributions whose algorithms differ between library implementations.
class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Standard normal by Box-Muller (1 - u keeps the logarithm's argument in (0, 1]).
  double normal() {
    const double u1 = 1.0 - uniform();
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
  }

 private:
  std::uint64_t state_;
};

enum class Stream : std::uint64_t { scale = 1, keyframes, timing, jitter, noise };

// One independent stream per (seed, subject, activity, purpose), so that changing the number of
// subjects or the order of drawing never changes another trajectory.
Random stream(std::uint64_t seed, int subject, int activity, Stream purpose) {
  Random mix(seed);
  std::uint64_t s = mix.next();
  for (std::uint64_t word : {static_cast<std::uint64_t>(subject), static_cast<std::uint64_t>(activity),
                             static_cast<std::uint64_t>(purpose)}) {
    Random step(s ^ (word * 0xD1B54A32D192ED03ULL));
    s = step.next();
  }
  return Random(s);
}

// ------------------------------------------------------------------ activities ----

// One step of an activity: move (nominal move_s) to a keyframe [deg], then rest there for hold_s.
struct Step {
  std::array<double, 7> deg;
  double move_s;
  double hold_s;
};

struct Activity {
  const char* name;
  std::vector<Step> steps;  // the first step's move_s is unused: the activity starts there
};

// Keyframes (right arm, q = 0 hanging down; q1 abduction, q2 flexion, q3 internal rotation, q4
// elbow flexion, q5 pronation, q6 wrist flexion, q7 deviation), chosen with the arm's forward
// kinematics for a seated subject: the table top about 0.28 m below the shoulder, the mouth
// 0.15-0.2 m medial and a little above it. Nominal times sum to about 10 s; they are rescaled.
const std::vector<Activity>& activities() {
  static const std::array<double, 7> home{10, 15, 10, 85, 0, 0, -10};  // palm on the table in front
  static const std::vector<Activity> list{
      {"reaching",
       {{home, 0, 0.4},
        {{5, 80, 5, 15, 0, 10, -5}, 1.8, 0.3},  // forward at shoulder height
        {home, 1.6, 0.3},
        {{40, 55, 0, 20, -20, 0, -10}, 1.6, 0.3},  // forward right
        {home, 1.5, 0.3},
        {{5, 60, 40, 30, 20, 0, -10}, 1.5, 0.3},  // forward left, lower
        {home, 1.5, 0.2}}},
      {"wiping",
       {{home, 0, 0.2},
        {{10, 28, 20, 75, -10, 5, -10}, 1.0, 0.2},  // centre of the wiped patch
        {{5, 30, 35, 65, 0, 0, -10}, 0.8, 0},       // left
        {{22, 25, 0, 68, 0, 0, -10}, 0.9, 0},       // right
        {{5, 30, 35, 65, 0, 0, -10}, 0.9, 0},
        {{22, 25, 0, 68, 0, 0, -10}, 0.9, 0},
        {{8, 45, 25, 50, 0, 0, -10}, 0.8, 0},   // far
        {{12, 20, 10, 85, 0, 0, -10}, 0.8, 0},  // near
        {{8, 45, 25, 50, 0, 0, -10}, 0.8, 0},
        {{12, 20, 10, 85, 0, 0, -10}, 0.8, 0},
        {{10, 28, 20, 75, -10, 5, -10}, 0.7, 0},
        {home, 1.0, 0.2}}},
      {"lifting",
       {{home, 0, 0.3},
        {{10, 25, 15, 70, 0, 0, -10}, 1.0, 0.4},     // grasp the object on the table
        {{15, 70, 15, 45, -10, 0, -10}, 2.0, 0.6},   // lifted to shoulder height
        {{10, 25, 15, 70, 0, 0, -10}, 2.0, 0.4},     // put down
        {home, 1.0, 0.3}}},
      {"drinking",
       {{home, 0, 0.3},
        {{10, 35, 20, 60, -30, 10, -10}, 1.2, 0.4},   // grasp the cup
        {{10, 55, 45, 135, -30, 20, -10}, 2.0, 0.2},  // cup at the mouth
        {{10, 55, 45, 140, -60, 30, -10}, 0.8, 0.8},  // tilted: supination and wrist flexion
        {{10, 55, 45, 135, -30, 20, -10}, 0.8, 0},
        {{10, 35, 20, 60, -30, 10, -10}, 2.0, 0.4},   // cup back on the table
        {home, 1.0, 0.3}}},
      {"side_reach",
       {{home, 0, 0.3},
        {{80, 20, -25, 20, 0, 0, -10}, 1.8, 0.5},  // a shelf out to the side, arm abducted
        {home, 1.7, 0.3},
        {{60, 50, 30, 40, 0, 0, -10}, 1.5, 0.4},   // forward and out
        {{80, 20, -25, 20, 0, 0, -10}, 1.4, 0.4},  // back to the shelf
        {home, 1.6, 0.3}}},
  };
  return list;
}

// ------------------------------------------------------------------ the joint path ----

// Per-subject keyframes: each joint perturbed by a Gaussian cut at 2 sigma, then kept `margin`
// inside the limits (the quintics between them stay inside too).
std::vector<Vector7d> perturbed_keyframes(const Activity& activity, const HumanArmData& arm,
                                          const SyntheticOptions& o, Random& random) {
  std::vector<Vector7d> keys;
  for (const Step& step : activity.steps) {
    Vector7d q;
    for (int j = 0; j < 7; ++j) {
      const double noise = std::clamp(random.normal(), -2.0, 2.0) * o.keyframe_sigma_deg;
      const double lo = arm.lower(j) + o.keyframe_margin_deg * kDeg;
      const double hi = arm.upper(j) - o.keyframe_margin_deg * kDeg;
      q(j) = std::clamp((step.deg[j] + noise) * kDeg, lo, hi);
    }
    keys.push_back(q);
  }
  return keys;
}

// Shortest duration of a quintic move from a to b that keeps every joint's peak velocity and
// acceleration within fraction * maximum (plus a hair, so sampled peaks never exceed it).
double minimum_duration(const Vector7d& a, const Vector7d& b, const HumanArmData& arm, double fraction) {
  double T = 0.0;
  for (int j = 0; j < 7; ++j) {
    const double dq = std::abs(b(j) - a(j));
    T = std::max(T, kPeakVelocity * dq / (fraction * arm.velocity_max(j)));
    T = std::max(T, std::sqrt(kPeakAcceleration * dq / (fraction * arm.acceleration_max(j))));
  }
  return T * (1.0 + 1e-9);
}

// Durations T_i = max(lambda w_i, T_min_i) with lambda chosen (bisection; the sum is monotone in
// lambda) so that they add up to `total`; when the minima alone exceed it, the activity is longer.
std::vector<double> fit_durations(const std::vector<double>& weights, const std::vector<double>& minima,
                                  double total) {
  double weight_sum = 0.0, minimum_sum = 0.0;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    weight_sum += weights[i];
    minimum_sum += minima[i];
  }
  auto durations = [&](double lambda) {
    std::vector<double> T(weights.size());
    for (std::size_t i = 0; i < T.size(); ++i) T[i] = std::max(lambda * weights[i], minima[i]);
    return T;
  };
  auto sum = [](const std::vector<double>& T) {
    double s = 0.0;
    for (double t : T) s += t;
    return s;
  };
  if (minimum_sum >= total) return durations(total / weight_sum);
  double lo = 0.0, hi = total / weight_sum;  // sum(hi) >= total
  for (int iteration = 0; iteration < 200; ++iteration) {
    const double mid = 0.5 * (lo + hi);
    (sum(durations(mid)) < total ? lo : hi) = mid;
  }
  return durations(hi);
}

QuinticPath make_path(const Activity& activity, const HumanArmData& arm, const SyntheticOptions& o,
                      Random& keyframe_random, Random& timing_random) {
  const std::vector<Vector7d> keys = perturbed_keyframes(activity, arm, o, keyframe_random);
  QuinticPath path;
  std::vector<double> weights, minima;
  auto add = [&](const Vector7d& to, double weight) {
    const double w = weight * timing_random.uniform(0.85, 1.15);
    if (w <= 0.0) return;
    minima.push_back(minimum_duration(path.keyframes.back(), to, arm, o.speed_fraction));
    weights.push_back(w);
    path.keyframes.push_back(to);
  };
  path.keyframes.push_back(keys[0]);
  add(keys[0], activity.steps[0].hold_s);
  for (std::size_t i = 1; i < keys.size(); ++i) {
    add(keys[i], activity.steps[i].move_s);
    add(keys[i], activity.steps[i].hold_s);
  }
  path.durations = fit_durations(weights, minima, o.duration_s);
  return path;
}

// ------------------------------------------------------------------ kinematics ----

Eigen::Matrix3d rotation_of(const Eigen::Vector4d& wxyz) {
  return Eigen::Quaterniond(wxyz(0), wxyz(1), wxyz(2), wxyz(3)).normalized().toRotationMatrix();
}

// Quaternion (w, x, y, z) of R with the sign closest to `previous` (continuity), or w >= 0 first.
Eigen::Vector4d continuous_quaternion(const Eigen::Matrix3d& R, const Eigen::Vector4d* previous) {
  const Eigen::Quaterniond e(R);
  Eigen::Vector4d q(e.w(), e.x(), e.y(), e.z());
  const bool flip = previous ? q.dot(*previous) < 0.0 : q(0) < 0.0;
  return flip ? Eigen::Vector4d(-q) : q;
}

// Jdot qdot by a central difference of J along qdot (J is smooth; h = 1e-5 s leaves errors
// near 1e-10 from truncation and rounding alike).
Eigen::Matrix<double, 6, 1> jdot_qdot(const HumanArm& arm, const Vector7d& q, const Vector7d& qdot) {
  const double h = 1e-5;
  const Matrix67d dJ = (arm.jacobian(q + h * qdot) - arm.jacobian(q - h * qdot)) / (2.0 * h);
  return dJ * qdot;
}

Eigen::VectorXd sample_times(double duration, const SyntheticOptions& o, bool jittered, Random& random) {
  const int n = static_cast<int>(std::floor(duration * o.rate_hz + 1e-9)) + 1;
  Eigen::VectorXd t(n);
  for (int k = 0; k < n; ++k) {
    t(k) = k / o.rate_hz;
    // The recorder's clock starts at 0; later stamps wander around the nominal grid.
    if (jittered && k > 0) t(k) += random.uniform(-o.time_jitter_s, o.time_jitter_s);
  }
  return t;
}

void fill_kinematics(SyntheticTrajectory& t, const HumanArm& arm) {
  const Eigen::Index n = t.time.size();
  t.q.resize(n, 7), t.qdot.resize(n, 7), t.qddot.resize(n, 7);
  t.position.resize(n, 3), t.quaternion.resize(n, 4), t.twist.resize(n, 6), t.twist_rate.resize(n, 6);
  for (Eigen::Index k = 0; k < n; ++k) {
    Vector7d q, qd, qdd;
    t.path.evaluate(t.time(k), &q, &qd, &qdd);
    t.q.row(k) = q.transpose(), t.qdot.row(k) = qd.transpose(), t.qddot.row(k) = qdd.transpose();
    const Eigen::Isometry3d T = arm.forward(q);
    t.position.row(k) = T.translation().transpose();
    const Eigen::Vector4d previous = k > 0 ? Eigen::Vector4d(t.quaternion.row(k - 1).transpose()) : Eigen::Vector4d::Zero();
    t.quaternion.row(k) = continuous_quaternion(T.linear(), k > 0 ? &previous : nullptr).transpose();
    const Matrix67d J = arm.jacobian(q);
    t.twist.row(k) = (J * qd).transpose();
    t.twist_rate.row(k) = (J * qdd + jdot_qdot(arm, q, qd)).transpose();
  }
}

// Measurement noise: Gaussian position, and a Gaussian rotation vector applied in S.
void add_noise(SyntheticTrajectory& t, const SyntheticOptions& o, Random& random) {
  const Eigen::Index n = t.time.size();
  t.noisy_position.resize(n, 3), t.noisy_quaternion.resize(n, 4);
  for (Eigen::Index k = 0; k < n; ++k) {
    Eigen::Vector3d dp, r;
    for (int i = 0; i < 3; ++i) dp(i) = o.position_noise_m * random.normal();
    for (int i = 0; i < 3; ++i) r(i) = o.orientation_noise_deg * kDeg * random.normal();
    t.noisy_position.row(k) = t.position.row(k) + dp.transpose();
    const double angle = r.norm();
    const Eigen::Matrix3d E = angle > 0.0 ? Eigen::AngleAxisd(angle, r / angle).toRotationMatrix()
                                          : Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d R = E * rotation_of(t.quaternion.row(k).transpose());
    const Eigen::Vector4d previous = k > 0 ? Eigen::Vector4d(t.noisy_quaternion.row(k - 1).transpose()) : Eigen::Vector4d::Zero();
    t.noisy_quaternion.row(k) = continuous_quaternion(R, k > 0 ? &previous : nullptr).transpose();
  }
}

void check_options(const SyntheticOptions& o) {
  if (o.subjects < 1 || o.subjects > 99) fail("subjects = " + std::to_string(o.subjects) + ": must be in [1, 99]");
  if (!(o.duration_s > 0) || !(o.rate_hz > 0)) fail("duration_s and rate_hz must be > 0");
  if (!(o.position_noise_m >= 0) || !(o.orientation_noise_deg >= 0)) fail("noise sigmas must be >= 0");
  if (!(o.speed_fraction > 0 && o.speed_fraction <= 1)) fail("speed_fraction must be in (0, 1]");
  if (!(o.time_jitter_s >= 0 && o.time_jitter_s < 0.5 / o.rate_hz))
    fail("time_jitter_s must be in [0, half the sampling period): stamps must stay increasing");
  if (!(o.keyframe_sigma_deg >= 0) || !(o.keyframe_margin_deg >= 0)) fail("keyframe sigma and margin must be >= 0");
}

std::string subject_name(int index) {
  char name[16];
  std::snprintf(name, sizeof name, "S%02d", index + 1);
  return name;
}

// ------------------------------------------------------------------ text output ----

// Fixed decimals without a "-0.000..." for values that round to zero.
std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  std::string s = text;
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

// Up to 6 decimals with trailing zeros dropped: BVH files are mostly numbers, and this keeps the
// data set small without losing any printed precision.
std::string compact(double value) {
  std::string s = fixed(value, 6);
  s.erase(s.find_last_not_of('0') + 1);
  if (s.back() == '.') s.pop_back();
  return s;
}

}  // namespace

// ------------------------------------------------------------------ QuinticPath ----

double QuinticPath::duration() const {
  double total = 0.0;
  for (double T : durations) total += T;
  return total;
}

std::vector<double> QuinticPath::boundaries() const {
  std::vector<double> b{0.0};
  for (double T : durations) b.push_back(b.back() + T);
  return b;
}

void QuinticPath::evaluate(double t, Vector7d* q, Vector7d* qdot, Vector7d* qddot) const {
  std::size_t i = 0;
  double start = 0.0;
  while (i + 1 < durations.size() && t >= start + durations[i]) start += durations[i++];
  const double T = durations.empty() ? 1.0 : durations[i];
  const double s = std::clamp((t - start) / T, 0.0, 1.0);
  const Vector7d& a = keyframes[i];
  const Vector7d dq = durations.empty() ? Vector7d::Zero() : Vector7d(keyframes[i + 1] - a);
  // Outside the path it rests: velocity and acceleration are zero there.
  const bool moving = t > start && t < start + T;
  const double s2 = s * s, s3 = s2 * s;
  if (q) *q = a + dq * (s3 * (10.0 - 15.0 * s + 6.0 * s2));
  if (qdot) *qdot = moving ? Vector7d(dq * (30.0 * s2 * (1.0 - s) * (1.0 - s) / T)) : Vector7d::Zero();
  if (qddot) *qddot = moving ? Vector7d(dq * (s * (60.0 - 180.0 * s + 120.0 * s2) / (T * T))) : Vector7d::Zero();
}

// ------------------------------------------------------------------ generator ----

std::vector<std::string> synthetic_activities() {
  std::vector<std::string> names;
  for (const Activity& a : activities()) names.push_back(a.name);
  return names;
}

double subject_arm_scale(std::uint64_t seed, int index) {
  return stream(seed, index, -1, Stream::scale).uniform(0.90, 1.10);
}

HumanArmData scaled_arm(const HumanArmData& arm, double scale) {
  if (!(scale > 0)) fail("arm scale must be > 0");
  HumanArmData out = arm;
  for (DhRow& row : out.dh) row.d *= scale, row.a *= scale;
  for (auto& segment : out.segments) segment.second *= scale;
  char suffix[32];
  std::snprintf(suffix, sizeof suffix, " x%.6g", scale);
  out.name += suffix;
  return out;
}

std::vector<SyntheticTrajectory> make_synthetic_motion(const HumanArmData& arm, const SyntheticOptions& options) {
  check_options(options);
  std::vector<SyntheticTrajectory> out;
  for (int s = 0; s < options.subjects; ++s) {
    const double scale = subject_arm_scale(options.seed, s);
    const HumanArm subject_arm(scaled_arm(arm, scale));
    for (int a = 0; a < static_cast<int>(activities().size()); ++a) {
      SyntheticTrajectory t;
      t.subject = subject_name(s);
      t.activity = activities()[a].name;
      t.arm_scale = scale;
      t.jittered = s + 1 >= options.first_jittered_subject;
      t.rate_hz = options.rate_hz;
      Random keyframes = stream(options.seed, s, a, Stream::keyframes);
      Random timing = stream(options.seed, s, a, Stream::timing);
      Random jitter = stream(options.seed, s, a, Stream::jitter);
      Random noise = stream(options.seed, s, a, Stream::noise);
      t.path = make_path(activities()[a], subject_arm.data(), options, keyframes, timing);
      t.time = sample_times(t.path.duration(), options, t.jittered, jitter);
      fill_kinematics(t, subject_arm);
      add_noise(t, options, noise);
      out.push_back(std::move(t));
    }
  }
  return out;
}

SyntheticTrajectory speed_up(const SyntheticTrajectory& trajectory, double k) {
  if (!(k > 0) || !std::isfinite(k)) fail("speed_up: k must be a finite number > 0");
  SyntheticTrajectory t = trajectory;
  t.time /= k;
  t.qdot *= k;
  t.qddot *= k * k;
  t.twist *= k;
  t.twist_rate *= k * k;
  t.rate_hz *= k;
  for (double& T : t.path.durations) T /= k;
  return t;
}

// ------------------------------------------------------------------ CSV ----

std::string motion_csv(const SyntheticTrajectory& t) {
  std::string out = "# hapsyn-motion 1\n# subject: " + t.subject + "\n# activity: " + t.activity +
                    "\n# unit: m\n# time_unit: s\ntime,x,y,z,qw,qx,qy,qz\n";
  out.reserve(out.size() + static_cast<std::size_t>(t.time.size()) * 80);
  for (Eigen::Index k = 0; k < t.time.size(); ++k) {
    out += fixed(t.time(k), 6);
    for (int i = 0; i < 3; ++i) out += ',' + fixed(t.noisy_position(k, i), 6);
    for (int i = 0; i < 4; ++i) out += ',' + fixed(t.noisy_quaternion(k, i), 7);
    out += '\n';
  }
  return out;
}

// ------------------------------------------------------------------ BVH ----

Eigen::Matrix3d bvh_recording_rotation() { return Eigen::Vector3d(-1.0, 1.0, -1.0).asDiagonal(); }

Eigen::Vector3d euler_zxy(const Eigen::Matrix3d& R) {
  // R = Rz(a) Rx(b) Ry(c) has R(0,1) = -sin a cos b, R(1,1) = cos a cos b. Near gimbal lock these
  // are tiny and a is ill-conditioned, but any a will do: b and c are then read from
  // Rz(a)^T R = Rx(b) Ry(c) = [[cc, 0, sc], [sb sc, cb, -sb cc], [-cb sc, sb, cb cc]], whose first
  // row and middle column are well-conditioned, so the decomposition is exact for every a.
  const double a = std::atan2(-R(0, 1), R(1, 1));
  const Eigen::Matrix3d M = Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R;
  return {a, std::atan2(M(2, 1), M(1, 1)), std::atan2(M(0, 2), M(0, 0))};
}

namespace {

// Euler angles of R closest to `previous` (the other ZXY solution (a + pi, pi - b, c + pi) and
// 2 pi shifts), so the channel curves do not jump where the principal branch would.
Eigen::Vector3d continuous_euler(const Eigen::Matrix3d& R, const Eigen::Vector3d* previous) {
  const Eigen::Vector3d e = euler_zxy(R);
  if (!previous) return e;
  const Eigen::Vector3d candidates[2] = {e, Eigen::Vector3d(e(0) + kPi, kPi - e(1), e(2) + kPi)};
  Eigen::Vector3d best = e;
  double best_distance = INFINITY;
  for (Eigen::Vector3d c : candidates) {
    for (int i = 0; i < 3; ++i) c(i) += 2.0 * kPi * std::round(((*previous)(i) - c(i)) / (2.0 * kPi));
    const double distance = (c - *previous).cwiseAbs().sum();
    if (distance < best_distance) best = c, best_distance = distance;
  }
  return best;
}

// DH frames 0..7 of the arm at q: T_i = Rz(q_i + theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i), as in
// HumanArm::forward (which only returns frame 7).
std::array<Eigen::Isometry3d, 8> dh_frames(const HumanArmData& arm, const Vector7d& q) {
  std::array<Eigen::Isometry3d, 8> T;
  T[0] = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 7; ++i) {
    const DhRow& r = arm.dh[i];
    const double theta = q(i) + r.theta_offset;
    Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
    step.linear() = (Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()) *
                     Eigen::AngleAxisd(r.alpha, Eigen::Vector3d::UnitX())).toRotationMatrix();
    step.translation() = Eigen::Vector3d(r.a * std::cos(theta), r.a * std::sin(theta), r.d);
    T[i + 1] = T[i] * step;
  }
  return T;
}

// The skeleton's fixed parts [BVH units]: torso proportions scaled with the arm, the arm segments
// as the rest pose q = 0 (hanging down) puts them.
struct BvhSkeleton {
  double scale;
  Eigen::Vector3d upper_arm, hand;  // RightForeArm and RightHand OFFSETs
  Eigen::Matrix3d R3_rest, R4_rest;  // DH frames 3 (after the shoulder) and 4 (after the elbow) at q = 0
};

BvhSkeleton bvh_skeleton(const HumanArmData& arm, double scale) {
  const Eigen::Matrix3d C = bvh_recording_rotation();
  const auto rest = dh_frames(arm, Vector7d::Zero());
  BvhSkeleton s;
  s.scale = scale;
  s.upper_arm = C.transpose() * rest[3].translation() / kBvhUnit;
  s.hand = C.transpose() * (rest[7].translation() - rest[3].translation()) / kBvhUnit;
  s.R3_rest = rest[3].linear();
  s.R4_rest = rest[4].linear();
  return s;
}

std::string vector_text(const Eigen::Vector3d& v) { return compact(v(0)) + " " + compact(v(1)) + " " + compact(v(2)); }

constexpr double kHipsHeight = 98, kSpineLength = 10, kShoulderRise = 35, kShoulderSide = 3, kClavicle = 15,
                 kFingers = 8, kHipsYawDeg = 10;

std::string bvh_hierarchy(const BvhSkeleton& s) {
  const double k = s.scale;
  std::ostringstream h;
  const char* rot = "CHANNELS 3 Zrotation Xrotation Yrotation\n";
  h << "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n"
    << "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    << "  JOINT Spine\n  {\n    OFFSET 0 " << compact(kSpineLength * k) << " 0\n    " << rot
    << "    JOINT RightShoulder\n    {\n      OFFSET " << compact(-kShoulderSide * k) << " "
    << compact(kShoulderRise * k) << " 0\n      " << rot
    << "      JOINT RightArm\n      {\n        OFFSET " << compact(-kClavicle * k) << " 0 0\n        " << rot
    << "        JOINT RightForeArm\n        {\n          OFFSET " << vector_text(s.upper_arm) << "\n          " << rot
    << "          JOINT RightHand\n          {\n            OFFSET " << vector_text(s.hand) << "\n"
    << "            CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    << "            End Site\n            {\n              OFFSET " << compact(-kFingers * k) << " 0 0\n"
    << "            }\n          }\n        }\n      }\n    }\n  }\n}\n";
  return h.str();
}

// The channel values of one frame: shoulder and elbow rotations from the DH frames (joints 1-3,
// joint 4), the hand placed exactly on the noisy palm pose.
struct BvhFrame {
  Eigen::Vector3d arm, forearm, hand_position, hand;  // Euler angles [rad] and position channels [units]
};

BvhFrame bvh_frame(const BvhSkeleton& s, const HumanArmData& arm, const Vector7d& q, const Eigen::Vector3d& p,
                   const Eigen::Matrix3d& R, const BvhFrame* previous) {
  const Eigen::Matrix3d C = bvh_recording_rotation();
  const auto frames = dh_frames(arm, q);
  // Global rotations in the shoulder frame F (= RightShoulder's axes): identity at rest.
  const Eigen::Matrix3d G_arm = C.transpose() * frames[3].linear() * s.R3_rest.transpose() * C;
  const Eigen::Matrix3d G_forearm = C.transpose() * frames[4].linear() * s.R4_rest.transpose() * C;
  const Eigen::Vector3d elbow = G_arm * s.upper_arm;  // where the BVH chain itself puts the elbow
  const Eigen::Vector3d palm = C.transpose() * p / kBvhUnit;
  BvhFrame f;
  f.arm = continuous_euler(G_arm, previous ? &previous->arm : nullptr);
  f.forearm = continuous_euler(G_arm.transpose() * G_forearm, previous ? &previous->forearm : nullptr);
  f.hand_position = G_forearm.transpose() * (palm - elbow) - s.hand;
  f.hand = continuous_euler(G_forearm.transpose() * C.transpose() * R, previous ? &previous->hand : nullptr);
  return f;
}

std::string degrees_text(const Eigen::Vector3d& e) { return vector_text(e / kDeg); }

}  // namespace

std::string motion_bvh(const SyntheticTrajectory& t, const HumanArmData& arm_of_subject) {
  const BvhSkeleton s = bvh_skeleton(arm_of_subject, t.arm_scale);
  const Eigen::Index n = t.time.size();
  // The nominal frame time: BVH has no per-frame stamps (a jittered subject's frames carry the
  // poses at its jittered times, as a recorder with a wandering clock would).
  char header[96];
  std::snprintf(header, sizeof header, "MOTION\nFrames: %ld\nFrame Time: %.9g\n", static_cast<long>(n), 1.0 / t.rate_hz);
  std::string out = bvh_hierarchy(s) + header;
  const std::string torso = compact(0.0) + " " + compact(kHipsHeight * s.scale) + " 0 0 0 " +
                            compact(kHipsYawDeg) + " 0 0 0 0 0 0 ";
  BvhFrame previous;
  for (Eigen::Index k = 0; k < n; ++k) {
    const Vector7d q = t.q.row(k).transpose();
    const BvhFrame f = bvh_frame(s, arm_of_subject, q, t.noisy_position.row(k).transpose(),
                                 rotation_of(t.noisy_quaternion.row(k).transpose()), k > 0 ? &previous : nullptr);
    out += torso + degrees_text(f.arm) + " " + degrees_text(f.forearm) + " " + vector_text(f.hand_position) + " " +
           degrees_text(f.hand) + "\n";
    previous = f;
  }
  return out;
}

}  // namespace hapsyn::plugins::motion
