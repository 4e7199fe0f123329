// Inverse kinematics of a Chain (chain_ik.hpp): Levenberg-Marquardt on the task rows, with
// joint limits by projection and an active set, seeded restarts, the closest-to-home rule and,
// for redundant chains, self-motion toward home.
//
// Why the pieces are as they are:
// - Scaling: the position rows are divided by the chain's reach (the sum of its fixed
//   translations) and prismatic coordinates measured in reaches, so every row and column is
//   dimensionless; the damping mu I and the step cap then mean the same for a 0.2 m device and
//   a 2 m arm.
// - Damping (Nielsen 1999): mu starts at kTau max(diag J^T J) and follows the gain ratio rho of
//   the actual to the predicted cost reduction; a rejected step multiplies mu by nu = 2, 4, 8...
//   With mu > 0 the normal matrix is positive definite, so a singular Jacobian (wrist, elbow,
//   stretched arm, zero-length link, a joint that cannot move the tip) gives a short finite
//   step, never a NaN. A run stops (stalls) when mu exceeds kMuMax or the step or the relative
//   cost reduction vanishes: a local minimum of |e| that is not a solution.
// - Limits: a clamped joint sitting at a bound whose step points outward is held fixed and the
//   system re-solved without it (active set, at most n passes), so the other joints still make
//   full progress; the rest of the step is clamped. Continuous revolute joints are wrapped.
// - The step is capped at kMaxStep (1 rad, or one reach for a prismatic joint): far from the
//   solution the Gauss-Newton step of an ill-conditioned Jacobian is meaningless in size.
// - Determinism: no clock, no threads, no unordered containers, no state between calls;
//   restarts come from splitmix64 seeded by (seed, index), so every platform with IEEE doubles
//   gives the same starts (the last bits of an answer still depend on libm and FMA contraction).
// - Allocation: every matrix has a fixed capacity (IkScratch); nothing here allocates.
#include "chain_ik.hpp"

#include "shared/closed_form_ik/angles.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace hapsyn::plugins {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPi = 2.0 * kPi;
constexpr double kTau = 1e-3;      // initial damping relative to max(diag J^T J)
constexpr double kMuFloor = 1e-12;  // damping floor when J^T J vanishes (zero-reach chain)
constexpr double kMuMax = 1e16;     // damping beyond which a run has stalled
constexpr double kMaxStep = 1.0;    // largest joint step per iteration [rad or reach]
constexpr double kStepStall = 1e-14;  // relative step (and relative cost reduction) of a stall
constexpr double kNullspaceDone = 1e-6;  // self-motion step [rad or reach] below which home is reached

// --- joints ---------------------------------------------------------------------------------

bool is_revolute(const ChainJoint& j) { return j.type == ChainJointType::kRevolute; }

// A revolute joint whose limits span a full turn never meets them: it is wrapped, not clamped.
bool is_continuous(const ChainJoint& j) { return is_revolute(j) && !(j.upper - j.lower < kTwoPi); }

// x wrapped into (-pi, pi].
double wrap_pi(double x) {
  double r = closed_form_ik::remainder_two_pi(x);  // std::remainder's bits, several times faster
  if (r <= -kPi) r += kTwoPi;
  return r;
}

// x wrapped into a full turn inside a continuous joint's limits: (-pi, pi] when that fits,
// else [lower, lower + 2 pi), else (upper - 2 pi, upper].
double wrap_continuous(const ChainJoint& j, double x) {
  const double w = wrap_pi(x);
  if (j.lower <= -kPi && j.upper >= kPi) return w;
  if (std::isfinite(j.lower)) {
    double r = w - j.lower;
    r -= kTwoPi * std::floor(r / kTwoPi);
    return j.lower + (r >= kTwoPi ? 0.0 : r);
  }
  double r = j.upper - w;
  r -= kTwoPi * std::floor(r / kTwoPi);
  return j.upper - (r >= kTwoPi ? 0.0 : r);
}

// Joint value x moved into joint j's limits (clamped or wrapped).
double project(const ChainJoint& j, double x) {
  return is_continuous(j) ? wrap_continuous(j, x) : std::clamp(x, j.lower, j.upper);
}

const ChainJoint& joint(const Chain& chain, int i) { return chain.joints[static_cast<std::size_t>(i)]; }

