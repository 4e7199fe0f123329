#include "fivebar.hpp"

#include <hapsyn/error.hpp>

#include <Eigen/Core>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <optional>
#include <limits>

namespace hapsyn::plugins {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr const char* kName = "fivebar";
// solve_leg's rounding bound of its area term, in units of spread^2 (26 eps, rounded up).
constexpr double kAreaTolerance = 32.0 * kEps;

std::string show(double value) { return Json(value).dump(); }

/// One leg solved in its own frame: the left leg in the mechanism frame, the right leg in the
/// frame mirrored about x = 0 (so both legs run the same code and the model is exactly
/// mirror-symmetric).
struct Leg {
  double ux = 0.0, uy = 0.0;  // unit vector along the actuated link
  double wx = 0.0, wy = 0.0;  // free link vector E - B [m]
  double q_act = 0.0;         // atan2(E - A) + acos(c), in (-pi, 2pi]
  double q_free = 0.0;        // angle of E - B, in [-pi/2, 3pi/2)
};

enum class LegResult { kSolved, kUnreachable, kOnJoint };

/// Elbow-out inverse kinematics of one leg with E - A = (dx, dy).
///
/// Without the angle at A or rho = |E - A| (KERNELS.md section 13.2): with along = 2 l1 rho
/// cos(angle) = l1^2 - l2^2 + rho^2 and root = 2 l1 rho sin(angle) >= 0, the law of cosines in
/// Heron's form gives root^2 = ((l1 + l2)^2 - rho^2)(rho^2 - (l1 - l2)^2), and the actuated link's
/// unit vector is (along (dx, dy) + root (-dy, dx)) / (2 l1 rho^2): one square root and one
/// division, where the cosine, the sine and the unit vector of E - A took three and two (on this
/// kind of CPU a vector square root or division costs 16 to 24 multiplications).
LegResult solve_leg(double dx, double dy, double l1, double l2, Leg& leg) {
  const double rho2 = dx * dx + dy * dy;
  const double diff = (l1 - l2) * (l1 + l2);  // l1^2 - l2^2 without cancellation
  const double spread = l1 * l1 + l2 * l2 + rho2;
  if (!(rho2 > 0.0)) {
    // E on the actuated joint: reachable only folded (l1 = l2), with any q1; singular.
    return std::abs(diff) <= 8.0 * kEps * spread ? LegResult::kOnJoint : LegResult::kUnreachable;
  }
  const double sum = l1 + l2, fold = l1 - l2;
  const double area = (sum * sum - rho2) * (rho2 - fold * fold);  // root^2
  // Rounding bound of area (each factor is off by at most 10 eps spread, and |factor| <= 2
  // spread): a sample on the reach boundary (rho = l1 + l2 or |l1 - l2|) may compute a slightly
  // negative area; it counts as 0 (and is then classified singular), never NaN.
  const double tolerance = kAreaTolerance * spread * spread;
  if (!(area >= -tolerance)) return LegResult::kUnreachable;
  const double root = std::sqrt(area > 0.0 ? area : 0.0);
  const double along = diff + rho2;
  const double inv = 1.0 / (2.0 * l1 * rho2);
  leg.ux = (along * dx - root * dy) * inv;  // E - A rotated counter-clockwise by the angle: elbow out
  leg.uy = (along * dy + root * dx) * inv;
  leg.wx = dx - l1 * leg.ux;
  leg.wy = dy - l1 * leg.uy;
  leg.q_act = std::atan2(dy, dx) + std::atan2(root, along);
  double q_free = std::atan2(leg.wy, leg.wx);
  if (q_free < -0.5 * kPi) q_free += 2.0 * kPi;
  leg.q_free = q_free;
  return LegResult::kSolved;
}

void check_length(const char* name, double value, bool allow_zero) {
  if (!std::isfinite(value) || value < 0.0 || (!allow_zero && value == 0.0)) {
    throw Error(kName, std::string("design ") + name + " = " + show(value) +
                           (allow_zero ? ": must be finite and >= 0" : ": must be finite and > 0"));
  }
}

}  // namespace

