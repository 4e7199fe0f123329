// Tests of the serial_chain model: the Chain's kinematics and dynamics against finite
// differences, KDL and a second formulation; the chain files (URDF, DH) against each other and
// against the haptic6r mechanism's own model; fixed-joint folding; parameters; every error path.
#include "chain.hpp"
#include "chain_template.hpp"
#include "haptic6r.hpp"
#include "serial_chain.hpp"

#include "test_support.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/options.hpp>

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iomanip>
#include <random>
#include <string>
#include <vector>

#ifdef HAPSYN_HAVE_KDL
#include <kdl/chain.hpp>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#endif

using namespace hapsyn;
using namespace hapsyn::plugins;
using hapsyn::test::expect_error;

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string share(const std::string& name) { return std::string(HAPSYN_SOURCE_DIR) + "/share/serial_chain/" + name; }

// A chain file with the base and tip links of a URDF.
struct ChainFile {
  std::string name, base, tip;  // base / tip empty for a DH table
};

std::vector<ChainFile> shipped_files() {
  std::vector<ChainFile> files = {{"haptic6r_dh.json", "", ""}, {"ur5_like_dh.json", "", ""}};
#ifdef HAPSYN_HAVE_URDFDOM
  files.push_back({"haptic6r.urdf", "base_link", "ee_link"});
  files.push_back({"ur5_like.urdf", "world", "tool0"});
  files.push_back({"phantom_3r.urdf", "world", "stylus_tip"});
#endif
  return files;
}

ChainTemplate load(const ChainFile& f) {
  return f.base.empty() ? ChainTemplate::from_dh_file(share(f.name)) : ChainTemplate::from_urdf(share(f.name), f.base, f.tip);
}

std::vector<double> nominal(const ChainTemplate& t) {
  std::vector<double> v;
  for (const ChainParameter& p : t.parameters()) v.push_back(p.nominal);
  return v;
}

Chain instantiate(const ChainTemplate& t, const std::vector<double>& values) {
  Chain c;
  t.instantiate(values.data(), nullptr, c);
  return c;
}

Chain nominal_chain(const ChainTemplate& t) { return instantiate(t, nominal(t)); }

double& value_of(const ChainTemplate& t, std::vector<double>& values, const std::string& name) {
  const int i = t.find(name);
  EXPECT_GE(i, 0) << name;
  return values.at(static_cast<std::size_t>(i));
}

std::vector<double> random_q(int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-kPi, kPi);
  std::vector<double> q(static_cast<std::size_t>(n));
  for (double& x : q) x = u(rng);
  return q;
}

// What the tests compare: one configuration's kinematics and dynamics.
struct State {
  ChainFrames frames;
  TaskJointMatrix jacobian;
  JointMatrix inertia;
  JointVector gravity;
};

State state_at(const Chain& c, const std::vector<double>& q) {
  State s;
  chain_frames(c, q.data(), s.frames);
  chain_jacobian(c, s.frames, s.jacobian);
  chain_inertia(c, s.frames, s.inertia);
  chain_gravity(c, s.frames, s.gravity);
  return s;
}

double pose_error(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm() + (a.linear() - b.linear()).norm();
}

// Expects the same tip pose, Jacobian, inertia and gravity at random configurations.
void expect_same_chain(const Chain& a, const Chain& b, int samples = 20, double tolerance = 1e-9) {
  ASSERT_EQ(a.dof(), b.dof());
  std::mt19937 rng(7);
  for (int k = 0; k < samples; ++k) {
    const std::vector<double> q = random_q(a.dof(), rng);
    const State sa = state_at(a, q), sb = state_at(b, q);
    EXPECT_LT(pose_error(sa.frames.tip, sb.frames.tip), tolerance);
    EXPECT_LT((sa.jacobian - sb.jacobian).norm(), tolerance);
    EXPECT_LT((sa.inertia - sb.inertia).norm(), tolerance) << sa.inertia << "\n\n" << sb.inertia;
    EXPECT_LT((sa.gravity - sb.gravity).norm(), tolerance) << sa.gravity.transpose() << "\n" << sb.gravity.transpose();
  }
}

// A random chain with mixed revolute / prismatic joints, oblique axes, offset coms and full
// inertias (what no shipped file has).
Chain random_chain(int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto vec = [&] { return Eigen::Vector3d(u(rng), u(rng), u(rng)); };
  auto pose = [&] {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
    t.translation() = 0.3 * vec();
    return t;
  };
  Chain c;
  for (int i = 0; i < n; ++i) {
    ChainJoint j;
    j.name = "j" + std::to_string(i);
    j.type = i % 3 == 1 ? ChainJointType::kPrismatic : ChainJointType::kRevolute;
    j.origin = pose();
    j.axis = vec().normalized();
    c.joints.push_back(j);
    ChainBody b;
    b.mass = 0.5 + 0.5 * (u(rng) + 1.0);
    b.com = 0.2 * vec();
    const Eigen::Matrix3d a = 0.1 * Eigen::Matrix3d::Random();
    b.inertia = a * a.transpose() + 0.01 * Eigen::Matrix3d::Identity();
    c.bodies.push_back(b);
  }
  c.tip = pose();
  c.gravity = Eigen::Vector3d(0.5, -1.0, -9.81);
  return c;
}

// Every chain the dynamics tests run on: the shipped files and random chains.
std::vector<std::pair<std::string, Chain>> test_chains() {
  std::vector<std::pair<std::string, Chain>> chains;
  for (const ChainFile& f : shipped_files()) chains.emplace_back(f.name, nominal_chain(load(f)));
  std::mt19937 rng(3);
  for (int n = 1; n <= kMaxChainJoints; ++n) chains.emplace_back("random " + std::to_string(n), random_chain(n, rng));
  return chains;
}

// Writes a test file into the test temporary directory and returns its path.
std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "chain_test_" + name;
  std::ofstream(path) << text;
  return path;
}

// The rotation vector of R (small angles): the log map.
Eigen::Vector3d rotation_vector(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.angle() * aa.axis();
}

}  // namespace

// ---- Chain: kinematics and dynamics ----

// chain_well_conditioned against JacobiSVD's sigma_min > tolerance sigma_max on matrices of known
// condition (U diag V^T, random orthogonal U, V) from far below to far above 1 / tolerance, with
// conditions within 1e-3 of the threshold, exactly singular ones, and non-square ones.
TEST(Chain, WellConditionedIsTheSvdsAnswer) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), exponent(0.0, 12.0), near(-1e-3, 1e-3);
  auto orthogonal = [&](int n) {
    const Eigen::MatrixXd a = Eigen::MatrixXd::NullaryExpr(n, n, [&] { return unit(rng); });
    return Eigen::MatrixXd(Eigen::HouseholderQR<Eigen::MatrixXd>(a).householderQ());
  };
  const double tolerance = 1e-6;
  int regular = 0, singular = 0;
  for (int k = 0; k < 3000; ++k) {
    const int rows = k % 10 == 0 ? 5 : 6, cols = k % 10 == 1 ? 5 : 6;
    const int m = std::min(rows, cols);
    const double condition = k % 3 == 0 ? std::pow(10.0, 6.0 + near(rng)) : std::pow(10.0, exponent(rng));
    Eigen::VectorXd sigma(m);
    for (int i = 0; i < m; ++i) sigma(i) = std::pow(condition, -static_cast<double>(i) / (m - 1));
    if (k % 50 == 7) sigma(m - 1) = 0.0;  // exactly singular
    Eigen::MatrixXd diag = Eigen::MatrixXd::Zero(rows, cols);
    diag.topLeftCorner(m, m) = sigma.asDiagonal();
    const hapsyn::TaskJointMatrix j = 3.0 * orthogonal(rows) * diag * orthogonal(cols).transpose();
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd{Eigen::MatrixXd(j)};
    const auto& s = svd.singularValues();
    const bool expected = s(s.size() - 1) > tolerance * s(0);
    EXPECT_EQ(hapsyn::plugins::chain_well_conditioned(j, tolerance), expected) << "condition " << condition << ", "
                                                                                << rows << " x " << cols;
    (expected ? regular : singular) += 1;
  }
  EXPECT_GT(regular, 1000);
  EXPECT_GT(singular, 1000);
}

TEST(Chain, JacobianMatchesCentralDifferencesOfFrames) {
  for (const auto& [name, chain] : test_chains()) {
    SCOPED_TRACE(name);
    std::mt19937 rng(11);
    for (int k = 0; k < 5; ++k) {
      std::vector<double> q = random_q(chain.dof(), rng);
      const State s = state_at(chain, q);
      const double h = 1e-6;
      for (int i = 0; i < chain.dof(); ++i) {
        std::vector<double> qp = q, qm = q;
        qp[static_cast<std::size_t>(i)] += h;
        qm[static_cast<std::size_t>(i)] -= h;
        ChainFrames fp, fm;
        chain_frames(chain, qp.data(), fp);
        chain_frames(chain, qm.data(), fm);
        const Eigen::Vector3d v = (fp.tip.translation() - fm.tip.translation()) / (2 * h);
        const Eigen::Vector3d w = rotation_vector(fp.tip.linear() * fm.tip.linear().transpose()) / (2 * h);
        EXPECT_LT((s.jacobian.col(i).head<3>() - w).norm(), 1e-7) << "joint " << i;
        EXPECT_LT((s.jacobian.col(i).tail<3>() - v).norm(), 1e-7) << "joint " << i;
      }
    }
  }
}

// A second formulation: H = sum_i J_com_i^T m_i J_com_i + J_w_i^T R_i I_i R_i^T J_w_i with each
// body's Jacobians built column by column; tau_g = -sum_i J_com_i^T m_i g.
TEST(Chain, InertiaAndGravityMatchTheSumOverBodies) {
  for (const auto& [name, chain] : test_chains()) {
    SCOPED_TRACE(name);
    std::mt19937 rng(5);
    for (int k = 0; k < 5; ++k) {
      const std::vector<double> q = random_q(chain.dof(), rng);
      const State s = state_at(chain, q);
      const int n = chain.dof();
      Eigen::MatrixXd h = Eigen::MatrixXd::Zero(n, n);
      Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
      for (int b = 0; b < n; ++b) {
        const ChainBody& body = chain.bodies[static_cast<std::size_t>(b)];
        const Eigen::Isometry3d& fb = s.frames.joint[static_cast<std::size_t>(b)];
        const Eigen::Vector3d c = fb * body.com;
        Eigen::MatrixXd jv = Eigen::MatrixXd::Zero(3, n), jw = Eigen::MatrixXd::Zero(3, n);
        for (int i = 0; i <= b; ++i) {
          const ChainJoint& j = chain.joints[static_cast<std::size_t>(i)];
          const Eigen::Isometry3d& fi = s.frames.joint[static_cast<std::size_t>(i)];
          const Eigen::Vector3d z = fi.linear() * j.axis;
          if (j.type == ChainJointType::kRevolute) {
            jw.col(i) = z;
            jv.col(i) = z.cross(c - fi.translation());
          } else {
            jv.col(i) = z;
          }
        }
        const Eigen::Matrix3d iw = fb.linear() * body.inertia * fb.linear().transpose();
        h += body.mass * jv.transpose() * jv + jw.transpose() * iw * jw;
        g -= jv.transpose() * (body.mass * chain.gravity);
      }
      EXPECT_LT((s.inertia - h).norm(), 1e-9 * (1.0 + h.norm()));
      EXPECT_LT((s.gravity - g).norm(), 1e-9 * (1.0 + g.norm()));
      EXPECT_LT((s.inertia - s.inertia.transpose()).norm(), 1e-12 * (1.0 + h.norm()));
    }
  }
}

// The gravity torque is the gradient of the potential energy V(q) = -sum_i m_i g . c_i(q).
TEST(Chain, GravityIsTheGradientOfThePotentialEnergy) {
  for (const auto& [name, chain] : test_chains()) {
    SCOPED_TRACE(name);
    auto energy = [&chain = chain](const std::vector<double>& q) {
      ChainFrames f;
      chain_frames(chain, q.data(), f);
      double v = 0.0;
      for (int b = 0; b < chain.dof(); ++b) {
        const ChainBody& body = chain.bodies[static_cast<std::size_t>(b)];
        v -= body.mass * chain.gravity.dot(f.joint[static_cast<std::size_t>(b)] * body.com);
      }
      return v;
    };
    std::mt19937 rng(9);
    const std::vector<double> q = random_q(chain.dof(), rng);
    const State s = state_at(chain, q);
    for (int i = 0; i < chain.dof(); ++i) {
      std::vector<double> qp = q, qm = q;
      qp[static_cast<std::size_t>(i)] += 1e-6;
      qm[static_cast<std::size_t>(i)] -= 1e-6;
      EXPECT_NEAR(s.gravity(i), (energy(qp) - energy(qm)) / 2e-6, 1e-6 * (1.0 + s.gravity.norm()));
    }
  }
}

