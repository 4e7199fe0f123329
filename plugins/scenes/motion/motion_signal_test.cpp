// Tests of the motion scene's signal processing against independent analytic results: the
// bilinear Butterworth magnitude, |H|^2 with zero phase for filtfilt, Taylor error terms of the
// differences, closed-form derivatives of polynomial, sinusoidal and rotational motion, exact
// interpolation of linear motion; and the refused inputs with their messages.
#include "motion_signal.hpp"

#include <hapsyn/error.hpp>

#include <Eigen/Geometry>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <functional>
#include <string>
#include <vector>

namespace {

namespace motion = hapsyn::plugins::motion;
using motion::SecondOrderSection;
using testing::HasSubstr;

constexpr double kPi = 3.14159265358979323846;

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const hapsyn::Error& e) {
    return e.what();
  }
  return "(no error)";
}

// Frequency response of the cascade at f [Hz]: the product of the sections at z = e^{i w}.
std::complex<double> response(const std::vector<SecondOrderSection>& sos, double f, double rate) {
  const std::complex<double> z1 = std::polar(1.0, -2.0 * kPi * f / rate);  // z^-1
  std::complex<double> h = 1.0;
  for (const SecondOrderSection& s : sos) h *= (s.b0 + s.b1 * z1 + s.b2 * z1 * z1) / (1.0 + s.a1 * z1 + s.a2 * z1 * z1);
  return h;
}

// |H| of the bilinear-transformed Butterworth low-pass (the pre-warped analog magnitude).
double butterworth_magnitude(int order, double f, double cutoff, double rate) {
  return 1.0 / std::sqrt(1.0 + std::pow(std::tan(kPi * f / rate) / std::tan(kPi * cutoff / rate), 2.0 * order));
}

Eigen::VectorXd times(Eigen::Index n, double rate) {
  return Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1) / rate);
}

// Least-squares fit x(t) ~ a sin(2 pi f t) + b cos(2 pi f t) over rows [first, last): amplitude
// sqrt(a^2 + b^2) and phase atan2(b, a) relative to sin(2 pi f t).
struct Fit {
  double amplitude, phase;
};
Fit fit_sinusoid(const Eigen::VectorXd& t, const Eigen::VectorXd& x, double f, Eigen::Index first, Eigen::Index last) {
  const Eigen::Index m = last - first;
  Eigen::MatrixXd basis(m, 2);
  basis.col(0) = (2.0 * kPi * f * t.segment(first, m)).array().sin();
  basis.col(1) = (2.0 * kPi * f * t.segment(first, m)).array().cos();
  const Eigen::Vector2d ab = basis.colPivHouseholderQr().solve(x.segment(first, m));
  return {ab.norm(), std::atan2(ab(1), ab(0))};
}

// max |a - b| over rows [margin, n - margin).
double interior_error(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, Eigen::Index margin) {
  const Eigen::Index m = a.rows() - 2 * margin;
  return (a.middleRows(margin, m) - b.middleRows(margin, m)).cwiseAbs().maxCoeff();
}

Eigen::Vector4d wxyz(const Eigen::Quaterniond& q) { return {q.w(), q.x(), q.y(), q.z()}; }

Eigen::Quaterniond axis_angle(double angle, const Eigen::Vector3d& axis) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
}

// ---------------------------------------------------------------------------------------------
// Butterworth design

TEST(MotionSignal, ButterworthMatchesTheAnalyticMagnitude) {
  const double rate = 120.0, cutoff = 5.0;
  for (int order : {1, 3, 4, 5, 10}) {
    SCOPED_TRACE("order " + std::to_string(order));
    const auto sos = motion::butterworth_lowpass(order, cutoff, rate);
    ASSERT_EQ(sos.size(), static_cast<std::size_t>((order + 1) / 2));
    int first_order = 0;
    for (const SecondOrderSection& s : sos) {
      if (s.a2 == 0.0 && s.b2 == 0.0) ++first_order;
      // Inside the stability triangle: both poles strictly inside the unit circle.
      EXPECT_LT(std::abs(s.a2), 1.0);
      EXPECT_LT(std::abs(s.a1), 1.0 + s.a2);
    }
    EXPECT_EQ(first_order, order % 2);
    EXPECT_NEAR(std::abs(response(sos, 0.0, rate)), 1.0, 1e-12);
    EXPECT_NEAR(std::abs(response(sos, cutoff, rate)), 1.0 / std::sqrt(2.0), 1e-12);
    for (int k = 0; k < 30; ++k) {
      const double f = (k + 0.5) * 59.9 / 30.0;  // (0, 60) Hz: below the Nyquist frequency
      EXPECT_NEAR(std::abs(response(sos, f, rate)), butterworth_magnitude(order, f, cutoff, rate), 1e-10) << f;
    }
  }
}

