// hapsyn/chain_motion.hpp: the Jacobian rate term against finite differences of J, the velocity
// torque against KDL's recursive Newton-Euler and against the Christoffel symbols of the
// inertia matrix, and the joint-rate solve (square, redundant, allocation-free use).
#include <hapsyn/chain_motion.hpp>

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdio>
#include <random>
#include <vector>

#ifdef HAPSYN_HAVE_KDL
#include <kdl/chain.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#endif

using namespace hapsyn;

// Eigen's heap goes to malloc, not operator new: counted too (see malloc_counter.hpp).
#include "malloc_counter.hpp"

namespace {

// A test chain in the form KDL builds: T_i = T_{i-1} M_i(q_i) F_i from T_{-1} = base, where M_i
// turns about / slides along the unit axis a_i (in frame T_{i-1}, through its origin) and F_i is
// fixed; body i is given in frame T_i; the point of interest is T_{n-1}'s origin.
struct TestChain {
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Vector3d> axis;
  std::vector<bool> prismatic;
  std::vector<Eigen::Isometry3d> fixed;
  std::vector<WorldBody> bodies;  // in frame T_i
  int n() const { return static_cast<int>(axis.size()); }
};

Eigen::Isometry3d random_pose(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
  t.translation() = 0.4 * Eigen::Vector3d(u(rng), u(rng), u(rng));
  return t;
}

// Mixed revolute / prismatic joints (all revolute when `revolute_only`), oblique axes, offset
// centres of mass and full inertias.
TestChain random_chain(int n, std::mt19937& rng, bool revolute_only = false) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  TestChain c;
  c.base = random_pose(rng);
  for (int i = 0; i < n; ++i) {
    c.axis.push_back(Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized());
    c.prismatic.push_back(!revolute_only && i % 3 == 1);
    c.fixed.push_back(random_pose(rng));
    WorldBody b;
    b.mass = 0.5 + 0.5 * (u(rng) + 1.0);
    b.com = 0.2 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    Eigen::Matrix3d a;
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) a(r, k) = 0.1 * u(rng);
    }
    b.inertia = a * a.transpose() + 0.01 * Eigen::Matrix3d::Identity();
    c.bodies.push_back(b);
  }
  return c;
}

// The world description at q: joints, bodies, and the point (T_{n-1}'s origin).
struct World {
  std::vector<WorldJoint> joints;
  std::vector<WorldBody> bodies;
  std::vector<Eigen::Isometry3d> frames;  // T_i
  Eigen::Vector3d point;
};

World world_at(const TestChain& c, const Eigen::VectorXd& q) {
  World w;
  Eigen::Isometry3d t = c.base;
  for (int i = 0; i < c.n(); ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
    if (c.prismatic[k]) {
      motion.translation() = q(i) * c.axis[k];
    } else {
      motion.linear() = Eigen::AngleAxisd(q(i), c.axis[k]).toRotationMatrix();
    }
    WorldJoint j;
    j.axis = t.linear() * c.axis[k];
    j.prismatic = c.prismatic[k];
    t = t * motion;
    j.origin = t.translation();
    t = t * c.fixed[k];
    w.joints.push_back(j);
    w.frames.push_back(t);
    WorldBody b = c.bodies[k];
    b.com = t * c.bodies[k].com;
    b.inertia = t.linear() * c.bodies[k].inertia * t.linear().transpose();
    w.bodies.push_back(b);
  }
  w.point = t.translation();
  return w;
}

// Geometric Jacobian (6 x n, rows omega then v) of the point p of the last body.
Eigen::MatrixXd jacobian(const World& w, const Eigen::Vector3d& p, int columns) {
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(6, columns);
  for (int i = 0; i < columns; ++i) {
    const WorldJoint& a = w.joints[static_cast<std::size_t>(i)];
    if (a.prismatic) {
      j.col(i).tail<3>() = a.axis;
    } else {
      j.col(i).head<3>() = a.axis;
      j.col(i).tail<3>() = a.axis.cross(p - a.origin);
    }
  }
  return j;
}