#ifdef HAPSYN_HAVE_KDL
namespace {

KDL::Vector kdl_vector(const Eigen::Vector3d& v) { return KDL::Vector(v.x(), v.y(), v.z()); }

KDL::Frame kdl_frame(const Eigen::Isometry3d& t) {
  const Eigen::Matrix3d& r = t.linear();
  return KDL::Frame(KDL::Rotation(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)),
                    kdl_vector(t.translation()));
}

KDL::RigidBodyInertia kdl_inertia(const ChainBody& b) {
  const Eigen::Matrix3d& i = b.inertia;
  return KDL::RigidBodyInertia(b.mass, kdl_vector(b.com),
                               KDL::RotationalInertia(i(0, 0), i(1, 1), i(2, 2), i(0, 1), i(0, 2), i(1, 2)));
}

// The KDL chain of a Chain, built from its numbers only: segment i's joint turns about (slides
// along) the axis through O_i's origin in the parent frame, its tip frame is joint frame i and
// carries body i; a last fixed segment holds T_tip.
KDL::Chain kdl_chain(const Chain& c) {
  KDL::Chain k;
  for (int i = 0; i < c.dof(); ++i) {
    const ChainJoint& j = c.joints[static_cast<std::size_t>(i)];
    const KDL::Joint joint(j.name, kdl_vector(j.origin.translation()), kdl_vector(j.origin.linear() * j.axis),
                           j.type == ChainJointType::kRevolute ? KDL::Joint::RotAxis : KDL::Joint::TransAxis);
    k.addSegment(KDL::Segment(j.name, joint, kdl_frame(j.origin), kdl_inertia(c.bodies[static_cast<std::size_t>(i)])));
  }
  k.addSegment(KDL::Segment("tip", KDL::Joint(KDL::Joint::None), kdl_frame(c.tip)));
  return k;
}

struct KdlState {
  Eigen::MatrixXd jacobian, inertia;
  Eigen::VectorXd gravity;
};

KdlState kdl_state(const KDL::Chain& k, const Eigen::Vector3d& gravity, const std::vector<double>& q) {
  const unsigned n = k.getNrOfJoints();
  KDL::JntArray kq(n);
  for (unsigned i = 0; i < n; ++i) kq(i) = q[i];
  KDL::ChainDynParam dyn(k, kdl_vector(gravity));
  KDL::ChainJntToJacSolver jac_solver(k);
  KDL::JntSpaceInertiaMatrix kh(n);
  KDL::JntArray kg(n);
  KDL::Jacobian kj(n);
  EXPECT_GE(dyn.JntToMass(kq, kh), 0);
  EXPECT_GE(dyn.JntToGravity(kq, kg), 0);
  EXPECT_GE(jac_solver.JntToJac(kq, kj), 0);
  KdlState s{Eigen::MatrixXd(6, n), kh.data, kg.data};
  s.jacobian.topRows(3) = kj.data.bottomRows(3);  // KDL's rows are (v, omega); ours (omega, v)
  s.jacobian.bottomRows(3) = kj.data.topRows(3);
  return s;
}

// KDL's recursive Newton-Euler: tau for q, qdot, qddot under `gravity`.
Eigen::VectorXd kdl_torque(const KDL::Chain& k, const Eigen::Vector3d& gravity, const double* q, const double* qdot,
                           const double* qddot) {
  const unsigned n = k.getNrOfJoints();
  KDL::JntArray kq(n), kqd(n), kqdd(n), tau(n);
  for (unsigned i = 0; i < n; ++i) {
    kq(i) = q[i];
    kqd(i) = qdot[i];
    kqdd(i) = qddot[i];
  }
  KDL::ChainIdSolver_RNE rne(k, kdl_vector(gravity));
  KDL::Wrenches wrenches(k.getNrOfSegments(), KDL::Wrench::Zero());
  EXPECT_GE(rne.CartToJnt(kq, kqd, kqdd, wrenches, tau), 0);
  return tau.data;
}

}  // namespace

// tau = H qddot + c + g with c from hapsyn/chain_motion.hpp on chain_world_joints / _bodies,
// against KDL's recursive Newton-Euler, on the shipped files and random chains with prismatic
// joints, oblique axes and full inertias.
TEST(Chain, FullInverseDynamicsMatchesKdlRecursiveNewtonEuler) {
  double worst = 0.0;
  for (const auto& [name, chain] : test_chains()) {
    SCOPED_TRACE(name);
    const KDL::Chain k = kdl_chain(chain);
    const int n = chain.dof();
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(-2.0, 2.0);
    for (int sample = 0; sample < 20; ++sample) {
      const std::vector<double> q = random_q(n, rng);
      Eigen::VectorXd qdot(n), qddot(n);
      for (int i = 0; i < n; ++i) {
        qdot(i) = u(rng);
        qddot(i) = u(rng);
      }
      const State s = state_at(chain, q);
      std::array<WorldJoint, kMaxChainJoints> joints;
      std::array<WorldBody, kMaxChainJoints> bodies;
      chain_world_joints(chain, s.frames, joints.data());
      chain_world_bodies(chain, s.frames, bodies.data());
      Eigen::VectorXd c(n);
      velocity_torque(joints.data(), bodies.data(), n, qdot.data(), c.data());
      const Eigen::VectorXd tau = Eigen::MatrixXd(s.inertia) * qddot + c + Eigen::VectorXd(s.gravity);
      const Eigen::VectorXd expected = kdl_torque(k, chain.gravity, q.data(), qdot.data(), qddot.data());
      const double error = (tau - expected).norm() / (1.0 + expected.norm());
      worst = std::max(worst, error);
      EXPECT_LT(error, 1e-9) << tau.transpose() << "\n" << expected.transpose();
    }
  }
  std::printf("chain: tau = H qddot + c + g vs KDL RNE: worst relative error %.3g\n", worst);
}

// The same through the serial_chain plugin's solve(): its joint rates and accelerations for a
// random demanded motion, base and tool frames, every task; the torque of its H, c and g is KDL's.
TEST(Chain, PluginsDemandedMotionTorqueMatchesKdl) {
  double worst = 0.0;
  int checked = 0;
  for (const char* task : {"pose", "position", "position_axis"}) {
    Json o{{"dh_file", task == std::string("pose") ? "serial_chain/haptic6r_dh.json" : "serial_chain/ur5_like_dh.json"},
           {"task", task}, {"base_xyz", {0.1, -0.2, 0.3}}, {"base_rpy", {10, -20, 30}},
           {"tool_xyz", {0.02, 0.0, 0.05}}, {"tool_rpy", {0, 30, 45}}};
    const SerialChain m(make_options<SerialChainOptions>(o));
    std::vector<double> design;
    for (const VariableDecl& v : m.variables()) design.insert(design.end(), static_cast<std::size_t>(v.size), v.default_lower[0]);
    const auto model = m.build(design.data());
    const Chain& chain = static_cast<const SerialChainModel&>(*model).chain();
    const KDL::Chain k = kdl_chain(chain);
    const auto scratch = m.make_scratch();
    std::mt19937 rng(19);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int sample = 0; sample < 20; ++sample) {
      ChainFrames f;
      const std::vector<double> q0 = random_q(chain.dof(), rng);
      chain_frames(chain, q0.data(), f);
      // The scene pose of P whose target is this tip pose: T_S^P = T_S^B T_B^E T_E^P.
      const Eigen::Isometry3d p = m.setup().base_from_scene.inverse() * f.tip * m.setup().sample_to_tip.inverse();
      const Eigen::Quaterniond rot(p.linear());
      const double pose[7] = {p.translation().x(), p.translation().y(), p.translation().z(), rot.w(), rot.x(), rot.y(), rot.z()};
      double twist[6], twist_rate[6];
      for (int r = 0; r < 6; ++r) {
        twist[r] = u(rng);
        twist_rate[r] = u(rng);
      }
      SampleQuantities out;
      out.twist = twist;
      out.twist_rate = twist_rate;
      model->solve(pose, kNeedInertia | kNeedGravity | kNeedJointVelocity | kNeedJointAcceleration | kNeedVelocityTorque,
                   *scratch, out);
      if (out.status != SampleStatus::kReachable) continue;
      ++checked;
      const Eigen::VectorXd tau = Eigen::MatrixXd(out.inertia) * Eigen::VectorXd(out.joint_acceleration) +
                                  Eigen::VectorXd(out.velocity_torque) + Eigen::VectorXd(out.gravity);
      const Eigen::VectorXd expected =
          kdl_torque(k, chain.gravity, out.q.data(), out.joint_velocity.data(), out.joint_acceleration.data());
      const double error = (tau - expected).norm() / (1.0 + expected.norm());
      worst = std::max(worst, error);
      EXPECT_LT(error, 1e-9) << task << "\n" << tau.transpose() << "\n" << expected.transpose();
    }
  }
  EXPECT_GT(checked, 40);
  std::printf("serial_chain solve(): tau = H qddot + c + g vs KDL RNE: worst relative error %.3g (%d samples)\n", worst,
              checked);
}

TEST(Chain, JacobianInertiaAndGravityMatchKdl) {
  for (const auto& [name, chain] : test_chains()) {
    SCOPED_TRACE(name);
    const KDL::Chain k = kdl_chain(chain);
    std::mt19937 rng(13);
    for (int sample = 0; sample < 20; ++sample) {
      const std::vector<double> q = random_q(chain.dof(), rng);
      const State s = state_at(chain, q);
      const KdlState ks = kdl_state(k, chain.gravity, q);
      EXPECT_LT((s.jacobian - ks.jacobian).norm(), 1e-9);
      EXPECT_LT((s.inertia - ks.inertia).norm(), 1e-9) << s.inertia << "\n\n" << ks.inertia;
      EXPECT_LT((s.gravity - ks.gravity).norm(), 1e-9) << s.gravity.transpose() << "\n" << ks.gravity.transpose();
    }
  }
}
#endif  // HAPSYN_HAVE_KDL

TEST(Chain, InertiaIsPositiveDefiniteForChainsWithMass) {
  for (const auto& [name, chain] : test_chains()) {
    SCOPED_TRACE(name);
    std::mt19937 rng(17);
    const State s = state_at(chain, random_q(chain.dof(), rng));
    const Eigen::MatrixXd h = s.inertia;
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(h).eigenvalues().minCoeff(), 0.0) << h;
  }
}

TEST(Chain, SphericalWristWithZeroLengthLinksRotatesAboutOnePoint) {
  // Three revolute joints whose frames all sit at the base origin (a = d = 0): the tip does not
  // move, every mass sits on every axis (no gravity torque), only the end effector's rotational
  // inertia enters H.
  Json doc = {{"format", "hapsyn-dh"}, {"format_version", 1}, {"convention", "dh"},
              {"units", {{"length", "m"}, {"angle", "deg"}}},
              {"joints", Json::array({{{"joint", "w1"}, {"theta", 0}, {"d", 0}, {"a", 0}, {"alpha", 90}},
                                      {{"joint", "w2"}, {"theta", 0}, {"d", 0}, {"a", 0}, {"alpha", -90}},
                                      {{"joint", "w3"}, {"theta", 0}, {"d", 0}, {"a", 0}, {"alpha", 0}}})},
              {"mass_model", {{"kind", "fennel"}, {"motor_mass", {1.0, 2.0, 3.0}}}}};
  const ChainTemplate t = ChainTemplate::from_dh_file(write_file("wrist.json", doc.dump()));
  const Chain c = nominal_chain(t);
  const FennelMassModel defaults;
  EXPECT_DOUBLE_EQ(c.bodies[0].mass, defaults.motor_mass_factor * 2.0);  // motor 2 only: no tube
  EXPECT_DOUBLE_EQ(c.bodies[1].mass, defaults.motor_mass_factor * 3.0);
  EXPECT_DOUBLE_EQ(c.bodies[2].mass, defaults.ee_mass);
  EXPECT_TRUE(c.bodies[0].inertia.isZero(0.0));
  std::mt19937 rng(19);
  for (int k = 0; k < 10; ++k) {
    const State s = state_at(c, random_q(3, rng));
    EXPECT_LT(s.frames.tip.translation().norm(), 1e-15);
    EXPECT_LT(s.jacobian.bottomRows(3).norm(), 1e-15);
    EXPECT_LT(s.gravity.norm(), 1e-12);
    const double r = 0.5 * defaults.ee_diameter, h = defaults.ee_length, m = defaults.ee_mass;
    const Eigen::Matrix3d ee_local =
        Eigen::Vector3d(m * (3 * r * r + h * h) / 12, m * (3 * r * r + h * h) / 12, m * r * r / 2).asDiagonal();
    const Eigen::Matrix3d ee = s.frames.tip.linear() * ee_local * s.frames.tip.linear().transpose();
    const Eigen::Matrix3d jw = s.jacobian.topRows(3);
    EXPECT_LT((s.inertia - jw.transpose() * ee * jw).norm(), 1e-15);
  }
}