TEST(MotionSignal, ButterworthRefusesBadOrderCutoffAndRate) {
  EXPECT_THAT(error_of([] { motion::butterworth_lowpass(4, 70.0, 120.0); }),
              HasSubstr("motion: cutoff = 70 Hz: must be in (0, 60) Hz (below half the sampling rate 120 Hz)"));
  EXPECT_THAT(error_of([] { motion::butterworth_lowpass(4, 60.0, 120.0); }), HasSubstr("cutoff = 60 Hz: must be in"));
  EXPECT_THAT(error_of([] { motion::butterworth_lowpass(4, 0.0, 120.0); }), HasSubstr("cutoff = 0 Hz: must be in"));
  EXPECT_THAT(error_of([] { motion::butterworth_lowpass(0, 5.0, 120.0); }),
              HasSubstr("motion: filter order = 0: must be in 1..10"));
  EXPECT_THAT(error_of([] { motion::butterworth_lowpass(11, 5.0, 120.0); }), HasSubstr("filter order = 11"));
  EXPECT_THAT(error_of([] { motion::butterworth_lowpass(4, 5.0, -120.0); }),
              HasSubstr("motion: sampling rate = -120 Hz: must be finite and > 0"));
  EXPECT_THAT(error_of([] { motion::butterworth_lowpass(4, 5.0, std::nan("")); }), HasSubstr("sampling rate = nan"));
}

// ---------------------------------------------------------------------------------------------
// filtfilt

TEST(MotionSignal, FiltfiltIsZeroPhaseWithGainMagnitudeSquared) {
  const double rate = 120.0, cutoff = 5.0;
  const auto sos = motion::butterworth_lowpass(4, cutoff, rate);
  const Eigen::Index n = 7200;  // 60 s
  const Eigen::VectorXd t = times(n, rate);
  for (double f : {2.0, cutoff}) {
    SCOPED_TRACE("f = " + std::to_string(f));
    const Eigen::VectorXd x = (2.0 * kPi * f * t).array().sin();
    const Eigen::VectorXd y = motion::filtfilt(sos, x);
    const Fit fit = fit_sinusoid(t, y, f, n / 4, 3 * n / 4);  // the middle 30 s
    const double gain = std::pow(butterworth_magnitude(4, f, cutoff, rate), 2);
    EXPECT_NEAR(fit.amplitude, gain, 1e-9);
    EXPECT_NEAR(fit.phase, 0.0, 1e-6);
    if (f == cutoff) {
      EXPECT_NEAR(fit.amplitude, 0.5, 1e-4);
    }
  }
}

TEST(MotionSignal, FiltfiltPreservesConstantsAndRamps) {
  const double rate = 120.0;
  const auto sos = motion::butterworth_lowpass(4, 5.0, rate);
  const Eigen::Index n = 600;
  const Eigen::VectorXd t = times(n, rate);
  Eigen::MatrixXd constant(n, 2);
  constant.col(0).setConstant(3.7);
  constant.col(1).setConstant(-0.25);
  EXPECT_LT((motion::filtfilt(sos, constant) - constant).cwiseAbs().maxCoeff(), 1e-12);

  Eigen::MatrixXd ramp(n, 1);
  ramp.col(0) = (0.3 + 2.0 * t.array()).matrix();
  const Eigen::MatrixXd y = motion::filtfilt(sos, ramp);
  // A ramp is not exact at the ends (nor is it in scipy: the section states start from a
  // constant): measured 1.1e-2 at most (slope 2 / s: 5.5 ms worth), 1.9e-5 at 0.5 s from the
  // ends; 2 s (240 samples) from the ends the transient is gone.
  EXPECT_LT((y - ramp).cwiseAbs().maxCoeff(), 2e-2);
  EXPECT_LT(interior_error(y, ramp, 60), 5e-5);
  EXPECT_LT(interior_error(y, ramp, 240), 1e-9);
}