FiveBarModel::FiveBarModel(const FiveBarDesign& design, const FiveBarOptions& options)
    : design_(design), singularity_tolerance_(options.singularity_tolerance), rho_(options.rho), k_(options.k) {
  // One test for the usual case (a model is built per design); the messages only on failure.
  const bool usable = design.l0 >= 0.0 && design.l1 > 0.0 && design.l2 > 0.0 && design.l0 < kInfinity &&
                      design.l1 < kInfinity && design.l2 < kInfinity && std::abs(design.r) < kInfinity;
  if (!usable) {
    check_length("l0", design.l0, true);
    check_length("l1", design.l1, false);
    check_length("l2", design.l2, false);
    if (!std::isfinite(design.r)) throw Error(kName, "design r = " + show(design.r) + ": must be finite");
  }
  h0_ = 0.5 * design.l0;
  m1_ = options.rho * design.l1;
  m2_ = options.rho * design.l2;
  const double k2 = options.k * options.k;
  inertia_a_ = m1_ * (4.0 * design.l1 * design.l1 + k2) / 12.0;
  inertia_f_ = m2_ * (design.l2 * design.l2 + k2) / 12.0;
  l2_squared_ = design.l2 * design.l2;
  block_ = FiveBarBlockDesign{h0_, design.l1, design.l2, design.r, options.singularity_tolerance, m2_, inertia_a_, inertia_f_};
}

std::vector<Segment> FiveBarModel::segments(const SampleSet& scene, int sample, MechanismScratch& scratch) const {
  SampleQuantities q;
  solve(scene.pose(sample), kNeedPose, scratch, q);
  if (q.status == SampleStatus::kUnreachable) return {};
  // Scene frame = mechanism frame shifted by (0, -r): A1 = (-l0/2, -r), A2 = (l0/2, -r).
  const double l1 = design_.l1, y0 = -design_.r;
  const Eigen::Vector3d a1(-h0_, y0, 0.0), a2(h0_, y0, 0.0);
  const Eigen::Vector3d b1 = a1 + l1 * Eigen::Vector3d(std::cos(q.q[0]), std::sin(q.q[0]), 0.0);
  const Eigen::Vector3d b2 = a2 + l1 * Eigen::Vector3d(std::cos(q.q[3]), std::sin(q.q[3]), 0.0);
  const Eigen::Vector3d e(scene.pose(sample)[0], scene.pose(sample)[1], 0.0);
  return {Segment{"links", {a1, b1, e, b2, a2}}, Segment{"base", {a1, a2}}};
}

void FiveBarModel::solve_block(const PoseBlock& poses, Needs needs, MechanismScratch& scratch,
                               QuantityBlock& out) const {
#if HAPSYN_HAVE_HIGHWAY
  (void)scratch;
  solve_fivebar_block(block_, poses.coordinate[0], poses.coordinate[1], needs, out);
#else
  MechanismAcceleration::solve_block(poses, needs, scratch, out);  // built without Highway: solve() per lane
#endif
}

