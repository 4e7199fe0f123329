#pragma once
/// \file
/// Mechanisms: per design, a const model that classifies task-space samples and computes the
/// requested quantities, with per-thread scratch so the per-sample loop is allocation-free.
#include <hapsyn/design_space.hpp>
#include <hapsyn/quantities.hpp>
#include <hapsyn/scene.hpp>

#include <memory>
#include <vector>

namespace hapsyn {

/// Per-thread scratch a model may use. Mechanisms that need none use this base as is.
class MechanismScratch {
 public:
  virtual ~MechanismScratch() = default;
};

/// The mechanism for one design (Pinocchio's Model): immutable once built, shared by threads.
class MechanismModel {
 public:
  virtual ~MechanismModel() = default;
  /// Classifies the sample and, when reachable, fills the quantities asked for by `needs`.
  /// \param pose   one scene sample (SampleSet::pose), in the scene frame
  /// \param needs  bit set of Need flags
  /// \param scratch per-thread scratch from Mechanism::make_scratch
  /// \param out    written; `out.status` always set. Must not allocate.
  virtual void solve(const double* pose, Needs needs, MechanismScratch& scratch,
                     SampleQuantities& out) const = 0;
};

/// Mechanism plugin. Implementations must be thread-safe for concurrent const calls.
class Mechanism {
 public:
  virtual ~Mechanism() = default;
  /// Builds the model for a full design vector (layout: DesignSpace::components()).
  virtual std::unique_ptr<const MechanismModel> build(const double* design) const = 0;
  /// Optional fast path: builds the model for `design` inside the per-thread `scratch` and
  /// returns it (valid until the next call with the same scratch), so that a solver visiting
  /// millions of designs allocates nothing per design. Default: nullptr (build() is used).
  virtual const MechanismModel* build_in(const double* design, MechanismScratch& scratch) const {
    return nullptr;
  }
  /// The design variables (defaults and hard limits).
  virtual std::vector<VariableDecl> variables() const { return {}; }
  /// Design constraints g(p) <= 0 (may depend on the scene's extent; never on a sample).
  virtual std::vector<ConstraintDecl> constraints() const { return {}; }
  /// Evaluates the constraints declared by constraints() into g (size constraints().size()).
  virtual void evaluate_constraints(const double* design, const SampleSet& scene, double* g) const {}
  /// Per-thread scratch for MechanismModel::solve.
  virtual std::unique_ptr<MechanismScratch> make_scratch() const {
    return std::make_unique<MechanismScratch>();
  }
  /// Throws hapsyn::Error when the scene's samples are not of a kind this mechanism serves.
  virtual void check_scene(const SampleSet& scene) const {}
  /// Quantities this mechanism can compute (Need flags); the framework refuses a metric that
  /// needs more. Default: pose and Jacobian.
  virtual Needs provides() const { return kNeedJacobian; }
};

}  // namespace hapsyn