// ---- ChainTemplate: the shipped files ----

TEST(ChainTemplate, ShippedFilesLoadWithTheirJointCounts) {
  for (const ChainFile& f : shipped_files()) {
    SCOPED_TRACE(f.name);
    const ChainTemplate t = load(f);
    const int expected = f.name.rfind("phantom", 0) == 0 ? 3 : 6;
    EXPECT_EQ(t.dof(), expected);
    const Chain c = nominal_chain(t);
    EXPECT_EQ(c.dof(), expected);
    EXPECT_EQ(t.source(), share(f.name));
    EXPECT_EQ(t.fennel_mass_model() != nullptr, f.name == "haptic6r_dh.json");
  }
}

#ifdef HAPSYN_HAVE_URDFDOM
TEST(ChainTemplate, UrdfAndDhFormsOfHaptic6rAreTheSameChain) {
  const Chain dh = nominal_chain(ChainTemplate::from_dh_file(share("haptic6r_dh.json")));
  const Chain urdf = nominal_chain(ChainTemplate::from_urdf(share("haptic6r.urdf"), "base_link", "ee_link"));
  expect_same_chain(dh, urdf);
  for (int i = 0; i < 6; ++i) {
    EXPECT_LT(pose_error(dh.joints[static_cast<std::size_t>(i)].origin, urdf.joints[static_cast<std::size_t>(i)].origin), 1e-12);
    EXPECT_NEAR(dh.joints[static_cast<std::size_t>(i)].lower, urdf.joints[static_cast<std::size_t>(i)].lower, 1e-12);
    EXPECT_NEAR(dh.joints[static_cast<std::size_t>(i)].upper, urdf.joints[static_cast<std::size_t>(i)].upper, 1e-12);
  }
}

TEST(ChainTemplate, UrdfAndDhFormsOfUr5LikeAreTheSameChain) {
  const Chain dh = nominal_chain(ChainTemplate::from_dh_file(share("ur5_like_dh.json")));
  for (const char* base : {"world", "base_link"}) {
    SCOPED_TRACE(base);
    // The DH table has no gripper: the file without its folded gripper_base.
    const Chain urdf = nominal_chain(ChainTemplate::from_urdf(share("ur5_like.urdf"), base, "tool0", false));
    expect_same_chain(dh, urdf);
    std::mt19937 rng(23);
    const std::vector<double> q = random_q(6, rng);
    const State a = state_at(dh, q), b = state_at(urdf, q);
    for (std::size_t i = 0; i < 6; ++i) {
      // The URDF's link frames lie on the same joint axes, moved along them by d_i.
      EXPECT_LT((a.frames.joint[i].linear() - b.frames.joint[i].linear()).norm(), 1e-12);
      const Eigen::Vector3d offset = b.frames.joint[i].translation() - a.frames.joint[i].translation();
      EXPECT_LT(offset.cross(a.frames.joint[i].linear().col(2)).norm(), 1e-12);
      EXPECT_EQ(dh.joints[i].name, urdf.joints[i].name);
      EXPECT_NEAR(dh.joints[i].lower, urdf.joints[i].lower, 1e-12);
      EXPECT_NEAR(dh.joints[i].upper, urdf.joints[i].upper, 1e-12);
      EXPECT_NEAR(dh.joints[i].max_velocity, urdf.joints[i].max_velocity, 1e-12);
      EXPECT_EQ(dh.joints[i].max_effort, urdf.joints[i].max_effort);
      EXPECT_NEAR(dh.bodies[i].mass, urdf.bodies[i].mass, 1e-15);
    }
  }
}
#endif

// The haptic6r mechanism's own model (closed-form DH kernels and its mass model) for the
// nominal design with sizes s = [3, 3, 2, 2, 1, 1], against both haptic6r chain files.
TEST(ChainTemplate, Haptic6rFilesMatchTheHaptic6rModel) {
  const Haptic6RSetup setup = Haptic6RSetup::from_options(make_options<Haptic6ROptions>(Json::object()));
  Haptic6RModel model;
  const std::vector<double> design = {0.45, 0.45, 0.65, 0.55, 0.15, 3, 3, 2, 2, 1, 1, 1, 2, 3, 4, 5, 6};
  model.rebuild(design.data(), setup);
  std::vector<ChainFile> files = {{"haptic6r_dh.json", "", ""}};
#ifdef HAPSYN_HAVE_URDFDOM
  files.push_back({"haptic6r.urdf", "base_link", "ee_link"});
#endif
  for (const ChainFile& f : files) {
    SCOPED_TRACE(f.name);
    const Chain c = nominal_chain(load(f));
    for (int i = 0; i < 6; ++i) {
      EXPECT_NEAR(c.joints[static_cast<std::size_t>(i)].lower, setup.joint_lower(i), 1e-12);
      EXPECT_NEAR(c.joints[static_cast<std::size_t>(i)].upper, setup.joint_upper(i), 1e-12);
    }
    std::mt19937 rng(29);
    for (int k = 0; k < 20; ++k) {
      const std::vector<double> q = random_q(6, rng);
      const Vector6d qv = Eigen::Map<const Vector6d>(q.data());
      const State s = state_at(c, q);
      std::array<Eigen::Isometry3d, 7> frames;
      model.frames(qv, frames);
      Matrix6d j, h;
      Vector6d g;
      model.quantities(qv, &j, &h, &g);
      EXPECT_LT(pose_error(s.frames.tip, frames[6]), 1e-9);
      for (std::size_t i = 0; i < 6; ++i) {
        // Joint frame i+1 is DH frame i turned about its z: same origin, same z.
        EXPECT_LT((s.frames.joint[i].translation() - frames[i].translation()).norm(), 1e-9);
        EXPECT_LT((s.frames.joint[i].linear().col(2) - frames[i].linear().col(2)).norm(), 1e-9);
        // Body i in the world: same mass and centre of mass.
        const Haptic6RBody& hb = model.bodies()[i];
        EXPECT_NEAR(c.bodies[i].mass, hb.mass, 1e-12);
        EXPECT_LT((s.frames.joint[i] * c.bodies[i].com - frames[i + 1] * hb.com).norm(), 1e-9);
      }
      EXPECT_LT((s.jacobian - j).norm(), 1e-9);
      EXPECT_LT((s.inertia - h).norm(), 1e-9) << s.inertia << "\n\n" << h;
      EXPECT_LT((s.gravity - g).norm(), 1e-9) << s.gravity.transpose() << "\n" << g.transpose();
    }
  }
}

TEST(ChainTemplate, MotorMassesReplaceTheFilesOnesInTheFennelModel) {
  const ChainTemplate t = ChainTemplate::from_dh_file(share("haptic6r_dh.json"));
  ASSERT_NE(t.fennel_mass_model(), nullptr);
  EXPECT_EQ(t.fennel_mass_model()->motor_mass, (std::vector<double>{2.5, 2.5, 1.6, 1.6, 0.9, 0.9}));
  const Haptic6RSetup setup = Haptic6RSetup::from_options(make_options<Haptic6ROptions>(Json::object()));
  Haptic6RModel model;
  const std::vector<double> design = {0.45, 0.45, 0.65, 0.55, 0.15, 3, 3, 3, 3, 3, 3, 1, 1, 1, 1, 1, 1};
  model.rebuild(design.data(), setup);
  const std::vector<double> values = nominal(t), motors(6, setup.actuators.mass[2]);
  Chain c;
  t.instantiate(values.data(), motors.data(), c);
  std::mt19937 rng(31);
  for (int k = 0; k < 5; ++k) {
    const std::vector<double> q = random_q(6, rng);
    const State s = state_at(c, q);
    Matrix6d h;
    Vector6d g;
    model.dynamics(Eigen::Map<const Vector6d>(q.data()), &h, &g);
    EXPECT_LT((s.inertia - h).norm(), 1e-9);
    EXPECT_LT((s.gravity - g).norm(), 1e-9);
  }
}

#ifdef HAPSYN_HAVE_URDFDOM
namespace {

// A URDF link with an inertial: origin xyz/rpy, mass, ixx ixy ixz iyy iyz izz.
std::string urdf_link(const std::string& name, const std::string& xyz = "", const std::string& rpy = "0 0 0",
                      double mass = 0.0, const std::string& inertia = "") {
  if (xyz.empty()) return "<link name=\"" + name + "\"/>\n";
  std::istringstream in(inertia);
  double i[6];
  for (double& x : i) in >> x;
  std::ostringstream s;
  s << "<link name=\"" << name << "\"><inertial><origin xyz=\"" << xyz << "\" rpy=\"" << rpy << "\"/><mass value=\""
    << mass << "\"/><inertia ixx=\"" << i[0] << "\" ixy=\"" << i[1] << "\" ixz=\"" << i[2] << "\" iyy=\"" << i[3]
    << "\" iyz=\"" << i[4] << "\" izz=\"" << i[5] << "\"/></inertial></link>\n";
  return s.str();
}

std::string urdf_joint(const std::string& name, const std::string& type, const std::string& parent,
                       const std::string& child, const std::string& xyz, const std::string& rpy,
                       const std::string& axis = "0 0 1", const std::string& extra = "") {
  std::string s = "<joint name=\"" + name + "\" type=\"" + type + "\"><parent link=\"" + parent + "\"/><child link=\"" +
                  child + "\"/><origin xyz=\"" + xyz + "\" rpy=\"" + rpy + "\"/>";
  if (type != "fixed") s += "<axis xyz=\"" + axis + "\"/><limit lower=\"-1\" upper=\"1\" effort=\"5\" velocity=\"2\"/>";
  return s + extra + "</joint>\n";
}

std::string robot(const std::string& body) { return "<?xml version=\"1.0\"?>\n<robot name=\"t\">\n" + body + "</robot>\n"; }

// A chain with fixed joints everywhere they may be: before the first moving joint (with an
// inertial riding on the base), between moving joints (with inertials at rotated frames) and after
// the last one (into T_tip).
std::string folded_urdf() {
  return robot(urdf_link("world") +
               urdf_joint("mount", "fixed", "world", "plate", "0 0 0.1", "0 0 0.3") +
               urdf_link("plate", "0 0 0.01", "0 0 0", 5.0, "0.1 0 0 0.1 0 0.2") +
               urdf_joint("j1", "revolute", "plate", "l1", "0.1 0 0.2", "0.1 0.2 0.3", "0 0 1") +
               urdf_link("l1", "0.1 0 0", "0 0 0", 1.0, "0.01 0 0 0.02 0 0.03") +
               urdf_joint("f1", "fixed", "l1", "l1b", "0.3 0 0", "0.4 -0.2 0.1") +
               urdf_link("l1b", "0.05 0.02 0", "0.3 0.1 -0.2", 2.0, "0.02 0.001 0.002 0.03 0.003 0.04") +
               urdf_joint("j2", "prismatic", "l1b", "l2", "0 0.1 0", "0 0.5 0", "0 1 0") +
               urdf_link("l2", "0 0 0.1", "0 0 0", 0.5, "0.004 0 0 0.005 0 0.006") +
               urdf_joint("j3", "continuous", "l2", "l3", "0.2 0 0", "-0.3 0 0", "1 0 0") +
               urdf_link("l3", "0 0.1 0", "0 0 0.2", 0.7, "0.003 0 0.0005 0.002 0 0.004") +
               urdf_joint("f2", "fixed", "l3", "l4", "0 0 0.2", "0 0 0") +
               urdf_link("l4", "0.01 0 0", "0.5 0 0", 0.3, "0.001 0 0 0.002 0 0.003") +
               urdf_joint("f3", "fixed", "l4", "tip", "0.1 0 0", "0 0 0.7") + urdf_link("tip"));
}

}  // namespace

