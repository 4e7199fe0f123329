// SerialChainModel: one design's chain, and the per-sample work: the target in the base frame,
// the IK, the classification and the quantities the metrics asked for.
#include "serial_chain.hpp"

#include <hapsyn/actuator_table.hpp>
#include <hapsyn/chain_motion.hpp>
#include <hapsyn/error.hpp>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>

namespace hapsyn::plugins {

namespace {

std::uint64_t next_model_id() {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
}

constexpr Needs kMotion = kNeedJointVelocity | kNeedJointAcceleration | kNeedVelocityTorque;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The task rows (task_jacobian's selection and projection) of one geometric 6-vector (omega, v).
void task_rows(const IkTask& task, const Eigen::Isometry3d& tip, const Vector6d& geometric, TaskJointMatrix& out) {
  TaskJointMatrix column = geometric;
  task_jacobian(task, tip, column, out);
}

}  // namespace

SerialChainModel::SerialChainModel(const double* design, const SerialChainSetup& setup)
    : setup_(&setup), id_(next_model_id()) {
  const ChainTemplate& t = setup.chain_template;
  const int n = t.dof();
  const int p = setup.parameter_count;
  JointVector motor_mass(n);
  const double* size = design + p;
  const double* gear = design + p + n;
  if (setup.actuators) {
    for (int i = 0; i < n; ++i) motor_mass(i) = setup.actuators->mass[static_cast<std::size_t>(std::lround(size[i]) - 1)];
  }
  t.instantiate(design, setup.actuators ? motor_mass.data() : nullptr, chain_);
  if (!t.meshes().visuals.empty()) mesh_parameters_.assign(design, design + t.parameters().size());
  if (setup.closed_form) {
    try {
      closed_form_ = std::make_unique<const ChainClosedFormIk>(chain_, setup.redundancy);
    } catch (const Error& e) {
      // The design moved an axis out of the nominal chain's family.
      if (setup.options.ik.solver == "closed_form") {
        throw Error("serial_chain", "options.ik.solver = \"closed_form\": this design's chain has no closed form (" +
                                        std::string(e.what()).substr(e.component().size() + 2) + ")");
      }
    }
  }
  max_velocity_.resize(n);
  max_torque_.resize(n);
  for (int i = 0; i < n; ++i) {
    const ChainJoint& j = chain_.joints[static_cast<std::size_t>(i)];
    if (setup.actuators) {
      const int s = static_cast<int>(std::lround(size[i])), r = static_cast<int>(std::lround(gear[i]));
      max_velocity_(i) = setup.actuators->max_velocity(s, r);
      max_torque_(i) = setup.actuators->max_torque(s, r);
    } else {
      max_velocity_(i) = j.max_velocity;
      max_torque_(i) = j.max_effort;
    }
  }
}

Eigen::Isometry3d SerialChainModel::target(const double* pose, int dimension) const {
  Eigen::Isometry3d sample = Eigen::Isometry3d::Identity();
  sample.translation() = Eigen::Vector3d(pose[0], pose[1], pose[2]);
  if (dimension == 7) {
    // Scenes give unit quaternions (the framework checks samples are finite; normalising here
    // keeps a slightly denormalised file quaternion from skewing the target).
    sample.linear() = Eigen::Quaterniond(pose[3], pose[4], pose[5], pose[6]).normalized().toRotationMatrix();
  }
  return setup_->base_from_scene * sample * setup_->sample_to_tip;
}

void SerialChainModel::solve(const double* pose, Needs needs, MechanismScratch& scratch, SampleQuantities& out) const {
  auto& s = static_cast<SerialChainScratch&>(scratch);
  const SerialChainSetup& setup = *setup_;
  const int dimension = out.scene ? out.scene->dimension() : (setup.task.orientation == IkTask::Orientation::kNone ? 3 : 7);
  const Eigen::Isometry3d goal = target(pose, dimension);
  out.q.resize(chain_.dof());
  IkStatus status;
  if (closed_form_) {
    status = closed_form_->solve(chain_, goal, setup.home.data(), setup.first_found, out.q.data(), s.closed_form);
  } else {
    const double* starts[2];
    int start_count = 0;
    if (setup.options.ik.warm_start && s.last_model == id_) starts[start_count++] = s.last_q.data();
    starts[start_count++] = setup.home.data();
    status = solve_ik(chain_, setup.task, setup.ik, goal, starts, start_count, setup.home.data(), setup.first_found,
                      out.q.data(), s.ik);
  }
  if (status == IkStatus::kUnreachable) {
    out.status = SampleStatus::kUnreachable;
    return;
  }
  if (status == IkStatus::kJointLimit) {
    out.status = SampleStatus::kInvalid;
    return;
  }
  if (setup.options.ik.warm_start) {
    s.last_q = out.q;
    s.last_model = id_;
  }
  chain_frames(chain_, out.q.data(), s.frames);
  chain_jacobian(chain_, s.frames, s.geometric);
  task_jacobian(setup.task, s.frames.tip, s.geometric, s.task);
  // Singularity: the task Jacobian with its angular rows times the characteristic length, so
  // that every row is a velocity [m/s]; its inverse condition number against the tolerance.
  const int angular = s.task.rows() - 3;
  TaskJointMatrix scaled = s.task;
  scaled.topRows(angular) *= setup.characteristic_length;
  if (!chain_well_conditioned(scaled, setup.options.singularity_tolerance)) {
    out.status = SampleStatus::kSingular;
    return;
  }
  out.status = SampleStatus::kReachable;
  fill_quantities(s.frames, s.task, needs, out);
  if (needs & kMotion) fill_motion(pose, dimension, goal, s, needs, out);
}

bool SerialChainModel::drawn_frames(const SampleSet& scene, int sample, MechanismScratch& scratch,
                                    ChainFrames& frames) const {
  SampleQuantities q;
  q.scene = &scene;
  q.sample = sample;
  solve(scene.pose(sample), kNeedPose, scratch, q);
  if (q.status == SampleStatus::kUnreachable || q.status == SampleStatus::kInvalid) return false;
  chain_frames(chain_, q.q.data(), frames);
  return true;
}

std::vector<Segment> SerialChainModel::segments(const SampleSet& scene, int sample, MechanismScratch& scratch) const {
  ChainFrames frames;
  if (!drawn_frames(scene, sample, scratch, frames)) return {};
  const Eigen::Isometry3d scene_from_base = setup_->base_from_scene.inverse();
  Segment links{"links", {scene_from_base.translation()}};
  for (int i = 0; i < chain_.dof(); ++i) {
    links.points.push_back(scene_from_base * frames.joint[static_cast<std::size_t>(i)].translation());
  }
  links.points.push_back(scene_from_base * frames.tip.translation());
  // The tool point P (the sample's point) when a tool frame moves it off the tip.
  const Eigen::Vector3d tool = scene_from_base * (frames.tip * setup_->sample_to_tip.inverse()).translation();
  if ((tool - links.points.back()).norm() > 1e-12) links.points.push_back(tool);
  return {links};
}

DemandedMotion SerialChainModel::demanded_motion(const double* pose, int dimension, const Eigen::Isometry3d& goal,
                                                 const double* twist, const double* twist_rate) const {
  const Eigen::Matrix3d& r = setup_->base_from_scene.linear();
  const Eigen::Vector3d lever = goal.translation() - setup_->base_from_scene * Eigen::Vector3d(pose[0], pose[1], pose[2]);
  DemandedMotion m;
  m.twist.head<3>() = r * Eigen::Vector3d(twist[0], twist[1], twist[2]);
  // A position sample has no orientation: its target E does not turn about P.
  const Eigen::Vector3d w = dimension == 7 ? Eigen::Vector3d(m.twist.head<3>()) : Eigen::Vector3d::Zero();
  m.twist.tail<3>() = r * Eigen::Vector3d(twist[3], twist[4], twist[5]) + w.cross(lever);
  if (twist_rate) {
    m.twist_rate.head<3>() = r * Eigen::Vector3d(twist_rate[0], twist_rate[1], twist_rate[2]);
    const Eigen::Vector3d dw = dimension == 7 ? Eigen::Vector3d(m.twist_rate.head<3>()) : Eigen::Vector3d::Zero();
    m.twist_rate.tail<3>() =
        r * Eigen::Vector3d(twist_rate[3], twist_rate[4], twist_rate[5]) + dw.cross(lever) + w.cross(w.cross(lever));
  } else {
    m.twist_rate.setConstant(kNaN);
  }
  return m;
}

void SerialChainModel::fill_motion(const double* pose, int dimension, const Eigen::Isometry3d& goal,
                                   SerialChainScratch& s, Needs needs, SampleQuantities& out) const {
  const int n = chain_.dof();
  std::array<WorldJoint, kMaxChainJoints> joints;
  chain_world_joints(chain_, s.frames, joints.data());
  out.joint_velocity.resize(n);
  if (!out.twist) {  // outside the evaluator (Problem refuses a scene without the twist)
    out.joint_velocity.setConstant(kNaN);
  } else {
    const DemandedMotion demand = demanded_motion(pose, dimension, goal, out.twist, out.twist_rate);
    TaskJointMatrix rows;
    task_rows(setup_->task, s.frames.tip, demand.twist, rows);
    JointRateSolver solver;
    solver.compute(s.task);
    solver.solve(rows.data(), out.joint_velocity);
    if (needs & kNeedJointAcceleration) {
      Vector6d rate;
      jacobian_rate_times_rate(joints.data(), n, s.frames.tip.translation(), out.joint_velocity.data(), rate.data());
      Vector6d wanted = demand.twist_rate - rate;
      if (setup_->task.orientation == IkTask::Orientation::kAxis) {
        wanted.head<3>() += axis_rate_term(s.frames.tip.linear().col(setup_->task.axis), demand.twist.head<3>(),
                                           s.geometric.topRows<3>() * out.joint_velocity);
      }
      task_rows(setup_->task, s.frames.tip, wanted, rows);
      solver.solve(rows.data(), out.joint_acceleration);
    }
  }
  if (needs & kNeedVelocityTorque) {
    std::array<WorldBody, kMaxChainJoints> bodies;
    chain_world_bodies(chain_, s.frames, bodies.data());
    out.velocity_torque.resize(n);
    velocity_torque(joints.data(), bodies.data(), n, out.joint_velocity.data(), out.velocity_torque.data());
  }
}

Eigen::Vector3d SerialChainModel::axis_rate_term(const Eigen::Vector3d& axis, const Eigen::Vector3d& omega,
                                                 const Eigen::Vector3d& omega_chain) {
  return axis.dot(omega_chain - omega) * omega.cross(axis);
}

void SerialChainModel::fill_quantities(const ChainFrames& frames, const TaskJointMatrix& jacobian, Needs needs,
                                       SampleQuantities& out) const {
  if (needs & kNeedJacobian) out.jacobian = jacobian;
  if (needs & (kNeedInertia | kNeedEffectiveMass)) chain_inertia(chain_, frames, out.inertia);
  if (needs & kNeedEffectiveMass) {
    // M = (J H^-1 J^T)^-1: J^-T H J^-1 for a square J, and the task-space inertia of a
    // redundant chain (Khatib) otherwise. H is symmetric positive definite for a chain whose
    // every joint moves some mass; LDLT keeps a massless joint from producing a NaN silently.
    const Eigen::LDLT<JointMatrix> h(out.inertia);
    const TaskJointMatrix j_h_inv = h.solve(jacobian.transpose()).transpose();  // (H^-1 J^T)^T = J H^-1
    const TaskMatrix lambda_inv = j_h_inv * jacobian.transpose();
    out.effective_mass = lambda_inv.inverse();
  }
  if (needs & kNeedGravity) chain_gravity(chain_, frames, out.gravity);
  if (needs & kNeedActuatorLimits) {
    out.max_velocity = max_velocity_;
    out.max_torque = max_torque_;
  }
}

}  // namespace hapsyn::plugins
