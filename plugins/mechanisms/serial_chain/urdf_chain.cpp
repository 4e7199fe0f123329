// ChainTemplate::from_urdf: the base -> tip path of a URDF file (urdfdom) as a chain template.
// A URDF is a tree of links joined by joints whose child link frame is the joint frame; the
// path's fixed joints fold into the next moving joint's origin (after the last one: into T_tip)
// and their child links' inertials into the body before them, and so do the inertials of links
// hanging off the path through fixed joints only (a gripper, a payload), unless switched off.
#include "chain_template_impl.hpp"
#include "xml_shape.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/read_file.hpp>

#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <set>
#include <string>
#include <vector>

#ifdef HAPSYN_HAVE_URDFDOM
#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include "urdf_meshes.hpp"

#include <algorithm>
#include <array>
#include <map>
#include <mutex>
#endif

namespace hapsyn::plugins {

#ifndef HAPSYN_HAVE_URDFDOM

ChainTemplate ChainTemplate::from_urdf(const std::string& path, const std::string&, const std::string&, bool) {
  throw Error(kSerialChainName, path +
                                    ": hapsyn was built without URDF support (HAPSYN_WITH_URDFDOM=OFF): "
                                    "rebuild with liburdfdom-dev installed, or describe the chain as a DH table");
}

#else

using namespace serial_chain_detail;

namespace {

// A link's <inertial> in its link frame.
struct UrdfInertial {
  std::string link;
  double mass = 0.0;
  Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();  // the inertial frame in the link frame
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();        // about the com, inertial frame axes
  int mass_parameter = -1;                                  // "<link>:mass", -1 when none
};

// One joint of the base -> tip path and the link it carries.
struct UrdfStep {
  bool moving = false;
  ChainJoint joint;                     // type, axis, limits (origin: from the parameters)
  int origin_parameter = -1;            // "<joint>:x", then y, z, roll, pitch, yaw
  std::optional<UrdfInertial> child;    // the child link's inertial, if any
  // The inertials of the links fixed to the child link off the path (recursively), their frames
  // in the child link's frame (the fixed joints' origins as written).
  std::vector<UrdfInertial> folded;
};

struct UrdfPath {
  std::vector<UrdfStep> steps;
  std::vector<std::string> on_base;  // links with an inertial fixed off the path to the base (or before joint 1)
  int dof = 0;
  int mass_scale_parameter = -1;
};

// A URDF of a robot arm is well below this; a FIFO, a device or a huge file is refused before
// it is read.
constexpr std::uint64_t kMaxUrdfFileBytes = 64u << 20;

std::string read_text(const std::string& path) {
  return read_regular_file(path, kSerialChainName, "URDF file", kMaxUrdfFileBytes);
}

// A joint's <origin> as the file writes it: x, y, z, roll, pitch, yaw.
using Origin = std::array<double, 6>;

// Parses the numbers of an attribute ("0 0.5 1"); false when it has not exactly three.
bool three_numbers(const char* text, double* out) {
  std::istringstream in(text);
  for (int k = 0; k < 3; ++k) {
    if (!(in >> out[k])) return false;
  }
  std::string rest;
  return !(in >> rest);
}

// The XML pass: TinyXML (urdfdom's own parser) names the line and column of an XML error, which
// urdfdom reports only as "Error parsing XML"; and the joints' origins as written, because
// urdfdom keeps a quaternion whose getRPY() snaps pitches within 0.99999 of +-90 deg (the nominal
// parameters would be off by up to ~4 mrad).
std::map<std::string, Origin> read_xml_origins(const std::string& path, const std::string& text) {
  TiXmlDocument doc;
  doc.Parse(text.c_str());
  if (doc.Error()) {
    throw Error(kSerialChainName, path + ": not valid XML: line " + std::to_string(doc.ErrorRow()) + ", column " +
                                      std::to_string(doc.ErrorCol()) + ": " + doc.ErrorDesc());
  }
  std::map<std::string, Origin> origins;
  const TiXmlElement* robot = doc.FirstChildElement("robot");
  if (!robot) return origins;  // urdfdom names the problem
  // A link that is the child of two joints closes a loop. urdfdom accepts it and builds a cycle
  // of shared pointers (never freed, and a parent walk that never ends): refuse it here, first.
  std::map<std::string, std::string> parent_joint_of;
  for (const TiXmlElement* j = robot->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
    const char* name = j->Attribute("name");
    if (!name) continue;
    const TiXmlElement* child = j->FirstChildElement("child");
    const char* child_link = child ? child->Attribute("link") : nullptr;
    if (child_link) {
      const auto [it, inserted] = parent_joint_of.emplace(child_link, name);
      if (!inserted) {
        throw Error(kSerialChainName, path + ": line " + std::to_string(j->Row()) + ": link \"" + child_link +
                                          "\" is the child of joints \"" + it->second + "\" and \"" + name +
                                          "\": a closed kinematic loop (a serial chain's file must be a tree)");
      }
    }
    Origin o{};
    if (const TiXmlElement* origin = j->FirstChildElement("origin")) {
      const char* xyz = origin->Attribute("xyz");
      const char* rpy = origin->Attribute("rpy");
      if ((xyz && !three_numbers(xyz, o.data())) || (rpy && !three_numbers(rpy, o.data() + 3))) {
        throw Error(kSerialChainName, path + ": line " + std::to_string(origin->Row()) + ": joint \"" + name +
                                          "\" origin = xyz \"" + (xyz ? xyz : "") + "\" rpy \"" + (rpy ? rpy : "") +
                                          "\": must be three numbers each");
      }
    }
    origins[name] = o;
  }
  return origins;
}

// Collects urdfdom's console_bridge messages (it logs why it refuses a file, then returns null).
class CapturedLog : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) messages.push_back(text);
    errors += level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR;
  }
  std::vector<std::string> messages;
  int errors = 0;
};

