#pragma once
/// \file
/// The symmetric planar five-bar linkage of Unal, Kiziltas & Patoglu (Haptics Symposium 2008),
/// elbow-out posture, as a hapsyn mechanism.
///
/// Frames and conventions (docs/design.md section 3):
/// - Design vector (SI metres): l0 (distance between the actuated joints), l1 (actuated links,
///   l1 = l4), l2 (free links, l2 = l3), r (placement: the scene's centre lies at (0, r) in the
///   mechanism frame).
/// - Mechanism frame: actuated joints A1 = (-l0/2, 0), A2 = (+l0/2, 0); a scene sample (x, y)
///   [m] puts the end effector at E = (x, y + r). Angles are measured from +x, counter-clockwise.
/// - Joint vector q = (q1, q2, q3, q4) [rad]: q1, q4 the actuated links, q2, q3 the free links
///   (left and right). Actuated coordinates (q1, q4).
/// - Elbow-out inverse kinematics: q1 = atan2(E - A1) + acos(c1), q4 = atan2(E - A2) - acos(c2)
///   (law of cosines), q2 = angle(E - B1), q3 = angle(E - B2), B1, B2 the elbows.
///   Representations: q1 in (-pi, 2pi], q2 in [-pi/2, 3pi/2), and their exact mirror images
///   q4 = pi - (mirrored q1) in [-pi, 2pi), q3 = pi - (mirrored q2) in (-pi/2, 3pi/2], so that
///   reflecting a sample about x = 0 maps (q1, q2, q3, q4) to (pi - q4, pi - q3, pi - q2, pi - q1)
///   bit for bit.
/// - Validity (the paper's G): q2 >= 0, q2 <= q1, q3 <= pi, q4 <= q3 (within
///   kFiveBarAngleTolerance), working mode 0 < q3 - q2 < pi (so 0 <= q2 < q3 <= pi: the end
///   effector above both elbows), and |sin(q1 - q2)|, |sin(q3 - q4)|, |sin(q3 - q2)| >=
///   singularity_tolerance. Classification order: no IK solution -> kUnreachable, a sine
///   below the tolerance -> kSingular, G violated -> kInvalid, else kReachable.
/// - J maps (q1dot, q4dot) [rad/s] to (xdot, ydot) [m/s]; D is the joint-space inertia in
///   (q1, q4) [kg m^2] of four uniform bars of width k and linear density rho; the effective
///   mass at the end effector is M = J^-T D J^-1 [kg].
#include <hapsyn/accel/mechanism_acceleration.hpp>
#include <hapsyn/mechanism.hpp>
#include <hapsyn/options.hpp>

#include "fivebar_block.hpp"
#include "fivebar_envelope.hpp"

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// Options of the five-bar, declared once (the plugin's schema is derived from them). Tests and
/// benchmarks that build a FiveBarModel directly take them from hapsyn::default_options or
/// hapsyn::make_options.
struct FiveBarOptions {
  std::string elbow{};                ///< assembly branch; only "out" (the paper's)
  double rho{};                       ///< linear density of every bar [kg/m]
  double k{};                         ///< width of every bar [m] (enters the bar inertias)
  double singularity_tolerance{};     ///< smallest admissible |sin| of the three transmission angles [-]
  /// Footprint limit (Unal 2008, Figure 7) [m]: width (x) and height (y) of the box the
  /// mechanism must fit in; 0 = no limit. When either is set, a second design constraint
  /// "footprint" is declared (see FiveBar::footprint_constraint).
  double footprint_width{};
  double footprint_height{};

