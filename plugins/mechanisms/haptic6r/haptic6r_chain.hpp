#pragma once
/// \file
/// Private to the haptic6r model: the forward-chain kernels shared by the per-sample solve()
/// (haptic6r_kinematics.cpp) and by quantities() / frames() / jacobian() / dynamics()
/// (haptic6r_dynamics.cpp). Every function is [[gnu::always_inline]]: it is compiled inside each
/// multiversioned caller (hapsyn/accel/multiversion.hpp), so the AVX2/FMA clone gets an AVX2/FMA copy
/// and the baseline clone a baseline one, exactly as when they shared one file.
#include "haptic6r.hpp"

#include <hapsyn/accel/fast_math.hpp>
#include <hapsyn/accel/lanes.hpp>

#include <Eigen/Core>
#include <array>
#include <cstddef>

namespace hapsyn::plugins::haptic6r_chain {

// The chain's DH frames in B as plain scalars (axes x, y, z and origin o of frame i = 0..6).
// Plain arrays, not Eigen 3-vectors: the per-sample kernels are scalar code with many
// live values, and Eigen's 2-wide packing of 3-vectors spilled halves to the stack and read
// them back as pairs (store-forwarding stalls that cost more than the arithmetic).
// T = double for one sample, T = a lanes type (hapsyn::LanesOf) for a block of samples (hapsyn/accel/lanes.hpp): the
// kernels below are templates on it, one source for the per-sample and the block path.
template <typename T>
struct ChainOf {
  T x[7][3], y[7][3], z[7][3], o[7][3];
};
using Chain = ChainOf<double>;

[[gnu::always_inline]] inline void assign(double& t, double value) { t = value; }
template <int B, int N>
[[gnu::always_inline]] inline void assign(LanesOf<B, N>& t, double value) { t = LanesOf<B, N>::splat(value); }

// The structure read_haptic6r_dh() admits (docs/design.md section 4.4): alpha = (0, 0, 90, 0, 90,
// 0) deg, a = (l1, l2, 0, l4, 0, 0), d = (0, 0, -l3, 0, 0, l5). The kernels below multiply none of
// its zeros and ones: joints 1 to 3 turn about e_z, frames 1 and 2 and the axis z_3 = z_4 are
// horizontal, y_3 = e_z and o_0 = 0. The values are those of the general DH recursion
// (R_{i+1} = R_i Rz(theta) Rx(alpha), o_{i+1} = o_i + R_i (a ct, a st, d)) up to the sign of a
// zero and the compiler's fusion of multiply-adds (KDL checks them, haptic6r_test).

// One turn of the general recursion where the axis does not change (alpha = 0): x' = ct x + st y,
// y' = ct y - st x, z' = z; rows r0..r1 only (the others are zero in both x and y).
template <typename T>
[[gnu::always_inline]] inline void turn_about_z(const T& ct, const T& st, int r0, int r1, const ChainOf<T>& c, int i,
                                                ChainOf<T>& out) {
  for (int r = r0; r <= r1; ++r) {
    out.x[i + 1][r] = ct * c.x[i][r] + st * c.y[i][r];
    out.y[i + 1][r] = ct * c.y[i][r] - st * c.x[i][r];
  }
}

// cosine[i], sine[i]: of the DH angle theta_i (i = 0..5); d, a: the design's DH lengths [m]
// (entries the structure fixes at zero are not read).
template <typename T>
[[gnu::always_inline]] inline void chain_from(const T* cosine, const T* sine, const std::array<double, 6>& d,
                                              const std::array<double, 6>& a, ChainOf<T>& c) {
  T zero, one;
  assign(zero, 0.0);
  assign(one, 1.0);
  for (int r = 0; r < 3; ++r) {
    c.x[0][r] = r == 0 ? one : zero;
    c.y[0][r] = r == 1 ? one : zero;
    c.o[0][r] = zero;
  }
  for (int i = 0; i < 3; ++i) {  // frames 0 to 2: z = e_z, x and y horizontal
    c.z[i][0] = c.z[i][1] = zero;
    c.z[i][2] = one;
  }
  // Joint 1 (a = l1) from the base: x_1 = (c1, s1, 0), y_1 = (-s1, c1, 0).
  c.x[1][0] = cosine[0];
  c.x[1][1] = sine[0];
  c.y[1][0] = -sine[0];
  c.y[1][1] = cosine[0];
  c.x[1][2] = c.y[1][2] = c.o[1][2] = zero;
  c.o[1][0] = a[0] * cosine[0];
  c.o[1][1] = a[0] * sine[0];
  // Joint 2 (a = l2).
  turn_about_z(cosine[1], sine[1], 0, 1, c, 1, c);
  c.x[2][2] = c.y[2][2] = c.o[2][2] = zero;
  for (int r = 0; r < 2; ++r) c.o[2][r] = c.o[1][r] + a[1] * c.x[2][r];
  // Joint 3 (d = -l3, alpha = 90 deg): x_3 = c3 x_2 + s3 y_2, y_3 = z_2 = e_z, z_3 = -(c3 y_2 - s3 x_2).
  for (int r = 0; r < 2; ++r) {
    c.x[3][r] = cosine[2] * c.x[2][r] + sine[2] * c.y[2][r];
    c.z[3][r] = -(cosine[2] * c.y[2][r] - sine[2] * c.x[2][r]);
    c.y[3][r] = zero;
    c.o[3][r] = c.o[2][r];
  }
  c.x[3][2] = c.z[3][2] = zero;
  c.y[3][2] = one;
  assign(c.o[3][2], d[2]);
  // Joint 4 (a = l4): x_4 = c4 x_3 + s4 e_z, y_4 = c4 e_z - s4 x_3, z_4 = z_3.
  for (int r = 0; r < 2; ++r) {
    c.x[4][r] = cosine[3] * c.x[3][r];
    c.y[4][r] = -(sine[3] * c.x[3][r]);
  }
  c.x[4][2] = sine[3];
  c.y[4][2] = cosine[3];
  for (int r = 0; r < 3; ++r) {
    c.z[4][r] = c.z[3][r];
    c.o[4][r] = c.o[3][r] + a[3] * c.x[4][r];
  }
  // Joint 5 (alpha = 90 deg): x_5 = c5 x_4 + s5 y_4, y_5 = z_4, z_5 = -(c5 y_4 - s5 x_4), o_5 = o_4.
  for (int r = 0; r < 3; ++r) {
    c.x[5][r] = cosine[4] * c.x[4][r] + sine[4] * c.y[4][r];
    c.z[5][r] = -(cosine[4] * c.y[4][r] - sine[4] * c.x[4][r]);
    c.y[5][r] = c.z[4][r];
    c.o[5][r] = c.o[4][r];
  }
  // Joint 6 (d = l5): y_5 is horizontal.
  turn_about_z(cosine[5], sine[5], 0, 1, c, 5, c);
  c.x[6][2] = cosine[5] * c.x[5][2];
  c.y[6][2] = -(sine[5] * c.x[5][2]);
  for (int r = 0; r < 3; ++r) {
    c.z[6][r] = c.z[5][r];
    c.o[6][r] = c.o[5][r] + d[5] * c.z[5][r];
  }
}

[[gnu::always_inline]] inline void chain_from(const JointTrig& trig, const std::array<double, 6>& d, const std::array<double, 6>& a,
                                              Chain& c) {
  chain_from(trig.c.data(), trig.s.data(), d, a, c);
}

[[gnu::always_inline]] inline void chain_from(const Vector6d& q, const std::array<double, 6>& offset, const std::array<double, 6>& d,
                                              const std::array<double, 6>& a, Chain& c) {
  JointTrig trig;
  for (std::size_t i = 0; i < 6; ++i) {
    const double theta = q(static_cast<Eigen::Index>(i)) + offset[i];
    fast::sin_cos(theta, trig.s[i], trig.c[i]);
  }
  chain_from(trig, d, a, c);
}

// Geometric Jacobian of E, column i = (z_i, z_i x (p - o_i)), written into `j` (6 x 6).
// Columns 0 to 2 (z = e_z) are (0, 0, 1, -r_y, r_x, 0).
template <typename T, typename Matrix>
[[gnu::always_inline]] inline void jacobian_from(const ChainOf<T>& c, Matrix& j) {
  const T* p = c.o[6];
  for (int i = 0; i < 3; ++i) {
    j(0, i) = j(1, i) = j(5, i) = c.z[i][0];  // zero
    j(2, i) = c.z[i][2];                      // one
    j(3, i) = -(p[1] - c.o[i][1]);
    j(4, i) = p[0] - c.o[i][0];
  }
  for (int i = 3; i < 6; ++i) {
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
  T zero, mass, h[3], kxx, kyy, kzz, kxy, kxz, kyz;
  for (T* t : {&zero, &mass, &h[0], &h[1], &h[2], &kxx, &kyy, &kzz, &kxy, &kxz, &kyz}) assign(*t, 0.0);
  T arm[6][3];  // z_i x o_i: (-o_y, o_x, 0) for the vertical axes 0 to 2 (arm_0 = 0: o_0 = 0)
  for (int i = 0; i < 3; ++i) {
    arm[i][0] = -c.o[i][1];
    arm[i][1] = c.o[i][0];
    arm[i][2] = zero;
  }
  for (int i = 3; i < 6; ++i) {
    const T *z = c.z[i], *o = c.o[i];
    arm[i][0] = z[1] * o[2] - z[2] * o[1];
    arm[i][1] = z[2] * o[0] - z[0] * o[2];
    arm[i][2] = z[0] * o[1] - z[1] * o[0];
  }
  // Unrolled, so that the structure's cases below are decided at compile time.
#pragma GCC unroll 6
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
      const T* aj = arm[j];
      T momentum[3] = {zero, zero, zero}, angular[3] = {zero, zero, zero};
      if (j < 3) {  // z_j = e_z: only the z component of L and the horizontal ones of P are read
        momentum[0] = -lever[1];
        momentum[1] = lever[0];
        angular[2] = kzz - (h[0] * aj[1] - h[1] * aj[0]);
      } else {
        momentum[0] = zj[1] * lever[2] - zj[2] * lever[1];
        momentum[1] = zj[2] * lever[0] - zj[0] * lever[2];
        momentum[2] = zj[0] * lever[1] - zj[1] * lever[0];
        angular[0] = kxx * zj[0] + kxy * zj[1] + kxz * zj[2] - (h[1] * aj[2] - h[2] * aj[1]);
        angular[1] = kxy * zj[0] + kyy * zj[1] + kyz * zj[2] - (h[2] * aj[0] - h[0] * aj[2]);
        angular[2] = kxz * zj[0] + kyz * zj[1] + kzz * zj[2] - (h[0] * aj[1] - h[1] * aj[0]);
      }
#pragma GCC unroll 6
      for (int i = 0; i <= j; ++i) {
        const T *zi = c.z[i], *ai = arm[i];
        T value;
        if (i == 0) {  // z_0 = e_z, arm_0 = 0
          value = angular[2];
        } else if (i < 3) {  // z_i = e_z, arm_i horizontal
          value = angular[2] - (ai[0] * momentum[0] + ai[1] * momentum[1]);
        } else {
          value = zi[0] * angular[0] + zi[1] * angular[1] + zi[2] * angular[2] -
                  (ai[0] * momentum[0] + ai[1] * momentum[1] + ai[2] * momentum[2]);
        }
        (*inertia)(i, j) = value;
        (*inertia)(j, i) = value;
      }
    }
    // lever x e_z = (lever_y, -lever_x, 0); zero about the vertical axes 0 to 2.
    if (gravity) (*gravity)(j) = j < 3 ? zero : g * (zj[0] * lever[1] - zj[1] * lever[0]);
  }
}

// The demanded motion at the chain's configuration (kNeedJointVelocity, kNeedJointAcceleration,
// kNeedVelocityTorque, whichever `needs` holds): qdot = J^-1 twist, qddot = J^-1 (twist_rate -
// Jdot qdot) and c = C(q, qdot) qdot from the same bodies as dynamics_from(). Out of line
// (haptic6r_motion.cpp): only samples that ask for it pay for it. Allocation-free.
void joint_motion(const Chain& c, const std::array<Haptic6RBody, 6>& bodies, Needs needs, SampleQuantities& out);

}  // namespace hapsyn::plugins::haptic6r_chain