urdf::ModelInterfaceSharedPtr parse_urdf(const std::string& path, const std::string& text) {
  // console_bridge's handler is process-global: one parse at a time swaps it.
  static std::mutex mutex;
  const std::lock_guard<std::mutex> lock(mutex);
  CapturedLog log;
  console_bridge::useOutputHandler(&log);
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(text);
  } catch (const std::exception& e) {
    log.messages.push_back(e.what());
  }
  console_bridge::restorePreviousOutputHandler();
  // urdfdom logs an error and goes on for some elements it cannot read (a mass of "nan" leaves
  // an inertial of mass 0): a file it logged an error for is refused, never read in part.
  if (!model || log.errors > 0) {
    std::string why;
    for (const std::string& m : log.messages) why += (why.empty() ? "" : "; ") + m;
    throw Error(kSerialChainName, path + ": not a valid URDF: " + (why.empty() ? "urdfdom refused it" : why));
  }
  return model;
}

urdf::LinkConstSharedPtr find_link(const urdf::ModelInterface& model, const std::string& path, const char* role,
                                   const std::string& name) {
  urdf::LinkConstSharedPtr link = model.getLink(name);
  if (link) return link;
  std::vector<urdf::LinkSharedPtr> links;
  model.getLinks(links);
  std::vector<std::string> names;
  for (const auto& l : links) names.push_back(l->name);
  std::sort(names.begin(), names.end());
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  throw Error(kSerialChainName, path + ": " + role + " = \"" + name + "\": no such link" + did_you_mean(name, names) +
                                    " (links: " + list + ")");
}

