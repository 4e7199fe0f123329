#pragma once
/// \file
/// The options of the serial_chain mechanism, declared once (`hapsyn describe serial_chain`).
#include <hapsyn/options.hpp>

#include <string>
#include <utility>
#include <vector>

namespace hapsyn::plugins {

/// IK settings as the problem file gives them (a nested group "ik").
struct SerialChainIkOptions {
  std::string solver{};
  std::string selection{};
  std::string redundant_joint{};
  int redundant_steps{};
  double position_tolerance{};
  double orientation_tolerance{};
  int max_iterations{};
  int restarts{};
  long long seed{};
  bool warm_start{};

  static void declare(OptionDeclarations<SerialChainIkOptions>& d) {
    d.describe(
        "Inverse kinematics: every solution in closed form for 6R arms whose axes allow it, else damped least squares "
        "with joint limits and restarts (docs/design.md, serial chains).");
    d.add(&SerialChainIkOptions::solver, "solver", "auto",
          "'auto': the closed form (every solution, subproblem decomposition) when the chain has 6 revolute joints, "
          "the task is 'pose' and its axes form a supported family (spherical wrist, three parallel axes as UR "
          "arms, axes 1-2-3 and 4-5 parallel as the haptic 6R, or axes 5 x 6 meeting: a 1-D search), else the "
          "numerical IK; 'closed_form' refuses a chain without one (naming its axis geometry); 'numerical' always "
          "the damped least squares. The run header and result.json's mechanism_summary name the solver a chain got. "
          "position_tolerance, orientation_tolerance, max_iterations, restarts, seed and warm_start are the "
          "numerical IK's. 7 revolute joints: the closed form with one joint discretised (redundant_joint, "
          "redundant_steps).")
        .one_of({"auto", "closed_form", "numerical"});
    d.add(&SerialChainIkOptions::selection, "selection", "closest_to_home",
          "Which solution a sample gets: the one closest to home (sum of squared joint differences, revolute ones "
          "wrapped) among all solutions inside the limits (closed form: the true closest) or among those converged "
          "from 'home' and the restarts (numerical: may miss a closer one), or the first one found (closed form: the "
          "engine's first in-limit solution; numerical: faster). Deterministic either way.")
        .one_of({"closest_to_home", "first_found"});
    d.add(&SerialChainIkOptions::redundant_joint, "redundant_joint", "auto",
          "7 revolute joints, closed form: the joint discretised (locked at each of redundant_steps values; each "
          "value's 6R solved in closed form, the solutions' union selected from). 'auto': the first of joints 4, 3, "
          "5, 2, 6, 1, 7 whose locking leaves a 6R with a closed-form family and a full-rank Jacobian at the test "
          "angles 0, 1, -2, sqrt 2 rad (and, at model build, at every grid value), one without the 1-D search "
          "preferred; or a joint's name. Only for 7-joint chains.");
    d.add(&SerialChainIkOptions::redundant_steps, "redundant_steps", 17,
          "Values of the redundant joint: evenly over its limits, both ends included (over a full turn for an "
          "unlimited joint). Each costs one 6R solve per sample; a solution between two values is not found (the "
          "human_arm scene's joint3_steps likewise).")
        .range(2, 1000);  // kMaxRedundantSteps (chain_closed_form_ik.hpp)
    d.add(&SerialChainIkOptions::position_tolerance, "position_tolerance", 1e-10, "Converged when the position error is below this.")
        .greater_than(0)
        .maximum(1e-3)
        .unit("m");
    d.add(&SerialChainIkOptions::orientation_tolerance, "orientation_tolerance", 1e-10,
          "... and the orientation error below this.")
        .greater_than(0)
        .maximum(1e-3)
        .unit("rad");
    d.add(&SerialChainIkOptions::max_iterations, "max_iterations", 100, "Iteration budget per start.").range(1, 10000);
    d.add(&SerialChainIkOptions::restarts, "restarts", 8,
          "Numerical IK: deterministic pseudo-random starts inside the joint limits tried after 'home'. More find the "
          "configuration closest to home more often (the haptic 6R: 95 % of a workspace's poses with 8, all with "
          "24) at a proportional cost.")
        .range(0, 1000);
    d.add(&SerialChainIkOptions::seed, "seed", 1, "Seed of the restarts' starts (not the study's seed: the model is "
                                                    "the same in every run).")
        .minimum(0);
    d.add(&SerialChainIkOptions::warm_start, "warm_start", false,
          "Numerical IK: also start from the previous sample's solution on the same thread. Faster on dense scenes, but the "
          "configuration a sample gets then depends on how samples are split over threads (results repeat for a "
          "given --threads).");
    using I = SerialChainIkOptions;
    d.rule({"redundant_joint", "solver"}, "redundant_joint only with solver auto or closed_form", [](const I& o) {
      return o.solver == "numerical" && o.redundant_joint != "auto" ? std::string("only for the closed form (solver is \"numerical\")")
                                                                    : std::string();
    });
    d.rule({"redundant_steps", "solver"}, "redundant_steps only with solver auto or closed_form", [](const I& o) {
      return o.solver == "numerical" && o.redundant_steps != 17 ? std::string("only for the closed form (solver is \"numerical\")")
                                                                : std::string();
    });
  }
};

/// Options of the serial_chain mechanism.
struct SerialChainOptions {
  std::string urdf{};
  std::string base_link{};
  std::string tip_link{};
  bool fold_fixed_links{};
  std::string dh_file{};
  std::string task{};
  std::string task_axis{};
  std::vector<double> base_xyz{};
  std::vector<double> base_rpy{};
  std::vector<double> tool_xyz{};
  std::vector<double> tool_rpy{};
  std::vector<double> home{};
  double singularity_tolerance{};
  double characteristic_length{};
  std::string actuator_file{};
  std::vector<int> actuator_size{};
  std::vector<int> actuator_gear{};
  std::vector<std::string> constraints{};
  SerialChainIkOptions ik{};

