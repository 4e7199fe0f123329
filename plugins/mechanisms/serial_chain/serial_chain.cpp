// The serial_chain plugin: its options resolved once into a SerialChainSetup (files read,
// frames and home posture in SI), and the Mechanism interface (design space, constraints).
#include "serial_chain.hpp"
#include "number_text.hpp"

#include <hapsyn/actuator_table.hpp>
#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>

#include <cmath>

namespace hapsyn::plugins {

namespace {

constexpr const char* kName = "serial_chain";
constexpr double kDeg = 3.14159265358979323846 / 180.0;

// R = Rz(yaw) Ry(pitch) Rx(roll) with the angles in degrees, as URDF's rpy.
Eigen::Isometry3d pose_from(const std::vector<double>& xyz, const std::vector<double>& rpy_deg) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(rpy_deg[2] * kDeg, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(rpy_deg[1] * kDeg, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rpy_deg[0] * kDeg, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  t.translation() = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
  return t;
}

ChainTemplate read_chain(const SerialChainOptions& o) {
  // Exactly one of urdf and dh_file, the links with a URDF only: declared rules (serial_chain_options.hpp).
  if (!o.dh_file.empty()) return ChainTemplate::from_dh_file(find_data_file(kName, "dh_file", o.dh_file));
  return ChainTemplate::from_urdf(find_data_file(kName, "urdf", o.urdf), o.base_link, o.tip_link, o.fold_fixed_links);
}

IkTask task_of(const SerialChainOptions& o) {
  IkTask t;
  t.position = true;
  t.orientation = o.task == "pose" ? IkTask::Orientation::kFull
                  : o.task == "position_axis" ? IkTask::Orientation::kAxis
                                               : IkTask::Orientation::kNone;
  t.axis = o.task_axis == "x" ? 0 : o.task_axis == "y" ? 1 : 2;
  return t;
}

// The home posture in SI from the option (deg for revolute, m for prismatic joints), or the
// middle of each limited joint's range.
JointVector home_of(const SerialChainOptions& o, const Chain& chain) {
  const int n = chain.dof();
  if (!o.home.empty() && static_cast<int>(o.home.size()) != n) {
    throw Error(kName, "options.home has " + std::to_string(o.home.size()) + " values: the chain has " + std::to_string(n) +
                           " joints (one value per joint, or none)");
  }
  JointVector home(n);
  for (int i = 0; i < n; ++i) {
    const ChainJoint& j = chain.joints[static_cast<std::size_t>(i)];
    const double scale = j.type == ChainJointType::kRevolute ? kDeg : 1.0;
    if (o.home.empty()) {
      home(i) = std::isfinite(j.lower) && std::isfinite(j.upper) ? 0.5 * (j.lower + j.upper) : 0.0;
      continue;
    }
    home(i) = o.home[static_cast<std::size_t>(i)] * scale;
    if (home(i) < j.lower - 1e-12 || home(i) > j.upper + 1e-12) {
      throw Error(kName, "options.home[" + std::to_string(i) + "] = " + number_text(o.home[static_cast<std::size_t>(i)]) +
                             ": outside joint " + j.name + "'s limits [" + number_text(j.lower / scale) + ", " +
                             number_text(j.upper / scale) + "] " + (scale == 1.0 ? "m" : "deg"));
    }
  }
  return home;
}

// The chain's reach at the nominal design: the sum of the distances between consecutive joint
// origins and to the tip (what makes an angular rate comparable to a linear one).
double reach_of(const Chain& chain) {
  double reach = chain.tip.translation().norm();
  for (std::size_t i = 1; i < chain.joints.size(); ++i) reach += chain.joints[i].origin.translation().norm();
  return reach;
}

std::vector<double> nominal_values(const ChainTemplate& t) {
  std::vector<double> v;
  for (const ChainParameter& p : t.parameters()) v.push_back(p.nominal);
  return v;
}

void check_codes(const std::vector<int>& codes, int n, int max, const std::string& option) {
  if (!codes.empty() && static_cast<int>(codes.size()) != n) {
    throw Error(kName, "options." + option + " has " + std::to_string(codes.size()) + " values: the chain has " +
                           std::to_string(n) + " joints (one code per joint, or none)");
  }
  for (std::size_t i = 0; i < codes.size(); ++i) {
    if (codes[i] < 1 || codes[i] > max) {
      throw Error(kName, "options." + option + "[" + std::to_string(i) + "] = " + std::to_string(codes[i]) +
                             ": must be in 1.." + std::to_string(max) + " (the actuator table's codes)");
    }
  }
}

// A 7R chain under ik.solver auto / closed_form: the redundant joint (ik.redundant_joint, or the
// automatic choice) and its grid; sets closed_form, redundancy and solver_summary.
void choose_redundant(const SerialChainOptions& o, const Chain& nominal, SerialChainSetup& s) {
  const std::string numerical = "numerical (damped least squares, " + std::to_string(o.ik.restarts) + " restarts";
  int k = -1;
  std::string why_not;
  if (o.ik.redundant_joint == "auto") {
    k = choose_redundant_joint(nominal);
    if (k < 0) {
      for (int i = 0; i < 7; ++i) why_not += (why_not.empty() ? "" : "; ") + redundant_joint_unsuitability(nominal, i);
      why_not = "no joint whose locking leaves a 6R with a closed form (" + why_not + ")";
    }
  } else {
    std::string names;
    for (int i = 0; i < 7; ++i) {
      const std::string& name = nominal.joints[static_cast<std::size_t>(i)].name;
      if (name == o.ik.redundant_joint) k = i;
      names += (names.empty() ? "" : ", ") + name;
    }
    const std::string option = "options.ik.redundant_joint = \"" + o.ik.redundant_joint + "\": ";
    if (k < 0) throw Error(kName, option + "not a moving joint of the chain (its joints: " + names + "; or \"auto\")");
    why_not = redundant_joint_unsuitability(nominal, k);
    if (!why_not.empty()) throw Error(kName, option + why_not + "; use another joint or \"auto\"");
  }
  if (!why_not.empty()) {
    if (o.ik.solver == "closed_form") throw Error(kName, "options.ik.solver = \"closed_form\": 7R: " + why_not);
    s.solver_summary = numerical + "; no closed form: 7R, " + why_not + ")";
    return;
  }
  s.redundancy = {k, o.ik.redundant_steps};
  const ChainJoint& j = nominal.joints[static_cast<std::size_t>(k)];
  const std::vector<double> grid = redundant_grid(j, o.ik.redundant_steps);
  closed_form_ik::ChainGeometry geometry;
  redundant_joint_unsuitability(nominal, k, &geometry);
  s.closed_form = true;
  s.solver_summary = "closed form (7R: joint " + std::to_string(k + 1) + " (" + j.name + ") discretised in " +
                     std::to_string(grid.size()) + " steps over [" + number_text(grid.front() / kDeg) + ", " +
                     number_text(grid.back() / kDeg) + "] deg, each a 6R of the other joints numbered 1-6: " + geometry.describe() + ")";
}

// Which IK the nominal chain gets (option ik.solver): sets closed_form and solver_summary.
void choose_solver(const SerialChainOptions& o, const Chain& nominal, SerialChainSetup& s) {
  const std::string numerical = "numerical (damped least squares, " + std::to_string(o.ik.restarts) + " restarts";
  if (o.ik.solver == "numerical") {
    s.solver_summary = numerical + ")";
    return;
  }
  if (o.ik.redundant_joint != "auto" && nominal.dof() != 7) {
    throw Error(kName, "options.ik.redundant_joint = \"" + o.ik.redundant_joint + "\": the chain has " +
                           std::to_string(nominal.dof()) + " moving joints (a redundant joint is for 7 revolute joints)");
  }
  const std::string why_not = closed_form_applicability(nominal, s.task);
  if (!why_not.empty()) {
    if (o.ik.solver == "closed_form") throw Error(kName, "options.ik.solver = \"closed_form\": " + why_not);
    s.solver_summary = numerical + "; no closed form: " + why_not + ")";
    return;
  }
  if (nominal.dof() == 7) {
    choose_redundant(o, nominal, s);
    return;
  }
  const closed_form_ik::ChainGeometry geometry = closed_form_ik::classify(poe_chain_of(nominal));
  if (geometry.family == closed_form_ik::IkFamily::kUnsupported) {
    if (o.ik.solver == "closed_form") {
      throw Error(kName, "options.ik.solver = \"closed_form\": no closed-form decomposition for this chain's axes (" +
                             geometry.describe() + "); use \"auto\" or \"numerical\"");
    }
    s.solver_summary = numerical + "; no closed form for the axes: " + geometry.describe() + ")";
    return;
  }
  s.closed_form = true;
  s.solver_summary = "closed form (" + geometry.describe() + ")";
}

std::shared_ptr<SerialChainSetup> make_setup(const SerialChainOptions& o) {
  auto s = std::make_shared<SerialChainSetup>();
  s->options = o;
  s->chain_template = read_chain(o);
  s->parameter_count = static_cast<int>(s->chain_template.parameters().size());
  const int n = s->chain_template.dof();
  if (!o.actuator_file.empty()) {
    const std::string file = find_data_file(kName, "actuator_file", o.actuator_file);
    try {
      s->actuators = std::make_shared<const ActuatorTable>(read_actuator_table(file, kName));
    } catch (const Error& e) {
      // The table names its JSON paths; the message names the option that gave the file.
      throw Error(kName, "options.actuator_file: " + std::string(e.what()).substr(e.component().size() + 2));
    }
  }  // actuator_size and actuator_gear without an actuator_file: declared rules
  check_codes(o.actuator_size, n, 3, "actuator_size");
  check_codes(o.actuator_gear, n, 6, "actuator_gear");
  s->task = task_of(o);
  if (n < s->task.rows()) {
    // "position" needs the fewest rows: suggest it only when it would fit.
    const std::string hint = o.task != "position" && n >= 3
                                 ? "try task \"position\""
                                 : "check base_link and tip_link: the chain between them has " + std::to_string(n) +
                                       " moving joint" + (n == 1 ? "" : "s");
    throw Error(kName, "options.task = \"" + o.task + "\": matches " + std::to_string(s->task.rows()) +
                           " task rows, but the chain has only " + std::to_string(n) +
                           " joints (a non-redundant task needs at least as many joints as rows; " + hint + ")");
  }
  s->ik.position_tolerance = o.ik.position_tolerance;
  s->ik.orientation_tolerance = o.ik.orientation_tolerance;
  s->ik.max_iterations = o.ik.max_iterations;
  s->ik.restarts = o.ik.restarts;
  s->ik.seed = static_cast<std::uint64_t>(o.ik.seed);
  s->first_found = o.ik.selection == "first_found";
  s->base_from_scene = pose_from(o.base_xyz, o.base_rpy).inverse();
  s->sample_to_tip = pose_from(o.tool_xyz, o.tool_rpy).inverse();
  Chain nominal;
  s->chain_template.instantiate(nominal_values(s->chain_template).data(), nullptr, nominal);
  s->home = home_of(o, nominal);
  s->characteristic_length = o.characteristic_length > 0.0 ? o.characteristic_length : std::max(reach_of(nominal), 1e-3);
  choose_solver(o, nominal, *s);
  return s;
}

}  // namespace

namespace {

// Every parameter of the chain file, fixed at its value, then size and gear with an actuator table.
std::vector<VariableDecl> variable_decls(const SerialChainSetup& setup) {
  std::vector<VariableDecl> out;
  for (const ChainParameter& p : setup.chain_template.parameters()) {
    VariableDecl v;
    v.name = p.name;
    v.description = p.description + " (fixed at the file's value unless freed)";
    v.unit = p.unit;
    v.default_lower = {p.nominal};
    v.default_upper = {p.nominal};
    if (std::isfinite(p.hard_lower)) v.hard_lower = {p.hard_lower};
    if (std::isfinite(p.hard_upper)) v.hard_upper = {p.hard_upper};
    out.push_back(std::move(v));
  }
  if (setup.actuators) {
    const int n = setup.chain_template.dof();
    const auto nominal = [n](const std::vector<int>& codes) {
      std::vector<double> v(static_cast<std::size_t>(n), 1.0);
      for (std::size_t i = 0; i < codes.size(); ++i) v[i] = codes[i];
      return v;
    };
    const std::vector<double> size = nominal(setup.options.actuator_size), gear = nominal(setup.options.actuator_gear);
    out.push_back({"size", "actuator size code per joint (1 smallest .. 3 largest, actuator table)", "", n, true, size, size,
                   {1}, {3}});
    out.push_back({"gear", "gear code per joint (index into the actuator table's gear_ratios)", "", n, true, gear, gear, {1}, {6}});
  }
  return out;
}

std::vector<std::string> component_names(const std::vector<VariableDecl>& variables) {
  std::vector<std::string> names;
  for (const VariableDecl& v : variables) {
    for (int i = 0; i < v.size; ++i) names.push_back(v.size > 1 ? v.name + "[" + std::to_string(i) + "]" : v.name);
  }
  return names;
}

}  // namespace

SerialChain::SerialChain(const SerialChainOptions& options) {
  auto setup = make_setup(options);
  setup->constraints =
      parse_linear_constraints(options.constraints, component_names(variable_decls(*setup)), kName, "options.constraints");
  setup_ = std::move(setup);
}

std::unique_ptr<const MechanismModel> SerialChain::build(const double* design) const {
  return std::make_unique<SerialChainModel>(design, *setup_);
}

std::unique_ptr<MechanismScratch> SerialChain::make_scratch() const { return std::make_unique<SerialChainScratch>(); }

std::vector<VariableDecl> SerialChain::variables() const { return variable_decls(*setup_); }

std::vector<ConstraintDecl> SerialChain::constraints() const {
  std::vector<ConstraintDecl> out;
  for (const LinearConstraint& c : setup_->constraints) out.push_back({c.name, c.description});
  return out;
}

void SerialChain::evaluate_constraints(const double* design, const SampleSet&, double* g) const {
  for (std::size_t k = 0; k < setup_->constraints.size(); ++k) g[k] = setup_->constraints[k].evaluate(design);
}

void SerialChain::check_scene(const SampleSet& scene) const {
  const int d = scene.dimension();
  const std::string& task = setup_->options.task;
  if (d == 7 || (d == 3 && task == "position")) return;
  throw Error(kName, "scene: samples have " + std::to_string(d) + " coordinates; task \"" + task + "\" needs " +
                         (task == "position" ? "positions (x, y, z) [m] or poses (x, y, z, qw, qx, qy, qz)"
                                             : "poses (x, y, z, qw, qx, qy, qz)"));
}

Needs SerialChain::provides() const {
  Needs n = kNeedJacobian | kNeedInertia | kNeedEffectiveMass | kNeedGravity | kNeedJointVelocity |
            kNeedJointAcceleration | kNeedVelocityTorque;
  if (setup_->actuators) return n | kNeedActuatorLimits;
  Chain nominal;
  setup_->chain_template.instantiate(nominal_values(setup_->chain_template).data(), nullptr, nominal);
  for (const ChainJoint& j : nominal.joints) {
    if (!(j.max_velocity > 0.0) || !(j.max_effort > 0.0)) return n;
  }
  return n | kNeedActuatorLimits;
}

// The joints as read from the file at its own values: a wrong tip_link (a chain one joint short,
// a Jacobian with a zero column) shows here, in the run header, before any result does.
std::string SerialChain::summary() const {
  Chain nominal;
  setup_->chain_template.instantiate(nominal_values(setup_->chain_template).data(), nullptr, nominal);
  const SerialChainOptions& o = setup_->options;
  std::string joints;
  for (const ChainJoint& j : nominal.joints) {
    joints += (joints.empty() ? "" : ", ") + j.name + (j.type == ChainJointType::kPrismatic ? " (prismatic)" : " (revolute)");
  }
  const std::string path = o.urdf.empty() ? "from " + o.dh_file : o.base_link + " -> " + o.tip_link;
  // What each body carries besides its own link: a payload that went missing shows here too.
  std::string folded;
  for (const ChainFoldedLinks& f : setup_->chain_template.folded_links()) {
    std::string links;
    for (const std::string& l : f.links) links += (links.empty() ? "" : ", ") + l;
    folded += "; folded: " + links + " -> " + f.body_link;
  }
  return std::to_string(nominal.joints.size()) + " moving joint" + (nominal.joints.size() == 1 ? "" : "s") + " " +
         path + ": " + joints + folded + "; task " + o.task + "; IK selection " + o.ik.selection + "; IK solver " + setup_->solver_summary;
}

}  // namespace hapsyn::plugins