// The chain's length scale [m]: the sum of its fixed translations (1 m for a chain without any).
double chain_reach(const Chain& chain) {
  double r = chain.tip.translation().norm();
  for (const ChainJoint& j : chain.joints) r += j.origin.translation().norm();
  return r > 1e-9 ? r : 1.0;
}

double home_distance(const Chain& chain, const double* q, const double* home) { return ik_home_distance(chain, q, home); }

std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// Uniform in [0, 1) from the top 53 bits.
double unit_uniform(std::uint64_t& state) { return static_cast<double>(splitmix64(state) >> 11) * 0x1.0p-53; }

// --- task error -----------------------------------------------------------------------------

// The rotation vector (axis times angle in [0, pi]) of a rotation matrix, via the quaternion
// (robust at any angle, no acos).
Eigen::Vector3d rotation_vector(const Eigen::Matrix3d& r) {
  const Eigen::Quaterniond quat(r);
  double w = quat.w();
  Eigen::Vector3d v = quat.vec();
  if (w < 0.0) {
    w = -w;
    v = -v;
  }
  const double s = v.norm();
  return v * (s > 0.0 ? 2.0 * std::atan2(s, w) / s : 2.0 / w);
}

// The rotation vector of the shortest rotation carrying unit a onto unit b (pi u1 when they
// are exactly opposite: any axis orthogonal to b does). Its direction a x b is made orthogonal
// to b explicitly: near opposite axes |a x b| is rounding noise with no direction of its own.
Eigen::Vector3d axis_rotation(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& u1) {
  const Eigen::Vector3d c = a.cross(b);
  const double angle = std::atan2(c.norm(), a.dot(b));
  const Eigen::Vector3d direction = c - c.dot(b) * b;
  const double length = direction.norm();
  if (length > 0.0) return direction * (angle / length);
  return angle > kPi / 2 ? Eigen::Vector3d(kPi * u1) : Eigen::Vector3d::Zero();
}

// The task error with a given kAxis basis (u1, u2 orthogonal to the target's axis).
void error_rows(const IkTask& task, const Eigen::Isometry3d& tip, const Eigen::Isometry3d& target,
                const Eigen::Vector3d& u1, const Eigen::Vector3d& u2, TaskVector& e) {
  e.resize(task.rows());
  int row = 0;
  if (task.orientation == IkTask::Orientation::kFull) {
    e.head<3>() = rotation_vector(target.linear() * tip.linear().transpose());
    row = 3;
  } else if (task.orientation == IkTask::Orientation::kAxis) {
    const Eigen::Vector3d r = axis_rotation(tip.linear().col(task.axis), target.linear().col(task.axis), u1);
    e(0) = u1.dot(r);
    e(1) = u2.dot(r);
    row = 2;
  }
  if (task.position) e.segment<3>(row) = target.translation() - tip.translation();
}

// The task Jacobian rows with a given kAxis basis.
void jacobian_rows(const IkTask& task, const Eigen::Vector3d& u1, const Eigen::Vector3d& u2,
                   const TaskJointMatrix& geometric, TaskJointMatrix& out) {
  const auto n = geometric.cols();
  out.resize(task.rows(), n);
  int row = 0;
  if (task.orientation == IkTask::Orientation::kFull) {
    out.topRows<3>() = geometric.topRows<3>();
    row = 3;
  } else if (task.orientation == IkTask::Orientation::kAxis) {
    out.row(0) = u1.transpose() * geometric.topRows<3>();
    out.row(1) = u2.transpose() * geometric.topRows<3>();
    row = 2;
  }
  if (task.position) out.middleRows<3>(row) = geometric.bottomRows<3>();
}

// --- one run --------------------------------------------------------------------------------

// Everything about one target that does not change between iterations.
struct Problem {
  const Chain& chain;
  const IkTask& task;
  const IkSettings& settings;
  const Eigen::Isometry3d& target;
  Eigen::Vector3d u1 = Eigen::Vector3d::UnitX(), u2 = Eigen::Vector3d::UnitY();
  double reach = 1.0;
  int n = 0;
  int orientation_rows = 0;

