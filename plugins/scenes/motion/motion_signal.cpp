#include "motion_signal.hpp"

#include <hapsyn/error.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cassert>
#include <array>
#include <charconv>
#include <cmath>
#include <complex>
#include <string>

namespace hapsyn::plugins::motion {
namespace {

constexpr const char* kComponent = "motion";
constexpr double kPi = 3.14159265358979323846;
// A grid finer than this is a mistake (a rate in Hz given as a period, say), not a request.
constexpr double kMaxResampled = 1e8;

// The shortest decimal that reads back as `v`: messages show 70 and 0.1, not 7e+01 or
// 0.10000000000000001.
std::string show(double v) {
  std::array<char, 32> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), v);
  return std::string(buffer.data(), result.ptr);
}

bool finite_positive(double v) { return std::isfinite(v) && v > 0.0; }

std::string samples(Eigen::Index n) { return std::to_string(n) + (n == 1 ? " sample" : " samples"); }

void check_rate(double rate_hz, const std::string& what) {
  if (!finite_positive(rate_hz)) throw Error(kComponent, what + " = " + show(rate_hz) + " Hz: must be finite and > 0");
}

// Steady-state response of a section to a constant input: H(1).
double dc_gain(const SecondOrderSection& s) { return (s.b0 + s.b1 + s.b2) / (1.0 + s.a1 + s.a2); }

// Unit-DC-gain section with both zeros at z = -1 and the poles z, conj(z).
SecondOrderSection pole_pair_section(std::complex<double> z) {
  const double a1 = -2.0 * z.real();
  const double a2 = std::norm(z);
  const double g = (1.0 + a1 + a2) / 4.0;
  return {g, 2.0 * g, g, a1, a2};
}

// Unit-DC-gain first-order section with its zero at z = -1 and the real pole p.
SecondOrderSection real_pole_section(double p) {
  const double a1 = -p;
  const double g = (1.0 + a1) / 2.0;
  return {g, g, 0.0, a1, 0.0};
}

// In-place filtering of `y` by the cascade (transposed direct form II, as scipy's sosfilt),
// every section started at the steady state of the constant input `level`.
void sosfilt_from_steady_state(const std::vector<SecondOrderSection>& sos, double level, std::vector<double>& y) {
  for (const SecondOrderSection& s : sos) {
    const double g = dc_gain(s);
    // The states a constant input `level` leaves behind (scipy's sosfilt_zi, in closed form).
    double z1 = (g - s.b0) * level;
    double z2 = (s.b2 - s.a2 * g) * level;
    for (double& v : y) {
      const double in = v;
      const double out = s.b0 * in + z1;
      z1 = s.b1 * in - s.a1 * out + z2;
      z2 = s.b2 * in - s.a2 * out;
      v = out;
    }
    level *= g;
  }
}

int padlen(const std::vector<SecondOrderSection>& sos) {
  const auto sections = static_cast<int>(sos.size());
  const auto no_b2 = static_cast<int>(std::count_if(sos.begin(), sos.end(), [](const auto& s) { return s.b2 == 0.0; }));
  const auto no_a2 = static_cast<int>(std::count_if(sos.begin(), sos.end(), [](const auto& s) { return s.a2 == 0.0; }));
  return 3 * (2 * sections + 1 - std::min(no_b2, no_a2));
}

// One column of filtfilt: odd extension, forward, backward, unpadded.
void filtfilt_column(const std::vector<SecondOrderSection>& sos, int pad, const double* x, Eigen::Index n,
                     double* out) {
  const auto p = static_cast<Eigen::Index>(pad);
  std::vector<double> ext(static_cast<std::size_t>(n + 2 * p));
  for (Eigen::Index i = 0; i < p; ++i) {
    ext[static_cast<std::size_t>(i)] = 2.0 * x[0] - x[p - i];
    ext[static_cast<std::size_t>(n + p + i)] = 2.0 * x[n - 1] - x[n - 2 - i];
  }
  std::copy(x, x + n, ext.begin() + p);
  sosfilt_from_steady_state(sos, ext.front(), ext);
  std::reverse(ext.begin(), ext.end());
  sosfilt_from_steady_state(sos, ext.front(), ext);
  std::reverse(ext.begin(), ext.end());
  std::copy(ext.begin() + p, ext.begin() + p + n, out);
}

