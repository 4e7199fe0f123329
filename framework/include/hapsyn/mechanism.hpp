#pragma once
/// \file
/// Mechanisms: per design, a const model that classifies task-space samples and computes the
/// requested quantities, with per-thread scratch so the per-sample loop is allocation-free.
#include <hapsyn/design_space.hpp>
#include <hapsyn/quantities.hpp>
#include <hapsyn/scene.hpp>

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

namespace hapsyn {

class MechanismAcceleration;  // hapsyn/accel/mechanism_acceleration.hpp

/// One polyline of a mechanism's drawing (MechanismModel::segments): straight pieces joining
/// consecutive points, e.g. the links from the base through the joints to the end effector.
struct Segment {
  std::string name;                     ///< what it shows ("links", "left leg", "base"), for a legend
  std::vector<Eigen::Vector3d> points;  ///< at least two, in the frame of the scene's poses [m]
};

/// Per-thread scratch a model may use (Pinocchio's Data): made once per thread by
/// Mechanism::make_scratch, reused for every sample and design that thread evaluates, never
/// shared between threads. Mechanisms that need none use this base as is. Aligned to a cache
/// line (so its size is a multiple of one): the scratches of two threads, written per sample,
/// never share a line.
class alignas(64) MechanismScratch {
 public:
  virtual ~MechanismScratch() = default;
};

/// The mechanism for one design (Pinocchio's Model): immutable once built, shared by threads.
class MechanismModel {
 public:
  MechanismModel() = default;
  MechanismModel(const MechanismModel&) = delete;
  MechanismModel& operator=(const MechanismModel&) = delete;
  virtual ~MechanismModel() = default;
  /// Classifies one sample and, when it is reachable, fills the quantities asked for.
  /// \param pose    one scene sample (SampleSet::pose: SampleSet::dimension() values, in the
  ///                scene frame and its units, e.g. (x, y) [m] or (x, y, z, qw, qx, qy, qz))
  /// \param needs   bit set of Need flags: compute these and nothing else (a study computes only
  ///                what its metrics need); kNeedPose alone means classification only
  /// \param scratch this thread's scratch from Mechanism::make_scratch
  /// \param out     `out.status` always set; the quantities in `needs` when kReachable, in the
  ///                units of SampleQuantities (SI); the others may keep stale values
  /// Called concurrently for different samples from several threads (each with its own
  /// scratch), millions of times: must not allocate, lock or throw. A sample at or too near a
  /// singularity is kSingular, never a NaN: the evaluator refuses NaN/inf quantities.
  virtual void solve(const double* pose, Needs needs, MechanismScratch& scratch,
                     SampleQuantities& out) const = 0;
  /// The mechanism drawn at the configuration solve() picks for sample `sample` (an index) of
  /// `scene`: polylines through its joints, in the frame of the scene's poses [m] (a planar one at
  /// z = 0), for viewers (`hapsyn view`). Empty when solve() finds the sample kUnreachable (or,
  /// for a mechanism without a configuration there, kInvalid). Called once per picture, outside
  /// the per-sample loop, with a `scratch` from Mechanism::make_scratch: may allocate.
  /// Default: one segment "end effector" from the scene frame's origin to the pose's position
  /// (its first three coordinates, missing ones 0), which draws nothing of the links.
  /// solve() is given `scene` and `sample` in SampleQuantities::scene and SampleQuantities::sample.
  virtual std::vector<Segment> segments(const SampleSet& scene, int sample, MechanismScratch& scratch) const;
};


/// What a mechanism is and can compute: read once, at load (Mechanism::specs()).
struct MechanismSpecs {
  /// Quantities this mechanism can compute (Need flags); the framework refuses a metric that
  /// needs more. Default: pose and Jacobian.
  Needs provides = kNeedJacobian;
  /// One line saying what the options made of this mechanism (e.g. a chain's moving joints from
  /// base to tip, and its task), shown in the run header, in result.json ("mechanism_summary")
  /// and by `hapsyn describe NAME --options`, so that a wrong reading of a file is seen before
  /// a study runs. Default: "" (nothing shown).
  std::string summary;
};

/// Mechanism plugin: the one pure virtual is build(); everything else has a default.
///
/// Life cycle: created once per study (options filled from its declarations, see
/// hapsyn/options.hpp); specs(), variables() and constraints() are read once at load and
/// check_scene() runs once after the scene is built; then build() runs once per design
/// evaluation and make_scratch() once per worker thread. The const methods are called
/// concurrently unless the class declares ThreadSafety::kSerialized.
///
/// What the framework checks centrally, so a mechanism need not: design values are finite and
/// within the bounds the problem file gives (which it keeps inside the declared hard limits),
/// constraints return finite values, every metric's needs are provided.
///
/// Speed: a mechanism that can solve several samples or designs at once, build a model without
/// allocating, or bound a block of designs says so through acceleration()
/// (hapsyn/accel/mechanism_acceleration.hpp); nothing else in this class is about speed.
class Mechanism {
 public:
  Mechanism() = default;
  Mechanism(const Mechanism&) = delete;
  Mechanism& operator=(const Mechanism&) = delete;
  virtual ~Mechanism() = default;
  /// Builds the model for a full design vector (layout: DesignSpace::components(), i.e. the
  /// variables() flattened in declaration order, in their units). May allocate (once per
  /// design). Throws nothing for a design within the bounds: an unusable design is one whose
  /// constraints fail or whose samples are unreachable.
  virtual std::unique_ptr<const MechanismModel> build(const double* design) const = 0;
  /// The design variables (names, units, default bounds, hard limits, integer or not).
  virtual std::vector<VariableDecl> variables() const { return {}; }
  /// Design constraints g(p) <= 0 (may depend on the scene's extent; never on a sample).
  virtual std::vector<ConstraintDecl> constraints() const { return {}; }
  /// Evaluates the constraints declared by constraints() into g (constraints().size() values;
  /// g <= 0 is satisfied). Called before any sample of the design is solved.
  virtual void evaluate_constraints(const double* design, const SampleSet& scene, double* g) const {}
  /// Per-thread scratch for MechanismModel::solve (called once per worker thread).
  virtual std::unique_ptr<MechanismScratch> make_scratch() const {
    return std::make_unique<MechanismScratch>();
  }
  /// Throws hapsyn::Error when the scene's samples are not of a kind this mechanism serves
  /// (e.g. 2 coordinates for a planar mechanism). Called once, after the scene is built.
  virtual void check_scene(const SampleSet& scene) const {}
  /// What this mechanism provides and what the options made of it (read once, at load).
  virtual MechanismSpecs specs() const { return {}; }
  /// The optional speed layer (block kernels, design lanes, models built in scratch, bounds for
  /// grid solvers), or null (the default): the framework then calls build() and
  /// MechanismModel::solve() per sample. Read once, at load; the object must live as long as
  /// the mechanism (usually `this`: the mechanism derives from MechanismAcceleration too).
  virtual const MechanismAcceleration* acceleration() const { return nullptr; }
};

}  // namespace hapsyn