  Problem(const Chain& c, const IkTask& t, const IkSettings& s, const Eigen::Isometry3d& x)
      : chain(c), task(t), settings(s), target(x), reach(chain_reach(c)), n(c.dof()),
        orientation_rows(t.orientation_rows()) {
    assert(n >= 1 && n <= kMaxChainJoints);
    assert(t.rows() >= 1 && t.rows() <= kMaxTask && t.axis >= 0 && t.axis < 3);
    if (t.orientation == IkTask::Orientation::kAxis) axis_basis(x.linear().col(t.axis), u1, u2);
  }
  // Internal (dimensionless) units of joint i per chain unit.
  double joint_scale(int i) const { return is_revolute(joint(chain, i)) ? 1.0 : 1.0 / reach; }
};

// FK at q into scratch.frames, the scaled error into e and the residual; returns 1/2 |e|^2.
double evaluate(const Problem& p, const double* q, IkScratch& s, TaskVector& e, IkResidual& residual) {
  chain_frames(p.chain, q, s.frames);
  error_rows(p.task, s.frames.tip, p.target, p.u1, p.u2, e);
  residual.orientation = p.orientation_rows > 0 ? e.head(p.orientation_rows).norm() : 0.0;
  residual.position = 0.0;
  if (p.task.position) {
    residual.position = e.tail<3>().norm();
    e.tail<3>() /= p.reach;
  }
  return 0.5 * e.squaredNorm();
}

// The scaled task Jacobian at scratch.frames into scratch.task_jacobian.
void scaled_jacobian(const Problem& p, IkScratch& s) {
  chain_jacobian(p.chain, s.frames, s.jacobian);
  jacobian_rows(p.task, p.u1, p.u2, s.jacobian, s.task_jacobian);
  if (p.task.position) s.task_jacobian.bottomRows<3>() /= p.reach;
  for (int i = 0; i < p.n; ++i) s.task_jacobian.col(i) /= p.joint_scale(i);
}

bool at_bound_pushing_out(const ChainJoint& j, double x, double step) {
  return !is_continuous(j) && ((x <= j.lower && step < 0.0) || (x >= j.upper && step > 0.0));
}

// The damped step (internal units) into scratch.step for the normal equations in
// scratch.normal / scratch.gradient; joints at a bound pushing out are held (limited runs).
void damped_step(const Problem& p, const double* q, double mu, bool limited, IkScratch& s) {
  std::array<bool, kMaxChainJoints> held{};
  for (int pass = 0; pass <= p.n; ++pass) {
    IkJointMatrix m = s.normal;
    IkJointVector g = s.gradient;
    for (int i = 0; i < p.n; ++i) {
      if (held[static_cast<std::size_t>(i)]) {
        m.row(i).setZero();
        m.col(i).setZero();
        g(i) = 0.0;
      }
      m(i, i) += held[static_cast<std::size_t>(i)] ? 1.0 : mu;
    }
    s.llt.compute(m);
    s.step = s.llt.solve(g);
    if (!limited) return;
    bool changed = false;
    for (int i = 0; i < p.n; ++i) {
      if (!held[static_cast<std::size_t>(i)] && at_bound_pushing_out(joint(p.chain, i), q[i], s.step(i))) {
        held[static_cast<std::size_t>(i)] = true;
        changed = true;
      }
    }
    if (!changed) return;
  }
}

enum class RunEnd { kConverged, kFailed };