TEST(MotionSignal, FiltfiltNeedsScipysPadlenPlusOneSamples) {
  // scipy: padlen = 3 (2 sections + 1 - min(#b2 == 0, #a2 == 0)).
  EXPECT_EQ(motion::filtfilt_min_samples(motion::butterworth_lowpass(4, 5.0, 120.0)), 16);
  EXPECT_EQ(motion::filtfilt_min_samples(motion::butterworth_lowpass(5, 5.0, 120.0)), 19);
  EXPECT_EQ(motion::filtfilt_min_samples(motion::butterworth_lowpass(1, 5.0, 120.0)), 7);
  EXPECT_EQ(motion::filtfilt_min_samples({}), 0);
  const auto sos = motion::butterworth_lowpass(4, 5.0, 120.0);
  EXPECT_NO_THROW(motion::filtfilt(sos, Eigen::MatrixXd::Ones(16, 3)));
  EXPECT_THAT(error_of([&] { motion::filtfilt(sos, Eigen::MatrixXd::Ones(15, 3)); }),
              HasSubstr("motion: the signal has 15 samples; the filter needs at least 16 ("));
  EXPECT_THAT(error_of([&] {
                motion::differentiate(Eigen::MatrixXd::Zero(10, 3), Eigen::MatrixXd(0, 4), 120.0, sos);
              }),
              HasSubstr("the signal has 10 samples; the filter needs at least 16"));
}

// ---------------------------------------------------------------------------------------------
// derivative

TEST(MotionSignal, DerivativeIsExactForQuadratics) {
  const double dt = 0.01;
  const Eigen::Index n = 50;
  const Eigen::ArrayXd t = Eigen::ArrayXd::LinSpaced(n, 1.0, 1.0 + (n - 1) * dt);
  Eigen::MatrixXd x(n, 2);
  x.col(0) = (0.5 - 2.0 * t + 3.0 * t * t).matrix();
  x.col(1) = (-1.0 + 0.7 * t - 0.2 * t * t).matrix();
  Eigen::MatrixXd exact(n, 2);
  exact.col(0) = (-2.0 + 6.0 * t).matrix();
  exact.col(1) = (0.7 - 0.4 * t).matrix();
  const Eigen::MatrixXd d = motion::derivative(x, dt);
  for (Eigen::Index i = 0; i < n; ++i) {  // ends included
    for (Eigen::Index c = 0; c < 2; ++c) EXPECT_NEAR(d(i, c), exact(i, c), 1e-9 * std::abs(exact(i, c))) << i;
  }
}

TEST(MotionSignal, DerivativeErrorOfACubicIsTheTaylorTerm) {
  // x = 2 t^3: x''' = 12. Central: x' + dt^2 / 6 x''' exactly; one-sided: x' - dt^2 / 3 x'''.
  const double dt = 0.01;
  const Eigen::Index n = 40;
  const Eigen::ArrayXd t = Eigen::ArrayXd::LinSpaced(n, 0.5, 0.5 + (n - 1) * dt);
  const Eigen::MatrixXd x = (2.0 * t.cube()).matrix();
  const Eigen::ArrayXd exact = 6.0 * t.square();
  const Eigen::MatrixXd d = motion::derivative(x, dt);
  for (Eigen::Index i = 1; i + 1 < n; ++i) EXPECT_NEAR(d(i, 0) - exact(i), dt * dt / 6.0 * 12.0, 1e-9) << i;
  EXPECT_NEAR(d(0, 0) - exact(0), -dt * dt / 3.0 * 12.0, 1e-9);
  EXPECT_NEAR(d(n - 1, 0) - exact(n - 1), -dt * dt / 3.0 * 12.0, 1e-9);
}

TEST(MotionSignal, DerivativeRefusesShortInput) {
  EXPECT_THAT(error_of([] { motion::derivative(Eigen::MatrixXd::Zero(2, 3), 0.01); }),
              HasSubstr("motion: the signal has 2 samples; the derivative needs at least 3"));
  EXPECT_THAT(error_of([] { motion::derivative(Eigen::MatrixXd::Zero(5, 3), 0.0); }),
              HasSubstr("time step = 0 s: must be finite and > 0"));
}

// ---------------------------------------------------------------------------------------------
// differentiate (the pipeline)