#ifdef HAPSYN_HAVE_KDL
// KDL merges fixed segments itself: the KDL chain is written from the URDF's numbers directly
// (one segment per URDF joint, fixed ones as Joint::None), its inertias placed by KDL's own
// Frame * RigidBodyInertia.
TEST(ChainTemplate, FixedJointsFoldLikeKdlFixedSegments) {
  const ChainTemplate t = ChainTemplate::from_urdf(write_file("folded.urdf", folded_urdf()), "world", "tip");
  ASSERT_EQ(t.dof(), 3);
  const Chain c = nominal_chain(t);
  auto frame = [&](double x, double y, double z, double r, double p, double w) {
    return KDL::Frame(KDL::Rotation::RPY(r, p, w), KDL::Vector(x, y, z));
  };
  auto inertial = [&](const KDL::Frame& at, double m, double ixx, double ixy, double ixz, double iyy, double iyz, double izz) {
    return at * KDL::RigidBodyInertia(m, KDL::Vector::Zero(), KDL::RotationalInertia(ixx, iyy, izz, ixy, ixz, iyz));
  };
  auto moving = [&](const KDL::Frame& origin, const KDL::Vector& axis, KDL::Joint::JointType type) {
    return KDL::Joint(origin.p, origin.M * axis, type);
  };
  KDL::Chain k;
  k.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), frame(0, 0, 0.1, 0, 0, 0.3),
                            inertial(frame(0, 0, 0.01, 0, 0, 0), 5.0, 0.1, 0, 0, 0.1, 0, 0.2)));
  const KDL::Frame o1 = frame(0.1, 0, 0.2, 0.1, 0.2, 0.3);
  k.addSegment(KDL::Segment(moving(o1, KDL::Vector(0, 0, 1), KDL::Joint::RotAxis), o1,
                            inertial(frame(0.1, 0, 0, 0, 0, 0), 1.0, 0.01, 0, 0, 0.02, 0, 0.03)));
  k.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), frame(0.3, 0, 0, 0.4, -0.2, 0.1),
                            inertial(frame(0.05, 0.02, 0, 0.3, 0.1, -0.2), 2.0, 0.02, 0.001, 0.002, 0.03, 0.003, 0.04)));
  const KDL::Frame o2 = frame(0, 0.1, 0, 0, 0.5, 0);
  k.addSegment(KDL::Segment(moving(o2, KDL::Vector(0, 1, 0), KDL::Joint::TransAxis), o2,
                            inertial(frame(0, 0, 0.1, 0, 0, 0), 0.5, 0.004, 0, 0, 0.005, 0, 0.006)));
  const KDL::Frame o3 = frame(0.2, 0, 0, -0.3, 0, 0);
  k.addSegment(KDL::Segment(moving(o3, KDL::Vector(1, 0, 0), KDL::Joint::RotAxis), o3,
                            inertial(frame(0, 0.1, 0, 0, 0, 0.2), 0.7, 0.003, 0, 0.0005, 0.002, 0, 0.004)));
  k.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), frame(0, 0, 0.2, 0, 0, 0),
                            inertial(frame(0.01, 0, 0, 0.5, 0, 0), 0.3, 0.001, 0, 0, 0.002, 0, 0.003)));
  k.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), frame(0.1, 0, 0, 0, 0, 0.7)));
  ASSERT_EQ(k.getNrOfJoints(), 3u);
  std::mt19937 rng(37);
  for (int sample = 0; sample < 20; ++sample) {
    const std::vector<double> q = random_q(3, rng);
    const State s = state_at(c, q);
    const KdlState ks = kdl_state(k, c.gravity, q);
    EXPECT_LT((s.jacobian - ks.jacobian).norm(), 1e-9);
    EXPECT_LT((s.inertia - ks.inertia).norm(), 1e-9) << s.inertia << "\n\n" << ks.inertia;
    EXPECT_LT((s.gravity - ks.gravity).norm(), 1e-9);
  }
  EXPECT_NEAR(c.bodies[0].mass, 3.0, 1e-15);  // l1 + l1b
  EXPECT_NEAR(c.bodies[2].mass, 1.0, 1e-15);  // l3 + l4
  EXPECT_EQ(c.joints[1].type, ChainJointType::kPrismatic);
  EXPECT_TRUE(std::isinf(c.joints[2].lower) && std::isinf(c.joints[2].upper));  // continuous
  EXPECT_EQ(c.joints[2].max_effort, 5.0);
}
#endif

TEST(ChainTemplate, FixedJointsFoldIntoTheSameChainWrittenWithoutThem) {
  // Fixed joints with pure translations compose by adding, a massless fixed link adds nothing.
  const std::string with = robot(
      urdf_link("base") + urdf_joint("f0", "fixed", "base", "b2", "0 0 0.1", "0 0 0") + urdf_link("b2") +
      urdf_joint("j1", "revolute", "b2", "l1", "0.1 0 0", "0 0 0.4", "0 0 1") +
      urdf_link("l1", "0.1 0 0", "0 0 0", 1.0, "0.01 0 0 0.02 0 0.03") +
      urdf_joint("f1", "fixed", "l1", "l1b", "0.2 0 0", "0 0 0") + urdf_link("l1b") +
      urdf_joint("j2", "revolute", "l1b", "l2", "0.3 0 0", "0.5 0 0", "0 1 0") +
      urdf_link("l2", "0 0 0.1", "0 0 0", 0.5, "0.004 0 0 0.005 0 0.006") +
      urdf_joint("f2", "fixed", "l2", "tip", "0 0 0.25", "0 0 0") + urdf_link("tip"));
  const std::string without = robot(
      urdf_link("base") + urdf_joint("j1", "revolute", "base", "l1", "0.1 0 0.1", "0 0 0.4", "0 0 1") +
      urdf_link("l1", "0.1 0 0", "0 0 0", 1.0, "0.01 0 0 0.02 0 0.03") +
      urdf_joint("j2", "revolute", "l1", "l2", "0.5 0 0", "0.5 0 0", "0 1 0") +
      urdf_link("l2", "0 0 0.1", "0 0 0", 0.5, "0.004 0 0 0.005 0 0.006") +
      urdf_joint("f2", "fixed", "l2", "tip", "0 0 0.25", "0 0 0") + urdf_link("tip"));
  const Chain a = nominal_chain(ChainTemplate::from_urdf(write_file("with.urdf", with), "base", "tip"));
  const Chain b = nominal_chain(ChainTemplate::from_urdf(write_file("without.urdf", without), "base", "tip"));
  expect_same_chain(a, b);
  for (std::size_t i = 0; i < 2; ++i) EXPECT_LT(pose_error(a.joints[i].origin, b.joints[i].origin), 1e-15);
}

TEST(ChainTemplate, UrdfFingerIsAPrismaticChain) {
  const ChainTemplate t = ChainTemplate::from_urdf(share("ur5_like.urdf"), "gripper_base", "finger_left");
  ASSERT_EQ(t.dof(), 1);
  const Chain c = nominal_chain(t);
  EXPECT_EQ(c.joints[0].type, ChainJointType::kPrismatic);
  EXPECT_EQ(c.joints[0].lower, 0.0);
  EXPECT_EQ(c.joints[0].upper, 0.04);
  EXPECT_EQ(c.joints[0].max_velocity, 0.1);
  EXPECT_NEAR(c.bodies[0].mass, 0.05, 1e-15);
  const double q = 0.03;
  ChainFrames f;
  chain_frames(c, &q, f);
  EXPECT_LT((f.tip.translation() - Eigen::Vector3d(0, 0.01 + q, 0.08)).norm(), 1e-15);
}
#endif  // HAPSYN_HAVE_URDFDOM

// ---- ChainTemplate: parameters ----

namespace {

Eigen::Isometry3d xyz_rpy(double x, double y, double z, double roll, double pitch, double yaw) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, z);
  return t;
}

void expect_same_bodies(const Chain& a, const Chain& b, double tolerance = 1e-12) {
  ASSERT_EQ(a.bodies.size(), b.bodies.size());
  for (std::size_t i = 0; i < a.bodies.size(); ++i) {
    EXPECT_NEAR(a.bodies[i].mass, b.bodies[i].mass, tolerance) << "body " << i;
    EXPECT_LT((a.bodies[i].com - b.bodies[i].com).norm(), tolerance) << "body " << i;
    EXPECT_LT((a.bodies[i].inertia - b.bodies[i].inertia).norm(), tolerance) << "body " << i;
  }
}

}  // namespace

TEST(ChainTemplate, DhParametersAreListedAsDocumented) {
  const ChainTemplate h = ChainTemplate::from_dh_file(share("haptic6r_dh.json"));
  const std::vector<ChainParameter>& p = h.parameters();
  ASSERT_GE(p.size(), 6u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(p[static_cast<std::size_t>(i)].name, "l" + std::to_string(i + 1));  // the file's order
    EXPECT_EQ(p[static_cast<std::size_t>(i)].unit, "m");
    EXPECT_EQ(p[static_cast<std::size_t>(i)].hard_lower, 0.0);
  }
  EXPECT_EQ(p[2].nominal, 0.65);
  EXPECT_EQ(p.back().name, "mass_scale");
  EXPECT_EQ(p.back().nominal, 1.0);
  EXPECT_EQ(p.back().hard_lower, 0.0);
  EXPECT_EQ(h.find("joint1:a"), -1);  // a = "l1": set through l1
  EXPECT_EQ(h.find("joint3:d"), -1);  // d = "-l3"
  ASSERT_GE(h.find("joint4:theta"), 0);
  EXPECT_EQ(p[static_cast<std::size_t>(h.find("joint4:theta"))].nominal, -90.0);
  EXPECT_EQ(p[static_cast<std::size_t>(h.find("joint4:theta"))].unit, "deg");
  EXPECT_EQ(h.find("joint1:mass"), -1);  // the Fennel model gives the bodies
  EXPECT_EQ(h.find("nope"), -1);

  const ChainTemplate u = ChainTemplate::from_dh_file(share("ur5_like_dh.json"));
  const ChainParameter& a2 = u.parameters()[static_cast<std::size_t>(u.find("shoulder_lift_joint:a"))];
  EXPECT_EQ(a2.nominal, -0.425);
  EXPECT_EQ(a2.hard_upper, 0.0);  // keeps its sign
  EXPECT_TRUE(std::isinf(a2.hard_lower));
  const ChainParameter& d1 = u.parameters()[static_cast<std::size_t>(u.find("shoulder_pan_joint:d"))];
  EXPECT_EQ(d1.hard_lower, 0.0);
  const ChainParameter& a1 = u.parameters()[static_cast<std::size_t>(u.find("shoulder_pan_joint:a"))];
  EXPECT_TRUE(std::isinf(a1.hard_lower) && std::isinf(a1.hard_upper));  // zero: either sign
  const ChainParameter& m4 = u.parameters()[static_cast<std::size_t>(u.find("wrist_1_joint:mass"))];
  EXPECT_EQ(m4.nominal, 1.219);
  EXPECT_EQ(m4.unit, "kg");
  EXPECT_EQ(m4.hard_lower, 0.0);
}