  static void declare(OptionDeclarations<SerialChainOptions>& d) {
    d.describe(
        "A serial manipulator (1 to 7 revolute or prismatic joints) read from a URDF file (base_link to tip_link) or "
        "a DH / modified-DH table (dh_file). Every model parameter (joint origins, DH entries, named lengths, link "
        "masses, mass_scale) is a design variable fixed at the file's value unless the problem file's design "
        "section frees it; actuator sizes and gear codes too when an actuator table is given. Numerical IK, "
        "geometric Jacobian, CRBA inertia, gravity. Scene samples: positions (x, y, z) or poses (x, y, z, qw, qx, "
        "qy, qz) in the scene frame. See docs/design.md, serial chains.");
    d.add(&SerialChainOptions::urdf, "urdf", "",
          "URDF file: absolute, relative to the current directory, or to hapsyn's share directory. Exactly one of "
          "urdf and dh_file.");
    d.add(&SerialChainOptions::base_link, "base_link", "", "URDF link the chain starts at (its frame is the base).");
    d.add(&SerialChainOptions::tip_link, "tip_link", "", "URDF link whose frame is the tip (the end effector).");
    d.add(&SerialChainOptions::fold_fixed_links, "fold_fixed_links", true,
          "URDF: fold every link hanging off the base -> tip path through fixed joints only (a gripper and its "
          "fixed fingers, a payload, a tool) into the moving body it hangs from (mass, centre of mass, inertia; a "
          "design variable LINK:mass each). Links fixed to the base carry no dynamics; links behind a moving "
          "joint off the path are never folded. The summary lists what each body carries (folded: ... -> link). "
          "false: only the path's own links.");
    d.add(&SerialChainOptions::dh_file, "dh_file", "", "DH or modified-DH table (format hapsyn-dh, share/serial_chain/README.md).");
    d.add(&SerialChainOptions::task, "task", "pose",
          "What of a sample the tip must match: the full pose (6 rows; needs 7-coordinate samples), the position "
          "(3 rows), or the position and the direction of one tip axis (5 rows; rotation about it is free).")
        .one_of({"pose", "position", "position_axis"});
    d.add(&SerialChainOptions::task_axis, "task_axis", "z", "The tip axis of task position_axis.").one_of({"x", "y", "z"});
    d.add(&SerialChainOptions::base_xyz, "base_xyz", {0, 0, 0}, "Position of the chain's base frame in the scene frame.")
        .size(3)
        .unit("m");
    d.add(&SerialChainOptions::base_rpy, "base_rpy", {0, 0, 0},
          "Orientation of the base frame in the scene frame: R = Rz(yaw) Ry(pitch) Rx(roll), as URDF.")
        .size(3)
        .unit("deg");
    d.add(&SerialChainOptions::tool_xyz, "tool_xyz", {0, 0, 0},
          "Position of the scene's sample frame (the handle, say) in the tip frame: the tool offset.")
        .size(3)
        .unit("m");
    d.add(&SerialChainOptions::tool_rpy, "tool_rpy", {0, 0, 0}, "Orientation of the sample frame in the tip frame.")
        .size(3)
        .unit("deg");
    d.add(&SerialChainOptions::home, "home", std::vector<double>{},
          "Reference posture, one value per joint (deg for revolute, m for prismatic joints): the first IK start "
          "and the 'closest_to_home' reference. Empty: the middle of each limited joint's range, 0 for unlimited.");
    d.add(&SerialChainOptions::singularity_tolerance, "singularity_tolerance", 1e-6,
          "A reachable sample whose scaled task Jacobian has sigma_min / sigma_max below this is classified "
          "singular (angular rows scaled by characteristic_length).")
        .minimum(0)
        .less_than(1);
    d.add(&SerialChainOptions::characteristic_length, "characteristic_length", 0.0,
          "Length that makes angular and linear task rows comparable in the singularity test. 0: the chain's "
          "reach at the nominal design (sum of the distances between consecutive joint origins and the tip).")
        .minimum(0)
        .unit("m");
    d.add(&SerialChainOptions::actuator_file, "actuator_file", "",
          "Actuator table (format hapsyn-actuator-table, e.g. haptic6r/actuators_assumed.json). When given, the "
          "design variables size and gear (one per joint) choose each joint's actuator: velocity and torque limits "
          "from the table, and motor masses for a table using the Fennel mass model. Empty: the file's limits.");
    d.add(&SerialChainOptions::actuator_size, "actuator_size", std::vector<int>{},
          "Nominal size code per joint (the design variable size's value unless the design section frees it); "
          "empty: 1 for every joint.");
    d.add(&SerialChainOptions::actuator_gear, "actuator_gear", std::vector<int>{},
          "Nominal gear code per joint; empty: 1 for every joint.");
    d.add(&SerialChainOptions::constraints, "constraints", std::vector<std::string>{},
          "Linear design constraints over design variables, e.g. \"l1 + l2 <= 0.9\" or the monotone sequence "
          "\"size[0] >= size[1] >= size[2]\".");
    d.add(&SerialChainOptions::ik, "ik", "Inverse kinematics.");
    declare_rules(d);
  }

