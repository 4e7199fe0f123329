#pragma once
/// \file
/// The velocity terms of a serial chain, for mechanism authors who provide kNeedJointVelocity,
/// kNeedJointAcceleration and kNeedVelocityTorque (hapsyn/quantities.hpp): the rate term
/// Jdot qdot of a point's Jacobian, the Coriolis / centrifugal torque c = C(q, qdot) qdot, and
/// the solve J x = b for joint rates.
///
/// The chain is described at the current configuration in world (base) coordinates: one
/// WorldJoint and one WorldBody per moving joint, base to tip. Body i moves with joint i. So a
/// mechanism whose kinematics is DH, URDF or anything else only has to hand over its joint axes
/// and its bodies' mass data in the base frame, from the frames it already computed for the
/// Jacobian. Every function here:
/// - takes n = 1..kMaxDof joints, SI units (m, rad, kg, kg m^2; m for a prismatic coordinate);
/// - is allocation-free (fixed-capacity storage) and does not throw: it is meant for the
///   per-sample solve(), called only when a metric asked for these quantities;
/// - orders twists and accelerations (omega, v), the rows of hapsyn's geometric Jacobians.
///
/// Derivation (world coordinates throughout, at qddot = 0 and without gravity; the velocity
/// terms are what is left of the inverse dynamics then). Body -1 is the fixed base. For joint i
/// with unit axis z_i through o_i and body i-1 known by its angular velocity w_{i-1}, angular
/// acceleration dw_{i-1}, and the velocity v_{i-1} and acceleration a_{i-1} of its point at
/// o_{i-1}:
/// - The axis is fixed in body i-1, so dz_i/dt = w_{i-1} x z_i. The point of body i-1 at o_i
///   has, with r = o_i - o_{i-1}, the velocity v' = v_{i-1} + w_{i-1} x r and the acceleration
///   a' = a_{i-1} + dw_{i-1} x r + w_{i-1} x (w_{i-1} x r).
/// - Revolute: w_i = w_{i-1} + z_i qdot_i, dw_i = dw_{i-1} + (w_{i-1} x z_i) qdot_i; o_i is on
///   the axis, so body i's point there moves like body i-1's: v_i = v', a_i = a'.
/// - Prismatic: w_i = w_{i-1}, dw_i = dw_{i-1}; body i's point at o_i slides along z_i:
///   v_i = v' + z_i qdot_i, a_i = a' + 2 w_{i-1} x z_i qdot_i (Coriolis; qddot = 0).
/// - A point p of the last body accelerates by a_n + dw_n x (p - o_n) + w_n x (w_n x (p - o_n)):
///   with dw_n that is (d/dt (J qdot)) at qddot = 0, i.e. Jdot qdot of the Jacobian of p.
/// - Newton-Euler backward: body k with mass m_k, centre of mass c_k and inertia I_k (about c_k)
///   needs the force f_k = m_k a_ck (a_ck the acceleration of c_k, as for p above) and the
///   moment about c_k n_k = I_k dw_k + w_k x I_k w_k. Joint i carries bodies i..n-1:
///   revolute tau_i = z_i . sum_{k >= i} (n_k + (c_k - o_i) x f_k), prismatic
///   tau_i = z_i . sum_{k >= i} f_k. Summed as F = sum f_k and N = sum (n_k + c_k x f_k) (about
///   the base origin), the moment about o_i is N - o_i x F: O(n) in all.
/// Checked in tests/chain_motion_test.cpp against finite differences of J, KDL's
/// ChainIdSolver_RNE and the Christoffel symbols of the inertia matrix.
#include <hapsyn/quantities.hpp>

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/QR>

namespace hapsyn {

/// One joint at the current configuration, in the base frame.
struct WorldJoint {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();    ///< unit direction of the joint axis
  /// A point on the axis [m]. Revolute: any point of the axis. Prismatic: the point of body i
  /// (e.g. joint frame i's origin after the joint's motion); any such point gives the same
  /// torques.
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  bool prismatic = false;
};

/// The rigid body moving with joint i, in the base frame at the current configuration.
struct WorldBody {
  double mass = 0.0;                                  ///< [kg]
  Eigen::Vector3d com = Eigen::Vector3d::Zero();      ///< centre of mass [m]
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  ///< about the com, base axes [kg m^2]
};

/// Jdot qdot of the point `point` fixed in the last body (rows omega then v: [rad/s^2; m/s^2]),
/// i.e. the point's acceleration at qddot = 0 — what the task acceleration lacks beyond
/// J qddot.
/// \param joints n joints
/// \param n      the number of joints
/// \param point  the point, fixed in the last body [m, base axes]
/// \param qdot   n joint rates [rad/s or m/s]
/// \param out    6 values
void jacobian_rate_times_rate(const WorldJoint* joints, int n, const Eigen::Vector3d& point, const double* qdot,
                              double out[6]);

/// c = C(q, qdot) qdot [N m or N], n values: the joint torques of the velocity terms alone
/// (Newton-Euler at qddot = 0 without gravity), so that tau = H qddot + c + gravity torque for
/// the inertia H of the same bodies.
/// \param joints n joints
/// \param bodies n bodies, body i moving with joint i
/// \param n      the number of joints
/// \param qdot   n joint rates [rad/s or m/s]
/// \param out    n values
void velocity_torque(const WorldJoint* joints, const WorldBody* bodies, int n, const double* qdot, double* out);

/// Solves J x = b for joint rates x (n = J.cols() values): J square by LU with partial
/// pivoting; J wide (a redundant chain: rows < cols) for the solution of minimum norm, from the
/// Householder QR of J^T (J = R^T Q^T, x = Q R^-T b); J tall (rows > cols) for the least-squares
/// solution, from the QR of J. Factorize once with compute(), solve for several right-hand sides
/// (the rates, then the accelerations). Fixed capacity (rows <= kMaxTask, cols <= kMaxDof):
/// nothing allocates — which is why this is not Eigen's CompleteOrthogonalDecomposition, whose
/// solve takes a heap temporary for a wide matrix. J must have full rank min(rows, cols) (classify
/// singular samples first): a rank-deficient J gives meaningless, possibly infinite values, not
/// an error.
class JointRateSolver {
 public:
  /// Factorizes J (rows <= kMaxTask, cols <= kMaxDof).
  void compute(const TaskJointMatrix& jacobian);
  /// x = J^-1 b (minimum norm, or least squares; see the class).
  /// \param b J.rows() values
  /// \param x J.cols() values
  void solve(const double* b, JointVector& x) const;

 private:
  Eigen::Index rows_ = 0, cols_ = 0;
  Eigen::PartialPivLU<TaskMatrix> lu_;      // square J
  Eigen::HouseholderQR<JointMatrix> qr_;    // of J^T (wide J) or J (tall J)
};

/// One right-hand side: JointRateSolver::compute then solve.
void solve_joint_rates(const TaskJointMatrix& jacobian, const double* b, JointVector& x);

}  // namespace hapsyn
