#pragma once
/// \file
/// A chain file (URDF or DH / modified-DH table in JSON) read once, with the named scalar
/// parameters a design may set, and the Chain (chain.hpp) it gives for a set of parameter values.
///
/// Parameter names: "<joint>:x|y|z|roll|pitch|yaw" (a URDF
/// joint origin: metres, radians), "<joint>:a|d|alpha|theta" (a DH row, named by the row's
/// "joint"; angles in the table's angle unit), a DH table's own named lengths ("l1"),
/// "<link>:mass" (a URDF link whose inertial rides on a moving body) or "<joint>:mass" (a DH row's
/// body; its inertia scales with it, its com stays) and "mass_scale" (every mass and inertia).
/// ':' keeps the names free of '.', which problem-file paths and --set use as a separator. The
/// full rules, and the DH table format, are in share/serial_chain/README.md.
#include "chain.hpp"
#include "chain_meshes.hpp"

#include <memory>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// A named scalar of a chain file that a design may set.
struct ChainParameter {
  std::string name;         ///< e.g. "shoulder_pan_joint:z", "l1", "upper_arm_link:mass", "mass_scale"
  std::string description;  ///< one line for `hapsyn describe` and the did-you-mean list
  std::string unit;         ///< "m", "rad", "deg", "kg" or "" (a scale)
  double nominal = 0.0;     ///< the file's value, in `unit`
  /// Hard limits a design must respect: masses and mass_scale >= 0; a DH table's named lengths
  /// >= 0; a DH a or d whose file value is non-zero keeps its sign; otherwise unbounded.
  double hard_lower = -INFINITY, hard_upper = INFINITY;
};

/// The simple mass model of Fennel et al. 2022 (docs/design.md, "serial chains"): a motor point
/// mass at each joint frame's origin carried by the body before it (joint 1's motor sits on the
/// base and has no effect), a thin-walled tube of linear density `link_density` from each joint
/// frame's origin to the next one's (the last to the tip) carried by the body between them, and
/// a solid cylinder end effector centred at the tip with its axis along the tip's z. The same
/// parts as Haptic6RModel::rebuild (plugins/mechanisms/haptic6r). Joint origins are taken at
/// q = 0 (a prismatic joint's travel does not stretch a tube); a zero-length link has no tube.
struct FennelMassModel {
  std::vector<double> motor_mass;    ///< n motor masses [kg] (before motor_mass_factor)
  double motor_mass_factor = 1.2;    ///< [-]
  double link_density = 4.0;         ///< [kg/m]
  double tube_outer_diameter = 0.1;  ///< [m]
  double tube_wall = 0.002;          ///< [m]
  double ee_mass = 0.5;              ///< [kg]
  double ee_diameter = 0.1;          ///< [m]
  double ee_length = 0.05;           ///< [m]
};

/// The links of a URDF whose inertials one moving body carries besides its own link's.
struct ChainFoldedLinks {
  int body = 0;                    ///< index of the moving body (0: the one after the first moving joint)
  std::string body_link;           ///< the body's own link (the child link of its moving joint)
  std::vector<std::string> links;  ///< path order; a link's fixed subtree depth-first after it
};

