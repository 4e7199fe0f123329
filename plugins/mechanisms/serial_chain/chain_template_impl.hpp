#pragma once
/// \file
/// Private to the serial_chain model: what ChainTemplate keeps of a file (its builder) and the
/// small pieces the readers (urdf_chain.cpp, dh_chain.cpp) and the mass model
/// (fennel_mass_model.cpp) share. Not installed, not part of the contract.
#include "chain_template.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// The component name of every serial_chain error.
constexpr const char* kSerialChainName = "serial_chain";

/// What a reader leaves behind: the chain builder for parameter values.
struct ChainTemplate::Impl {
  int dof = 0;
  std::optional<FennelMassModel> fennel;  ///< set when the file asks for the Fennel mass model
  /// Builds the chain (values: the template's parameters; motor_mass: see instantiate()).
  std::function<void(const double* values, const double* motor_mass, Chain& out)> build;
  ChainMeshes meshes;  ///< a URDF's drawable mesh visuals (none for a DH table)
  std::vector<ChainFoldedLinks> folded_links;  ///< see ChainTemplate::folded_links
  std::vector<std::string> links_on_base;      ///< see ChainTemplate::links_on_base
};

namespace serial_chain_detail {

/// R = Rz(yaw) Ry(pitch) Rx(roll): the URDF rpy convention.
Eigen::Matrix3d rpy_rotation(double roll, double pitch, double yaw);
/// A pose from a translation and URDF rpy angles.
Eigen::Isometry3d xyz_rpy_pose(const Eigen::Vector3d& xyz, double roll, double pitch, double yaw);

/// m (|r|^2 1 - r r^T): the parallel-axis term of a point mass m at r.
Eigen::Matrix3d parallel_axis(double m, const Eigen::Vector3d& r);
/// Adds a rigid part (mass m, centre c, inertia about c, all in the body's frame) to a body.
void add_part(ChainBody& body, double m, const Eigen::Vector3d& c, const Eigen::Matrix3d& inertia);
/// A body's data re-expressed in another frame: `pose` maps the body's current frame into it.
ChainBody transformed(const ChainBody& body, const Eigen::Isometry3d& pose);
/// Multiplies mass and inertia by `factor` (the com stays).
void scale_body(ChainBody& body, double factor);

/// The Fennel mass model's bodies for a chain whose joints and tip are set: replaces
/// chain.bodies. \param motor_mass n motor masses [kg] before the mass factor.
void apply_fennel_mass_model(const FennelMassModel& model, const double* motor_mass, Chain& chain);

/// ", did you mean \"x\"?" for the closest candidate (edit distance <= max(2, |name|/3)), else "".
/// The "mass_scale" parameter every chain file has (factor on every mass and inertia, >= 0).
ChainParameter mass_scale_parameter();

std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates);

/// Why `inertia` (a body's, about its centre of mass, kg m^2) is no rigid body's, or "" when it
/// is one: not finite, a principal moment below 0, or one larger than the sum of the other two
/// (the triangle inequality every mass distribution meets), within 1e-6 of their sum so that
/// files rounded to a few digits pass.
std::string inertia_implausibility(const Eigen::Matrix3d& inertia);
/// A number as the messages print it (shortest round trip, e.g. 0.45, 1e-09, inf).
std::string show_number(double x);

}  // namespace serial_chain_detail

}  // namespace hapsyn::plugins