 private:
  // Which options go together: the chain from exactly one file, the links only with a URDF, the
  // actuator codes only with a table.
  static void declare_rules(OptionDeclarations<SerialChainOptions>& d) {
    using O = SerialChainOptions;
    const auto when = [](bool broken, const char* what) { return broken ? std::string(what) : std::string(); };
    d.rule({"urdf", "dh_file"}, "urdf or dh_file given", [when](const O& o) {
      return when(o.urdf.empty() && o.dh_file.empty(), "give the chain as options.urdf or options.dh_file");
    });
    d.rule({"dh_file", "urdf"}, "not both urdf and dh_file", [when](const O& o) {
      return when(!o.urdf.empty() && !o.dh_file.empty(), "give either urdf or dh_file, not both");
    });
    for (const char* link : {"base_link", "tip_link"}) {
      const std::string name = link;
      const auto member = name == "base_link" ? &O::base_link : &O::tip_link;
      d.rule({name, "dh_file"}, name + " only with urdf", [when, member](const O& o) {
        return when(!o.dh_file.empty() && !(o.*member).empty(), "only for a URDF (a DH table's chain is its rows)");
      });
      d.rule({name, "urdf"}, "a URDF chain needs " + name, [when, member](const O& o) {
        return when(!o.urdf.empty() && (o.*member).empty(),
                    "a URDF chain needs base_link and tip_link (the links it runs between)");
      });
    }
    d.rule({"fold_fixed_links", "dh_file"}, "fold_fixed_links only with urdf", [when](const O& o) {
      return when(!o.dh_file.empty() && !o.fold_fixed_links, "only for a URDF (a DH table has no fixed links)");
    });
    for (const auto& [name, member] : {std::pair{"actuator_size", &O::actuator_size}, std::pair{"actuator_gear", &O::actuator_gear}}) {
      d.rule({name, "actuator_file"}, std::string(name) + " only with actuator_file", [when, member = member](const O& o) {
        return when(o.actuator_file.empty() && !(o.*member).empty(), "only with an actuator_file");
      });
    }
  }
};

}  // namespace hapsyn::plugins
