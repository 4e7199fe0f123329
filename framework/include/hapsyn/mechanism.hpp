#pragma once
/// \file
/// Mechanisms: per design, a const model that classifies task-space samples and computes the
/// requested quantities, with per-thread scratch so the per-sample loop is allocation-free.
#include <hapsyn/design_space.hpp>
#include <hapsyn/quantities.hpp>
#include <hapsyn/accel/sample_envelope.hpp>
#include <hapsyn/accel/sample_block.hpp>
#include <hapsyn/scene.hpp>

#include <memory>
#include <string>
#include <vector>

namespace hapsyn {

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
  /// Optional block path (hapsyn/accel/sample_block.hpp): classifies the `poses.count` samples of a
  /// block and fills, for the reachable lanes, the quantities in `needs`, as solve() would for
  /// each (to rounding: agreement to 1e-12 relative, the same status). Called only when
  /// Mechanism::solves_blocks(needs) is true, with the same rules as solve() (concurrent, no
  /// allocation, lock or throw; no NaN reaches a reachable lane). Lanes at or beyond
  /// poses.count, and unreachable lanes, may hold any values. Default: solve() per lane.
  virtual void solve_block(const PoseBlock& poses, Needs needs, MechanismScratch& scratch, QuantityBlock& out) const;
};