void check_quaternion_columns(const Eigen::MatrixXd& q, const std::string& what) {
  if (q.cols() != 4) {
    throw Error(kComponent, what + " has " + std::to_string(q.cols()) + " columns: must have 4 (w, x, y, z)");
  }
}

Eigen::Vector4d normalized_row(const Eigen::MatrixXd& q, Eigen::Index i) {
  const Eigen::Vector4d row = q.row(i).transpose();
  const double norm = row.norm();
  if (!finite_positive(norm)) {
    throw Error(kComponent, "quaternion row " + std::to_string(i) + " has norm " + show(norm) +
                                ": must be finite and > 0");
  }
  return row / norm;
}

Eigen::Quaterniond quaternion_of(const Eigen::Vector4d& wxyz) {
  return Eigen::Quaterniond(wxyz(0), wxyz(1), wxyz(2), wxyz(3));
}

void check_time(const Eigen::VectorXd& time) {
  if (time.size() < 2) {
    throw Error(kComponent, "the recording has " + samples(time.size()) + ": resampling needs at least 2");
  }
  for (Eigen::Index i = 0; i < time.size(); ++i) {
    if (!std::isfinite(time(i))) {
      throw Error(kComponent, "time[" + std::to_string(i) + "] = " + show(time(i)) + ": must be finite");
    }
    if (i > 0 && !(time(i) > time(i - 1))) {
      throw Error(kComponent, "time[" + std::to_string(i) + "] = " + show(time(i)) + " after time[" +
                                  std::to_string(i - 1) + "] = " + show(time(i - 1)) +
                                  ": times must increase strictly");
    }
  }
}

}  // namespace

std::vector<SecondOrderSection> butterworth_lowpass(int order, double cutoff_hz, double rate_hz) {
  check_rate(rate_hz, "sampling rate");
  if (order < 1 || order > kMaxButterworthOrder) {
    throw Error(kComponent, "filter order = " + std::to_string(order) + ": must be in 1.." +
                                std::to_string(kMaxButterworthOrder));
  }
  const double nyquist = rate_hz / 2.0;
  if (!(cutoff_hz > 0.0 && cutoff_hz < nyquist)) {
    throw Error(kComponent, "cutoff = " + show(cutoff_hz) + " Hz: must be in (0, " + show(nyquist) +
                                ") Hz (below half the sampling rate " + show(rate_hz) + " Hz)");
  }
  // Analog pole s = wc p with the pre-warped wc = 2 rate tan(pi cutoff / rate); the bilinear map
  // z = (2 rate + s) / (2 rate - s) then only needs s / (2 rate) = tan(pi cutoff / rate) p.
  const double warped = std::tan(kPi * cutoff_hz / rate_hz);
  const auto digital = [warped](std::complex<double> p) { return (1.0 + warped * p) / (1.0 - warped * p); };
  std::vector<std::complex<double>> upper;  // one pole of each conjugate pair
  for (int m = -order + 1; m < 0; m += 2) {
    upper.push_back(digital(-std::exp(std::complex<double>(0.0, kPi * m / (2.0 * order)))));
  }
  // scipy's order: poles closest to the unit circle last (the real pole is farthest).
  std::sort(upper.begin(), upper.end(), [](auto a, auto b) { return std::abs(a) < std::abs(b); });
  std::vector<SecondOrderSection> sos;
  if (order % 2 == 1) sos.push_back(real_pole_section(digital(-1.0).real()));
  for (const auto& z : upper) sos.push_back(pole_pair_section(z));
  return sos;
}

int filtfilt_min_samples(const std::vector<SecondOrderSection>& sos) { return sos.empty() ? 0 : padlen(sos) + 1; }

Eigen::MatrixXd filtfilt(const std::vector<SecondOrderSection>& sos, const Eigen::MatrixXd& x) {
  if (sos.empty()) return x;
  const int pad = padlen(sos);
  const Eigen::Index n = x.rows();
  if (n < pad + 1) {
    throw Error(kComponent, "the signal has " + samples(n) + "; the filter needs at least " + std::to_string(pad + 1) +
                                " (an odd extension of " + std::to_string(pad) + " samples at each end, " +
                                "scipy's sosfiltfilt rule, plus one)");
  }
  Eigen::MatrixXd y(n, x.cols());
  // MatrixXd is column-major: each column is contiguous.
  for (Eigen::Index c = 0; c < x.cols(); ++c) filtfilt_column(sos, pad, x.col(c).data(), n, y.col(c).data());
  return y;
}

