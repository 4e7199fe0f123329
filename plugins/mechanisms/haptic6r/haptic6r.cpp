// The haptic6r plugin: the options resolved into a Haptic6RSetup (data files read, angles in
// radians) and the Mechanism interface (design space, constraints, models).
#include "haptic6r.hpp"

#include <hapsyn/error.hpp>

#include <cstddef>
#include <string>

namespace hapsyn::plugins {

namespace {

constexpr const char* kName = "haptic6r";
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// A 6-angle option [deg] in radians (the declarations guarantee 6 finite numbers).
Vector6d radians(const std::vector<double>& degrees) {
  Vector6d out;
  for (int i = 0; i < 6; ++i) out(i) = degrees[static_cast<std::size_t>(i)] * kDeg;
  return out;
}

Haptic6RSelection selection_rule(const std::string& name) {
  return name == "elbow_left" ? Haptic6RSelection::kElbowLeft
         : name == "elbow_right" ? Haptic6RSelection::kElbowRight
                                 : Haptic6RSelection::kClosestToHome;
}

}  // namespace

std::string haptic6r_joint_range_rule(const Haptic6ROptions& o) {
  const Vector6d lower = radians(o.joint_lower), upper = radians(o.joint_upper);
  for (int i = 0; i < 6; ++i) {
    // Compared in radians, as the model compares the angles; reported in degrees.
    if (!(upper(i) >= lower(i)) || upper(i) - lower(i) > 2.0 * kPi + 1e-12) {
      return "[" + std::to_string(i) + "] = " + std::to_string(upper(i) / kDeg) + ": must be >= joint_lower[" +
             std::to_string(i) + "] (" + std::to_string(lower(i) / kDeg) + ") and span at most 360 deg";
    }
  }
  return "";
}

Haptic6RSetup Haptic6RSetup::from_options(const Haptic6ROptions& options) {
  Haptic6RSetup s;
  s.options = options;
  s.dh = read_haptic6r_dh(resolve_haptic6r_file("dh_file", options.dh_file));
  s.actuators = read_actuator_table(resolve_haptic6r_file("actuator_file", options.actuator_file), kName);
  s.selection = selection_rule(options.selection);
  s.home = radians(options.home);
  s.joint_lower = radians(options.joint_lower);
  s.joint_upper = radians(options.joint_upper);
  return s;
}

namespace {
struct Haptic6RScratch final : MechanismScratch {
  Haptic6RModel model;
};
}  // namespace

std::unique_ptr<const MechanismModel> Haptic6R::build(const double* design) const {
  auto model = std::make_unique<Haptic6RModel>();
  model->rebuild(design, setup_);
  return model;
}

const MechanismModel* Haptic6R::build_in(const double* design, MechanismScratch& scratch) const {
  auto* s = dynamic_cast<Haptic6RScratch*>(&scratch);
  if (!s) return nullptr;
  s->model.rebuild(design, setup_);
  return &s->model;
}

std::unique_ptr<MechanismScratch> Haptic6R::make_scratch() const { return std::make_unique<Haptic6RScratch>(); }

std::vector<VariableDecl> Haptic6R::variables() const {
  VariableDecl l{"l", "link lengths l1..l5 (SCARA links, vertical drop, vertical-SCARA link, wrist to end effector)", "m", 5,
                 false, {0.3, 0.3, 0.3, 0.3, 0.12}, {1.0, 1.0, 1.5, 1.0, 0.3}, {0.001}, {10.0}};
  VariableDecl s{"s", "joint sizes (1 smallest .. 3 largest), s_i >= s_{i+1}", "", 6, true, {3, 3, 1, 1, 1, 1}, {3}, {1}, {3}};
  VariableDecl r{"r", "gear codes (index into the actuator table's gear_ratios)", "", 6, true, {1}, {6}, {1}, {6}};
  return {l, s, r};
}

std::vector<ConstraintDecl> Haptic6R::constraints() const {
  std::vector<ConstraintDecl> c;
  for (int i = 1; i <= 5; ++i) {
    c.push_back({"s_monotone_" + std::to_string(i),
                 "s" + std::to_string(i) + " >= s" + std::to_string(i + 1) + ": g = s" + std::to_string(i + 1) + " - s" +
                     std::to_string(i) + " <= 0"});
  }
  return c;
}

void Haptic6R::evaluate_constraints(const double* design, const SampleSet&, double* g) const {
  for (int i = 0; i < 5; ++i) g[i] = design[5 + i + 1] - design[5 + i];
}

void Haptic6R::check_scene(const SampleSet& scene) const {
  if (scene.dimension() != 7) {
    throw Error(kName, "scene: samples have " + std::to_string(scene.dimension()) +
                           " coordinates; haptic6r serves end-effector poses (x, y, z, qw, qx, qy, qz) [m]");
  }
}

Needs Haptic6R::provides() const {
  return kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits | kNeedJointVelocity | kNeedJointAcceleration |
         kNeedVelocityTorque;
}

}  // namespace hapsyn::plugins