// H = sum_b m_b Jv_b^T Jv_b + Jw_b^T I_b Jw_b, each body's Jacobian at its centre of mass.
Eigen::MatrixXd inertia(const TestChain& c, const Eigen::VectorXd& q) {
  const World w = world_at(c, q);
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(c.n(), c.n());
  for (int b = 0; b < c.n(); ++b) {
    const WorldBody& body = w.bodies[static_cast<std::size_t>(b)];
    const Eigen::MatrixXd j = jacobian(w, body.com, b + 1);
    Eigen::MatrixXd full = Eigen::MatrixXd::Zero(6, c.n());
    full.leftCols(b + 1) = j;
    h += body.mass * full.bottomRows<3>().transpose() * full.bottomRows<3>() +
         full.topRows<3>().transpose() * body.inertia * full.topRows<3>();
  }
  return h;
}

Eigen::VectorXd random_vector(int n, std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v(i) = u(rng);
  return v;
}

Eigen::VectorXd velocity_torque_at(const TestChain& c, const Eigen::VectorXd& q, const Eigen::VectorXd& qdot) {
  const World w = world_at(c, q);
  Eigen::VectorXd out(c.n());
  velocity_torque(w.joints.data(), w.bodies.data(), c.n(), qdot.data(), out.data());
  return out;
}

}  // namespace

// Jdot qdot = d/dt (J(q(t))) qdot along q(t) = q + t qdot: central differences of J.
TEST(ChainMotion, JacobianRateMatchesCentralDifferencesOfTheJacobian) {
  std::mt19937 rng(1);
  double worst = 0.0;
  for (int n = 1; n <= kMaxDof; ++n) {
    for (int k = 0; k < 10; ++k) {
      const TestChain c = random_chain(n, rng);
      const Eigen::VectorXd q = random_vector(n, rng, 3.0), qdot = random_vector(n, rng, 2.0);
      const World w = world_at(c, q);
      Eigen::Matrix<double, 6, 1> rate;
      jacobian_rate_times_rate(w.joints.data(), n, w.point, qdot.data(), rate.data());
      const double h = 1e-6;
      const World wp = world_at(c, q + h * qdot), wm = world_at(c, q - h * qdot);
      const Eigen::VectorXd expected =
          (jacobian(wp, wp.point, n) - jacobian(wm, wm.point, n)) * qdot / (2.0 * h);
      const double error = (rate - expected).norm() / (1.0 + expected.norm());
      worst = std::max(worst, error);
      EXPECT_LT(error, 1e-7) << "n = " << n << "\n" << rate.transpose() << "\n" << expected.transpose();
    }
  }
  std::printf("Jdot qdot vs central differences: worst relative error %.3g\n", worst);
}

// c_i = sum_jk (dH_ij/dq_k - 1/2 dH_jk/dq_i) qdot_j qdot_k, dH by central differences.
TEST(ChainMotion, VelocityTorqueMatchesTheChristoffelSymbolsOfTheInertia) {
  std::mt19937 rng(2);
  double worst = 0.0;
  for (int n = 1; n <= kMaxDof; ++n) {
    for (int k = 0; k < 5; ++k) {
      const TestChain c = random_chain(n, rng);
      const Eigen::VectorXd q = random_vector(n, rng, 3.0), qdot = random_vector(n, rng, 2.0);
      const double h = 1e-5;
      std::vector<Eigen::MatrixXd> dh;  // dH/dq_k
      for (int m = 0; m < n; ++m) {
        Eigen::VectorXd qp = q, qm = q;
        qp(m) += h;
        qm(m) -= h;
        dh.push_back((inertia(c, qp) - inertia(c, qm)) / (2.0 * h));
      }
      Eigen::VectorXd expected = Eigen::VectorXd::Zero(n);
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          for (int m = 0; m < n; ++m) {
            expected(i) += (dh[static_cast<std::size_t>(m)](i, j) - 0.5 * dh[static_cast<std::size_t>(i)](j, m)) *
                           qdot(j) * qdot(m);
          }
        }
      }
      const Eigen::VectorXd got = velocity_torque_at(c, q, qdot);
      const double error = (got - expected).norm() / (1.0 + expected.norm());
      worst = std::max(worst, error);
      EXPECT_LT(error, 1e-6) << "n = " << n << "\n" << got.transpose() << "\n" << expected.transpose();
    }
  }
  std::printf("c vs Christoffel symbols of H: worst relative error %.3g\n", worst);
}