void FiveBarModel::solve(const double* pose, Needs needs, MechanismScratch& /*scratch*/,
                         SampleQuantities& out) const {
  const double l1 = design_.l1, l2 = design_.l2;
  const double x = pose[0];
  const double y = pose[1] + design_.r;
  out.q.resize(4);

  Leg left, right;  // right: solved in the mirrored frame (x -> -x)
  const LegResult rl = solve_leg(x + h0_, y, l1, l2, left);
  const LegResult rr = solve_leg(h0_ - x, y, l1, l2, right);
  if (rl == LegResult::kUnreachable || rr == LegResult::kUnreachable) {
    out.q.setZero();
    out.status = SampleStatus::kUnreachable;
    return;
  }
  if (rl == LegResult::kOnJoint || rr == LegResult::kOnJoint) {
    out.q.setZero();
    out.status = SampleStatus::kSingular;
    return;
  }

  const double q1 = left.q_act, q2 = left.q_free;
  const double q3 = kPi - right.q_free, q4 = kPi - right.q_act;
  out.q << q1, q2, q3, q4;

  // Vectors in the mechanism frame.
  const double u1x = left.ux, u1y = left.uy, w1x = left.wx, w1y = left.wy;
  const double u4x = -right.ux, u4y = right.uy, w2x = -right.wx, w2y = right.wy;

  // Transmission sines (cross products of the link vectors).
  const double inv_l2 = 1.0 / l2;
  const double s12 = (left.wx * left.uy - left.wy * left.ux) * inv_l2;      // sin(q1 - q2)
  const double s34 = (right.wx * right.uy - right.wy * right.ux) * inv_l2;  // sin(q3 - q4)
  const double cross12 = w1x * w2y - w1y * w2x;                              // l2^2 sin(q3 - q2)
  const double s23 = cross12 * (1.0 / l2_squared_);
  const double tol = singularity_tolerance_;
  if (!(std::abs(s12) >= tol && std::abs(s34) >= tol && std::abs(s23) >= tol)) {
    out.status = SampleStatus::kSingular;
    return;
  }

  // The paper's G: q2 >= 0, q2 <= q1, q3 <= pi, q3 >= q4 (closed inequalities with a small
  // tolerance, docs/design.md section 6) and the working mode 0 < q3 - q2 < pi. Together they give
  // 0 <= q2 < q3 <= pi: the end effector lies above both elbows.
  const double t = kFiveBarAngleTolerance;
  const double mode = q3 - q2;
  const bool valid = q2 >= -t && q2 <= q1 + t && q3 <= kPi + t && q4 <= q3 + t && mode > 0.0 && mode < kPi;
  if (!valid) {
    out.status = SampleStatus::kInvalid;
    return;
  }
  out.status = SampleStatus::kReachable;
  if ((needs & (kNeedJacobian | kNeedInertia | kNeedEffectiveMass)) == 0) return;

  // Jacobian. For each leg (E - B_i) . (Edot - l1 qidot perp(u_i)) = 0, i.e.
  // W Edot = diag(b1, b2) qdot with W = [w1^T; w2^T], b_i = l1 cross(u_i, w_i).
  const double b1 = l1 * (u1x * w1y - u1y * w1x);  // -l1 l2 sin(q1 - q2)
  const double b2 = l1 * (u4x * w2y - u4y * w2x);  //  l1 l2 sin(q3 - q4)
  const double inv_det = 1.0 / cross12;
  Eigen::Matrix2d jac;
  jac << w2y * b1 * inv_det, -w1y * b2 * inv_det,  //
      -w2x * b1 * inv_det, w1x * b2 * inv_det;
  if (needs & kNeedJacobian) {
    out.jacobian.resize(2, 2);
    out.jacobian = jac;
  }
  if ((needs & (kNeedInertia | kNeedEffectiveMass)) == 0) return;

  // Joint-space inertia from the kinetic energy of the four bars:
  //  actuated bars rotate about their joints: 1/2 I_a qidot^2, I_a = m1 (4 l1^2 + k^2) / 12;
  //  free bar i: centre velocity = (velocity of B_i + velocity of E) / 2 = C_i qdot,
  //  angular rate = perp(w_i) . (Edot - Bdot_i) / l2^2 = a_i^T qdot, I_f = m2 (l2^2 + k^2) / 12.
  Eigen::Matrix2d p1 = Eigen::Matrix2d::Zero(), p2 = Eigen::Matrix2d::Zero();
  p1(0, 0) = -l1 * u1y;  // velocity of B1 per q1dot: l1 perp(u1)
  p1(1, 0) = l1 * u1x;
  p2(0, 1) = -l1 * u4y;  // velocity of B2 per q4dot: l1 perp(u4)
  p2(1, 1) = l1 * u4x;
  const Eigen::Matrix2d c1 = 0.5 * (p1 + jac);
  const Eigen::Matrix2d c2 = 0.5 * (p2 + jac);
  const double inv_l2_squared = 1.0 / l2_squared_;
  const Eigen::Vector2d a2 = (jac - p1).transpose() * Eigen::Vector2d(-w1y, w1x) * inv_l2_squared;
  const Eigen::Vector2d a3 = (jac - p2).transpose() * Eigen::Vector2d(-w2y, w2x) * inv_l2_squared;
  Eigen::Matrix2d inertia = m2_ * (c1.transpose() * c1 + c2.transpose() * c2) +
                            inertia_f_ * (a2 * a2.transpose() + a3 * a3.transpose());
  inertia(0, 0) += inertia_a_;
  inertia(1, 1) += inertia_a_;
  out.inertia.resize(2, 2);
  out.inertia = inertia;
  if ((needs & kNeedEffectiveMass) == 0) return;

  // M = J^-T D J^-1 with J^-1 = diag(b1, b2)^-1 W (no inversion of J).
  Eigen::Matrix2d jac_inv;
  const double inv_b1 = 1.0 / b1, inv_b2 = 1.0 / b2;
  jac_inv << w1x * inv_b1, w1y * inv_b1,  //
      w2x * inv_b2, w2y * inv_b2;
  out.effective_mass.resize(2, 2);
  out.effective_mass = jac_inv.transpose() * inertia * jac_inv;
}

