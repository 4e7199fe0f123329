#pragma once
/// \file
/// Signal processing of recorded hand trajectories for the motion scene: a Butterworth low-pass
/// filter applied forward and backward (zero phase), finite-difference derivatives, resampling of
/// irregular time stamps onto a uniform grid, and the documented pipeline (differentiate) that
/// turns positions and orientations into velocities and accelerations.
///
/// Signals are Eigen::MatrixXd with one row per time sample and one column per channel; every
/// column is processed independently. Quaternion rows are (w, x, y, z). Everything is
/// deterministic double precision. Bad input throws hapsyn::Error with component "motion"; the
/// messages are self-contained so that a caller can prefix a file name.
#include <Eigen/Core>

#include <vector>

namespace hapsyn::plugins::motion {

/// One second-order section of a digital filter (a0 = 1):
/// H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2). A first-order section has b2 = a2 = 0.
struct SecondOrderSection {
  double b0, b1, b2, a1, a2;
};

/// Largest filter order butterworth_lowpass accepts.
constexpr int kMaxButterworthOrder = 10;

/// Digital Butterworth low-pass of order `order`, designed like
/// scipy.signal.butter(order, cutoff_hz, fs=rate_hz, output='sos'): the analog prototype poles
/// -exp(i pi m / (2 order)), m = -order+1, -order+3, ..., order-1, scaled to the pre-warped cut-off
/// 2 rate tan(pi cutoff / rate), mapped by the bilinear transform; all zeros at z = -1.
/// Sections: for odd orders first the first-order section (real pole), then the conjugate pole
/// pairs, farthest from the unit circle first (scipy's order). Every section has unit DC gain
/// (scipy puts the whole gain in the first section: the product, hence the filter, is the same).
/// Magnitude response: |H(e^{i 2 pi f / rate})| = 1 / sqrt(1 + (tan(pi f / rate) / tan(pi cutoff / rate))^(2 order)).
/// \param order 1..kMaxButterworthOrder
/// \param cutoff_hz -3 dB frequency [Hz], in (0, rate_hz / 2)
/// \param rate_hz sampling rate [Hz], finite and > 0
/// \return (order + 1) / 2 sections
/// \throws hapsyn::Error naming the offending value and the rule
std::vector<SecondOrderSection> butterworth_lowpass(int order, double cutoff_hz, double rate_hz);

/// Number of samples filtfilt needs: padlen + 1, where padlen = 3 (2 sections + 1 - min(number of
/// sections with b2 == 0, number with a2 == 0)) is scipy's sosfiltfilt default (15 for order 4).
/// 0 for an empty `sos` (no filtering, no requirement).
int filtfilt_min_samples(const std::vector<SecondOrderSection>& sos);

/// Zero-phase filtering of each column of `x`, as scipy.signal.sosfiltfilt(sos, x, axis=0) with
/// its defaults: odd extension by padlen samples at each end (2 x[0] - x[padlen..1] before,
/// 2 x[n-1] - x[n-2..n-1-padlen] after), section states started at the steady state of a constant
/// equal to the first extended sample (scipy's sosfilt_zi), forward pass, then the same on the
/// reversed result, reversed back, padding dropped. The response is |H|^2 with no phase shift; a
/// constant passes exactly. A ramp does not quite (the starting states are those of a constant):
/// like scipy, 4th order at 5 Hz / 120 Hz leaves an error of about slope x 5 ms at the ends that
/// decays as exp(-t / tau), tau = 1 / (2 pi cutoff sin(pi / (2 order))) (83 ms here);
/// far from the ends polynomials up to degree 2 order - 1 pass exactly. An empty `sos` returns
/// `x` unchanged.
/// \param sos sections, e.g. from butterworth_lowpass
/// \param x n x channels, n >= filtfilt_min_samples(sos)
/// \return n x channels
/// \throws hapsyn::Error "the signal has N samples; the filter needs at least M (...)" when n is too small
Eigen::MatrixXd filtfilt(const std::vector<SecondOrderSection>& sos, const Eigen::MatrixXd& x);

/// d/dt of each column for samples spaced uniformly by `dt`, as numpy.gradient(x, dt, axis=0,
/// edge_order=2): central differences (x[i+1] - x[i-1]) / (2 dt) inside, the second-order
/// one-sided differences (-3 x[0] + 4 x[1] - x[2]) / (2 dt) and (3 x[n-1] - 4 x[n-2] + x[n-3]) / (2 dt)
/// at the ends. Exact for quadratics; inside, the error is dt^2 / 6 x''' + O(dt^4).
/// \param x n x channels, n >= 3 [unit]
/// \param dt sample spacing [s], finite and > 0
/// \return n x channels [unit / s]
/// \throws hapsyn::Error when n < 3 or dt is not finite and > 0
Eigen::MatrixXd derivative(const Eigen::MatrixXd& x, double dt);

/// Samples on a uniform time grid (the result of resample).
struct Uniform {
  Eigen::VectorXd time;         ///< m times [s], t0 + k / rate
  Eigen::MatrixXd positions;    ///< m x 3 [m]
  Eigen::MatrixXd quaternions;  ///< m x 4 unit (w, x, y, z), or 0 x 4 when none were given
};

/// True when every time stamp lies within relative_tolerance * dt of the uniform grid from the
/// first to the last stamp (dt = mean_step(time)); always true for fewer than 3 samples. The
/// default 1e-3 accepts stamps rounded when printed (6 decimals at 120 Hz: 6e-5 dt) and treats
/// real clock jitter (a 1 ms jitter at 120 Hz is 0.12 dt) as non-uniform. Treating such stamps
/// as the grid moves a sample by at most 1e-3 dt: 8 um at 1 m/s and 120 Hz.
bool is_uniform(const Eigen::VectorXd& time, double relative_tolerance = 1e-3);

/// The mean sampling interval (t_last - t_first) / (n - 1) [s] (n >= 2): the step of the grid
/// a uniform recording is taken to lie on.
double mean_step(const Eigen::VectorXd& time);

/// 1 / (median of the differences time[i+1] - time[i]) [Hz] (the mean of the two middle ones for
/// an even count).
/// \throws hapsyn::Error for fewer than 2 samples or a median that is not > 0
double median_rate(const Eigen::VectorXd& time);

/// Resamples a recording onto the grid t0, t0 + 1 / rate, ..., up to time[n-1] (which is included
/// when it lies on the grid within 1e-9 relative to the span). Positions are interpolated
/// linearly between the neighbouring samples, orientations by slerp
/// (Eigen::Quaterniond::slerp: the shorter arc; rows are normalized first).
/// \param time n times [s], finite, strictly increasing, n >= 2
/// \param positions n x 3 [m]
/// \param quaternions n x 4 (w, x, y, z), non-zero rows; or 0 rows (positions only)
/// \param rate_hz rate of the grid [Hz], finite and > 0
/// \throws hapsyn::Error for a decreasing or repeated time, naming the first offending index
///   ("time[12] = 0.1 after time[11] = 0.1: times must increase strictly"), for wrong sizes, a
///   non-finite time or a zero quaternion row
Uniform resample(const Eigen::VectorXd& time, const Eigen::MatrixXd& positions, const Eigen::MatrixXd& quaternions,
                 double rate_hz);

/// Makes the sign of the quaternion rows (n x 4) continuous: row i is negated whenever its dot
/// product with the (already corrected) row i-1 is negative. q and -q are the same rotation;
/// continuous components can be filtered and differentiated.
void make_continuous(Eigen::MatrixXd& quaternions);

/// Divides every row by its Euclidean norm (rows must be non-zero).
void normalize_rows(Eigen::MatrixXd& quaternions);

/// Angular velocity in the FIXED frame (the reference / world frame of the recording).
/// Convention: q rotates body coordinates into the reference frame, v_ref = q v_body q*, and
/// R = q.toRotationMatrix() then satisfies dR/dt = [omega]x R; equivalently qdot = 1/2 omega ⊗ q.
/// Computed as omega = 2 vec(qdot ⊗ q*) / |q|^2 (the division makes it exact for the direction of
/// a non-unit q as well; for unit q it is 1).
/// \param quaternions n x 4 rows (w, x, y, z), non-zero
/// \param quaternion_rates n x 4 their time derivatives [1/s]
/// \return n x 3 [rad/s]
Eigen::MatrixXd angular_velocity(const Eigen::MatrixXd& quaternions, const Eigen::MatrixXd& quaternion_rates);

/// Filtered pose, velocity and acceleration of a uniformly sampled trajectory; all in the
/// reference frame, SI units, one row per sample.
struct MotionDerivatives {
  Eigen::MatrixXd position;              ///< n x 3 [m], filtered
  Eigen::MatrixXd velocity;              ///< n x 3 [m/s]
  Eigen::MatrixXd acceleration;          ///< n x 3 [m/s^2]
  Eigen::MatrixXd quaternion;            ///< n x 4 unit (w, x, y, z), filtered; 0 x 4 without orientations
  Eigen::MatrixXd angular_velocity;      ///< n x 3 [rad/s], fixed frame; 0 x 3 without orientations
  Eigen::MatrixXd angular_acceleration;  ///< n x 3 [rad/s^2], fixed frame; 0 x 3 without orientations
};

/// The documented method of the motion scene. With F = filtfilt(sos, .) (identity for an empty
/// `sos`) and D = derivative(., 1 / rate_hz):
///  - position: p = F(positions), v = F(D(p)), a = F(D(v));
///  - orientation: make_continuous, q = F(4 components), normalize_rows(q), qdot = D(q),
///    omega = F(angular_velocity(q, qdot)), alpha = F(D(omega)).
/// Re-filtering each derivative removes the noise the differences amplify; with a zero-phase
/// filter it adds no delay. Inside, the error is that of the central differences, dt^2 / 6 times
/// the third derivative, per derivative, and the filter's attenuation |H|^2 per pass.
/// Ends: the odd extension keeps the ends free of a step, but the first and last ~1 / cutoff
/// seconds carry edge error (the filter's transient, the curvature the odd extension reverses,
/// the one-sided differences), decaying as exp(-t / tau), tau = 1 / (2 pi cutoff sin(pi / (2 order)));
/// the second derivatives suffer most. Measured at 120 Hz, 4th order at 5 Hz, on a 0.5 Hz
/// sinusoid: acceleration error 0.9 % of its amplitude 0.5 s from the ends, 2.4e-4 at 1 s (the
/// velocity: 5e-4, 1.1e-4). Callers that need accuracy there should trim about 5 / cutoff seconds.
/// \param positions n x 3 [m], uniformly sampled at rate_hz
/// \param quaternions n x 4 (w, x, y, z), non-zero rows; or 0 rows (positions only)
/// \param rate_hz sampling rate [Hz], finite and > 0
/// \param sos the low-pass filter (e.g. butterworth_lowpass(4, 6, rate_hz)); empty: no filtering
/// \throws hapsyn::Error for wrong sizes, or fewer than max(3, filtfilt_min_samples(sos)) samples
MotionDerivatives differentiate(const Eigen::MatrixXd& positions, const Eigen::MatrixXd& quaternions, double rate_hz,
                                const std::vector<SecondOrderSection>& sos);

}  // namespace hapsyn::plugins::motion