/// Mechanism plugin: the one pure virtual is build(); everything else has a default.
///
/// Life cycle: created once per study (options filled from its declarations, see
/// hapsyn/options.hpp); variables(), constraints(), provides() are read once at load and
/// check_scene() runs once after the scene is built; then build() (or build_in()) runs once per
/// design evaluation and make_scratch() once per worker thread. The const methods are called
/// concurrently unless the class declares ThreadSafety::kSerialized.
///
/// What the framework checks centrally, so a mechanism need not: design values are finite and
/// within the bounds the problem file gives (which it keeps inside the declared hard limits),
/// constraints return finite values, every metric's needs are provided.
class Mechanism {
 public:
  virtual ~Mechanism() = default;
  /// Builds the model for a full design vector (layout: DesignSpace::components(), i.e. the
  /// variables() flattened in declaration order, in their units). May allocate (once per
  /// design). Throws nothing for a design within the bounds: an unusable design is one whose
  /// constraints fail or whose samples are unreachable.
  virtual std::unique_ptr<const MechanismModel> build(const double* design) const = 0;
  /// Optional fast path: builds the model for `design` inside the per-thread `scratch` and
  /// returns it (valid until the next call with the same scratch), so that a solver visiting
  /// millions of designs allocates nothing per design. Default: nullptr (build() is used).
  virtual const MechanismModel* build_in(const double* design, MechanismScratch& scratch) const {
    return nullptr;
  }
  /// The design variables (names, units, default bounds, hard limits, integer or not).
  virtual std::vector<VariableDecl> variables() const { return {}; }
  /// Design constraints g(p) <= 0 (may depend on the scene's extent; never on a sample).
  virtual std::vector<ConstraintDecl> constraints() const { return {}; }
  /// Evaluates the constraints declared by constraints() into g (constraints().size() values;
  /// g <= 0 is satisfied). Called before any sample of the design is solved.
  virtual void evaluate_constraints(const double* design, const SampleSet& scene, double* g) const {}
  /// Optional block bound for grid solvers: an interval [lower, upper] of design component
  /// `component` (an index into the full design vector) outside which some constraint is
  /// violated, the other components as in `design`. It may be wider than the feasible set
  /// (inside it, evaluate_constraints decides) but never narrower: a solver counts the designs
  /// outside it as violating a constraint without evaluating them. The framework spot-checks
  /// the claim (plugins/solvers/grid/line_bound.hpp). An empty interval (lower > upper) means no
  /// value is feasible. Default: false (no bound known; every design is evaluated).
  /// Called once per line of a design grid; must not allocate or throw.
  virtual bool constraint_interval(const double* design, int component, const SampleSet& scene, double& lower,
                                   double& upper) const {
    return false;
  }
  /// Optional promise for grid solvers: true when, along design component `component` (the
  /// others fixed), the values at which evaluate_constraints returns every g <= 0 form one
  /// interval, as computed in floating point (every constraint is quasiconvex along it, e.g. a
  /// monotone function of |c + x|). A solver with a constraint_interval for the line then
  /// checks the constraints exactly at the two ends of the line's feasible run and skips them
  /// for the designs between (docs/design.md section 13.3). A false promise lets a violating
  /// design be evaluated: say true only with a proof (and a test on random lines).
  /// Default: false.
  virtual bool constraints_quasiconvex(int component) const { return false; }
  /// Optional block bound of one sample for grid solvers (docs/design.md section 13.5): bounds
  /// of the quantities at the sample `pose` over every design equal to `design` (a full design
  /// vector) except in component `component`, which runs over [lower, upper]. `needs` (Need
  /// flags, the study's) says which quantities' bounds are wanted: skip the others. Fill only
  /// what is proved, rounding included (the solver rules out whole blocks of designs on it; it
  /// spot-checks one design of each block it rules out and stops with an error on a false
  /// claim). Returns false when nothing is known (the default). Called for runs of a grid line
  /// (a few per line); must not allocate or throw.
  virtual bool sample_envelope(const double* design, int component, double lower, double upper, const double* pose,
                               Needs needs, SampleEnvelope& out) const {
    return false;
  }
  /// Optional line bound of one sample for grid solvers (docs/design.md section 13.6): an
  /// interval [lower, upper] of design component `component` outside which the sample `pose`
  /// cannot be solved (its status is not reachable), the other components as in `design` (a
  /// full design vector). It may be wider than the values where the sample solves, never
  /// narrower, rounding included: in a study where a failed sample fails the design (one with a
  /// worst-case metric), a solver counts the designs of a grid line outside it as failing there
  /// without solving them. An empty interval (lower > upper) means the sample fails for every
  /// value. The solver spot-checks the claim and stops with an error on a false one. Returns
  /// false when nothing is known (the default). Called a few times per grid line; must not
  /// allocate or throw.
  virtual bool reachable_interval(const double* design, int component, const double* pose, double& lower,
                                  double& upper) const {
    return false;
  }
  /// Optional design-lanes path (docs/design.md section 13.4): solves the one sample `pose` for
  /// up to kBlockLanes designs at once, lane i for the full design vector designs[i] (lanes at
  /// or beyond `count` repeat a valid design), filling out as build(designs[i])->solve_block
  /// would, bit for bit. Returns false when it cannot for these designs (the caller then
  /// evaluates them one by one). Same rules as solve_block. Default: false.
  virtual bool solve_designs(const double* const* designs, int count, const double* pose, Needs needs,
                             MechanismScratch& scratch, QuantityBlock& out) const {
    return false;
  }
  /// Optional: one line saying what the options made of this mechanism (e.g. a chain's moving
  /// joints from base to tip, and its task), shown in the run header, in result.json
  /// ("mechanism_summary") and by `hapsyn describe NAME --options`, so that a wrong reading of a
  /// file is seen before a study runs. Default: "" (nothing shown).
  virtual std::string summary() const { return {}; }
  /// Per-thread scratch for MechanismModel::solve (called once per worker thread).
  virtual std::unique_ptr<MechanismScratch> make_scratch() const {
    return std::make_unique<MechanismScratch>();
  }
  /// Throws hapsyn::Error when the scene's samples are not of a kind this mechanism serves
  /// (e.g. 2 coordinates for a planar mechanism). Called once, after the scene is built.
  virtual void check_scene(const SampleSet& scene) const {}
  /// Quantities this mechanism can compute (Need flags); the framework refuses a metric that
  /// needs more. Default: pose and Jacobian.
  virtual Needs provides() const { return kNeedJacobian; }
  /// True when the models' solve_block() is a real block kernel for these needs (read once per
  /// study, at load; the evaluator then takes the block path when every metric has one too).
  /// Default: false.
  virtual bool solves_blocks(Needs needs) const { return false; }
};

}  // namespace hapsyn