// Rate, filter and trim margin shared by the pipeline tests: 120 Hz, 4th order at 5 Hz.
constexpr double kRate = 120.0;
std::vector<SecondOrderSection> pipeline_filter() { return motion::butterworth_lowpass(4, 5.0, kRate); }

TEST(MotionSignal, DifferentiateRecoversSinusoidDerivatives) {
  const Eigen::Index n = 2400;  // 20 s
  const Eigen::ArrayXd t = times(n, kRate).array();
  const double w = 2.0 * kPi * 0.5;
  const Eigen::Array3d amplitude(0.1, 0.05, 0.2), phase(0.0, 1.0, -2.0);
  Eigen::MatrixXd p(n, 3), v(n, 3), a(n, 3);
  for (int c = 0; c < 3; ++c) {
    p.col(c) = (amplitude(c) * (w * t + phase(c)).sin()).matrix();
    v.col(c) = (amplitude(c) * w * (w * t + phase(c)).cos()).matrix();
    a.col(c) = (-amplitude(c) * w * w * (w * t + phase(c)).sin()).matrix();
  }
  const motion::MotionDerivatives d = motion::differentiate(p, Eigen::MatrixXd(0, 4), kRate, pipeline_filter());
  // Errors relative to the amplitudes A, A w, A w^2 (A = 0.2). Inside, each derivative errs by the
  // central-difference term (w dt)^2 / 6 = 1.14e-4 (measured 1.14e-4 and 2.4e-4 beyond 1 s from
  // the ends); 0.5 s from the ends the edge error dominates (measured 5.2e-4 and 8.9e-3).
  const double scale = amplitude.maxCoeff();
  EXPECT_LT(interior_error(d.position, p, 120) / scale, 1e-6);
  EXPECT_LT(interior_error(d.velocity, v, 60) / (scale * w), 1e-3);
  EXPECT_LT(interior_error(d.acceleration, a, 60) / (scale * w * w), 2e-2);
  EXPECT_LT(interior_error(d.velocity, v, 120) / (scale * w), 1.5e-4);
  EXPECT_LT(interior_error(d.acceleration, a, 120) / (scale * w * w), 3e-4);
  EXPECT_EQ(d.quaternion.rows(), 0);
}