// One Levenberg-Marquardt run from q (in/out). `limited`: inside the joint limits; otherwise the
// limits are ignored (the kJointLimit check). *cost: the final 1/2 |e|^2 (scaled).
RunEnd run(const Problem& p, double* q, bool limited, IkScratch& s, double* cost_out = nullptr) {
  const int n = p.n;
  if (limited) {
    for (int i = 0; i < n; ++i) q[i] = project(joint(p.chain, i), q[i]);
  }
  IkResidual residual, trial_residual;
  double cost = evaluate(p, q, s, s.error, residual);
  if (cost_out) *cost_out = cost;
  if (!std::isfinite(cost)) return RunEnd::kFailed;
  if (residual.within(p.settings)) return RunEnd::kConverged;
  double mu = -1.0, nu = 2.0;
  bool fresh = true;  // the frames in scratch are those of q: the normal equations need rebuilding
  for (int evaluation = 1; evaluation < p.settings.max_iterations; ++evaluation) {
    if (fresh) {
      scaled_jacobian(p, s);
      s.normal.noalias() = s.task_jacobian.transpose() * s.task_jacobian;
      s.gradient.noalias() = s.task_jacobian.transpose() * s.error;
      if (mu < 0.0) mu = std::max(kTau * s.normal.diagonal().maxCoeff(), kMuFloor);
      fresh = false;
    }
    damped_step(p, q, mu, limited, s);
    const double largest = s.step.cwiseAbs().maxCoeff();
    if (largest > kMaxStep) s.step *= kMaxStep / largest;
    double q_norm = 0.0;
    for (int i = 0; i < n; ++i) {
      const double x = q[i] + s.step(i) / p.joint_scale(i);
      const ChainJoint& j = joint(p.chain, i);
      s.trial[static_cast<std::size_t>(i)] = limited ? project(j, x) : x;
      // The step actually taken (clamping shortens it; wrapping does not change it).
      if (!(limited && is_continuous(j))) s.step(i) = (s.trial[static_cast<std::size_t>(i)] - q[i]) * p.joint_scale(i);
      q_norm = std::max(q_norm, std::abs(q[i] * p.joint_scale(i)));
    }
    const double predicted = s.gradient.dot(s.step) - 0.5 * s.step.dot(s.normal * s.step);
    const double trial_cost = evaluate(p, s.trial.data(), s, s.trial_error, trial_residual);
    const bool tiny_step = s.step.cwiseAbs().maxCoeff() <= kStepStall * (1.0 + q_norm);
    if (predicted > 0.0 && trial_cost < cost) {
      const double rho = (cost - trial_cost) / predicted;
      const bool no_progress = cost - trial_cost <= kStepStall * cost;
      std::copy_n(s.trial.data(), n, q);
      s.error = s.trial_error;
      cost = trial_cost;
      if (cost_out) *cost_out = cost;
      if (trial_residual.within(p.settings)) return RunEnd::kConverged;
      if (tiny_step || no_progress) return RunEnd::kFailed;
      const double r = 2.0 * rho - 1.0;
      mu *= std::max(1.0 / 3.0, 1.0 - r * r * r);
      mu = std::max(mu, kMuFloor);
      nu = 2.0;
      fresh = true;
    } else {
      if (tiny_step) return RunEnd::kFailed;
      mu *= nu;
      nu *= 2.0;
      if (mu > kMuMax) return RunEnd::kFailed;
    }
  }
  return RunEnd::kFailed;
}

// --- self-motion toward home (redundant chains) ----------------------------------------------

// A run stops as soon as the error is within the tolerances; a few more nearly undamped
// Gauss-Newton steps (quadratic convergence) take a converged solution to rounding level, so
// that what is computed at it (Jacobian, inertia, metrics) does not carry the tolerance's 1e-10
// and two solvers of the same configuration agree to their rounding. Only improvements are kept.
void polish(const Problem& p, double* q, IkScratch& s) {
  IkResidual residual, trial_residual;
  double cost = evaluate(p, q, s, s.error, residual);
  for (int iteration = 0; iteration < 3 && cost > 0.0; ++iteration) {
    scaled_jacobian(p, s);
    s.normal.noalias() = s.task_jacobian.transpose() * s.task_jacobian;
    s.gradient.noalias() = s.task_jacobian.transpose() * s.error;
    damped_step(p, q, std::max(1e-14 * s.normal.diagonal().maxCoeff(), kMuFloor), true, s);
    for (int i = 0; i < p.n; ++i) {
      s.trial[static_cast<std::size_t>(i)] = project(joint(p.chain, i), q[i] + s.step(i) / p.joint_scale(i));
    }
    const double trial_cost = evaluate(p, s.trial.data(), s, s.trial_error, trial_residual);
    if (!(trial_cost < cost)) break;
    std::copy_n(s.trial.data(), p.n, q);
    s.error = s.trial_error;
    cost = trial_cost;
  }
}

// The null-space component N (home - q) of the scaled task Jacobian at scratch.frames, in
// internal units, into scratch.step; returns its largest magnitude.
double nullspace_direction(const Problem& p, const double* q, const double* home, IkScratch& s) {
  scaled_jacobian(p, s);
  const TaskJointMatrix& j = s.task_jacobian;
  s.gradient.resize(p.n);
  for (int i = 0; i < p.n; ++i) {
    const double d = is_revolute(joint(p.chain, i)) ? wrap_pi(home[i] - q[i]) : home[i] - q[i];
    s.gradient(i) = d * p.joint_scale(i);
  }
  // N d = d - J^T (J J^T + eps I)^-1 J d; eps keeps a rank-deficient J J^T invertible.
  TaskMatrix jjt = j * j.transpose();
  jjt.diagonal().array() += 1e-12 * (1.0 + jjt.diagonal().maxCoeff());
  const TaskVector jd = j * s.gradient;
  const TaskVector y = jjt.llt().solve(jd);
  s.step = s.gradient - j.transpose() * y;
  return s.step.cwiseAbs().maxCoeff();
}