bool FiveBarModel::forward(double q1, double q4, double* xy) const {
  const double l1 = design_.l1, l2 = design_.l2;
  const double b1x = -h0_ + l1 * std::cos(q1), b1y = l1 * std::sin(q1);
  const double b2x = h0_ + l1 * std::cos(q4), b2y = l1 * std::sin(q4);
  const double ex = b2x - b1x, ey = b2y - b1y;
  const double d = std::hypot(ex, ey);
  if (!(d > 0.0) || d > 2.0 * l2) return false;
  const double h = std::sqrt(std::max(0.0, l2_squared_ - 0.25 * d * d));
  // E = midpoint + h * perp(e) / d: the branch with cross(E - B1, E - B2) > 0.
  xy[0] = 0.5 * (b1x + b2x) - h * ey / d;
  xy[1] = 0.5 * (b1y + b2y) + h * ex / d - design_.r;
  return true;
}

FiveBarDesign FiveBar::design_from(const double* design) {
  // Validated once, by the FiveBarModel constructor every caller passes it to (culling builds
  // ~1e9 models: checking twice is measurable).
  return FiveBarDesign{design[0], design[1], design[2], design[3]};
}

std::unique_ptr<const MechanismModel> FiveBar::build(const double* design) const {
  return std::make_unique<const FiveBarModel>(design_from(design), options_);
}

namespace {
// The model lives in the thread's scratch, so solvers that visit ~1e9 grid designs (culling)
// rebuild it in place instead of allocating one per design.
struct FiveBarScratch final : MechanismScratch {
  std::optional<FiveBarModel> model;
  // solve_designs' model of a grid line (r = -0), kept while the line's l0, l1, l2 stay the same
  // (bit for bit): a solver calls it once per sample for each group of the line's designs.
  std::optional<FiveBarModel> line_model;
  double line_key[3] = {};
};
}  // namespace

std::unique_ptr<MechanismScratch> FiveBar::make_scratch() const { return std::make_unique<FiveBarScratch>(); }

const MechanismModel* FiveBar::build_in(const double* design, MechanismScratch& scratch) const {
  // The evaluator passes the scratch this mechanism's make_scratch() made (the contract of
  // build_in); a dynamic_cast per design costs more than the model.
  assert(dynamic_cast<FiveBarScratch*>(&scratch));
  auto* own = static_cast<FiveBarScratch*>(&scratch);
  own->model.emplace(design_from(design), options_);
  return &*own->model;
}

bool FiveBar::solve_designs(const double* const* designs, int count, const double* pose, Needs needs,
                            MechanismScratch& scratch, QuantityBlock& out) const {
#if HAPSYN_HAVE_HIGHWAY
  if (!solves_blocks(needs)) return false;
  const double* first = designs[0];
  for (int i = 1; i < kBlockLanes; ++i) {
    if (designs[i][0] != first[0] || designs[i][1] != first[1] || designs[i][2] != first[2]) return false;
  }
  // The model of the line's l0, l1, l2 with r = -0: y + r_i + (-0) is y + r_i exactly, also
  // when y + r_i is -0, so every lane computes what its own design's model computes.
  assert(dynamic_cast<FiveBarScratch*>(&scratch));
  auto& own = static_cast<FiveBarScratch&>(scratch);
  if (!own.line_model || std::memcmp(own.line_key, first, sizeof own.line_key) != 0) {
    FiveBarDesign line = design_from(first);
    line.r = -0.0;
    own.line_model.emplace(line, options_);
    std::memcpy(own.line_key, first, sizeof own.line_key);
  }
  const FiveBarModel& model = *own.line_model;
  alignas(64) double x[kBlockLanes], y[kBlockLanes];
  for (int i = 0; i < kBlockLanes; ++i) {
    x[i] = pose[0];
    y[i] = pose[1] + designs[i][3];
  }
  PoseBlock poses;
  poses.coordinate[0] = x;
  poses.coordinate[1] = y;
  poses.dimension = 2;
  poses.count = count;
  model.solve_block(poses, needs, scratch, out);
  return true;
#else
  (void)designs, (void)count, (void)pose, (void)needs, (void)scratch, (void)out;
  return false;
#endif
}