TEST(ChainTemplate, DhParametersChangeTheChainAsDocumented) {
  const ChainTemplate t = ChainTemplate::from_dh_file(share("ur5_like_dh.json"));
  const Chain base = nominal_chain(t);
  std::vector<double> v = nominal(t);
  value_of(t, v, "elbow_joint:a") = -0.5;
  value_of(t, v, "shoulder_pan_joint:alpha") = 80.0;
  value_of(t, v, "wrist_3_joint:d") = 0.1;
  value_of(t, v, "wrist_1_joint:theta") = 30.0;
  value_of(t, v, "wrist_1_joint:mass") = 2.0;
  const Chain c = instantiate(t, v);
  // By hand: O_i = X_{i-1} Rz(theta_i) with X = Tz(d) Tx(a) Rx(alpha); bodies through X_i.
  Chain hand = base;
  hand.joints[1].origin = xyz_rpy(0, 0, 0.089159, 80.0 * kPi / 180, 0, 0);
  hand.joints[3].origin = xyz_rpy(-0.5, 0, 0, 0, 0, 30.0 * kPi / 180);
  hand.tip = xyz_rpy(0, 0, 0.1, 0, 0, 0);
  hand.bodies[0].com = xyz_rpy(0, 0, 0.089159, 80.0 * kPi / 180, 0, 0) * Eigen::Vector3d(0, -0.02561, 0.00193);
  const Eigen::Matrix3d r1 = Eigen::AngleAxisd(80.0 * kPi / 180, Eigen::Vector3d::UnitX()).toRotationMatrix();
  hand.bodies[0].inertia = r1 * Eigen::Vector3d(0.010267499999999999, 0.010267499999999999, 0.00666).asDiagonal() * r1.transpose();
  hand.bodies[2].com = Eigen::Vector3d(-0.5 + 0.15, 0, 0.0265);
  hand.bodies[3].mass = 2.0;
  hand.bodies[3].inertia *= 2.0 / 1.219;
  hand.bodies[5].com = Eigen::Vector3d(0, 0, 0.1 - 0.001159);
  expect_same_bodies(c, hand);
  expect_same_chain(c, hand);
}

TEST(ChainTemplate, DhNamedLengthsChangeEveryRowUsingThem) {
  const ChainTemplate t = ChainTemplate::from_dh_file(share("haptic6r_dh.json"));
  const Chain base = nominal_chain(t);
  std::vector<double> v = nominal(t);
  value_of(t, v, "l3") = 0.8;
  value_of(t, v, "l5") = 0.2;
  const Chain c = instantiate(t, v);
  // Kinematics by hand; the Fennel tubes follow the lengths.
  EXPECT_LT((c.joints[3].origin.translation() - Eigen::Vector3d(0, 0, -0.8)).norm(), 1e-15);
  EXPECT_LT((c.joints[3].origin.linear() - base.joints[3].origin.linear()).norm(), 1e-15);
  EXPECT_LT((c.tip.translation() - Eigen::Vector3d(0, 0, 0.2)).norm(), 1e-15);
  const FennelMassModel& m = *t.fennel_mass_model();
  EXPECT_NEAR(c.bodies[2].mass - base.bodies[2].mass, m.link_density * (0.8 - 0.65), 1e-12);
  EXPECT_NEAR(c.bodies[5].mass - base.bodies[5].mass, m.link_density * (0.2 - 0.15), 1e-12);
  for (int i : {0, 1, 3, 4}) EXPECT_EQ(c.bodies[static_cast<std::size_t>(i)].mass, base.bodies[static_cast<std::size_t>(i)].mass);
}

#ifdef HAPSYN_HAVE_URDFDOM
TEST(ChainTemplate, UrdfParametersAreListedAsDocumented) {
  const ChainTemplate t = ChainTemplate::from_urdf(share("ur5_like.urdf"), "world", "tool0");
  const std::vector<ChainParameter>& p = t.parameters();
  // Every joint on the path, fixed ones included, in path order.
  ASSERT_GE(p.size(), 6u);
  EXPECT_EQ(p[0].name, "world_joint:x");
  EXPECT_EQ(p[3].name, "world_joint:roll");
  EXPECT_EQ(p[5].unit, "rad");
  const ChainParameter& z = p[static_cast<std::size_t>(t.find("shoulder_pan_joint:z"))];
  EXPECT_EQ(z.nominal, 0.089159);
  EXPECT_EQ(z.unit, "m");
  EXPECT_EQ(p[static_cast<std::size_t>(t.find("shoulder_lift_joint:roll"))].nominal, kPi / 2);  // as written
  EXPECT_GE(t.find("flange-tool0:yaw"), 0);
  EXPECT_GE(t.find("upper_arm_link:mass"), 0);
  EXPECT_EQ(t.find("base_link_inertia:mass"), -1);  // rides on the base
  EXPECT_GE(t.find("gripper_base:mass"), 0);        // fixed beyond the tip: folded into wrist_3_link
  EXPECT_EQ(t.find("finger_left:mass"), -1);        // behind a prismatic joint: not folded
  EXPECT_EQ(t.find("finger_left_joint:x"), -1);
  EXPECT_EQ(p.back().name, "mass_scale");
}

TEST(ChainTemplate, UrdfParametersChangeTheChainAsDocumented) {
  // Without the gripper, which flange-tool0:z would move along with tool0.
  const ChainTemplate t = ChainTemplate::from_urdf(share("ur5_like.urdf"), "world", "tool0", false);
  const Chain base = nominal_chain(t);
  std::vector<double> v = nominal(t);
  value_of(t, v, "elbow_joint:x") = -0.5;
  value_of(t, v, "elbow_joint:yaw") = 0.2;
  value_of(t, v, "base_link-base_link_inertia:yaw") = 0.0;
  value_of(t, v, "flange-tool0:z") = 0.05;
  value_of(t, v, "upper_arm_link:mass") = 2 * 8.393;
  const Chain c = instantiate(t, v);
  Chain hand = base;
  hand.joints[0].origin = xyz_rpy(0, 0, 0.089159, 0, 0, kPi);  // Rz(0) * (Tz(d1) Rz(pi))
  hand.joints[2].origin = xyz_rpy(-0.5, 0, 0, 0, 0, 0.2);
  hand.tip = xyz_rpy(0, 0, 0, 0, -kPi / 2, -kPi / 2) * xyz_rpy(0, 0, 0.05, kPi / 2, 0, kPi / 2);
  hand.bodies[1].mass *= 2.0;
  hand.bodies[1].inertia *= 2.0;
  expect_same_bodies(c, hand);
  expect_same_chain(c, hand);
  EXPECT_GT(pose_error(c.joints[0].origin, base.joints[0].origin), 1.0);  // the fold did change O_1
}

TEST(ChainTemplate, UrdfLinkMassOfAFoldedLinkMovesTheBodysCom) {
  const ChainTemplate t = ChainTemplate::from_urdf(share("phantom_3r.urdf"), "world", "stylus_tip");
  std::vector<double> v = nominal(t);
  const Chain nominal_c = instantiate(t, v);
  // The forearm (0.215 kg, com (0, 0, 0.02)) carries the gimbal's 0.03 kg at (0, 0, -0.17).
  EXPECT_NEAR(nominal_c.bodies[2].mass, 0.245, 1e-15);
  EXPECT_LT((nominal_c.bodies[2].com - Eigen::Vector3d(0, 0, (0.215 * 0.02 - 0.03 * 0.17) / 0.245)).norm(), 1e-15);
  value_of(t, v, "stylus_tip:mass") = 0.3;
  const Chain c = instantiate(t, v);
  EXPECT_NEAR(c.bodies[2].mass, 0.515, 1e-15);
  EXPECT_LT((c.bodies[2].com - Eigen::Vector3d(0, 0, (0.215 * 0.02 - 0.3 * 0.17) / 0.515)).norm(), 1e-15);
  EXPECT_EQ(t.find("base_link:mass"), -1);  // on the base
  EXPECT_EQ(t.find("stylus:mass"), -1);     // the gimbal branch is not on the chain
}
#endif

TEST(ChainTemplate, MassScaleScalesEveryMassAndInertia) {
  for (const ChainFile& f : shipped_files()) {
    SCOPED_TRACE(f.name);
    const ChainTemplate t = load(f);
    const Chain base = nominal_chain(t);
    std::vector<double> v = nominal(t);
    value_of(t, v, "mass_scale") = 1.5;
    const Chain c = instantiate(t, v);
    Chain hand = base;
    for (ChainBody& b : hand.bodies) {
      b.mass *= 1.5;
      b.inertia *= 1.5;
    }
    expect_same_bodies(c, hand);
  }
}

TEST(ChainTemplate, ModifiedDhInMillimetresAndRadiansIsTheSameArm) {
  // The UR5-like arm in Craig's modified DH (row i: alpha_{i-1}, a_{i-1}, theta_i, d_i), mm, rad.
  const double h = kPi / 2;
  const double rows[6][4] = {{0, 0, 0, 89.159}, {h, 0, 0, 0}, {0, -425, 0, 0}, {0, -392.25, 0, 109.15},
                             {h, 0, 0, 94.65},  {-h, 0, 0, 82.3}};
  Json joints = Json::array();
  const char* names[6] = {"j1", "j2", "j3", "j4", "j5", "j6"};
  for (int i = 0; i < 6; ++i) {
    joints.push_back({{"joint", names[i]}, {"alpha", rows[i][0]}, {"a", rows[i][1]}, {"theta", rows[i][2]}, {"d", rows[i][3]}});
  }
  const Json doc = {{"format", "hapsyn-dh"}, {"format_version", 1}, {"convention", "modified_dh"},
                    {"units", {{"length", "mm"}, {"angle", "rad"}}}, {"joints", joints}};
  Chain modified = nominal_chain(ChainTemplate::from_dh_file(write_file("ur5_mdh.json", doc.dump())));
  Chain standard = nominal_chain(ChainTemplate::from_dh_file(share("ur5_like_dh.json")));
  for (ChainBody& b : standard.bodies) b = ChainBody{};  // kinematics only
  expect_same_chain(standard, modified);
}

TEST(ChainTemplate, DhPrismaticJointMovesAlongZ) {
  const Json doc = {{"format", "hapsyn-dh"}, {"format_version", 1}, {"convention", "dh"},
                    {"units", {{"length", "m"}, {"angle", "deg"}}},
                    {"joints", Json::array({{{"joint", "r"}, {"theta", 30}, {"d", 0.1}, {"a", 0.2}, {"alpha", 90},
                                             {"lower", -90}, {"upper", 90}, {"max_velocity", 90}},
                                            {{"joint", "p"}, {"type", "prismatic"}, {"theta", 0}, {"d", 0.1}, {"a", 0.2},
                                             {"alpha", 0}, {"lower", 0}, {"upper", 0.3}, {"max_velocity", 0.5}}})},
                    {"tip", {{"xyz", {0, 0, 0.05}}}}};
  const Chain c = nominal_chain(ChainTemplate::from_dh_file(write_file("prismatic.json", doc.dump())));
  EXPECT_EQ(c.joints[1].type, ChainJointType::kPrismatic);
  EXPECT_NEAR(c.joints[0].upper, kPi / 2, 1e-15);
  EXPECT_NEAR(c.joints[0].max_velocity, kPi / 2, 1e-15);
  EXPECT_EQ(c.joints[1].upper, 0.3);  // a length: metres
  EXPECT_EQ(c.joints[1].max_velocity, 0.5);
  const double q[2] = {0.4, 0.25};
  ChainFrames f;
  chain_frames(c, q, f);
  // By hand: T = Rz(30 deg + q1) Tz(0.1) Tx(0.2) Rx(90 deg) * Rz(0) Tz(0.1 + q2) Tx(0.2) * Tz(0.05).
  const Eigen::Isometry3d expected = xyz_rpy(0, 0, 0, 0, 0, kPi / 6 + q[0]) * xyz_rpy(0.2, 0, 0.1, kPi / 2, 0, 0) *
                                     xyz_rpy(0.2, 0, 0.1 + q[1], 0, 0, 0) * xyz_rpy(0, 0, 0.05, 0, 0, 0);
  EXPECT_LT(pose_error(f.tip, expected), 1e-15);
}

// ---- ChainTemplate: errors ----

#ifdef HAPSYN_HAVE_URDFDOM
// A link that is the child of two joints closes a loop; urdfdom accepts the file (and leaks
// the cycle it builds), so the XML pass refuses it before urdfdom sees it.
TEST(ChainTemplate, UrdfClosedLoopIsRefused) {
  const std::string path = ::testing::TempDir() + "hapsyn_loop.urdf";
  {
    std::ofstream f(path);
    f << "<robot name=\"loop\"><link name=\"a\"/><link name=\"b\"/><link name=\"c\"/>"
         "<joint name=\"j1\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/></joint>"
         "<joint name=\"j2\" type=\"continuous\"><parent link=\"b\"/><child link=\"c\"/></joint>"
         "<joint name=\"j3\" type=\"continuous\"><parent link=\"c\"/><child link=\"b\"/></joint></robot>";
  }
  std::string message;
  try {
    ChainTemplate::from_urdf(path, "a", "c");
  } catch (const hapsyn::Error& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("hapsyn_loop.urdf: line 1: link \"b\" is the child of joints \"j1\" and \"j3\": a closed "
                         "kinematic loop"),
            std::string::npos)
      << message;
  std::remove(path.c_str());
}