// Moves converged q (in/out) along its self-motion toward home; q stays converged.
void move_toward_home(const Problem& p, const double* home, double* q, IkScratch& s) {
  double distance = home_distance(p.chain, q, home);
  double gain = 1.0;
  double* moved = s.start.data();
  for (int k = 0; k < p.settings.nullspace_steps && gain > 1.0 / 64.0; ++k) {
    IkResidual unused;
    evaluate(p, q, s, s.error, unused);
    const double largest = nullspace_direction(p, q, home, s);
    if (largest < kNullspaceDone) return;  // home's projection on the self-motion reached
    const double scale = gain * std::min(1.0, kMaxStep / largest);
    for (int i = 0; i < p.n; ++i) moved[i] = q[i] + scale * s.step(i) / p.joint_scale(i);
    double moved_distance = 0.0;
    if (run(p, moved, true, s) == RunEnd::kConverged &&
        (moved_distance = home_distance(p.chain, moved, home)) < distance) {
      std::copy_n(moved, p.n, q);
      distance = moved_distance;
      gain = std::min(1.0, 2.0 * gain);
    } else {
      gain *= 0.5;
    }
  }
}

// q moved into the limits by whole turns of its revolute joints; false when some joint cannot be.
// The k-th start of solve_ik: given ones first, then the seeded pseudo-random ones.
void start_of(const Chain& chain, const IkSettings& settings, const double* const* starts, int start_count, int k,
              double* q) {
  if (k < start_count) {
    std::copy_n(starts[k], chain.dof(), q);
  } else {
    ik_random_start(chain, settings.seed, k - start_count, q);
  }
}

}  // namespace

void axis_basis(const Eigen::Vector3d& b, Eigen::Vector3d& u1, Eigen::Vector3d& u2) {
  int k = 0;
  for (int i = 1; i < 3; ++i) {
    if (std::abs(b(i)) < std::abs(b(k))) k = i;
  }
  u1 = Eigen::Vector3d::Unit(k) - b(k) * b;
  u1.normalize();
  u2 = b.cross(u1);
}

void task_error(const IkTask& task, const Eigen::Isometry3d& tip, const Eigen::Isometry3d& target, TaskVector& error) {
  Eigen::Vector3d u1 = Eigen::Vector3d::UnitX(), u2 = Eigen::Vector3d::UnitY();
  if (task.orientation == IkTask::Orientation::kAxis) axis_basis(target.linear().col(task.axis), u1, u2);
  error_rows(task, tip, target, u1, u2, error);
}

IkResidual task_residual(const IkTask& task, const Eigen::Isometry3d& tip, const Eigen::Isometry3d& target) {
  TaskVector e;
  task_error(task, tip, target, e);
  const int orows = task.orientation_rows();
  IkResidual r;
  r.orientation = orows > 0 ? e.head(orows).norm() : 0.0;
  r.position = task.position ? e.tail<3>().norm() : 0.0;
  return r;
}

void task_jacobian(const IkTask& task, const Eigen::Isometry3d& tip, const TaskJointMatrix& geometric,
                   TaskJointMatrix& out) {
  Eigen::Vector3d u1 = Eigen::Vector3d::UnitX(), u2 = Eigen::Vector3d::UnitY();
  if (task.orientation == IkTask::Orientation::kAxis) axis_basis(tip.linear().col(task.axis), u1, u2);
  jacobian_rows(task, u1, u2, geometric, out);
}

void ik_random_start(const Chain& chain, std::uint64_t seed, int index, double* q) {
  std::uint64_t state = seed ^ (0xD1B54A32D192ED03ULL * (static_cast<std::uint64_t>(index) + 1));
  const double reach = chain_reach(chain);
  for (int i = 0; i < chain.dof(); ++i) {
    const ChainJoint& j = joint(chain, i);
    const double u = unit_uniform(state);
    double x;
    if (std::isfinite(j.lower) && std::isfinite(j.upper) && !is_continuous(j)) {
      x = j.lower + (j.upper - j.lower) * u;
    } else if (is_revolute(j)) {
      x = kPi - kTwoPi * u;  // (-pi, pi]
    } else {
      x = reach * (1.0 - 2.0 * u);
    }
    q[i] = project(j, x);
  }
}