std::vector<VariableDecl> FiveBar::variables() const {
  auto scalar = [](const char* name, const char* description, double lower, double upper,
                   double hard_lower, double hard_upper) {
    VariableDecl v;
    v.name = name;
    v.description = description;
    v.unit = "m";
    v.default_lower = {lower};
    v.default_upper = {upper};
    v.hard_lower = {hard_lower};
    v.hard_upper = {hard_upper};
    return v;
  };
  return {scalar("l0", "distance between the actuated joints", 0.0, 0.3, 0.0, 10.0),
          scalar("l1", "actuated link length (l1 = l4)", 0.01, 0.3, 1e-4, 10.0),
          scalar("l2", "free link length (l2 = l3)", 0.01, 0.3, 1e-4, 10.0),
          scalar("r", "placement: distance from the actuated joints' midpoint to the scene centre",
                 0.0, 0.6, -10.0, 10.0)};
}

std::vector<ConstraintDecl> FiveBar::constraints() const {
  std::vector<ConstraintDecl> c = {ConstraintDecl{"reach",
                                                  "farthest corner of the scene's bounding box within l1 + l2 of both actuated "
                                                  "joints: max_i |corner - A_i|^2 - (l1 + l2)^2 <= 0 [m^2]"}};
  if (options_.footprint_width > 0.0 || options_.footprint_height > 0.0) {
    c.push_back(ConstraintDecl{"footprint",
                               "the box around both actuated joints' circles of radius l1 and the scene fits "
                               "footprint_width x footprint_height [m]"});
  }
  return c;
}

double FiveBar::footprint_constraint(const FiveBarDesign& design, double xmin, double xmax, double ymin, double ymax,
                                     double width, double height) {
  const double h0 = 0.5 * design.l0;
  const double box_width = std::max(h0 + design.l1, xmax) - std::min(-h0 - design.l1, xmin);
  const double box_height = std::max(design.l1, ymax + design.r) - std::min(-design.l1, ymin + design.r);
  double g = -std::numeric_limits<double>::infinity();
  if (width > 0.0) g = std::max(g, box_width - width);
  if (height > 0.0) g = std::max(g, box_height - height);
  return std::isfinite(g) ? g : -1.0;
}

double FiveBar::reach_constraint(const FiveBarDesign& design, double xmin, double xmax, double ymin,
                                 double ymax) {
  const double h0 = 0.5 * design.l0;
  const double ay = std::max(std::abs(ymin + design.r), std::abs(ymax + design.r));
  const double ax1 = std::max(std::abs(xmin + h0), std::abs(xmax + h0));  // from A1 = (-h0, 0)
  const double ax2 = std::max(std::abs(xmin - h0), std::abs(xmax - h0));  // from A2 = (+h0, 0)
  const double ax = std::max(ax1, ax2);
  const double reach = design.l1 + design.l2;
  return (ax * ax + ay * ay) - reach * reach;
}

void FiveBar::reach_interval(const FiveBarDesign& design, double xmin, double xmax, double ymin, double ymax,
                             double& lower, double& upper) {
  const double h0 = 0.5 * design.l0;
  const double ax = std::max(std::max(std::abs(xmin + h0), std::abs(xmax + h0)),
                             std::max(std::abs(xmin - h0), std::abs(xmax - h0)));
  const double reach = design.l1 + design.l2;
  const double room = reach * reach - ax * ax;  // R^2: what the y distance may use
  if (room < -1e-9 * reach * reach) {  // empty, beyond rounding: no corner placement reaches
    lower = 1.0;
    upper = -1.0;
    return;
  }
  const double r_max = std::sqrt(std::max(room, 0.0));
  lower = -r_max - ymin;
  upper = r_max - ymax;
}

bool FiveBar::constraint_interval(const double* design, int component, const SampleSet& scene, double& lower,
                                  double& upper) const {
  if (component != 3 || scene.dimension() != 2 || scene.size() == 0) return false;
  reach_interval(design_from(design), scene.min_coordinate(0), scene.max_coordinate(0), scene.min_coordinate(1),
                 scene.max_coordinate(1), lower, upper);
  if (lower > upper) return true;
  // Rounding: reach_constraint and this interval round differently; a margin far above their
  // few-ulp errors keeps the interval a superset of the designs reach_constraint accepts.
  const double margin = 1e-9 * (1.0 + std::abs(lower) + std::abs(upper));
  lower -= margin;
  upper += margin;
  return true;
}

