#pragma once
/// \file
/// The optional speed layer of a mechanism (Mechanism::acceleration()). Nothing here is needed
/// for a correct study: every method has a default that says "not available", and the framework
/// then takes the plain path (build(), MechanismModel::solve() per sample, every design of a
/// grid evaluated). A mechanism that implements some of them derives from this class as well as
/// from Mechanism and returns `this` from acceleration():
///
///     class MyMechanism final : public hapsyn::Mechanism, public hapsyn::MechanismAcceleration {
///       const hapsyn::MechanismAcceleration* acceleration() const override { return this; }
///       bool solves_blocks(hapsyn::Needs needs) const override { ... }
///       void solve_block(const hapsyn::MechanismModel& model, ...) const override { ... }
///     };
///
/// The contracts: each hook gives what the plain path gives (to the stated tolerance), and a
/// bound is proved, rounding included (the grid solvers spot-check every claim and stop with an
/// error on a false one). Block kernels use the vector types of hapsyn/accel/lanes.hpp.
#include <hapsyn/accel/sample_block.hpp>
#include <hapsyn/accel/sample_envelope.hpp>
#include <hapsyn/mechanism.hpp>

namespace hapsyn {

/// Speed hooks of a mechanism; see the file comment. Every method is optional.
class MechanismAcceleration {
 public:
  virtual ~MechanismAcceleration() = default;

  /// Builds the model for `design` inside the per-thread `scratch` and
  /// returns it (valid until the next call with the same scratch), so that a solver visiting
  /// millions of designs allocates nothing per design. Default: nullptr (build() is used).
  virtual const MechanismModel* build_in(const double* design, MechanismScratch& scratch) const {
    return nullptr;
  }
  /// True when solve_block() is a real block kernel for these needs (read once per
  /// study, at load; the evaluator then takes the block path when every metric has one too).
  /// Default: false.
  virtual bool solves_blocks(Needs needs) const { return false; }
  /// Block path (hapsyn/accel/sample_block.hpp): classifies the `poses.count` samples of a
  /// block with `model` (built by this mechanism, so a kernel may static_cast it to its own
  /// type) and fills, for the reachable lanes, the quantities in `needs`, as model.solve() would
  /// for each (to rounding: agreement to 1e-12 relative, the same status). Called only when
  /// solves_blocks(needs) is true, with the same rules as solve() (concurrent, no
  /// allocation, lock or throw; no NaN reaches a reachable lane). Lanes at or beyond
  /// poses.count, and unreachable lanes, may hold any values. Default: model.solve() per lane.
  virtual void solve_block(const MechanismModel& model, const PoseBlock& poses, Needs needs, MechanismScratch& scratch,
                           QuantityBlock& out) const;
  /// Design-lanes path (docs/design.md section 13.4): solves the one sample `pose` for
  /// up to kBlockLanes designs at once, lane i for the full design vector designs[i] (lanes at
  /// or beyond `count` repeat a valid design), filling out as solve_block of build(designs[i])
  /// would, bit for bit. Returns false when it cannot for these designs (the caller then
  /// evaluates them one by one). Same rules as solve_block. Default: false.
  virtual bool solve_designs(const double* const* designs, int count, const double* pose, Needs needs,
                             MechanismScratch& scratch, QuantityBlock& out) const {
    return false;
  }
  /// Block bound for grid solvers: an interval [lower, upper] of design component
  /// `component` (an index into the full design vector) outside which some constraint is
  /// violated, the other components as in `design`. It may be wider than the feasible set
  /// (inside it, evaluate_constraints decides) but never narrower: a solver counts the designs
  /// outside it as violating a constraint without evaluating them. The framework spot-checks
  /// the claim (plugins/solvers/shared/bounds/line_bound.hpp). An empty interval (lower > upper) means no
  /// value is feasible. Default: false (no bound known; every design is evaluated).
  /// Called once per line of a design grid; must not allocate or throw.
  virtual bool constraint_interval(const double* design, int component, const SampleSet& scene, double& lower,
                                   double& upper) const {
    return false;
  }
  /// Promise for grid solvers: true when, along design component `component` (the
  /// others fixed), the values at which evaluate_constraints returns every g <= 0 form one
  /// interval, as computed in floating point (every constraint is quasiconvex along it, e.g. a
  /// monotone function of |c + x|). A solver with a constraint_interval for the line then
  /// checks the constraints exactly at the two ends of the line's feasible run and skips them
  /// for the designs between (docs/design.md section 13.3). A false promise lets a violating
  /// design be evaluated: say true only with a proof (and a test on random lines).
  /// Default: false.
  virtual bool constraints_quasiconvex(int component) const { return false; }
  /// Block bound of one sample for grid solvers (docs/design.md section 13.5): bounds
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
  /// Line bound of one sample for grid solvers (docs/design.md section 13.6): an
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
};

}  // namespace hapsyn