  static void declare(OptionDeclarations<FiveBarOptions>& d) {
    d.describe(
        "Symmetric planar five-bar linkage (Unal, Kiziltas & Patoglu 2008), elbow-out. Design variables l0, l1, l2, r "
        "[m]; actuated joints at (-l0/2, 0) and (+l0/2, 0); a scene sample (x, y) puts the end effector at (x, y + r). "
        "Bars are uniform, of linear density rho and width k.");
    d.add(&FiveBarOptions::elbow, "elbow", "out",
          "Assembly branch: \"out\", the paper's elbow-out posture (left elbow bends left, right elbow right).")
        .one_of({"out"});
    d.add(&FiveBarOptions::rho, "rho", 1.08,
          "Linear density of every bar: m_i = rho * l_i (m1 = m4, m2 = m3). 1.08 kg/m reproduces Unal 2008 Table 2.")
        .greater_than(0)
        .unit("kg/m");
    d.add(&FiveBarOptions::k, "k", 0.005,
          "Width of every bar; a bar's inertia about its centre is m (l^2 + k^2) / 12. Any k in [0, 0.012] m "
          "reproduces the GDI values of Unal 2008 Table 2.")
        .minimum(0)
        .unit("m");
    d.add(&FiveBarOptions::footprint_width, "footprint_width", 0.0,
          "Footprint limit in x (Unal 2008, Figure 7): the box around both actuated joints' circles of radius l1 and "
          "the scene must be at most this wide; 0 = no limit. Adds the design constraint 'footprint'.")
        .minimum(0)
        .unit("m");
    d.add(&FiveBarOptions::footprint_height, "footprint_height", 0.0,
          "Footprint limit in y (see footprint_width); 0 = no limit.")
        .minimum(0)
        .unit("m");
    d.add(&FiveBarOptions::singularity_tolerance, "singularity_tolerance", 1e-4,
          "A sample whose |sin(q1 - q2)|, |sin(q3 - q4)| or |sin(q3 - q2)| is below this is classified singular.")
        .greater_than(0)
        .maximum(1);
  }
};

/// One design in SI units [m].
struct FiveBarDesign {
  double l0 = 0.0;  ///< distance between the actuated joints [m]
  double l1 = 0.0;  ///< actuated link length (l1 = l4) [m]
  double l2 = 0.0;  ///< free link length (l2 = l3) [m]
  double r = 0.0;   ///< placement: scene centre at (0, r) in the mechanism frame [m]
};

/// Tolerance [rad] of the closed inequalities of the validity set G (one-ulp rounding at a
/// limit must not change a classification; docs/design.md section 6).
constexpr double kFiveBarAngleTolerance = 1e-9;

/// The five-bar for one design. Immutable; solve() is const, allocation-free and thread-safe
/// (it needs no scratch).
class FiveBarModel final : public MechanismModel {
 public:
  /// \throws Error when a length is not finite, l0 < 0 or l1, l2 <= 0, or r is not finite.
  FiveBarModel(const FiveBarDesign& design, const FiveBarOptions& options);

  /// Classifies the sample (x, y) [m] (scene frame) and fills q, and on request J, D and M.
  /// q is filled for reachable, singular and invalid samples (the computed configuration; zeros
  /// when the end effector sits exactly on an actuated joint) and zeroed for unreachable ones.
  void solve(const double* pose, Needs needs, MechanismScratch& scratch,
             SampleQuantities& out) const override;
  /// Drawn in the scene frame at z = 0 (the mechanism frame shifted by -r in y): "links" A1 -> B1
  /// -> E -> B2 -> A2 at the configuration solve() computes, and "base" A1 -> A2. Empty for an
  /// unreachable sample.
  std::vector<Segment> segments(const SampleSet& scene, int sample, MechanismScratch& scratch) const override;

  /// The block path: solve() for kBlockLanes samples at once, without trigonometry
  /// (fivebar_block.hpp). Fills status and J, D, M; never q.
  void solve_block(const PoseBlock& poses, Needs needs, MechanismScratch& scratch, QuantityBlock& out) const;

  /// Forward kinematics: the end effector (x, y) [m] in the scene frame from the actuated
  /// angles q1, q4 [rad], on the working-mode branch (sin(q3 - q2) > 0, E to the left of
  /// B1 -> B2). \return false when the elbows are farther apart than 2 l2 or coincide.
  bool forward(double q1, double q4, double* xy) const;