bool FiveBar::reachable_interval(const double* design, int component, const double* pose, double& lower,
                                 double& upper) const {
  if (component != 3) return false;
  const FiveBarDesign d = design_from(design);
  if (!(d.l0 >= 0.0 && d.l1 > 0.0 && d.l2 > 0.0)) return false;
  const double h0 = 0.5 * d.l0, x = pose[0], y = pose[1];
  const double a = std::abs(x + h0), b = std::abs(h0 - x);
  const double near = std::min(a, b), far = std::max(a, b);
  // Relative slack on the squared distances, far above solve_leg's rounding bound of the law of
  // cosines (8 eps (l1^2 + l2^2 + rho^2) / (2 l1 rho) on c): a sample the interval leaves out is
  // unreachable beyond doubt.
  constexpr double kSlack = 1e-9;
  const double reach = d.l1 + d.l2, fold = d.l1 - d.l2;
  const double room = reach * reach * (1.0 + kSlack) - far * far;  // Y^2 the farther leg allows
  if (room < 0.0) {
    lower = 1.0;
    upper = -1.0;
    return true;
  }
  const double gap = fold * fold * (1.0 - kSlack) - near * near;  // Y^2 the nearer leg needs
  // Below the actuated joints' axis (Y < 0) no elbow-out posture satisfies G: with q2 >= -t
  // and q1 >= q2 - t, Y = l1 sin q1 + l2 sin q2 >= -(2 l1 + l2) t (t = 1e-9 rad). The margin
  // covers that and the rounding of y + r.
  const double margin = 1e-8 * (d.l1 + d.l2 + std::abs(x) + std::abs(y) + h0);
  lower = (gap > 0.0 ? std::sqrt(gap) : 0.0) - y - margin;
  upper = std::sqrt(room) - y + margin;
  return true;
}

bool FiveBar::sample_envelope(const double* design, int component, double lower, double upper, const double* pose,
                              Needs needs, SampleEnvelope& out) const {
  if (component != 3) return false;  // the run's r enters as y + r: the angles are monotone in it
  const FiveBarDesign d = design_from(design);
  if (!(d.l0 >= 0.0 && d.l1 > 0.0 && d.l2 > 0.0) || !(lower <= upper)) return false;
  // The masses and inertias as FiveBarModel computes them.
  const double k2 = options_.k * options_.k;
  const double m1 = options_.rho * d.l1, m2 = options_.rho * d.l2;
  FiveBarRun run;
  run.h0 = 0.5 * d.l0;
  run.l1 = d.l1;
  run.l2 = d.l2;
  run.y_low = pose[1] + lower;  // the model's rounded y + r, monotone in r
  run.y_high = pose[1] + upper;
  run.singularity_tolerance = options_.singularity_tolerance;
  run.inertia_a = m1 * (4.0 * d.l1 * d.l1 + k2) / 12.0;
  run.mass_f = m2;
  run.inertia_f = m2 * (d.l2 * d.l2 + k2) / 12.0;
  return fivebar_envelope(run, pose[0], (needs & kNeedEffectiveMass) != 0, out);
}

bool FiveBar::constraints_quasiconvex(int component) const {
  return component == 3 && options_.footprint_width <= 0.0 && options_.footprint_height <= 0.0;
}

void FiveBar::evaluate_constraints(const double* design, const SampleSet& scene, double* g) const {
  if (scene.dimension() != 2 || scene.size() == 0) check_scene(scene);
  // Cached by the framework once per study: O(1) and allocation-free per design.
  const double xmin = scene.min_coordinate(0), ymin = scene.min_coordinate(1);
  const double xmax = scene.max_coordinate(0), ymax = scene.max_coordinate(1);
  const FiveBarDesign d{design[0], design[1], design[2], design[3]};
  g[0] = reach_constraint(d, xmin, xmax, ymin, ymax);
  if (options_.footprint_width > 0.0 || options_.footprint_height > 0.0) {
    g[1] = footprint_constraint(d, xmin, xmax, ymin, ymax, options_.footprint_width, options_.footprint_height);
  }
}

void FiveBar::check_scene(const SampleSet& scene) const {
  if (scene.dimension() != 2) {
    throw Error(kName, "scene samples have " + std::to_string(scene.dimension()) +
                           " coordinates: the five-bar serves planar scenes of (x, y) [m] samples");
  }
  if (scene.size() == 0) throw Error(kName, "scene has no samples");
}

Needs FiveBar::provides() const { return kNeedJacobian | kNeedInertia | kNeedEffectiveMass; }

bool FiveBar::solves_blocks(Needs needs) const {
#if HAPSYN_HAVE_HIGHWAY
  return (needs & ~(kNeedJacobian | kNeedInertia | kNeedEffectiveMass)) == 0;
#else
  (void)needs;
  return false;
#endif
}

}  // namespace hapsyn::plugins