// The joints from base to tip, base first.
std::vector<urdf::JointConstSharedPtr> joints_between(const std::string& path, const urdf::LinkConstSharedPtr& base,
                                                      const urdf::LinkConstSharedPtr& tip) {
  std::vector<urdf::JointConstSharedPtr> joints;
  std::string ancestry = tip->name;
  std::set<std::string> visited;
  for (urdf::LinkConstSharedPtr link = tip; link != base; link = link->getParent()) {
    // urdfdom accepts a link that is the child of two joints (a closed loop) and then links
    // parents in a cycle: walking up would never end.
    if (!visited.insert(link->name).second) {
      throw Error(kSerialChainName, path + ": link \"" + link->name +
                                        "\" is its own ancestor (a closed kinematic loop: some link is the child of two "
                                        "joints); a serial chain must be a path in a tree (ancestors: " +
                                        ancestry + ")");
    }
    if (!link->parent_joint) {
      throw Error(kSerialChainName, path + ": tip_link = \"" + tip->name + "\": not below base_link \"" + base->name +
                                        "\" (its ancestors: " + ancestry + ")");
    }
    joints.push_back(link->parent_joint);
    ancestry += " <- " + link->parent_joint->parent_link_name;
  }
  std::reverse(joints.begin(), joints.end());
  return joints;
}

const char* type_name(int type) {
  switch (type) {
    case urdf::Joint::REVOLUTE: return "revolute";
    case urdf::Joint::CONTINUOUS: return "continuous";
    case urdf::Joint::PRISMATIC: return "prismatic";
    case urdf::Joint::FLOATING: return "floating";
    case urdf::Joint::PLANAR: return "planar";
    case urdf::Joint::FIXED: return "fixed";
    default: return "unknown";
  }
}

// The moving joint's type, axis and limits. Throws for a joint that cannot be on a chain.
UrdfStep step_of(const std::string& path, const urdf::Joint& j) {
  const std::string at = path + ": joint \"" + j.name + "\"";
  if (j.mimic) {
    throw Error(kSerialChainName, at + " mimic = \"" + j.mimic->joint_name +
                                      "\": a mimic joint on the chain is not supported (its coordinate would not be free)");
  }
  UrdfStep step;
  step.joint.name = j.name;
  switch (j.type) {
    case urdf::Joint::FIXED: return step;
    case urdf::Joint::REVOLUTE:
    case urdf::Joint::CONTINUOUS: step.joint.type = ChainJointType::kRevolute; break;
    case urdf::Joint::PRISMATIC: step.joint.type = ChainJointType::kPrismatic; break;
    default:
      throw Error(kSerialChainName, at + " type = \"" + type_name(j.type) +
                                        "\": only revolute, continuous, prismatic and fixed joints may be on the chain");
  }
  step.moving = true;
  const Eigen::Vector3d axis(j.axis.x, j.axis.y, j.axis.z);
  // Scaled by its largest entry before the norm: any finite non-zero vector is a direction,
  // (0 1e200 0) as much as (0 5e-324 0), and neither the square of the one overflows nor that of
  // the other underflows.
  const double largest = axis.cwiseAbs().maxCoeff();
  if (!(largest > 0.0) || !axis.allFinite()) {
    throw Error(kSerialChainName, at + " axis = (" + show_number(axis.x()) + " " + show_number(axis.y()) + " " +
                                      show_number(axis.z()) + "): must be a finite, non-zero direction");
  }
  step.joint.axis = (axis / largest).normalized();
  if (j.limits) {
    if (j.type != urdf::Joint::CONTINUOUS) {
      step.joint.lower = j.limits->lower;
      step.joint.upper = j.limits->upper;
    }
    step.joint.max_velocity = j.limits->velocity;
    step.joint.max_effort = j.limits->effort;
  }
  if (step.joint.lower > step.joint.upper) {
    throw Error(kSerialChainName, at + " limit lower = " + show_number(step.joint.lower) + ": must be <= upper (" +
                                      show_number(step.joint.upper) + ")");
  }
  return step;
}