  const FiveBarDesign& design() const { return design_; }
  double rho() const { return rho_; }  ///< linear density of the bars [kg/m] (option rho)
  double k() const { return k_; }      ///< width of the bars [m] (option k)
  double actuated_mass() const { return m1_; }  ///< m1 = m4 = rho l1 [kg]
  double free_mass() const { return m2_; }      ///< m2 = m3 = rho l2 [kg]

 private:
  // Only numbers: a model is built per design (culling builds ~1e9), so it copies no string.
  FiveBarDesign design_;
  double singularity_tolerance_ = 0.0;
  double rho_ = 0.0, k_ = 0.0;
  double h0_ = 0.0;         // l0 / 2 [m]
  double m1_ = 0.0;         // actuated bar mass [kg]
  double m2_ = 0.0;         // free bar mass [kg]
  double inertia_a_ = 0.0;  // actuated bar about its joint, m1 (4 l1^2 + k^2) / 12 [kg m^2]
  double inertia_f_ = 0.0;  // free bar about its centre, m2 (l2^2 + k^2) / 12 [kg m^2]
  double l2_squared_ = 0.0;
  FiveBarBlockDesign block_;
};

/// The five-bar mechanism plugin ("fivebar").
class FiveBar final : public Mechanism, public MechanismAcceleration {
 public:
  using Options = FiveBarOptions;
  /// \param options validated options (FiveBarOptions::declare), defaults filled.
  explicit FiveBar(const FiveBarOptions& options) : options_(options) {}

  /// \param design l0, l1, l2, r [m]. \throws Error for a non-finite or non-positive length.
  std::unique_ptr<const MechanismModel> build(const double* design) const override;
  /// The same model, built in the per-thread scratch (no allocation per design).
  const MechanismModel* build_in(const double* design, MechanismScratch& scratch) const override;
  /// Scratch holding the model that build_in() rebuilds.
  std::unique_ptr<MechanismScratch> make_scratch() const override;
  /// l0, l1, l2, r [m] with the paper's default bounds and hard limits.
  std::vector<VariableDecl> variables() const override;
  /// "reach" [m^2] (see reach_constraint()), and "footprint" [m] when options.footprint_width
  /// or footprint_height is set (see footprint_constraint()).
  std::vector<ConstraintDecl> constraints() const override;
  /// g[0] = reach_constraint(design, scene bounding box); g[1] = footprint_constraint when
  /// declared. O(1) with the framework's cached scene bounds, no allocation.
  void evaluate_constraints(const double* design, const SampleSet& scene, double* g) const override;
  /// For r (component 3): the closed-form interval of r where the reach constraint holds for
  /// the design's l0, l1, l2 (reach_interval), widened by a rounding margin. Other components:
  /// false. O(1), no allocation.
  bool constraint_interval(const double* design, int component, const SampleSet& scene, double& lower,
                           double& upper) const override;
  /// True for r (component 3) without a footprint constraint: reach_constraint is
  /// (ax^2 + max(|ymin + r|, |ymax + r|)^2) - (l1 + l2)^2, and each rounded step after the sums
  /// ymin + r, ymax + r (monotone in r) is monotone or a max of quasiconvex terms, so its
  /// sublevel set in r is one interval in floating point too (docs/design.md section 13.3).
  bool constraints_quasiconvex(int component) const override;
  /// For r (component 3): bounds of the sample's sigma_min(J) / sigma_max(J) and sigma_max(M),
  /// and proofs of failure, over a run of r (fivebar_envelope.hpp, docs/design.md section
  /// 13.5). False for other components and for runs that put the sample at or below the
  /// actuated joints' axis. O(1), no allocation.
  bool sample_envelope(const double* design, int component, double lower, double upper, const double* pose,
                       Needs needs, SampleEnvelope& out) const override;
  /// For r (component 3): the interval of r outside which the sample (x, y) fails, from the
  /// legs' reach and the end effector's side of the actuated joints' axis (docs/design.md
  /// section 13.5). With a, b the x distances |x + h0|, |h0 - x| of the sample from the actuated
  /// joints and Y = y + r its height, a sample solves only with |l1 - l2| <= |E - A_i| <= l1 + l2
  /// for both legs and Y >= 0 (up to the angle tolerance): Y in [sqrt(max(0, (l1 - l2)^2 -
  /// min(a, b)^2)), sqrt((l1 + l2)^2 - max(a, b)^2)], widened for rounding and the tolerance.
  /// Empty when l1 + l2 < max(a, b) beyond rounding. False for other components. O(1).
  bool reachable_interval(const double* design, int component, const double* pose, double& lower,
                          double& upper) const override;
  /// The interval of r [m] on which reach_constraint(design with that r, box) <= 0, for the
  /// design's l0, l1, l2 and the box [xmin, xmax] x [ymin, ymax]: with ax the larger x distance
  /// from an actuated joint to the box and R = sqrt((l1 + l2)^2 - ax^2), the farthest corner
  /// is within reach iff -R <= ymin + r and ymax + r <= R, i.e. r in [-R - ymin, R - ymax]
  /// (docs/design.md section 13.3). Empty (lower > upper) when (l1 + l2) < ax. Exact arithmetic;
  /// the caller widens it for rounding.
  static void reach_interval(const FiveBarDesign& design, double xmin, double xmax, double ymin, double ymax,
                             double& lower, double& upper);
  /// \throws Error unless the scene has samples with exactly two coordinates (x, y) [m].
  void check_scene(const SampleSet& scene) const override;
  /// kNeedJacobian | kNeedInertia | kNeedEffectiveMass.
  Needs provides() const;
  MechanismSpecs specs() const override { return {provides(), {}}; }
  const MechanismAcceleration* acceleration() const override { return this; }
  /// The block kernel of `model` (a FiveBarModel this mechanism built).
  void solve_block(const MechanismModel& model, const PoseBlock& poses, Needs needs, MechanismScratch& scratch,
                   QuantityBlock& out) const override {
    static_cast<const FiveBarModel&>(model).solve_block(poses, needs, scratch, out);
  }