TEST(MotionSignal, DifferentiateRecoversPolynomialDerivatives) {
  const Eigen::Index n = 1200;  // 10 s
  const Eigen::ArrayXd t = times(n, kRate).array();
  Eigen::MatrixXd p(n, 3), v(n, 3), a(n, 3);
  const Eigen::Array3d c0(0.1, -0.3, 0.2), c1(0.05, 0.2, -0.1), c2(-0.01, 0.03, 0.02);
  for (int c = 0; c < 3; ++c) {
    p.col(c) = (c0(c) + c1(c) * t + c2(c) * t * t).matrix();
    v.col(c) = (c1(c) + 2.0 * c2(c) * t).matrix();
    a.col(c).setConstant(2.0 * c2(c));
  }
  const motion::MotionDerivatives d = motion::differentiate(p, Eigen::MatrixXd(0, 4), kRate, pipeline_filter());
  // Far from the ends the filter passes quadratics and the differences are exact: measured
  // 1.3e-13 m, 4.1e-11 m/s, 7.7e-9 m/s^2 beyond 2 s from the ends (2.6e-4 m/s^2 beyond 1 s).
  EXPECT_LT(interior_error(d.position, p, 240), 1e-11);
  EXPECT_LT(interior_error(d.velocity, v, 240), 1e-9);
  EXPECT_LT(interior_error(d.acceleration, a, 240), 1e-7);
  EXPECT_LT(interior_error(d.acceleration, a, 120), 1e-3);
  // Unfiltered, the differences are exact everywhere (ends included).
  const motion::MotionDerivatives raw = motion::differentiate(p, Eigen::MatrixXd(0, 4), kRate, {});
  EXPECT_LT((raw.velocity - v).cwiseAbs().maxCoeff(), 1e-11);
  EXPECT_LT((raw.acceleration - a).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(MotionSignal, DifferentiateRecoversRotationAboutAFixedAxis) {
  // theta = 0.05 t^2 + 0.3 t about a fixed axis: omega = theta' axis, alpha = theta'' axis.
  const Eigen::Index n = 1200;  // 10 s
  const Eigen::Vector3d axis = Eigen::Vector3d(1.0, 2.0, 2.0) / 3.0;
  Eigen::MatrixXd q(n, 4), omega(n, 3), alpha(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / kRate;
    q.row(i) = wxyz(axis_angle(0.05 * t * t + 0.3 * t, axis)).transpose();
    omega.row(i) = ((0.1 * t + 0.3) * axis).transpose();
    alpha.row(i) = (0.1 * axis).transpose();
    if (i % 7 == 3) q.row(i) *= -1.0;  // the same rotations, signs to be made continuous
  }
  const motion::MotionDerivatives d = motion::differentiate(Eigen::MatrixXd::Zero(n, 3), q, kRate, pipeline_filter());
  // |omega| <= 1.3 rad/s, |alpha| = 0.1 rad/s^2. Measured beyond 1 s from the ends: 5.7e-6 rad/s,
  // 2.7e-4 rad/s^2; beyond 2 s: 2.6e-6 rad/s, 7.1e-7 rad/s^2.
  EXPECT_LT(interior_error(d.angular_velocity, omega, 120), 2e-5);
  EXPECT_LT(interior_error(d.angular_acceleration, alpha, 120), 1e-3);
  EXPECT_LT(interior_error(d.angular_acceleration, alpha, 240), 3e-6);
  EXPECT_LT((d.quaternion.rowwise().norm().array() - 1.0).abs().maxCoeff(), 1e-12);
}

// q(t) = qz(alpha(t)) qx(beta(t)): rotation about the world z by alpha = 0.8 t + 0.3 composed with
// one about the body x by beta = 0.6 sin(1.5 t).
struct MovingAxis {
  Eigen::Quaterniond q;
  Eigen::Vector3d omega, alpha;  // fixed frame, closed form
  Eigen::Vector3d omega_from_qdot;  // 2 vec(qdot q*), qdot from the analytic derivative
};
MovingAxis moving_axis(double t) {
  const double al = 0.8 * t + 0.3, al_d = 0.8, al_dd = 0.0;
  const double be = 0.6 * std::sin(1.5 * t), be_d = 0.9 * std::cos(1.5 * t), be_dd = -1.35 * std::sin(1.5 * t);
  const Eigen::Quaterniond qz(std::cos(al / 2), 0.0, 0.0, std::sin(al / 2));
  const Eigen::Quaterniond qx(std::cos(be / 2), std::sin(be / 2), 0.0, 0.0);
  const Eigen::Quaterniond qz_d(-al_d / 2 * std::sin(al / 2), 0.0, 0.0, al_d / 2 * std::cos(al / 2));
  const Eigen::Quaterniond qx_d(-be_d / 2 * std::sin(be / 2), be_d / 2 * std::cos(be / 2), 0.0, 0.0);
  MovingAxis m;
  m.q = qz * qx;
  const Eigen::Vector4d qdot = wxyz(qz_d * qx).array() + wxyz(qz * qx_d).array();
  const Eigen::Quaterniond product = Eigen::Quaterniond(qdot(0), qdot(1), qdot(2), qdot(3)) * m.q.conjugate();
  m.omega_from_qdot = 2.0 * product.vec();
  // R = Rz(alpha) Rx(beta): omega = alpha' z + beta' Rz x; alpha = its derivative.
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d x_rotated(std::cos(al), std::sin(al), 0.0);
  m.omega = al_d * z + be_d * x_rotated;
  m.alpha = al_dd * z + be_dd * x_rotated + be_d * al_d * z.cross(x_rotated);
  return m;
}

TEST(MotionSignal, DifferentiateRecoversRotationWithAMovingAxis) {
  const Eigen::Index n = 1800;  // 15 s
  Eigen::MatrixXd q(n, 4), omega(n, 3), alpha(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const MovingAxis m = moving_axis(static_cast<double>(i) / kRate);
    // The two analytic forms agree: the frame convention of the closed form is the code's.
    EXPECT_LT((m.omega - m.omega_from_qdot).norm(), 1e-14);
    q.row(i) = wxyz(m.q).transpose();
    omega.row(i) = m.omega.transpose();
    alpha.row(i) = m.alpha.transpose();
  }
  const motion::MotionDerivatives d = motion::differentiate(Eigen::MatrixXd::Zero(n, 3), q, kRate, pipeline_filter());
  // |omega| <= 1.2 rad/s, |alpha| <= 1.6 rad/s^2. Measured beyond 1 s from the ends: quaternion
  // 1.5e-8, omega 3.0e-5 rad/s (the central-difference term), alpha 2.3e-4 rad/s^2.
  EXPECT_LT(interior_error(d.quaternion, q, 120), 1e-7);
  EXPECT_LT(interior_error(d.angular_velocity, omega, 120), 1e-4);
  EXPECT_LT(interior_error(d.angular_acceleration, alpha, 120), 1e-3);
  EXPECT_LT((d.quaternion.rowwise().norm().array() - 1.0).abs().maxCoeff(), 1e-12);
}


// ---------------------------------------------------------------------------------------------
// resampling

TEST(MotionSignal, ResampleIsExactForLinearMotionOnJitteredTimes) {
  // Times 0.01 i + 0.003 sin(1.7 i) (increasing: the jitter moves less than half a step), linear
  // positions, rotation about a fixed axis at a constant rate: linear interpolation and slerp
  // reproduce both exactly.
  const Eigen::Index n = 200;
  Eigen::VectorXd time(n);
  for (Eigen::Index i = 0; i < n; ++i) time(i) = 0.01 * i + 0.003 * std::sin(1.7 * i);
  const Eigen::Vector3d p0(0.1, -0.2, 0.3), v(0.5, 1.5, -0.7), axis(1.0, -2.0, 0.5);
  const auto angle = [](double s) { return 0.4 + 1.1 * s; };
  Eigen::MatrixXd positions(n, 3), quaternions(n, 4);
  for (Eigen::Index i = 0; i < n; ++i) {
    positions.row(i) = (p0 + v * time(i)).transpose();
    quaternions.row(i) = wxyz(axis_angle(angle(time(i)), axis)).transpose();
  }
  const double rate = 50.0;
  const motion::Uniform u = motion::resample(time, positions, quaternions, rate);
  const auto m = static_cast<Eigen::Index>(std::floor((time(n - 1) - time(0)) * rate)) + 1;
  ASSERT_EQ(u.time.size(), m);
  ASSERT_EQ(u.positions.rows(), m);
  ASSERT_EQ(u.quaternions.rows(), m);
  for (Eigen::Index k = 0; k < m; ++k) {
    const double tk = time(0) + k / rate;
    EXPECT_NEAR(u.time(k), tk, 1e-12);
    EXPECT_LT((u.positions.row(k).transpose() - (p0 + v * tk)).norm(), 1e-12) << k;
    EXPECT_LT((u.quaternions.row(k).transpose() - wxyz(axis_angle(angle(tk), axis))).norm(), 1e-12) << k;
  }
}

TEST(MotionSignal, ResampleIncludesALastTimeOnTheGrid) {
  // (0.4 - 0.1) * 10 = 2.9999999999999996 in doubles: still 4 grid points, the last one 0.4.
  const Eigen::Vector4d time(0.1, 0.2, 0.25, 0.4);
  const Eigen::MatrixXd positions = Eigen::MatrixXd::Zero(4, 3);
  const motion::Uniform u = motion::resample(time, positions, Eigen::MatrixXd(0, 4), 10.0);
  ASSERT_EQ(u.time.size(), 4);
  EXPECT_NEAR(u.time(3), 0.4, 1e-15);
  EXPECT_EQ(u.quaternions.rows(), 0);
  // Off the grid: 0.1, 0.2, 0.3 only.
  EXPECT_EQ(motion::resample(Eigen::Vector3d(0.1, 0.2, 0.39), Eigen::MatrixXd::Zero(3, 3), Eigen::MatrixXd(0, 4), 10.0)
                .time.size(),
            3);
}

TEST(MotionSignal, ResampleSlerpsAtTheMidpoint) {
  // Halfway between the identity and 90 degrees about z: 45 degrees about z, also when the second
  // quaternion is given with the opposite sign (the shorter arc).
  const Eigen::Vector2d time(0.0, 1.0);
  const Eigen::MatrixXd positions = Eigen::MatrixXd::Zero(2, 3);
  const Eigen::Vector4d expected(std::cos(kPi / 8.0), 0.0, 0.0, std::sin(kPi / 8.0));
  for (double sign : {1.0, -1.0}) {
    Eigen::MatrixXd q(2, 4);
    q << 1.0, 0.0, 0.0, 0.0, sign * std::cos(kPi / 4.0), 0.0, 0.0, sign * std::sin(kPi / 4.0);
    const motion::Uniform u = motion::resample(time, positions, q, 2.0);
    ASSERT_EQ(u.time.size(), 3);
    EXPECT_LT((u.quaternions.row(1).transpose() - expected).norm(), 1e-12) << sign;
  }
}

TEST(MotionSignal, ResampleRefusesNonIncreasingTimes) {
  const Eigen::MatrixXd positions = Eigen::MatrixXd::Zero(4, 3);
  const Eigen::MatrixXd none(0, 4);
  EXPECT_THAT(error_of([&] { motion::resample(Eigen::Vector4d(0.0, 0.1, 0.05, 0.2), positions, none, 10.0); }),
              HasSubstr("motion: time[2] = 0.05 after time[1] = 0.1: times must increase strictly"));
  EXPECT_THAT(error_of([&] { motion::resample(Eigen::Vector4d(0.0, 0.1, 0.1, 0.2), positions, none, 10.0); }),
              HasSubstr("motion: time[2] = 0.1 after time[1] = 0.1: times must increase strictly"));
  EXPECT_THAT(error_of([&] { motion::resample(Eigen::Vector4d(0.0, 0.1, 0.2, 0.3), positions, none, 0.0); }),
              HasSubstr("resampling rate = 0 Hz: must be finite and > 0"));
  EXPECT_THAT(error_of([&] { motion::resample(Eigen::Vector3d(0.0, 0.1, 0.2), positions, none, 10.0); }),
              HasSubstr("positions are 4 x 3: must be 3 x 3"));
}

TEST(MotionSignal, IsUniformAndMedianRate) {
  const Eigen::VectorXd uniform = Eigen::VectorXd::LinSpaced(101, 2.0, 3.0);
  EXPECT_TRUE(motion::is_uniform(uniform));
  EXPECT_NEAR(motion::median_rate(uniform), 100.0, 1e-9);
  Eigen::VectorXd jittered = uniform;
  jittered(50) += 1e-4;  // one stamp 1 % of a step off the grid
  EXPECT_FALSE(motion::is_uniform(jittered));
  EXPECT_TRUE(motion::is_uniform(jittered, 0.02));
  // Stamps of a 120 Hz recording printed with 6 decimals are the grid, rounded: uniform.
  Eigen::VectorXd printed(1201);
  for (Eigen::Index i = 0; i < printed.size(); ++i) printed(i) = std::round(i / 120.0 * 1e6) / 1e6;
  EXPECT_FALSE(motion::is_uniform(printed, 1e-5));  // the stamps are up to 5e-7 s = 6e-5 dt off
  EXPECT_TRUE(motion::is_uniform(printed));
  EXPECT_NEAR(1.0 / motion::mean_step(printed), 120.0, 1e-9);
  EXPECT_NEAR(motion::median_rate(jittered), 100.0, 1e-9);
  EXPECT_NEAR(motion::median_rate(Eigen::Vector4d(0.0, 0.1, 0.3, 0.6)), 1.0 / 0.2, 1e-9);  // steps 0.1, 0.2, 0.3
  EXPECT_NEAR(motion::median_rate(Eigen::Vector3d(0.0, 0.1, 0.4)), 1.0 / 0.2, 1e-9);       // mean of 0.1 and 0.3
}

// ---------------------------------------------------------------------------------------------
// orientation helpers

TEST(MotionSignal, MakeContinuousUndoesSignFlips) {
  const Eigen::Index n = 30;
  Eigen::MatrixXd q(n, 4), flipped(n, 4);
  for (Eigen::Index i = 0; i < n; ++i) {
    q.row(i) = wxyz(axis_angle(0.3 * i, Eigen::Vector3d(0.0, 1.0, 1.0))).transpose();  // w crosses 0 near i = 10
    flipped.row(i) = (i % 3 == 1 || i > 20 ? -1.0 : 1.0) * q.row(i);
  }
  motion::make_continuous(flipped);
  EXPECT_LT((flipped - q).cwiseAbs().maxCoeff(), 1e-15);
}

}  // namespace