Eigen::MatrixXd derivative(const Eigen::MatrixXd& x, double dt) {
  if (!finite_positive(dt)) throw Error(kComponent, "time step = " + show(dt) + " s: must be finite and > 0");
  const Eigen::Index n = x.rows();
  if (n < 3) {
    throw Error(kComponent, "the signal has " + samples(n) +
                                "; the derivative needs at least 3 (second-order differences)");
  }
  Eigen::MatrixXd d(n, x.cols());
  const double h2 = 2.0 * dt;
  d.middleRows(1, n - 2) = (x.bottomRows(n - 2) - x.topRows(n - 2)) / h2;
  d.row(0) = (-3.0 * x.row(0) + 4.0 * x.row(1) - x.row(2)) / h2;
  d.row(n - 1) = (3.0 * x.row(n - 1) - 4.0 * x.row(n - 2) + x.row(n - 3)) / h2;
  return d;
}

bool is_uniform(const Eigen::VectorXd& time, double relative_tolerance) {
  if (time.size() < 3) return true;
  // Deviation of each stamp from the grid, not of each step: time stamps printed with a few
  // decimals (0.008333, 0.016667, ...) round every stamp by up to half a unit, which a step
  // criterion would double and mistake for jitter.
  const double dt = mean_step(time);
  const Eigen::VectorXd grid = Eigen::VectorXd::LinSpaced(time.size(), time(0), time(time.size() - 1));
  return (time - grid).cwiseAbs().maxCoeff() <= relative_tolerance * std::abs(dt);
}

double mean_step(const Eigen::VectorXd& time) {
  assert(time.size() >= 2);
  return (time(time.size() - 1) - time(0)) / static_cast<double>(time.size() - 1);
}

double median_rate(const Eigen::VectorXd& time) {
  if (time.size() < 2) throw Error(kComponent, "the recording has " + samples(time.size()) + ": a rate needs 2");
  std::vector<double> dt(static_cast<std::size_t>(time.size() - 1));
  for (std::size_t i = 0; i < dt.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    dt[i] = time(k + 1) - time(k);
  }
  std::sort(dt.begin(), dt.end());
  const std::size_t m = dt.size() / 2;
  const double median = dt.size() % 2 == 1 ? dt[m] : 0.5 * (dt[m - 1] + dt[m]);
  if (!finite_positive(median)) {
    throw Error(kComponent, "the median time step is " + show(median) + " s: must be finite and > 0");
  }
  return 1.0 / median;
}

Uniform resample(const Eigen::VectorXd& time, const Eigen::MatrixXd& positions, const Eigen::MatrixXd& quaternions,
                 double rate_hz) {
  check_time(time);
  check_rate(rate_hz, "resampling rate");
  const Eigen::Index n = time.size();
  if (positions.rows() != n || positions.cols() != 3) {
    throw Error(kComponent, "positions are " + std::to_string(positions.rows()) + " x " +
                                std::to_string(positions.cols()) + ": must be " + std::to_string(n) + " x 3");
  }
  const bool oriented = quaternions.rows() > 0;
  if (oriented && (quaternions.rows() != n || quaternions.cols() != 4)) {
    throw Error(kComponent, "quaternions are " + std::to_string(quaternions.rows()) + " x " +
                                std::to_string(quaternions.cols()) + ": must be " + std::to_string(n) +
                                " x 4 (w, x, y, z) or empty");
  }
  const double t0 = time(0);
  const double t_last = time(n - 1);
  const double steps = (t_last - t0) * rate_hz;
  if (!(steps < kMaxResampled)) {
    throw Error(kComponent, "resampling " + show(t_last - t0) + " s at " + show(rate_hz) + " Hz gives more than " +
                                show(kMaxResampled) + " samples");
  }
  // The last time counts as a grid point when it is one up to rounding.
  const auto m = static_cast<Eigen::Index>(std::floor(steps * (1.0 + 1e-9))) + 1;
  Uniform u;
  u.time.resize(m);
  u.positions.resize(m, 3);
  u.quaternions.resize(oriented ? m : 0, 4);
  Eigen::Index j = 0;  // time(j) <= t <= time(j + 1)
  for (Eigen::Index k = 0; k < m; ++k) {
    u.time(k) = t0 + static_cast<double>(k) / rate_hz;
    const double t = std::min(u.time(k), t_last);
    while (j + 2 < n && time(j + 1) <= t) ++j;
    const double s = std::clamp((t - time(j)) / (time(j + 1) - time(j)), 0.0, 1.0);
    u.positions.row(k) = (1.0 - s) * positions.row(j) + s * positions.row(j + 1);
    if (oriented) {
      const Eigen::Quaterniond q =
          quaternion_of(normalized_row(quaternions, j)).slerp(s, quaternion_of(normalized_row(quaternions, j + 1)));
      u.quaternions.row(k) << q.w(), q.x(), q.y(), q.z();
    }
  }
  return u;
}