// c is quadratic in qdot: c(q, s qdot) = s^2 c(q, qdot), and zero at rest.
TEST(ChainMotion, VelocityTorqueIsQuadraticInTheRates) {
  std::mt19937 rng(3);
  const TestChain c = random_chain(6, rng);
  const Eigen::VectorXd q = random_vector(6, rng, 3.0), qdot = random_vector(6, rng, 2.0);
  const Eigen::VectorXd c1 = velocity_torque_at(c, q, qdot);
  EXPECT_GT(c1.norm(), 1e-3);
  EXPECT_LT((velocity_torque_at(c, q, -3.0 * qdot) - 9.0 * c1).norm(), 1e-12 * (1.0 + 9.0 * c1.norm()));
  EXPECT_EQ(velocity_torque_at(c, q, Eigen::VectorXd::Zero(6)).norm(), 0.0);
}

#ifdef HAPSYN_HAVE_KDL
namespace {
KDL::Vector kdl(const Eigen::Vector3d& v) { return KDL::Vector(v.x(), v.y(), v.z()); }
KDL::Frame kdl(const Eigen::Isometry3d& t) {
  const Eigen::Matrix3d& r = t.linear();
  return KDL::Frame(KDL::Rotation(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)),
                    kdl(t.translation()));
}
KDL::Chain kdl_chain(const TestChain& c) {
  KDL::Chain chain;
  chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), kdl(c.base)));
  for (int i = 0; i < c.n(); ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    const WorldBody& b = c.bodies[k];
    const KDL::RotationalInertia ic(b.inertia(0, 0), b.inertia(1, 1), b.inertia(2, 2), b.inertia(0, 1), b.inertia(0, 2),
                                    b.inertia(1, 2));
    const KDL::Joint joint("j", KDL::Vector::Zero(), kdl(c.axis[k]),
                           c.prismatic[k] ? KDL::Joint::TransAxis : KDL::Joint::RotAxis);
    chain.addSegment(KDL::Segment(joint, kdl(c.fixed[k]), KDL::RigidBodyInertia(b.mass, kdl(b.com), ic)));
  }
  return chain;
}
}  // namespace

// KDL's recursive Newton-Euler with qddot = 0 and no gravity is c.
TEST(ChainMotion, VelocityTorqueMatchesKdlRecursiveNewtonEuler) {
  std::mt19937 rng(4);
  double worst = 0.0;
  for (int n = 1; n <= kMaxDof; ++n) {
    for (int k = 0; k < 10; ++k) {
      const TestChain c = random_chain(n, rng);
      const Eigen::VectorXd q = random_vector(n, rng, 3.0), qdot = random_vector(n, rng, 2.0);
      const KDL::Chain chain = kdl_chain(c);
      KDL::ChainIdSolver_RNE rne(chain, KDL::Vector::Zero());
      KDL::JntArray kq(static_cast<unsigned>(n)), kqd(static_cast<unsigned>(n)), kqdd(static_cast<unsigned>(n)),
          tau(static_cast<unsigned>(n));
      for (int i = 0; i < n; ++i) {
        kq(static_cast<unsigned>(i)) = q(i);
        kqd(static_cast<unsigned>(i)) = qdot(i);
      }
      KDL::Wrenches wrenches(chain.getNrOfSegments(), KDL::Wrench::Zero());
      ASSERT_EQ(rne.CartToJnt(kq, kqd, kqdd, wrenches, tau), 0);
      Eigen::VectorXd expected(n);
      for (int i = 0; i < n; ++i) expected(i) = tau(static_cast<unsigned>(i));
      const Eigen::VectorXd got = velocity_torque_at(c, q, qdot);
      const double error = (got - expected).norm() / (1.0 + expected.norm());
      worst = std::max(worst, error);
      EXPECT_LT(error, 1e-9) << "n = " << n << "\n" << got.transpose() << "\n" << expected.transpose();
    }
  }
  std::printf("c vs KDL ChainIdSolver_RNE: worst relative error %.3g\n", worst);
}
#endif