std::optional<UrdfInertial> inertial_of(const std::string& path, const urdf::Link& link) {
  if (!link.inertial) return std::nullopt;
  const urdf::Inertial& in = *link.inertial;
  UrdfInertial u;
  u.link = link.name;
  u.mass = in.mass;
  // urdfdom reads "nan", "inf" and negative masses as they are; each would change every dynamic
  // quantity without a word.
  if (!(std::isfinite(in.mass) && in.mass >= 0.0)) {
    throw Error(kSerialChainName, path + ": link \"" + link.name + "\" <inertial> <mass value=\"" + show_number(in.mass) +
                                      "\">: must be a finite mass >= 0 kg");
  }
  const urdf::Pose& p = in.origin;
  const double pose[] = {p.position.x, p.position.y, p.position.z, p.rotation.x, p.rotation.y, p.rotation.z, p.rotation.w};
  if (!std::all_of(std::begin(pose), std::end(pose), [](double x) { return std::isfinite(x); })) {
    throw Error(kSerialChainName, path + ": link \"" + link.name + "\" <inertial> <origin>: must be finite numbers");
  }
  u.frame.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  u.frame.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized().toRotationMatrix();
  u.inertia << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  if (const std::string why = inertia_implausibility(u.inertia); !why.empty()) {
    throw Error(kSerialChainName, path + ": link \"" + link.name + "\" <inertial> <inertia ixx=\"" +
                                      show_number(in.ixx) + "\" ixy=\"" + show_number(in.ixy) + "\" ixz=\"" +
                                      show_number(in.ixz) + "\" iyy=\"" + show_number(in.iyy) + "\" iyz=\"" +
                                      show_number(in.iyz) + "\" izz=\"" + show_number(in.izz) + "\">: " + why +
                                      ": no rigid body has this inertia");
  }
  return u;
}

void add_origin_parameters(const urdf::Joint& j, const Origin& o, std::vector<ChainParameter>& parameters) {
  const struct {
    const char* key;
    const char* what;
    const char* unit;
    double value;
  } items[] = {{"x", "origin x", "m", o[0]},           {"y", "origin y", "m", o[1]},
               {"z", "origin z", "m", o[2]},           {"roll", "origin roll (about x)", "rad", o[3]},
               {"pitch", "origin pitch (about y)", "rad", o[4]}, {"yaw", "origin yaw (about z)", "rad", o[5]}};
  for (const auto& item : items) {
    ChainParameter c;
    c.name = j.name + ":" + item.key;
    c.description = std::string("joint ") + j.name + " " + item.what + " in its parent link's frame (URDF <origin>)";
    c.unit = item.unit;
    c.nominal = item.value;
    parameters.push_back(c);
  }
}

ChainParameter mass_parameter(const UrdfInertial& in) {
  ChainParameter c;
  c.name = in.link + ":mass";
  c.description = "link " + in.link + " mass (URDF <inertial>; its inertia scales with it)";
  c.unit = "kg";
  c.nominal = in.mass;
  c.hard_lower = 0.0;
  return c;
}

// The names become design variables ("<joint>:x", "<link>:mass") written into result.json.
void check_utf8_name(const std::string& path, const char* what, const std::string& name) {
  if (const std::size_t bad = invalid_utf8_at(name); bad != std::string::npos) {
    throw Error(kSerialChainName, path + ": " + what + " name " + shown_bytes(name) + ": invalid UTF-8 at byte " +
                                      std::to_string(bad) + " (names become design variables written into "
                                      "result.json: they must be UTF-8)");
  }
}

// The inertials of the links hanging from `anchor` off the path through fixed joints only, in
// depth-first order, each frame in the anchor's frame. A moving joint off the path ends the walk:
// what lies behind it moves on its own and is not part of the body.
std::vector<UrdfInertial> fixed_subtree(const std::string& path, const urdf::ModelInterface& model,
                                        const urdf::Link& anchor, const std::set<std::string>& on_path,
                                        const std::map<std::string, Origin>& origins) {
  std::vector<UrdfInertial> out;
  // (link, its frame in the anchor's frame); an explicit stack: a file may nest thousands.
  std::vector<std::pair<const urdf::Link*, Eigen::Isometry3d>> stack{{&anchor, Eigen::Isometry3d::Identity()}};
  while (!stack.empty()) {
    const auto [link, frame] = stack.back();
    stack.pop_back();
    if (link != &anchor) {
      check_utf8_name(path, "link", link->name);
      if (std::optional<UrdfInertial> in = inertial_of(path, *link)) {
        in->frame = frame * in->frame;
        out.push_back(*in);
      }
    }
    // Reversed onto the stack: the file's (urdfdom's) order comes off first.
    for (auto j = link->child_joints.rbegin(); j != link->child_joints.rend(); ++j) {
      if ((*j)->type != urdf::Joint::FIXED || on_path.count((*j)->child_link_name)) continue;
      const urdf::LinkConstSharedPtr child = model.getLink((*j)->child_link_name);
      if (!child) continue;
      const auto o = origins.find((*j)->name);
      const Origin v = o == origins.end() ? Origin{} : o->second;
      stack.emplace_back(child.get(), frame * xyz_rpy_pose(Eigen::Vector3d(v[0], v[1], v[2]), v[3], v[4], v[5]));
    }
  }
  return out;
}

