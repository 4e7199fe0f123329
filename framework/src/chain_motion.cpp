// The velocity terms of a serial chain in world coordinates (hapsyn/chain_motion.hpp has the
// derivation): one forward sweep for the bodies' velocities and accelerations at qddot = 0, then
// the Jacobian rate term from the last body, or one backward Newton-Euler sweep for c.
#include <hapsyn/chain_motion.hpp>

#include <Eigen/Geometry>
#include <array>
#include <cassert>
#include <cstddef>

namespace hapsyn {

namespace {

using Eigen::Vector3d;

// Body i's motion at qddot = 0: angular velocity and acceleration, and the velocity and
// acceleration of its point at o_i.
struct BodyMotion {
  Vector3d w, dw, v, a;
};

// Acceleration of the point p of a body moving as m (point of reference at `origin`).
Vector3d point_acceleration(const BodyMotion& m, const Vector3d& origin, const Vector3d& p) {
  const Vector3d r = p - origin;
  return m.a + m.dw.cross(r) + m.w.cross(m.w.cross(r));
}

// The forward sweep base to tip; motion[i] for i < n.
void forward_sweep(const WorldJoint* joints, int n, const double* qdot, std::array<BodyMotion, kMaxDof>& motion) {
  assert(n >= 1 && n <= kMaxDof);
  BodyMotion previous{Vector3d::Zero(), Vector3d::Zero(), Vector3d::Zero(), Vector3d::Zero()};  // the base
  Vector3d previous_origin = Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const WorldJoint& j = joints[i];
    const Vector3d r = j.origin - previous_origin;
    // Body i-1's point at o_i; the axis turns with body i-1 (dz/dt = w_{i-1} x z).
    const Vector3d v = previous.v + previous.w.cross(r);
    const Vector3d a = point_acceleration(previous, previous_origin, j.origin);
    const Vector3d axis_rate = previous.w.cross(j.axis) * qdot[i];
    BodyMotion& m = motion[static_cast<std::size_t>(i)];
    if (j.prismatic) {
      m.w = previous.w;
      m.dw = previous.dw;
      m.v = v + j.axis * qdot[i];
      m.a = a + 2.0 * axis_rate;
    } else {
      m.w = previous.w + j.axis * qdot[i];
      m.dw = previous.dw + axis_rate;
      m.v = v;
      m.a = a;
    }
    previous = m;
    previous_origin = j.origin;
  }
}

}  // namespace

void jacobian_rate_times_rate(const WorldJoint* joints, int n, const Vector3d& point, const double* qdot,
                              double out[6]) {
  std::array<BodyMotion, kMaxDof> motion;
  forward_sweep(joints, n, qdot, motion);
  const BodyMotion& last = motion[static_cast<std::size_t>(n - 1)];
  const Vector3d a = point_acceleration(last, joints[n - 1].origin, point);
  for (int r = 0; r < 3; ++r) {
    out[r] = last.dw(r);
    out[3 + r] = a(r);
  }
}

void velocity_torque(const WorldJoint* joints, const WorldBody* bodies, int n, const double* qdot, double* out) {
  std::array<BodyMotion, kMaxDof> motion;
  forward_sweep(joints, n, qdot, motion);
  // Force and moment about the base origin of bodies k..n-1.
  Vector3d force = Vector3d::Zero(), moment = Vector3d::Zero();
  for (int k = n - 1; k >= 0; --k) {
    const WorldBody& b = bodies[k];
    const BodyMotion& m = motion[static_cast<std::size_t>(k)];
    const WorldJoint& j = joints[k];
    const Vector3d f = b.mass * point_acceleration(m, j.origin, b.com);
    force += f;
    moment += b.inertia * m.dw + m.w.cross(b.inertia * m.w) + b.com.cross(f);
    out[k] = j.prismatic ? j.axis.dot(force) : j.axis.dot(moment - j.origin.cross(force));
  }
}

void JointRateSolver::compute(const TaskJointMatrix& jacobian) {
  rows_ = jacobian.rows();
  cols_ = jacobian.cols();
  if (rows_ == cols_) {
    lu_.compute(jacobian);
  } else if (rows_ < cols_) {
    qr_.compute(jacobian.transpose());
  } else {
    qr_.compute(jacobian);
  }
}

void JointRateSolver::solve(const double* b, JointVector& x) const {
  // A column vector of compile-time width 1 and bounded height, so that Eigen's solvers size
  // their temporaries from it without the heap.
  using TaskVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxTask, 1>;
  const Eigen::Map<const TaskVector> rhs(b, rows_);
  if (rows_ == cols_) {
    x = lu_.solve(TaskVector(rhs));
    return;
  }
  if (rows_ < cols_) {
    // J = (Q R)^T = R^T Q^T with R square (rows_): z = R^-T b, x = Q (z, 0), which lies in the
    // row space of J: the solution of minimum norm.
    x.setZero(cols_);
    x.head(rows_) = rhs;
    qr_.matrixQR().topLeftCorner(rows_, rows_).triangularView<Eigen::Upper>().transpose().solveInPlace(x.head(rows_));
    x.applyOnTheLeft(qr_.householderQ());
    return;
  }
  // J = Q R: x = R^-1 (Q^T b)_(1..cols).
  TaskVector y = rhs;
  y.applyOnTheLeft(qr_.householderQ().adjoint());
  x = qr_.matrixQR().topLeftCorner(cols_, cols_).triangularView<Eigen::Upper>().solve(y.head(cols_));
}

void solve_joint_rates(const TaskJointMatrix& jacobian, const double* b, JointVector& x) {
  JointRateSolver solver;
  solver.compute(jacobian);
  solver.solve(b, x);
}

}  // namespace hapsyn
