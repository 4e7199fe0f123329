#include "evaluate.hpp"

#include <hapsyn/error.hpp>

#include <sstream>

namespace hapsyn::plugins {

void EvaluateSolver::check(const Problem& problem) const {
  if (problem.dimension() != 0) {
    const auto& c = problem.design_space().components()[static_cast<std::size_t>(problem.design_space().free_indices()[0])];
    throw Error("evaluate", "design." + c.variable + " is not fixed: the evaluate solver evaluates one given design, "
                            "so every design variable needs a \"value\" (" + std::to_string(problem.dimension()) +
                            " free component(s))");
  }
}

std::string describe_sample(const Problem& problem, int sample, SampleStatus status) {
  std::ostringstream s;
  s.precision(6);
  const SampleSet& samples = problem.samples();
  s << "sample " << sample << " at (";
  for (int c = 0; c < samples.dimension(); ++c) {
    const std::size_t uc = static_cast<std::size_t>(c);
    s << (c ? ", " : "") << (uc < samples.coordinates.size() ? samples.coordinates[uc] : "c" + std::to_string(c))
      << " = " << samples.poses(sample, c);
  }
  s << ")";
  if (!samples.unit.empty()) s << " " << samples.unit;
  s << " is " << to_string(status);
  return s.str();
}

std::string describe_failure(const Problem& problem, const Evaluation& e) {
  switch (e.status) {
    case EvalStatus::kConstraintViolated:
      return "design constraint '" + problem.constraint_names()[static_cast<std::size_t>(e.failed_constraint)] + "' is violated";
    case EvalStatus::kSampleFailed:
      return describe_sample(problem, e.failed_sample, e.failed_status);
    case EvalStatus::kPruned:
      return "pruned";
    case EvalStatus::kFeasible:
      break;
  }
  return "feasible";
}

SolverResult EvaluateSolver::solve(const Problem& problem, const SolverContext& context) const {
  SolverResult result;
  const Evaluation e = problem.evaluate_parallel(nullptr, context.threads);
  result.design_evaluations = 1;
  result.sample_evaluations = e.samples_evaluated;
  const Eigen::VectorXd full = problem.full_design(nullptr);
  Json per_metric = Json::object();
  if (e.status == EvalStatus::kFeasible) {
    for (std::size_t m = 0; m < problem.metrics().size(); ++m) {
      const auto locals = problem.metrics()[m].metric->locals();
      Json j = Json::object();
      for (std::size_t k = 0; k < locals.size(); ++k) {
        Json entry = {{"value", e.reduced[m][k]}};
        if (e.critical_samples[m][k] >= 0) {
          const int s = e.critical_samples[m][k];
          entry["sample"] = s;
          entry["pose"] = std::vector<double>(problem.samples().pose(s), problem.samples().pose(s) + problem.samples().dimension());
        }
        j[locals[k].name] = entry;
      }
      per_metric[problem.metrics()[m].plugin] = j;
    }
    result.best = SolutionPoint{full, e.objectives, e.score};
    result.status = SolverStatus::kConverged;
    result.message = "evaluated the fixed design over " + std::to_string(problem.samples().size()) + " samples";
  } else {
    result.status = SolverStatus::kInfeasible;
    result.message = "the fixed design is infeasible: " + describe_failure(problem, e);
  }
  result.statistics = {{"design", problem.design_to_json(full)}, {"reductions", per_metric}};
  return result;
}

}  // namespace hapsyn::plugins