// Reads the path's joints into steps and declares the parameters in path order.
UrdfPath read_path(const std::string& path, const std::string& base_link, const std::string& tip_link,
                   const std::vector<urdf::JointConstSharedPtr>& joints, const urdf::ModelInterface& model,
                   const std::map<std::string, Origin>& origins, bool fold_fixed_links,
                   std::vector<ChainParameter>& parameters) {
  UrdfPath p;
  std::set<std::string> on_path{base_link};
  for (const urdf::JointConstSharedPtr& j : joints) on_path.insert(j->child_link_name);
  if (fold_fixed_links) {
    // Fixed to the base: they ride on it and have no dynamics; named for the docs' sake only.
    for (const UrdfInertial& in : fixed_subtree(path, model, *model.getLink(base_link), on_path, origins)) {
      p.on_base.push_back(in.link);
    }
  }
  for (const urdf::JointConstSharedPtr& j : joints) {
    check_utf8_name(path, "joint", j->name);
    check_utf8_name(path, "link", j->child_link_name);
    UrdfStep step = step_of(path, *j);
    step.origin_parameter = static_cast<int>(parameters.size());
    const auto origin = origins.find(j->name);
    assert(origin != origins.end());  // urdfdom read the same joints
    add_origin_parameters(*j, origin == origins.end() ? Origin{} : origin->second, parameters);
    if (step.moving) ++p.dof;
    step.child = inertial_of(path, *model.getLink(j->child_link_name));
    // A link before the first moving joint rides on the base: it has no dynamics, no parameter.
    if (step.child && p.dof > 0 && step.child->mass > 0.0) {
      step.child->mass_parameter = static_cast<int>(parameters.size());
      parameters.push_back(mass_parameter(*step.child));
    }
    if (fold_fixed_links) {
      const urdf::LinkConstSharedPtr child = model.getLink(j->child_link_name);
      step.folded = fixed_subtree(path, model, *child, on_path, origins);
      for (UrdfInertial& in : step.folded) {
        if (p.dof == 0) {
          p.on_base.push_back(in.link);
        } else if (in.mass > 0.0) {
          in.mass_parameter = static_cast<int>(parameters.size());
          parameters.push_back(mass_parameter(in));
        }
      }
      if (p.dof == 0) step.folded.clear();
    }
    p.steps.push_back(step);
  }
  if (p.dof < 1 || p.dof > kMaxChainJoints) {
    throw Error(kSerialChainName, path + ": the path from base_link \"" + base_link + "\" to tip_link \"" + tip_link +
                                      "\" has " + std::to_string(p.dof) + " moving joints: must have 1 to " +
                                      std::to_string(kMaxChainJoints));
  }
  p.mass_scale_parameter = static_cast<int>(parameters.size());
  parameters.push_back(mass_scale_parameter());
  return p;
}

// The inertial's body part in the frame `link_frame` of its link, with the design's mass.
ChainBody inertial_part(const UrdfInertial& in, const Eigen::Isometry3d& link_frame, const double* values) {
  ChainBody b;
  b.mass = in.mass_parameter >= 0 ? values[in.mass_parameter] : in.mass;
  b.inertia = in.mass > 0.0 ? Eigen::Matrix3d(in.inertia * (b.mass / in.mass)) : in.inertia;
  const Eigen::Isometry3d frame = link_frame * in.frame;
  return transformed(b, frame);
}

