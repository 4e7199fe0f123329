#pragma once
/// \file
/// planar_2r: an example hapsyn mechanism plugin built out of tree (see README.md). A planar
/// serial arm of two revolute joints, both actuated, its base at the origin of the scene frame.
///
/// Conventions:
/// - Design vector (l1, l2) [m]: the lengths of link 1 (base to elbow) and link 2 (elbow to end
///   effector).
/// - Joint angles q = (q1, q2) [rad], counter-clockwise: q1 from +x to link 1, q2 from link 1 to
///   link 2. Forward kinematics: x = l1 c1 + l2 c12, y = l1 s1 + l2 s12 (c12 = cos(q1 + q2)).
/// - Inverse kinematics (closed form): c2 = (x^2 + y^2 - l1^2 - l2^2) / (2 l1 l2),
///   s2 = +-sqrt(1 - c2^2) (the sign is the option q2_sign), q2 = atan2(s2, c2),
///   q1 = atan2(y, x) - atan2(l2 s2, l1 + l2 c2).
/// - J maps (q1dot, q2dot) [rad/s] to (xdot, ydot) [m/s]:
///   J = [-l1 s1 - l2 s12, -l2 s12; l1 c1 + l2 c12, l2 c12], det J = l1 l2 s2.
/// - Classification: |c2| > 1 (beyond rounding) -> kUnreachable; |s2| < singularity_tolerance
///   (arm stretched or folded) -> kSingular; else kReachable. The arm has no joint limits.
#include <hapsyn/mechanism.hpp>
#include <hapsyn/options.hpp>

#include <memory>
#include <string>
#include <vector>

namespace planar_2r_example {

/// The options, declared once (`hapsyn describe planar_2r`). Member initialisers stay `{}`:
/// the declared defaults are the only ones.
struct Planar2ROptions {
  std::string q2_sign;           ///< "positive" (q2 in [0, pi]) or "negative" (q2 in [-pi, 0])
  double singularity_tolerance{};  ///< smallest admissible |sin q2| [-], in (0, 1)

  static void declare(hapsyn::OptionDeclarations<Planar2ROptions>& d) {
    d.describe(
        "Planar serial arm of two revolute joints (both actuated), base at the scene origin; design variables "
        "l1, l2 [m]. Closed-form inverse kinematics on the branch q2_sign; samples with |sin q2| below "
        "singularity_tolerance are singular.");
    d.add(&Planar2ROptions::q2_sign, "q2_sign", "positive",
          "Inverse-kinematics branch: the sign of the elbow angle q2")
        .one_of({"positive", "negative"});
    d.add(&Planar2ROptions::singularity_tolerance, "singularity_tolerance", 1e-6,
          "Smallest admissible |sin q2| (|det J| / (l1 l2)); below it a sample is singular")
        .greater_than(0)
        .less_than(1);
  }
};

/// The arm for one design. Immutable; solve() is const, allocation-free and thread-safe.
class Planar2RModel final : public hapsyn::MechanismModel {
 public:
  /// \param l1, l2 link lengths [m]. \throws hapsyn::Error when one is not finite and > 0.
  Planar2RModel(double l1, double l2, const Planar2ROptions& options);

  /// Classifies the sample (x, y) [m] and fills q (reachable and singular samples) and, when
  /// `needs` asks for it, the 2 x 2 Jacobian.
  void solve(const double* pose, hapsyn::Needs needs, hapsyn::MechanismScratch& scratch,
             hapsyn::SampleQuantities& out) const override;
  /// What `hapsyn view` draws: "links", the polyline base -> elbow -> end effector (z = 0) at
  /// the configuration solve() picks; empty for an unreachable sample. Optional: without it the
  /// default draws only the end effector's point.
  std::vector<hapsyn::Segment> segments(const hapsyn::SampleSet& scene, int sample,
                                        hapsyn::MechanismScratch& scratch) const override;

  /// End effector (x, y) [m] for joint angles (q1, q2) [rad].
  void forward(double q1, double q2, double* xy) const;
  /// The Jacobian at (q1, q2) [rad] into j (resized to 2 x 2; no allocation).
  void jacobian(double q1, double q2, hapsyn::TaskJointMatrix& j) const;

 private:
  double l1_, l2_;
  double q2_sign_;  // +1 or -1
  double singularity_tolerance_;
};

/// The mechanism plugin "planar_2r". Thread safety: immutable after construction.
class Planar2R final : public hapsyn::Mechanism {
 public:
  using Options = Planar2ROptions;
  explicit Planar2R(const Planar2ROptions& options) : options_(options) {}

  /// \param design (l1, l2) [m]. \throws hapsyn::Error when a length is not finite and > 0.
  std::unique_ptr<const hapsyn::MechanismModel> build(const double* design) const override;
  /// l1, l2 [m]: default bounds [0.05, 0.5], hard limits [1e-4, 10].
  std::vector<hapsyn::VariableDecl> variables() const override;
  /// \throws hapsyn::Error unless the samples are (x, y) pairs and there is at least one.
  void check_scene(const hapsyn::SampleSet& scene) const override;
  /// The Jacobian (and the pose, always).
  hapsyn::MechanismSpecs specs() const override { return {hapsyn::kNeedJacobian, {}}; }

 private:
  Planar2ROptions options_;
};

}  // namespace planar_2r_example
