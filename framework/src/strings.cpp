#include <hapsyn/metric.hpp>
#include <hapsyn/problem.hpp>
#include <hapsyn/quantities.hpp>
#include <hapsyn/solver.hpp>

namespace hapsyn {

const char* to_string(SampleStatus status) {
  switch (status) {
    case SampleStatus::kReachable: return "reachable";
    case SampleStatus::kUnreachable: return "unreachable";
    case SampleStatus::kSingular: return "singular";
    case SampleStatus::kInvalid: return "invalid";
  }
  return "unknown";
}

std::string need_names(Needs needs) {
  static const char* const kNames[] = {"jacobian", "inertia", "effective_mass", "gravity", "actuator_limits",
                                       "joint_velocity", "joint_acceleration", "velocity_torque"};
  std::string out;
  for (unsigned bit = 0; bit < 32; ++bit) {
    if (!(needs & (1u << bit))) continue;
    if (!out.empty()) out += ", ";
    out += bit < sizeof(kNames) / sizeof(kNames[0]) ? std::string(kNames[bit]) : "flag " + std::to_string(1u << bit);
  }
  return out.empty() ? "pose" : out;
}

const char* to_string(EvalStatus status) {
  switch (status) {
    case EvalStatus::kFeasible: return "feasible";
    case EvalStatus::kConstraintViolated: return "constraint_violated";
    case EvalStatus::kSampleFailed: return "sample_failed";
    case EvalStatus::kPruned: return "pruned";
  }
  return "unknown";
}

const char* to_string(SolverStatus status) {
  switch (status) {
    case SolverStatus::kConverged: return "converged";
    case SolverStatus::kBudgetExhausted: return "budget_exhausted";
    case SolverStatus::kInfeasible: return "infeasible";
    case SolverStatus::kStopped: return "stopped";
    case SolverStatus::kFailed: return "failed";
  }
  return "unknown";
}

Aggregation Metric::aggregation() const {
  for (const LocalValue& l : locals()) {
    if (l.reduction == Reduction::kSum) return Aggregation::kAveraging;
  }
  return Aggregation::kWorstCase;
}

}  // namespace hapsyn