void build_chain(const UrdfPath& p, const double* values, Chain& out) {
  out.joints.clear();
  out.bodies.clear();
  out.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  // The fixed transforms since the last moving joint, in its frame (or the base's).
  Eigen::Isometry3d pending = Eigen::Isometry3d::Identity();
  for (const UrdfStep& s : p.steps) {
    const double* o = values + s.origin_parameter;
    const Eigen::Isometry3d origin = xyz_rpy_pose(Eigen::Vector3d(o[0], o[1], o[2]), o[3], o[4], o[5]);
    if (s.moving) {
      out.joints.push_back(s.joint);
      out.joints.back().origin = pending * origin;
      out.bodies.emplace_back();
      pending = Eigen::Isometry3d::Identity();
    } else {
      pending = pending * origin;
    }
    if (out.bodies.empty()) continue;  // on the base: no dynamics
    if (s.child) {
      const ChainBody part = inertial_part(*s.child, pending, values);
      add_part(out.bodies.back(), part.mass, part.com, part.inertia);
    }
    for (const UrdfInertial& in : s.folded) {
      const ChainBody part = inertial_part(in, pending, values);
      add_part(out.bodies.back(), part.mass, part.com, part.inertia);
    }
  }
  out.tip = pending;
  const double scale = values[p.mass_scale_parameter];
  for (ChainBody& b : out.bodies) scale_body(b, scale);
}

// Which links' inertials each moving body carries besides its own link's (the summary's list),
// in path order.
std::vector<ChainFoldedLinks> folded_links_of(const UrdfPath& p, const std::vector<urdf::JointConstSharedPtr>& joints) {
  std::vector<ChainFoldedLinks> out;
  for (std::size_t k = 0; k < p.steps.size(); ++k) {
    const UrdfStep& s = p.steps[k];
    if (s.moving) {
      out.push_back({static_cast<int>(out.size()), joints[k]->child_link_name, {}});
    } else if (!out.empty() && s.child) {
      out.back().links.push_back(s.child->link);
    }
    for (const UrdfInertial& in : s.folded) {
      if (!out.empty()) out.back().links.push_back(in.link);
    }
  }
  out.erase(std::remove_if(out.begin(), out.end(), [](const ChainFoldedLinks& f) { return f.links.empty(); }), out.end());
  return out;
}

}  // namespace

ChainTemplate ChainTemplate::from_urdf(const std::string& path, const std::string& base_link, const std::string& tip_link,
                                       bool fold_fixed_links) {
  const std::string text = read_text(path);
  check_xml_shape(text, path, kSerialChainName);
  const std::map<std::string, Origin> origins = read_xml_origins(path, text);
  const urdf::ModelInterfaceSharedPtr model = parse_urdf(path, text);
  const urdf::LinkConstSharedPtr base = find_link(*model, path, "base_link", base_link);
  const urdf::LinkConstSharedPtr tip = find_link(*model, path, "tip_link", tip_link);
  const std::vector<urdf::JointConstSharedPtr> joints = joints_between(path, base, tip);
  ChainTemplate t;
  t.source_ = path;
  auto shared = std::make_shared<const UrdfPath>(
      read_path(path, base_link, tip_link, joints, *model, origins, fold_fixed_links, t.parameters_));
  auto impl = std::make_shared<Impl>();
  impl->dof = shared->dof;
  impl->folded_links = folded_links_of(*shared, joints);
  impl->links_on_base = shared->on_base;
  impl->build = [shared](const double* values, const double*, Chain& out) { build_chain(*shared, values, out); };
  std::vector<UrdfPathJoint> path_joints;
  for (std::size_t k = 0; k < joints.size(); ++k) {
    path_joints.push_back({joints[k], shared->steps[k].moving, shared->steps[k].origin_parameter});
  }
  const char* ros_package_path = std::getenv("ROS_PACKAGE_PATH");
  impl->meshes = collect_urdf_meshes(path, *model, base, path_joints, origins, ros_package_path ? ros_package_path : "");
  t.impl_ = impl;
  return t;
}

#endif  // HAPSYN_HAVE_URDFDOM

}  // namespace hapsyn::plugins