// Issue 53, cause 2: a joint axis is a direction of any finite length. (0 1e200 0) once became
// the zero axis (its squared norm overflowed) and 1e-200 or 5e-324 were refused as zero.
TEST(ChainTemplate, UrdfAxisOfAnyFiniteLengthIsItsDirection) {
  const auto one_joint = [](const std::string& axis) {
    return robot(urdf_link("base") + urdf_joint("j", "revolute", "base", "tip", "0.1 0 0", "0 0 0", axis) +
                 urdf_link("tip", "0.2 0 0", "0 0 0", 1.0, "0.01 0 0 0.01 0 0.01"));
  };
  const Chain unit = nominal_chain(ChainTemplate::from_urdf(write_file("unit.urdf", one_joint("0 1 0")), "base", "tip"));
  const State expected = state_at(unit, {0.3});
  for (const char* axis : {"0 1e200 0", "0 1e-200 0", "0 5e-324 0", "0 2 0"}) {
    const Chain c = nominal_chain(ChainTemplate::from_urdf(write_file("scaled.urdf", one_joint(axis)), "base", "tip"));
    const State s = state_at(c, {0.3});
    EXPECT_LT((s.jacobian - expected.jacobian).norm(), 1e-15) << axis;
    EXPECT_LT((s.inertia - expected.inertia).norm(), 1e-15) << axis;
  }
  expect_error([&] { ChainTemplate::from_urdf(write_file("zero.urdf", one_joint("0 0 0")), "base", "tip"); },
               {"joint \"j\"", "axis = (0 0 0): must be a finite, non-zero direction"});
}

// Issue 53, cause 5: TinyXML and urdfdom recurse once per nesting level and once per link, so a
// deep or very long file once overflowed the stack inside them. Its shape is refused before it is
// parsed, naming the line; a chain of 9,000 links (within the limits) still reads, and markup that
// holds no elements (comments, CDATA, a '>' in a quoted value) does not count.
TEST(ChainTemplate, UrdfNestingAndSizeAreBoundedBeforeParsing) {
  const std::string one_joint = urdf_link("base") + urdf_joint("j", "revolute", "base", "tip", "0.1 0 0", "0 0 0") +
                                urdf_link("tip", "0.2 0 0", "0 0 0", 1.0, "0.01 0 0 0.01 0 0.01");
  std::string nested;
  for (int k = 0; k < 100000; ++k) nested += "<x>";
  for (int k = 0; k < 100000; ++k) nested += "</x>";
  const std::string deep = write_file("deep.urdf", robot(one_joint + nested));
  expect_error([&] { ChainTemplate::from_urdf(deep, "base", "tip"); },
               {deep + ": line 6: <x> is nested 65 elements deep: at most 64 levels are read"});

  std::string fixed = urdf_link("f0");
  for (int k = 0; k < 150000; ++k) {
    fixed += urdf_joint("fj" + std::to_string(k), "fixed", "f" + std::to_string(k), "f" + std::to_string(k + 1),
                        "0 0 0", "0 0 0") + urdf_link("f" + std::to_string(k + 1));
  }
  const std::string long_chain = write_file("long.urdf", robot(fixed));
  expect_error([&] { ChainTemplate::from_urdf(long_chain, "f0", "f1"); },
               {long_chain + ": line ", ": more than 20000 <link> and <joint> elements: at most that many are read"});

  std::string within = urdf_link("base") + "<!-- <a><b><c> --><![CDATA[<d><e>]]>";
  std::string parent = "base";
  for (int k = 0; k < 4500; ++k) {
    const std::string child = "l" + std::to_string(k);
    within += urdf_joint("w" + std::to_string(k), "fixed", parent, child, "0.001 0 0", "0 0 0") +
              "<link name=\"" + child + "\"><visual name=\"a>b\"><geometry><box size=\"1 1 1\"/></geometry></visual></link>\n";
    parent = child;
  }
  within += urdf_joint("j", "revolute", parent, "tip", "0.1 0 0", "0 0 0") +
            urdf_link("tip", "0.2 0 0", "0 0 0", 1.0, "0.01 0 0 0.01 0 0.01");
  const Chain c = nominal_chain(ChainTemplate::from_urdf(write_file("within.urdf", robot(within)), "base", "tip"));
  // 4,500 fixed joints of 1 mm fold into the one moving joint's origin: 4.5 m + 0.1 m along x.
  EXPECT_NEAR(state_at(c, {0.0}).frames.tip.translation().x(), 4.6, 1e-9);
}

// What TinyXML reads wrongly without a word is refused before it: a second root element (a second
// <robot> was ignored) and a DOCTYPE declaring entities (urdfdom then "could not find the robot").
TEST(ChainTemplate, UrdfWithTwoRootsOrEntityDeclarationsIsRefused) {
  const std::string one = urdf_link("base") + urdf_joint("j", "revolute", "base", "tip", "0.1 0 0", "0 0 0") +
                          urdf_link("tip", "0.2 0 0", "0 0 0", 1.0, "0.01 0 0 0.01 0 0.01");
  const std::string two = write_file("two.urdf", robot(one) + "<robot name=\"x\"><link name=\"a\"/></robot>\n");
  expect_error([&] { ChainTemplate::from_urdf(two, "base", "tip"); },
               {two + ": line 7: <robot> after the root element has ended: a file holds one XML document (one <robot>)"});
  const std::string entities = write_file("entities.urdf", "<!DOCTYPE robot [<!ENTITY L \"0.1\">]>\n" + robot(one));
  expect_error([&] { ChainTemplate::from_urdf(entities, "base", "tip"); },
               {entities + ": line 1: a DOCTYPE with declarations (entities): they are not read"});
  EXPECT_NO_THROW(ChainTemplate::from_urdf(write_file("doctype.urdf", "<!DOCTYPE robot>\n" + robot(one)), "base", "tip"));
}

// Issue 53, cause 7: a URDF inertia no rigid body has is refused with the link and its values;
// a thin rod's (one principal moment 0, the triangle inequality met with equality) is one.
TEST(ChainTemplate, UrdfInertiaNoRigidBodyHasIsRefused) {
  const auto one_joint = [](const std::string& inertia) {
    return robot(urdf_link("base") + urdf_joint("j", "revolute", "base", "tip", "0.1 0 0", "0 0 0", "0 0 1") +
                 urdf_link("tip", "0.2 0 0", "0 0 0", 1.0, inertia));
  };
  EXPECT_NO_THROW(ChainTemplate::from_urdf(write_file("rod.urdf", one_joint("0 0 0 0.5 0 0.5")), "base", "tip"));
  EXPECT_NO_THROW(ChainTemplate::from_urdf(write_file("point.urdf", one_joint("0 0 0 0 0 0")), "base", "tip"));
  const std::string triangle = write_file("triangle.urdf", one_joint("0.1 0 0 0.1 0 0.3"));
  expect_error([&] { ChainTemplate::from_urdf(triangle, "base", "tip"); },
               {triangle + ": link \"tip\" <inertial> <inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" "
                           "izz=\"0.3\">: its principal moments (0.1, 0.1, 0.3) break the triangle inequality"});
  const std::string indefinite = write_file("indefinite.urdf", one_joint("0.1 0.2 0 0.1 0 0.1"));
  expect_error([&] { ChainTemplate::from_urdf(indefinite, "base", "tip"); },
               {"link \"tip\"", "must be >= 0 (positive semi-definite): no rigid body has this inertia"});
  // Each of these masses once changed GDI without a word: urdfdom logs "not a float" for nan and
  // inf and goes on with a mass of 0; a negative mass it reads as written.
  const auto with_mass = [&](double mass) {
    return write_file("mass.urdf", robot(urdf_link("base") + urdf_joint("j", "revolute", "base", "tip", "0.1 0 0", "0 0 0") +
                                         urdf_link("tip", "0.2 0 0", "0 0 0", mass, "0.01 0 0 0.01 0 0.01")));
  };
  for (const auto& [mass, shown] : {std::pair{std::nan(""), "nan"}, std::pair{HUGE_VAL, "inf"}}) {
    const std::string file = with_mass(mass);
    expect_error([&] { ChainTemplate::from_urdf(file, "base", "tip"); },
                 {file + ": not a valid URDF: Inertial: mass [" + shown + "] is not a float; Could not parse inertial "
                         "element for Link [tip]"});
  }
  const std::string negative = with_mass(-0.5);
  expect_error([&] { ChainTemplate::from_urdf(negative, "base", "tip"); },
               {negative + ": link \"tip\" <inertial> <mass value=\"-0.5\">: must be a finite mass >= 0 kg"});
}

// Issue 53, cause 6: joint and link names that are not UTF-8 are refused at load (they once
// failed the run only when result.json was written).
TEST(ChainTemplate, UrdfNamesThatAreNotUtf8AreRefusedAtLoad) {
  const std::string bad_joint = write_file("bad_joint.urdf",
      robot(urdf_link("base") + urdf_joint("j\xff" "1", "revolute", "base", "tip", "0.1 0 0", "0 0 0", "0 0 1") +
            urdf_link("tip", "0.2 0 0", "0 0 0", 1.0, "0.01 0 0 0.01 0 0.01")));
  expect_error([&] { ChainTemplate::from_urdf(bad_joint, "base", "tip"); },
               {bad_joint + ": joint name \"j\\xff1\": invalid UTF-8 at byte 1 (names become design variables"});
  const std::string bad_link = write_file("bad_link.urdf",
      robot(urdf_link("base") + urdf_joint("j", "revolute", "base", "t\xff", "0.1 0 0", "0 0 0", "0 0 1") +
            urdf_link("t\xff", "0.2 0 0", "0 0 0", 1.0, "0.01 0 0 0.01 0 0.01")));
  expect_error([&] { ChainTemplate::from_urdf(bad_link, "base", "t\xff"); },
               {bad_link + ": link name \"t\\xff\": invalid UTF-8 at byte 1"});
}