double ik_home_distance(const Chain& chain, const double* q, const double* home) {
  double d = 0.0;
  for (int i = 0; i < chain.dof(); ++i) {
    const double x = is_revolute(joint(chain, i)) ? wrap_pi(q[i] - home[i]) : q[i] - home[i];
    d += x * x;
  }
  return d;
}

bool ik_shift_into_limits(const Chain& chain, double* q, double tolerance) {
  for (int i = 0; i < chain.dof(); ++i) {
    const ChainJoint& j = joint(chain, i);
    if (is_continuous(j)) {
      q[i] = wrap_continuous(j, q[i]);
      continue;
    }
    double x = q[i];
    if (is_revolute(j)) {
      x = wrap_pi(x);
      if (x < j.lower - tolerance) x += kTwoPi;
      if (x > j.upper + tolerance) x -= kTwoPi;
    }
    if (x < j.lower - tolerance || x > j.upper + tolerance) return false;
    q[i] = std::clamp(x, j.lower, j.upper);
  }
  return true;
}

IkStatus solve_ik_from(const Chain& chain, const IkTask& task, const IkSettings& settings,
                       const Eigen::Isometry3d& target, const double* start, double* q, IkScratch& scratch) {
  const Problem p(chain, task, settings, target);
  if (q != start) std::copy_n(start, p.n, q);
  return run(p, q, true, scratch) == RunEnd::kConverged ? IkStatus::kConverged : IkStatus::kUnreachable;
}

IkStatus solve_ik(const Chain& chain, const IkTask& task, const IkSettings& settings,
                  const Eigen::Isometry3d& target, const double* const* starts, int start_count,
                  const double* home, bool first_converged, double* q, IkScratch& scratch) {
  const Problem p(chain, task, settings, target);
  const int n = p.n;
  const int total = start_count + std::max(settings.restarts, 0);
  const bool pick_first = first_converged || home == nullptr;
  const bool redundant = n > task.rows() && settings.nullspace_steps > 0;
  double* candidate = scratch.candidate.data();
  double closest = std::numeric_limits<double>::infinity(), lowest_cost = closest;
  bool found = false;
  for (int k = 0; k < total; ++k) {
    start_of(chain, settings, starts, start_count, k, candidate);
    double cost = 0.0;
    if (run(p, candidate, true, scratch, &cost) != RunEnd::kConverged) {
      if (!found && !(cost >= lowest_cost)) {  // also takes a NaN cost's iterate when nothing better exists
        lowest_cost = cost;
        std::copy_n(candidate, n, scratch.best.data());
      }
      continue;
    }
    if (pick_first) {
      std::copy_n(candidate, n, q);
      polish(p, q, scratch);
      return IkStatus::kConverged;
    }
    if (redundant) move_toward_home(p, home, candidate, scratch);
    const double distance = home_distance(chain, candidate, home);
    if (distance < closest) {
      closest = distance;
      std::copy_n(candidate, n, scratch.closest.data());
      found = true;
    }
  }
  if (found) {
    std::copy_n(scratch.closest.data(), n, q);
    polish(p, q, scratch);
    return IkStatus::kConverged;
  }
  // Nothing converged inside the limits: is the pose reachable at all?
  for (int k = 0; k < total; ++k) {
    start_of(chain, settings, starts, start_count, k, candidate);
    if (run(p, candidate, false, scratch) != RunEnd::kConverged) continue;
    std::copy_n(candidate, n, q);
    if (ik_shift_into_limits(chain, q, 0.0)) {
      IkResidual residual;
      evaluate(p, q, scratch, scratch.error, residual);
      if (residual.within(settings)) return IkStatus::kConverged;  // whole turns away from a limited run's reach
    }
    std::copy_n(candidate, n, q);
    return IkStatus::kJointLimit;
  }
  std::copy_n(scratch.best.data(), n, q);
  return IkStatus::kUnreachable;
}

}  // namespace hapsyn::plugins