  /// True when `needs` asks for nothing beyond J, D and M (the block kernel gives no q).
  bool solves_blocks(Needs needs) const override;
  /// Designs that differ only in r: the five-bar depends on r only through y + r, so lane i is
  /// the sample (x, y + r_i) of the design with r = -0 (bit for bit the same sums). False when
  /// l0, l1 or l2 differ between lanes, or without the block kernel.
  bool solve_designs(const double* const* designs, int count, const double* pose, Needs needs,
                     MechanismScratch& scratch, QuantityBlock& out) const override;

  const FiveBarOptions& options() const { return options_; }

  /// The paper's reach condition generalised to a bounding box [xmin, xmax] x [ymin, ymax] [m]
  /// (scene frame): max over both actuated joints of the squared distance to the farthest box
  /// corner, minus (l1 + l2)^2 [m^2]. For a square of side s centred at (0, 0) and r >= 0 this
  /// is (l0/2 + s/2)^2 + (r + s/2)^2 - (l1 + l2)^2.
  /// Footprint constraint [m]: the box holding both actuated joints' circles of radius l1 (where
  /// the elbows can be) and the scene's bounding box (where the end effector is) contains the
  /// whole mechanism in every posture (the distal links join the two); g = the larger excess of
  /// its width over `width` and of its height over `height` (a zero limit is not checked).
  static double footprint_constraint(const FiveBarDesign& design, double xmin, double xmax, double ymin, double ymax,
                                     double width, double height);
  static double reach_constraint(const FiveBarDesign& design, double xmin, double xmax, double ymin,
                                 double ymax);
  /// The design (l0, l1, l2, r) from a design vector (unchecked: FiveBarModel checks it).
  static FiveBarDesign design_from(const double* design);

 private:
  FiveBarOptions options_;
};

}  // namespace hapsyn::plugins
