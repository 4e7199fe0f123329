#pragma once
/// \file
/// Private to the haptic6r model: the forward-chain kernels shared by the per-sample solve()
/// (haptic6r_kinematics.cpp) and by quantities() / frames() / jacobian() / dynamics()
/// (haptic6r_dynamics.cpp). Every function is [[gnu::always_inline]]: it is compiled inside each
/// multiversioned caller (hapsyn/multiversion.hpp), so the AVX2/FMA clone gets an AVX2/FMA copy
/// and the baseline clone a baseline one, exactly as when they shared one file.
#include "haptic6r.hpp"

#include <hapsyn/fast_math.hpp>
#include <hapsyn/lanes.hpp>

#include <Eigen/Core>
#include <array>
#include <cstddef>

namespace hapsyn::plugins::haptic6r_chain {

// The chain's DH frames in B as plain scalars (axes x, y, z and origin o of frame i = 0..6).
// Plain arrays, not Eigen 3-vectors: the per-sample kernels are scalar code with many
// live values, and Eigen's 2-wide packing of 3-vectors spilled halves to the stack and read
// them back as pairs (store-forwarding stalls that cost more than the arithmetic).
// T = double for one sample, T = hapsyn::Lanes for a block of samples (hapsyn/lanes.hpp): the
// kernels below are templates on it, one source for the per-sample and the block path.
template <typename T>
struct ChainOf {
  T x[7][3], y[7][3], z[7][3], o[7][3];
};
using Chain = ChainOf<double>;

[[gnu::always_inline]] inline void assign(double& t, double value) { t = value; }
[[gnu::always_inline]] inline void assign(Lanes& t, double value) { t = Lanes::splat(value); }

// R_{i+1} = R_i Rz(theta) Rx(alpha) column by column, o_{i+1} = o_i + R_i (a ct, a st, d):
// 24 multiplications per joint instead of a 3x3 product.
// cosine[i], sine[i]: of the DH angle theta_i (i = 0..5).
template <typename T>
[[gnu::always_inline]] inline void chain_from(const T* cosine, const T* sine, const std::array<double, 6>& d,
                                              const std::array<double, 6>& a, const std::array<double, 6>& ca,
                                              const std::array<double, 6>& sa, ChainOf<T>& c) {
  for (int r = 0; r < 3; ++r) {
    assign(c.x[0][r], r == 0 ? 1.0 : 0.0);
    assign(c.y[0][r], r == 1 ? 1.0 : 0.0);
    assign(c.z[0][r], r == 2 ? 1.0 : 0.0);
    assign(c.o[0][r], 0.0);
  }
  for (std::size_t i = 0; i < 6; ++i) {
    const T ct = cosine[i], st = sine[i];
    for (int r = 0; r < 3; ++r) {
      const T xr = c.x[i][r], yr = c.y[i][r], zr = c.z[i][r];
      const T x_new = ct * xr + st * yr;
      const T u = ct * yr - st * xr;
      c.x[i + 1][r] = x_new;
      c.y[i + 1][r] = ca[i] * u + sa[i] * zr;
      c.z[i + 1][r] = ca[i] * zr - sa[i] * u;
      c.o[i + 1][r] = c.o[i][r] + a[i] * x_new + d[i] * zr;
    }
  }
}

[[gnu::always_inline]] inline void chain_from(const JointTrig& trig, const std::array<double, 6>& d, const std::array<double, 6>& a,
                const std::array<double, 6>& ca, const std::array<double, 6>& sa, Chain& c) {
  chain_from(trig.c.data(), trig.s.data(), d, a, ca, sa, c);
}

[[gnu::always_inline]] inline void chain_from(const Vector6d& q, const std::array<double, 6>& offset, const std::array<double, 6>& d,
                const std::array<double, 6>& a, const std::array<double, 6>& ca, const std::array<double, 6>& sa,
                Chain& c) {
  JointTrig trig;
  for (std::size_t i = 0; i < 6; ++i) {
    const double theta = q(static_cast<Eigen::Index>(i)) + offset[i];
    fast::sin_cos(theta, trig.s[i], trig.c[i]);
  }
  chain_from(trig, d, a, ca, sa, c);
}

// Geometric Jacobian of E, column i = (z_i, z_i x (p - o_i)), written into `j` (6 x 6).
template <typename T, typename Matrix>
[[gnu::always_inline]] inline void jacobian_from(const ChainOf<T>& c, Matrix& j) {
  const T* p = c.o[6];
  for (int i = 0; i < 6; ++i) {
    const T* z = c.z[i];
    const T rx = p[0] - c.o[i][0], ry = p[1] - c.o[i][1], rz = p[2] - c.o[i][2];
    j(0, i) = z[0];
    j(1, i) = z[1];
    j(2, i) = z[2];
    j(3, i) = z[1] * rz - z[2] * ry;
    j(4, i) = z[2] * rx - z[0] * rz;
    j(5, i) = z[0] * ry - z[1] * rx;
  }
}

// Composite rigid bodies in B, accumulated about the base origin so that adding a body needs no
// division or centre-of-mass shift: composite j (bodies j..5) has mass M, first moment h = M c
// and inertia K about the origin (symmetric: six numbers). A unit rate of joint j (axis z_j
// through o_j) gives it the linear momentum P = z_j x (h - M o_j) and the angular momentum about
// the origin L = K z_j - h x (z_j x o_j); then H_ij = z_i . (L - o_i x P) = z_i . L - (z_i x o_i) . P
// for i <= j, and the holding torque tau_j = z_j . ((h - M o_j) x g e_z).
template <typename T, typename InertiaMatrix, typename GravityVector>
[[gnu::always_inline]] inline void dynamics_from(const ChainOf<T>& c, const std::array<Haptic6RBody, 6>& bodies, double g, InertiaMatrix* inertia,
                   GravityVector* gravity) {
  T mass, h[3], kxx, kyy, kzz, kxy, kxz, kyz;
  for (T* t : {&mass, &h[0], &h[1], &h[2], &kxx, &kyy, &kzz, &kxy, &kxz, &kyz}) assign(*t, 0.0);
  T arm[6][3];  // z_i x o_i
  for (int i = 0; i < 6; ++i) {
    const T *z = c.z[i], *o = c.o[i];
    arm[i][0] = z[1] * o[2] - z[2] * o[1];
    arm[i][1] = z[2] * o[0] - z[0] * o[2];
    arm[i][2] = z[0] * o[1] - z[1] * o[0];
  }
  for (int j = 5; j >= 0; --j) {
    const Haptic6RBody& b = bodies[static_cast<std::size_t>(j)];
    if (b.mass > 0.0) {
      const int f = j + 1;  // body j lives in DH frame j + 1
      const T *X = c.x[f], *Y = c.y[f], *Z = c.z[f];
      const double lx = b.com.x(), ly = b.com.y(), lz = b.com.z();
      T com[3];
      for (int r = 0; r < 3; ++r) com[r] = c.o[f][r] + X[r] * lx + Y[r] * ly + Z[r] * lz;
      // R I R^T with I the body's inertia about its centre of mass in its frame: A = R I, then
      // K_ab = sum_k A_ak R_bk (only the six distinct entries).
      const Eigen::Matrix3d& in = b.inertia;
      T A[3][3];  // A[r][k]
      if (in(0, 1) == 0.0 && in(0, 2) == 0.0 && in(1, 2) == 0.0) {
        // Principal axes along the frame's (every body of the docs/design.md model): A = R diag(I).
        for (int r = 0; r < 3; ++r) {
          A[r][0] = X[r] * in(0, 0);
          A[r][1] = Y[r] * in(1, 1);
          A[r][2] = Z[r] * in(2, 2);
        }
      } else {
        for (int r = 0; r < 3; ++r) {
          for (int k = 0; k < 3; ++k) A[r][k] = X[r] * in(0, k) + Y[r] * in(1, k) + Z[r] * in(2, k);
        }
      }
      kxx += A[0][0] * X[0] + A[0][1] * Y[0] + A[0][2] * Z[0];
      kyy += A[1][0] * X[1] + A[1][1] * Y[1] + A[1][2] * Z[1];
      kzz += A[2][0] * X[2] + A[2][1] * Y[2] + A[2][2] * Z[2];
      kxy += A[0][0] * X[1] + A[0][1] * Y[1] + A[0][2] * Z[1];
      kxz += A[0][0] * X[2] + A[0][1] * Y[2] + A[0][2] * Z[2];
      kyz += A[1][0] * X[2] + A[1][1] * Y[2] + A[1][2] * Z[2];
      // Point mass at com about the origin: m (|c|^2 1 - c c^T).
      const T mx = b.mass * com[0], my = b.mass * com[1], mz = b.mass * com[2];
      kxx += my * com[1] + mz * com[2];
      kyy += mx * com[0] + mz * com[2];
      kzz += mx * com[0] + my * com[1];
      kxy -= mx * com[1];
      kxz -= mx * com[2];
      kyz -= my * com[2];
      h[0] += mx;
      h[1] += my;
      h[2] += mz;
      mass += b.mass;
    }
    const T *zj = c.z[j], *oj = c.o[j];
    const T lever[3] = {h[0] - mass * oj[0], h[1] - mass * oj[1], h[2] - mass * oj[2]};  // M (c - o_j)
    if (inertia) {
      const T momentum[3] = {zj[1] * lever[2] - zj[2] * lever[1], zj[2] * lever[0] - zj[0] * lever[2],
                                  zj[0] * lever[1] - zj[1] * lever[0]};
      const T* aj = arm[j];
      const T angular[3] = {kxx * zj[0] + kxy * zj[1] + kxz * zj[2] - (h[1] * aj[2] - h[2] * aj[1]),
                                 kxy * zj[0] + kyy * zj[1] + kyz * zj[2] - (h[2] * aj[0] - h[0] * aj[2]),
                                 kxz * zj[0] + kyz * zj[1] + kzz * zj[2] - (h[0] * aj[1] - h[1] * aj[0])};
      for (int i = 0; i <= j; ++i) {
        const T *zi = c.z[i], *ai = arm[i];
        const T value = zi[0] * angular[0] + zi[1] * angular[1] + zi[2] * angular[2] -
                             (ai[0] * momentum[0] + ai[1] * momentum[1] + ai[2] * momentum[2]);
        (*inertia)(i, j) = value;
        (*inertia)(j, i) = value;
      }
    }
    // lever x e_z = (lever_y, -lever_x, 0).
    if (gravity) (*gravity)(j) = g * (zj[0] * lever[1] - zj[1] * lever[0]);
  }
}

// The demanded motion at the chain's configuration (kNeedJointVelocity, kNeedJointAcceleration,
// kNeedVelocityTorque, whichever `needs` holds): qdot = J^-1 twist, qddot = J^-1 (twist_rate -
// Jdot qdot) and c = C(q, qdot) qdot from the same bodies as dynamics_from(). Out of line
// (haptic6r_motion.cpp): only samples that ask for it pay for it. Allocation-free.
void joint_motion(const Chain& c, const std::array<Haptic6RBody, 6>& bodies, Needs needs, SampleQuantities& out);

}  // namespace hapsyn::plugins::haptic6r_chain
