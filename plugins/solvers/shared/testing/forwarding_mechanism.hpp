#pragma once
/// \file
/// Test support for grid and culling tests: a mechanism that forwards to another (the five-bar)
/// its model, variables, constraints and constraint interval, and nothing else (no one-run
/// promise, no envelope, no design lanes), so that a test can add or change one claim.
#include <hapsyn/accel/mechanism_acceleration.hpp>
#include <hapsyn/mechanism.hpp>

#include <memory>
#include <vector>

namespace hapsyn::test {

class ForwardingMechanism : public Mechanism, public MechanismAcceleration {
 public:
  explicit ForwardingMechanism(std::shared_ptr<const Mechanism> inner) : inner_(std::move(inner)) {}
  std::unique_ptr<const MechanismModel> build(const double* design) const override { return inner_->build(design); }
  std::vector<VariableDecl> variables() const override { return inner_->variables(); }
  std::vector<ConstraintDecl> constraints() const override { return inner_->constraints(); }
  void evaluate_constraints(const double* design, const SampleSet& scene, double* g) const override {
    inner_->evaluate_constraints(design, scene, g);
  }
  MechanismSpecs specs() const override { return inner_->specs(); }
  const MechanismAcceleration* acceleration() const override { return this; }
  bool constraint_interval(const double* design, int component, const SampleSet& scene, double& lower,
                           double& upper) const override {
    return inner_acceleration().constraint_interval(design, component, scene, lower, upper);
  }

 protected:
  /// The inner mechanism's speed layer (the five-bar has one).
  const MechanismAcceleration& inner_acceleration() const { return *inner_->acceleration(); }

 private:
  std::shared_ptr<const Mechanism> inner_;
};

/// The five-bar, forwarding everything (line bounds and their one-run promise included), with a
/// sample envelope that claims every design of every run fails: a wrong block bound, which the
/// solvers' spot check must refuse.
class AllFailEnvelope final : public ForwardingMechanism {
 public:
  using ForwardingMechanism::ForwardingMechanism;
  bool constraints_quasiconvex(int component) const override { return inner_acceleration().constraints_quasiconvex(component); }
  bool sample_envelope(const double*, int, double, double, const double*, Needs, SampleEnvelope& out) const override {
    out = SampleEnvelope{};
    out.all_fail = true;
    return true;
  }
};

/// The five-bar, forwarding everything (line bounds and their one-run promise included), with a
/// reachable interval that claims every sample fails for every r: a wrong line bound, which the
/// solvers' spot check must refuse.
class NothingReachable final : public ForwardingMechanism {
 public:
  using ForwardingMechanism::ForwardingMechanism;
  bool constraints_quasiconvex(int component) const override { return inner_acceleration().constraints_quasiconvex(component); }
  bool reachable_interval(const double*, int, const double*, double& lower, double& upper) const override {
    lower = 1.0;
    upper = -1.0;
    return true;
  }
};

}  // namespace hapsyn::test