TEST(ChainTemplate, UrdfErrorsNameTheFileAndTheProblem) {
  expect_error([] { ChainTemplate::from_urdf("/nonexistent/arm.urdf", "a", "b"); },
               {"serial_chain: cannot read URDF file /nonexistent/arm.urdf: No such file or directory"});
  // A FIFO, a device or a directory is refused before it is read (nothing blocks or fills memory).
  expect_error([] { ChainTemplate::from_urdf("/dev/zero", "a", "b"); },
               {"serial_chain: URDF file /dev/zero is not a regular file (a device or socket)"});
  expect_error([] { ChainTemplate::from_urdf("/tmp", "a", "b"); },
               {"serial_chain: URDF file /tmp is not a regular file (a directory)"});
  const std::string bad_xml = write_file("bad_xml.urdf", "<?xml version=\"1.0\"?>\n<robot name=\"t\">\n  <link name=\"a\"/>\n"
                                                         "  <link name=\"b\"/>\n  <link name=\"c\"></joint>\n</robot>\n");
  expect_error([&] { ChainTemplate::from_urdf(bad_xml, "a", "b"); }, {bad_xml, "not valid XML: line 5, column 18: Error reading end tag"});
  const std::string refused = write_file("refused.urdf", robot(urdf_link("a") + urdf_joint("j", "revolute", "a", "missing", "0 0 0", "0 0 0")));
  expect_error([&] { ChainTemplate::from_urdf(refused, "a", "missing"); }, {refused, "not a valid URDF", "missing"});
  const std::string ur5 = share("ur5_like.urdf");
  expect_error([&] { ChainTemplate::from_urdf(ur5, "base_lnk", "tool0"); },
               {ur5, "base_link = \"base_lnk\": no such link, did you mean \"base_link\"?", "(links: base, base_link,"});
  expect_error([&] { ChainTemplate::from_urdf(ur5, "world", "tool1"); },
               {"tip_link = \"tool1\": no such link, did you mean \"tool0\"?"});
  expect_error([&] { ChainTemplate::from_urdf(ur5, "tool0", "base_link"); },
               {ur5, "tip_link = \"base_link\": not below base_link \"tool0\" (its ancestors: base_link <- world)"});
  expect_error([&] { ChainTemplate::from_urdf(ur5, "base", "tool0"); }, {"not below base_link \"base\""});
  expect_error([&] { ChainTemplate::from_urdf(ur5, "gripper_base", "finger_right"); },
               {ur5, "joint \"finger_right_joint\" mimic = \"finger_left_joint\"", "not supported"});
  expect_error([&] { ChainTemplate::from_urdf(ur5, "wrist_3_link", "tool0"); },
               {"from base_link \"wrist_3_link\" to tip_link \"tool0\" has 0 moving joints: must have 1 to 7"});
  expect_error([&] { ChainTemplate::from_urdf(ur5, "tool0", "tool0"); }, {"has 0 moving joints"});
  for (const char* type : {"floating", "planar"}) {
    const std::string path = write_file(std::string(type) + ".urdf",
                                        robot(urdf_link("a") + urdf_joint("j1", "revolute", "a", "b", "0 0 0", "0 0 0") +
                                              urdf_link("b") + urdf_joint("free", type, "b", "c", "0 0 0", "0 0 0") + urdf_link("c")));
    expect_error([&] { ChainTemplate::from_urdf(path, "a", "c"); },
                 {path, "joint \"free\" type = \"" + std::string(type) + "\": only revolute, continuous, prismatic and fixed"});
    EXPECT_EQ(ChainTemplate::from_urdf(path, "a", "b").dof(), 1);  // off the path: ignored
  }
  std::string links = urdf_link("l0");
  for (int i = 1; i <= 8; ++i) {
    links += urdf_joint("j" + std::to_string(i), "revolute", "l" + std::to_string(i - 1), "l" + std::to_string(i), "0 0 0.1", "0 0 0") +
             urdf_link("l" + std::to_string(i));
  }
  const std::string long_chain = write_file("eight.urdf", robot(links));
  expect_error([&] { ChainTemplate::from_urdf(long_chain, "l0", "l8"); }, {long_chain, "has 8 moving joints: must have 1 to 7"});
  EXPECT_EQ(ChainTemplate::from_urdf(long_chain, "l1", "l8").dof(), 7);
}

// ---- Fixed child links folded into the last moving body (issue 52) ----

namespace {

// A URDF link whose inertial is written with every digit (urdf_link prints 6).
std::string exact_link(const std::string& name, const Eigen::Vector3d& com, double mass, const Eigen::Matrix3d& i) {
  std::ostringstream s;
  s << std::setprecision(17) << "<link name=\"" << name << "\"><inertial><origin xyz=\"" << com.x() << " " << com.y()
    << " " << com.z() << "\" rpy=\"0 0 0\"/><mass value=\"" << mass << "\"/><inertia ixx=\"" << i(0, 0) << "\" ixy=\""
    << i(0, 1) << "\" ixz=\"" << i(0, 2) << "\" iyy=\"" << i(1, 1) << "\" iyz=\"" << i(1, 2) << "\" izz=\"" << i(2, 2)
    << "\"/></inertial></link>\n";
  return s.str();
}

// Two revolute joints about y along x; l2 carries a gripper on a rotated fixed joint, the gripper
// a finger on another (both inertials rotated, with products of inertia), and a jaw on a revolute
// joint (moving off the path: not folded); a camera is fixed to the base (no dynamics). `l2` is
// l2's link element, `extra` what hangs off the path.
std::string arm_with(const std::string& l2, const std::string& extra) {
  return robot(urdf_link("base") + urdf_joint("j1", "revolute", "base", "l1", "0 0 0.1", "0 0 0", "0 1 0") +
               urdf_link("l1", "0.25 0 0", "0 0 0", 2.0, "0.01 0 0 0.04 0 0.04") +
               urdf_joint("j2", "revolute", "l1", "l2", "0.5 0 0", "0 0 0", "0 1 0") + l2 +
               urdf_joint("tip_joint", "fixed", "l2", "tip", "0.4 0 0", "0 0 0") + urdf_link("tip") + extra);
}

const char* const kL2Inertia = "0.01 0.001 0 0.02 0 0.015";

std::string fold_extra(double gripper_mass = 0.8, const std::string& finger = "finger") {
  return urdf_link("camera", "0 0 0.05", "0 0 0", 0.2, "0.001 0 0 0.001 0 0.001") +
         urdf_joint("camera_mount", "fixed", "base", "camera", "0.1 0 0.3", "0 0.2 0") +
         urdf_joint("grip_mount", "fixed", "l2", "gripper", "0.4 0.02 -0.01", "0.3 -0.5 0.7") +
         urdf_link("gripper", "0.03 0.01 0.02", "0.1 0.2 0.3", gripper_mass,
                   "0.004 0.0005 -0.0003 0.005 0.0004 0.006") +
         urdf_joint("finger_mount", "fixed", "gripper", finger, "0.05 -0.02 0.03", "-0.4 0.6 1.1") +
         urdf_link(finger, "0.01 0.02 -0.03", "0.5 -0.3 0.2", 0.15, "0.0002 0.00003 -0.00002 0.0003 0.00001 0.00025") +
         urdf_joint("jaw_joint", "revolute", "gripper", "jaw", "0.08 0 0", "0 0 0", "0 0 1") +
         urdf_link("jaw", "0.02 0 0", "0 0 0", 0.3, "0.0001 0 0 0.0001 0 0.0001");
}

// One rigid part in l2's frame: mass, centre, inertia about the centre.
struct Part {
  double m;
  Eigen::Vector3d c;
  Eigen::Matrix3d i;
};

Part part_in(const Eigen::Isometry3d& link_in_l2, const Eigen::Isometry3d& inertial_in_link, double m,
             const Eigen::Matrix3d& i) {
  const Eigen::Isometry3d f = link_in_l2 * inertial_in_link;
  return {m, f.translation(), f.linear() * i * f.linear().transpose()};
}

Eigen::Matrix3d symmetric(double xx, double xy, double xz, double yy, double yz, double zz) {
  Eigen::Matrix3d i;
  i << xx, xy, xz, xy, yy, yz, xz, yz, zz;
  return i;
}

// l2, gripper and finger written out from the file's numbers and summed about the common centre:
// I = sum (R I_k R^T + m_k (|d_k|^2 1 - d_k d_k^T)), d_k from the common centre to part k's.
Part l2_with_gripper_by_hand() {
  const Eigen::Isometry3d gripper = xyz_rpy(0.4, 0.02, -0.01, 0.3, -0.5, 0.7);
  const Eigen::Isometry3d finger = gripper * xyz_rpy(0.05, -0.02, 0.03, -0.4, 0.6, 1.1);
  const std::vector<Part> parts = {
      part_in(Eigen::Isometry3d::Identity(), xyz_rpy(0.2, 0, 0, 0, 0, 0), 1.0,
              symmetric(0.01, 0.001, 0, 0.02, 0, 0.015)),
      part_in(gripper, xyz_rpy(0.03, 0.01, 0.02, 0.1, 0.2, 0.3), 0.8,
              symmetric(0.004, 0.0005, -0.0003, 0.005, 0.0004, 0.006)),
      part_in(finger, xyz_rpy(0.01, 0.02, -0.03, 0.5, -0.3, 0.2), 0.15,
              symmetric(0.0002, 0.00003, -0.00002, 0.0003, 0.00001, 0.00025))};
  Part sum{0.0, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero()};
  for (const Part& p : parts) {
    sum.m += p.m;
    sum.c += p.m * p.c;
  }
  sum.c /= sum.m;
  for (const Part& p : parts) {
    const Eigen::Vector3d d = p.c - sum.c;
    sum.i += p.i + p.m * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  return sum;
}

}  // namespace

TEST(ChainTemplate, FixedChildLinksFoldIntoTheirBodyAsTheHandMergedFile) {
  const std::string l2 = urdf_link("l2", "0.2 0 0", "0 0 0", 1.0, kL2Inertia);
  const std::string full = write_file("fold_full.urdf", arm_with(l2, fold_extra()));
  const Part hand = l2_with_gripper_by_hand();
  const std::string merged = write_file("fold_merged.urdf", arm_with(exact_link("l2", hand.c, hand.m, hand.i), ""));
  const Chain folded = nominal_chain(ChainTemplate::from_urdf(full, "base", "tip"));
  const Chain by_hand = nominal_chain(ChainTemplate::from_urdf(merged, "base", "tip"));
  ASSERT_EQ(folded.dof(), 2);
  // The body against the hand-written sum (l2's frame is body 1's frame).
  EXPECT_NEAR(folded.bodies[1].mass, 1.95, 1e-15);  // l2 + gripper + finger; not the jaw
  EXPECT_LT((folded.bodies[1].com - hand.c).norm(), 1e-15);
  EXPECT_LT((folded.bodies[1].inertia - hand.i).norm(), 1e-15) << folded.bodies[1].inertia << "\n\n" << hand.i;
  EXPECT_NEAR(folded.bodies[0].mass, 2.0, 1e-15);  // the camera rides on the base
  // H and the gravity torque against the file merged by hand.
  std::mt19937 rng(52);
  for (int k = 0; k < 20; ++k) {
    const std::vector<double> q = random_q(2, rng);
    const State a = state_at(folded, q), b = state_at(by_hand, q);
    EXPECT_LT((a.inertia - b.inertia).norm(), 1e-12) << a.inertia << "\n\n" << b.inertia;
    EXPECT_LT((a.gravity - b.gravity).norm(), 1e-12) << a.gravity.transpose() << "\n" << b.gravity.transpose();
  }
}

TEST(ChainTemplate, FoldingSwitchedOffIsTheFileWithoutTheChildLinks) {
  const std::string l2 = urdf_link("l2", "0.2 0 0", "0 0 0", 1.0, kL2Inertia);
  const std::string full = write_file("fold_off_full.urdf", arm_with(l2, fold_extra()));
  const std::string bare = write_file("fold_off_bare.urdf", arm_with(l2, ""));
  const ChainTemplate off = ChainTemplate::from_urdf(full, "base", "tip", false);
  const Chain a = nominal_chain(off), b = nominal_chain(ChainTemplate::from_urdf(bare, "base", "tip"));
  expect_same_bodies(a, b, 1e-15);
  expect_same_chain(a, b, 20, 1e-12);
  EXPECT_TRUE(off.folded_links().empty());
  EXPECT_TRUE(off.links_on_base().empty());
  EXPECT_EQ(off.find("gripper:mass"), -1);
  EXPECT_EQ(off.parameters().size(), ChainTemplate::from_urdf(bare, "base", "tip").parameters().size());
}

TEST(ChainTemplate, FoldedLinksAreListedAndTheirMassesAreDesignParameters) {
  const std::string l2 = urdf_link("l2", "0.2 0 0", "0 0 0", 1.0, kL2Inertia);
  const ChainTemplate t = ChainTemplate::from_urdf(write_file("fold_list.urdf", arm_with(l2, fold_extra())), "base", "tip");
  ASSERT_EQ(t.folded_links().size(), 1u);
  EXPECT_EQ(t.folded_links()[0].body, 1);
  EXPECT_EQ(t.folded_links()[0].body_link, "l2");
  EXPECT_EQ(t.folded_links()[0].links, (std::vector<std::string>{"gripper", "finger"}));
  EXPECT_EQ(t.links_on_base(), std::vector<std::string>{"camera"});
  EXPECT_EQ(t.find("camera:mass"), -1);  // no dynamics on the base
  EXPECT_EQ(t.find("jaw:mass"), -1);     // behind a moving joint: not folded
  std::vector<double> v = nominal(t);
  const Chain base = instantiate(t, v);
  value_of(t, v, "gripper:mass") = 1.6;
  value_of(t, v, "finger:mass") = 0.0;
  const Chain c = instantiate(t, v);
  EXPECT_NEAR(c.bodies[1].mass - base.bodies[1].mass, 0.8 - 0.15, 1e-15);
  // A fixed link on the path after a moving joint is listed too (the phantom's stylus tip).
  const ChainTemplate phantom = ChainTemplate::from_urdf(share("phantom_3r.urdf"), "world", "stylus_tip");
  ASSERT_EQ(phantom.folded_links().size(), 1u);
  EXPECT_EQ(phantom.folded_links()[0].body_link, "forearm");
  EXPECT_EQ(phantom.folded_links()[0].links, std::vector<std::string>{"stylus_tip"});
}

// Holding torque (tau_g = -sum J^T m g): at q = 0 the arm points along +x, and a positive turn
// about y lowers it, so a heavier payload needs more negative torque at both joints; their
// difference is the payload's weight times the 0.5 m between the two axes, whatever its centre.
TEST(ChainTemplate, APayloadAddsTheGravityTorqueOfItsWeightAtTheProximalJoints) {
  const std::string l2 = urdf_link("l2", "0.2 0 0", "0 0 0", 1.0, kL2Inertia);
  const ChainTemplate t = ChainTemplate::from_urdf(write_file("payload.urdf", arm_with(l2, fold_extra())), "base", "tip");
  const Chain with = nominal_chain(t);
  const Chain without = nominal_chain(ChainTemplate::from_urdf(write_file("payload_bare.urdf", arm_with(l2, "")), "base", "tip"));
  const State a = state_at(with, {0.0, 0.0}), b = state_at(without, {0.0, 0.0});
  const JointVector delta = a.gravity - b.gravity;
  EXPECT_LT(delta(0), 0.0);
  EXPECT_LT(delta(1), 0.0);
  EXPECT_LT(delta(0), delta(1));
  EXPECT_NEAR(delta(0) - delta(1), -9.81 * 0.95 * 0.5, 1e-12);
  // Released at rest the arm falls: both joints accelerate the way that lowers it.
  const JointVector qddot = a.inertia.ldlt().solve(-a.gravity);
  EXPECT_GT(qddot(0), 0.0);
  // Doubling the gripper's mass (a design variable) adds as much again of its share.
  std::vector<double> v = nominal(t);
  value_of(t, v, "gripper:mass") = 1.6;
  const JointVector heavier = state_at(instantiate(t, v), {0.0, 0.0}).gravity;
  EXPECT_LT(heavier(0), a.gravity(0));
  EXPECT_NEAR((heavier(0) - a.gravity(0)) - (heavier(1) - a.gravity(1)), -9.81 * 0.8 * 0.5, 1e-12);
}

TEST(ChainTemplate, ShippedUr5LikeCarriesItsGripperBaseButNotItsFingers) {
  const Chain on = nominal_chain(ChainTemplate::from_urdf(share("ur5_like.urdf"), "world", "tool0"));
  const Chain off = nominal_chain(ChainTemplate::from_urdf(share("ur5_like.urdf"), "world", "tool0", false));
  for (std::size_t i = 0; i < 5; ++i) EXPECT_EQ(on.bodies[i].mass, off.bodies[i].mass) << i;
  EXPECT_NEAR(on.bodies[5].mass - off.bodies[5].mass, 0.9, 1e-12);  // gripper_base; the fingers slide
}

TEST(ChainTemplate, FoldedLinkErrorsNameTheLinkAndTheRule) {
  const std::string l2 = urdf_link("l2", "0.2 0 0", "0 0 0", 1.0, kL2Inertia);
  const std::string negative = write_file("fold_negative.urdf", arm_with(l2, fold_extra(-0.5)));
  expect_error([&] { ChainTemplate::from_urdf(negative, "base", "tip"); },
               {negative + ": link \"gripper\" <inertial> <mass value=\"-0.5\">: must be a finite mass >= 0 kg"});
  EXPECT_NO_THROW(ChainTemplate::from_urdf(negative, "base", "tip", false));  // not read when not folded
  const std::string bad_name = write_file("fold_bad_name.urdf", arm_with(l2, fold_extra(0.8, "f\xff")));
  expect_error([&] { ChainTemplate::from_urdf(bad_name, "base", "tip"); },
               {bad_name + ": link name \"f\\xff\": invalid UTF-8 at byte 1 (names become design variables"});
  EXPECT_NO_THROW(ChainTemplate::from_urdf(bad_name, "base", "tip", false));
}
#else
TEST(ChainTemplate, UrdfWithoutUrdfdomIsRefusedClearly) {
  expect_error([] { ChainTemplate::from_urdf(share("ur5_like.urdf"), "world", "tool0"); },
               {"ur5_like.urdf: hapsyn was built without URDF support (HAPSYN_WITH_URDFDOM=OFF)"});
}
#endif

namespace {

// A valid two-row table the error tests break one thing of.
Json small_table() {
  return Json::parse(R"({
    "format": "hapsyn-dh", "format_version": 1, "convention": "dh",
    "units": {"length": "m", "angle": "deg"},
    "parameters": {"l1": 0.3, "l2": 0.2},
    "joints": [
      {"joint": "j1", "theta": 0, "d": 0.1, "a": "l1", "alpha": 90, "lower": -90, "upper": 90,
       "body": {"mass": 1.0, "com": [0.1, 0, 0], "inertia": [0.01, 0, 0, 0.02, 0, 0.03]}},
      {"joint": "j2", "theta": 0, "d": 0, "a": "-l2", "alpha": 0}
    ]
  })");
}

void expect_dh_error(const std::string& name, const Json& doc, std::initializer_list<std::string> fragments) {
  const std::string path = write_file(name + ".json", doc.dump());
  SCOPED_TRACE(name);
  expect_error([&] { ChainTemplate::from_dh_file(path); }, {path + ": "});
  expect_error([&] { ChainTemplate::from_dh_file(path); }, fragments);
}

}  // namespace