TEST(ChainMotion, JointRatesSolveSquareAndRedundantJacobians) {
  std::mt19937 rng(5);
  for (int n = 1; n <= kMaxDof; ++n) {
    const TestChain c = random_chain(n, rng, true);
    const World w = world_at(c, random_vector(n, rng, 3.0));
    const Eigen::MatrixXd full = jacobian(w, w.point, n);
    const int rows = std::min(n, 6);
    // Square: the first `rows` rows; redundant (n > 6): all six.
    TaskJointMatrix j = full.topRows(rows);
    const Eigen::VectorXd b = random_vector(rows, rng, 1.0);
    JointVector x;
    solve_joint_rates(j, b.data(), x);
    ASSERT_EQ(x.size(), n);
    EXPECT_LT((j * x - b).norm(), 1e-10 * (1.0 + b.norm())) << "n = " << n;
    if (n > rows) {
      // Minimum norm: x has no component in J's null space.
      const Eigen::MatrixXd jd = j;
      const Eigen::FullPivLU<Eigen::MatrixXd> lu(jd);
      const Eigen::MatrixXd kernel = lu.kernel();
      EXPECT_LT((kernel.transpose() * x).norm(), 1e-10 * (1.0 + x.norm()));
    }
  }
  // Wide with fewer rows than 6 (a 3-row position task on a 4-joint chain), two right-hand sides.
  const TestChain c = random_chain(4, rng, true);
  const World w = world_at(c, random_vector(4, rng, 3.0));
  const TaskJointMatrix j = jacobian(w, w.point, 4).bottomRows(3);
  JointRateSolver solver;
  solver.compute(j);
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector3d b = random_vector(3, rng, 1.0);
    JointVector x;
    solver.solve(b.data(), x);
    EXPECT_LT((j * x - b).norm(), 1e-10);
  }
  // Tall (more rows than joints): the least-squares solution, J^T (J x - b) = 0.
  const TestChain t = random_chain(3, rng, true);
  const World wt = world_at(t, random_vector(3, rng, 3.0));
  const TaskJointMatrix tall = jacobian(wt, wt.point, 3);
  const Eigen::VectorXd b6 = random_vector(6, rng, 1.0);
  JointVector x3;
  solve_joint_rates(tall, b6.data(), x3);
  ASSERT_EQ(x3.size(), 3);
  EXPECT_GT((tall * x3 - b6).norm(), 1e-3) << "not consistent: a real least-squares problem";
  const Eigen::MatrixXd jt = tall;
  const Eigen::VectorXd residual = jt * Eigen::VectorXd(x3) - b6;
  EXPECT_LT((jt.transpose() * residual).norm(), 1e-10);
}

#ifdef HAPSYN_COUNT_MALLOC
TEST(ChainMotion, NothingAllocates) {
  {  // the counter sees Eigen's heap
    const long before = g_mallocs.load();
    const Eigen::VectorXd v = Eigen::VectorXd::Zero(100);
    EXPECT_GT(g_mallocs.load() - before, 0) << v.size();
  }
  std::mt19937 rng(6);
  for (int n : {3, 6, 7}) {
    const TestChain c = random_chain(n, rng);
    const World w = world_at(c, random_vector(n, rng, 3.0));
    const Eigen::VectorXd qdot = random_vector(n, rng, 2.0);
    const TaskJointMatrix square = jacobian(w, w.point, n).topRows(std::min(n, 6));
    const TaskJointMatrix wide = jacobian(w, w.point, n).bottomRows(std::min(n, 6) - 1);
    const TaskJointMatrix tall = jacobian(w, w.point, n).leftCols(std::max(1, n - 2));
    const double b[6] = {0.1, -0.2, 0.3, 0.4, -0.5, 0.6};
    double rate[6], c_out[kMaxDof];
    JointVector x;
    JointRateSolver solver;
    const long before = g_mallocs.load();
    jacobian_rate_times_rate(w.joints.data(), n, w.point, qdot.data(), rate);
    velocity_torque(w.joints.data(), w.bodies.data(), n, qdot.data(), c_out);
    for (const TaskJointMatrix* j : {&square, &wide, &tall}) {
      solver.compute(*j);
      solver.solve(b, x);
      solve_joint_rates(*j, b, x);
    }
    EXPECT_EQ(g_mallocs.load() - before, 0) << "n = " << n;
  }
}
#endif