/// A chain file read once: its parameters and how to build a Chain from their values.
class ChainTemplate {
 public:
  /// Reads a URDF file (urdfdom) and extracts the path from `base_link` to `tip_link`: fixed
  /// joints fold into the next moving joint's origin (after the last one: into T_tip), their
  /// child links' inertials into the body before them (parallel-axis theorem; inertials riding on
  /// the base have no effect); revolute / continuous / prismatic joints become ChainJoints with
  /// the URDF's limits (continuous: unlimited position). With `fold_fixed_links`, every link
  /// hanging off the path through fixed joints only (recursively: a gripper and its fixed
  /// fingers, a payload, a tool) folds into the body of the path link it hangs from: its mass
  /// added, its inertial frame placed by the fixed joints' origins as written (not design
  /// parameters), a "<link>:mass" parameter when its mass is > 0; links so fixed to the base, or
  /// to a path link before the first moving joint, ride on the base (no dynamics). Links behind a
  /// moving joint off the path are never folded (they move on their own). Everything else off
  /// the path (transmissions, gazebo tags) is ignored. Gravity -9.81 along the base's z. The
  /// mesh visuals of the links it carries are collected for drawing (meshes(); urdf_meshes.hpp),
  /// package:// names searched also in the ROS_PACKAGE_PATH environment variable.
  /// The origins' parameters are the `<origin>` values as written (not urdfdom's quaternion).
  /// \throws Error("serial_chain", "<file>: ...") naming the file: a file that cannot be read,
  ///         is not XML (with TinyXML's line and column) or that urdfdom refuses (with its
  ///         console_bridge messages), a missing base or tip link (with the links it has and a
  ///         did-you-mean), a tip that is not below the base, a floating or planar joint or a
  ///         mimic joint on the path, fewer than 1 or more than kMaxChainJoints moving joints, a
  ///         bad inertial or a name that is not UTF-8 on a link it folds;
  ///         and, in a build without urdfdom (HAPSYN_WITH_URDFDOM=OFF), always.
  static ChainTemplate from_urdf(const std::string& path, const std::string& base_link, const std::string& tip_link,
                                 bool fold_fixed_links = true);

  /// Reads a DH or modified-DH table (JSON, format "hapsyn-dh" version 1, documented in
  /// share/serial_chain/README.md).
  /// \throws Error("serial_chain", "<file>: <json path> = <value>: <rule>"): a wrong shape or
  ///         type, an unknown key (with a did-you-mean), a missing required key, a reference to
  ///         an unknown named length, bad units, lower > upper, a negative mass or length, ...
  static ChainTemplate from_dh_file(const std::string& path);

  /// The parameters, in a fixed order (the file's order): the layout of instantiate's values.
  const std::vector<ChainParameter>& parameters() const { return parameters_; }
  /// Index of a parameter by name, -1 when absent.
  int find(const std::string& name) const;
  /// Number of moving joints.
  int dof() const;
  /// A URDF's drawable mesh visuals and a warning line for each visual left out (empty for a
  /// DH table).
  const ChainMeshes& meshes() const;
  /// A URDF's moving bodies that carry other links' inertials (fixed links on the path after
  /// their moving joint, and the folded links off it), in body order; bodies without any are
  /// left out. Empty for a DH table.
  const std::vector<ChainFoldedLinks>& folded_links() const;
  /// The links with an inertial fixed off the path to the base_link or to a path link before the
  /// first moving joint (folding on): they ride on the base and carry no dynamics.
  const std::vector<std::string>& links_on_base() const;
  /// The file it was read from.
  const std::string& source() const { return source_; }
  /// The Fennel mass model when the file asks for it (DH tables), else null: the chain's bodies
  /// then come from the file's inertials.
  const FennelMassModel* fennel_mass_model() const;

  /// Builds the chain for parameter values (parameters().size() values, in their units), into
  /// `out` (cleared first).
  /// \param motor_mass n motor masses [kg] replacing the file's (from an actuator table), or
  ///        null; used only with the Fennel mass model.
  /// Allocates (once per design); throws nothing for values within the hard limits.
  void instantiate(const double* values, const double* motor_mass, Chain& out) const;

 private:
  struct Impl;
  std::string source_;
  std::vector<ChainParameter> parameters_;
  std::shared_ptr<const Impl> impl_;
};

/// Resolves a chain-file option of the serial_chain mechanism: absolute, relative to the current
/// directory, or to hapsyn's share directory (source tree, then install tree; e.g.
/// "serial_chain/ur5_like.urdf"). \throws Error("serial_chain", "options.<option> = ...") when
/// no such file exists.
std::string resolve_serial_chain_file(const std::string& option_name, const std::string& value);

}  // namespace hapsyn::plugins