void make_continuous(Eigen::MatrixXd& quaternions) {
  for (Eigen::Index i = 1; i < quaternions.rows(); ++i) {
    if (quaternions.row(i).dot(quaternions.row(i - 1)) < 0.0) quaternions.row(i) *= -1.0;
  }
}

void normalize_rows(Eigen::MatrixXd& quaternions) {
  for (Eigen::Index i = 0; i < quaternions.rows(); ++i) {
    const double norm = quaternions.row(i).norm();
    if (!finite_positive(norm)) {
      throw Error(kComponent, "quaternion row " + std::to_string(i) + " has norm " + show(norm) +
                                  ": must be finite and > 0");
    }
    quaternions.row(i) /= norm;
  }
}

Eigen::MatrixXd angular_velocity(const Eigen::MatrixXd& quaternions, const Eigen::MatrixXd& quaternion_rates) {
  check_quaternion_columns(quaternions, "the quaternion matrix");
  check_quaternion_columns(quaternion_rates, "the quaternion rate matrix");
  if (quaternion_rates.rows() != quaternions.rows()) {
    throw Error(kComponent, "the quaternion rates have " + std::to_string(quaternion_rates.rows()) +
                                " rows: must have as many as the quaternions (" +
                                std::to_string(quaternions.rows()) + ")");
  }
  Eigen::MatrixXd omega(quaternions.rows(), 3);
  for (Eigen::Index i = 0; i < quaternions.rows(); ++i) {
    const double w = quaternions(i, 0);
    const Eigen::Vector3d v = quaternions.row(i).tail<3>().transpose();
    const double wd = quaternion_rates(i, 0);
    const Eigen::Vector3d vd = quaternion_rates.row(i).tail<3>().transpose();
    // vec(qdot ⊗ q*) with q* = (w, -v): w vd - wd v - vd x v.
    const Eigen::Vector3d product = w * vd - wd * v - vd.cross(v);
    omega.row(i) = (2.0 / (w * w + v.squaredNorm()) * product).transpose();
  }
  return omega;
}

MotionDerivatives differentiate(const Eigen::MatrixXd& positions, const Eigen::MatrixXd& quaternions, double rate_hz,
                                const std::vector<SecondOrderSection>& sos) {
  check_rate(rate_hz, "sampling rate");
  if (positions.cols() != 3) {
    throw Error(kComponent, "positions have " + std::to_string(positions.cols()) + " columns: must have 3");
  }
  const bool oriented = quaternions.rows() > 0;
  if (oriented) {
    check_quaternion_columns(quaternions, "the quaternion matrix");
    if (quaternions.rows() != positions.rows()) {
      throw Error(kComponent, "there are " + std::to_string(quaternions.rows()) + " quaternions for " +
                                  std::to_string(positions.rows()) + " positions: must be as many (or none)");
    }
  }
  const double dt = 1.0 / rate_hz;
  MotionDerivatives d;
  d.position = filtfilt(sos, positions);
  d.velocity = filtfilt(sos, derivative(d.position, dt));
  d.acceleration = filtfilt(sos, derivative(d.velocity, dt));
  if (!oriented) {
    d.quaternion.resize(0, 4);
    d.angular_velocity.resize(0, 3);
    d.angular_acceleration.resize(0, 3);
    return d;
  }
  Eigen::MatrixXd q = quaternions;
  make_continuous(q);
  d.quaternion = filtfilt(sos, q);
  normalize_rows(d.quaternion);
  d.angular_velocity = filtfilt(sos, angular_velocity(d.quaternion, derivative(d.quaternion, dt)));
  d.angular_acceleration = filtfilt(sos, derivative(d.angular_velocity, dt));
  return d;
}

}  // namespace hapsyn::plugins::motion