TEST(ChainTemplate, DhErrorsNameTheFileThePathTheValueAndTheRule) {
  EXPECT_EQ(ChainTemplate::from_dh_file(write_file("small.json", small_table().dump())).dof(), 2);
  expect_error([] { ChainTemplate::from_dh_file("/nonexistent/t.json"); },
               {"serial_chain: cannot read DH file /nonexistent/t.json: No such file or directory"});
  expect_error([] { ChainTemplate::from_dh_file("/dev/zero"); },
               {"serial_chain: DH file /dev/zero is not a regular file (a device or socket)"});
  const std::string not_json = write_file("not_json.json", "{\"format\": ");
  expect_error([&] { ChainTemplate::from_dh_file(not_json); }, {not_json + ":1:12: malformed JSON"});
  // Issue 53, cause 5: a deeply nested value once overflowed the stack (parsing it, then dumping it
  // into the message); it is refused before a document is built.
  const std::string deep = write_file("deep.json", "{\"format\": " + std::string(200000, '[') + std::string(200000, ']') + "}");
  expect_error([&] { ChainTemplate::from_dh_file(deep); },
               {"serial_chain: " + deep + ":1:267: nesting deeper than 256 levels (arrays and objects inside each other)"});

  Json d = small_table();
  d["format"] = "hapsyn-haptic6r-dh";
  expect_dh_error("format", d, {"format = \"hapsyn-haptic6r-dh\": must be \"hapsyn-dh\""});
  d = small_table();
  d["joints"] = Json::object();
  expect_dh_error("shape", d, {"joints = {}: must be an array of 1 to 7 rows"});
  d = small_table();
  for (int i = 0; i < 6; ++i) d["joints"].push_back({{"joint", "x" + std::to_string(i)}, {"theta", 0}, {"d", 0}, {"a", 0}, {"alpha", 0}});
  expect_dh_error("eight_rows", d, {"joints = 8 rows: must be an array of 1 to 7 rows"});
  d = small_table();
  d["joints"][0]["body"]["com"] = {0.1, 0};
  expect_dh_error("com", d, {"joints[0].body.com = [0.1,0]: must be an array of 3 numbers"});
  d = small_table();
  d["joints"][1]["alhpa"] = 0;
  expect_dh_error("unknown_key", d, {"joints[1].alhpa = 0: unknown key, did you mean \"alpha\"?", "(known: joint, type,"});
  d = small_table();
  d["unit"] = d["units"];
  expect_dh_error("unknown_top_key", d, {"unit = {", "unknown key, did you mean \"units\"?"});
  d = small_table();
  d["joints"][1]["a"] = "-l3";
  expect_dh_error("named", d, {"joints[1].a = \"-l3\": no such named length in \"parameters\", did you mean \"l1\"?", "(named: l1, l2)"});
  d = small_table();
  d["joints"][1]["theta"] = "l1";
  expect_dh_error("angle_named", d, {"joints[1].theta = \"l1\": must be a number"});
  d = small_table();
  d["units"]["length"] = "cm";
  expect_dh_error("units", d, {"units.length = \"cm\": must be \"m\" or \"mm\""});
  d = small_table();
  d["units"]["angle"] = "grad";
  expect_dh_error("angle_units", d, {"units.angle = \"grad\": must be \"deg\" or \"rad\""});
  d = small_table();
  d["units"].erase("angle");
  expect_dh_error("missing_unit", d, {"units.angle = (missing): required"});
  d = small_table();
  d["joints"][0].erase("theta");
  expect_dh_error("missing", d, {"joints[0].theta = (missing): required"});
  d = small_table();
  d["joints"][0]["lower"] = 100;
  expect_dh_error("limits", d, {"joints[0].lower = 100: must be <= upper (90)"});
  d = small_table();
  d["parameters"]["l1"] = -0.3;
  expect_dh_error("negative", d, {"parameters.l1 = -0.3: must be >= 0"});
  // Issue 53, cause 7: inertias no rigid body has (they changed GDI silently).
  d = small_table();
  d["joints"][0]["body"]["inertia"] = {1, 0, 0, 1, 0, 3};
  expect_dh_error("triangle", d, {"joints[0].body.inertia = [1,0,0,1,0,3]: its principal moments (1, 1, 3) break the "
                                  "triangle inequality: the largest may not exceed the sum of the other two: no rigid "
                                  "body has this inertia"});
  d = small_table();
  d["joints"][0]["body"]["inertia"] = {1, 2, 0, 1, 0, 1};
  expect_dh_error("not_definite", d, {"joints[0].body.inertia = [1,2,0,1,0,1]: its principal moments (-1, 1, 3) must be >= 0"});
  d = small_table();
  d["joints"][0]["type"] = "spherical";
  expect_dh_error("type", d, {"joints[0].type = \"spherical\": must be \"revolute\" or \"prismatic\""});
  d = small_table();
  d["joints"][1]["joint"] = "j1";
  expect_dh_error("duplicate", d, {"joints[1].joint = \"j1\": joint names must be unique"});
  d = small_table();
  d["convention"] = "craig";
  expect_dh_error("convention", d, {"convention = \"craig\": must be \"dh\" or \"modified_dh\""});
  d = small_table();
  d["mass_model"] = {{"kind", "fennel"}, {"motor_mass", {1, 1}}};
  expect_dh_error("body_and_model", d, {"joints[0].body", "exclude each other"});
  d = small_table();
  d["joints"][0].erase("body");
  d["mass_model"] = {{"kind", "fennel"}, {"motor_mass", {1, 1, 1}}};
  expect_dh_error("motor_count", d, {"mass_model.motor_mass = [1,1,1]: must be an array of 2 numbers"});
  d["mass_model"] = {{"kind", "fennel"}, {"motor_mass", {1, 1}}, {"tube_wal", 0.001}};
  expect_dh_error("model_key", d, {"mass_model.tube_wal = 0.001: unknown key, did you mean \"tube_wall\"?"});
  // Non-finite: JSON has no infinity or NaN, and nlohmann refuses a literal that overflows.
  const std::string huge = write_file("huge.json", "{\"format\": \"hapsyn-dh\", \"format_version\": 1, \"convention\": \"dh\", "
                                                   "\"units\": {\"length\": \"m\", \"angle\": \"deg\"}, \"joints\": [{\"joint\": "
                                                   "\"j\", \"theta\": 0, \"d\": 1e999, \"a\": 0, \"alpha\": 0}]}");
  expect_error([&] { ChainTemplate::from_dh_file(huge); }, {huge + ":1:151: malformed JSON: number 1e999 is out of range"});
}

TEST(ChainTemplate, ChainFilesResolveInTheShareDirectory) {
  const std::string path = resolve_serial_chain_file("chain_file", "serial_chain/ur5_like_dh.json");
  EXPECT_TRUE(std::ifstream(path).good()) << path;
  EXPECT_EQ(ChainTemplate::from_dh_file(path).dof(), 6);
  expect_error([] { resolve_serial_chain_file("chain_file", "serial_chain/nope.urdf"); },
               {"serial_chain: options.chain_file = \"serial_chain/nope.urdf\""});
}
