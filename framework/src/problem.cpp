// Problem: the public face of the evaluator (evaluator.hpp). Every method forwards (the cheap
// accessors, inline in problem.hpp, read pointers taken here at construction); the
// evaluation paths and their per-thread data stay private to the framework.
#include <hapsyn/problem.hpp>

#include "evaluator.hpp"

namespace hapsyn {

Problem::Problem(std::string mechanism_plugin, std::shared_ptr<const Mechanism> mechanism,
                 std::shared_ptr<const SampleSet> samples, std::vector<MetricEntry> metrics,
                 std::vector<Objective> objectives, DesignSpace space)
    : impl_(std::make_unique<const Evaluator>(std::move(mechanism_plugin), std::move(mechanism), std::move(samples),
                                              std::move(metrics), std::move(objectives), std::move(space))) {
  const Evaluator& e = *impl_;
  view_.space = &e.design_space();
  view_.samples = &e.samples();
  view_.mechanism = &e.mechanism();
  view_.metrics = &e.metrics();
  view_.objectives = &e.objectives();
  view_.constraint_names = &e.constraint_names();
  view_.sample_order = &e.sample_order();
  view_.mechanism_acceleration = &e.mechanism_acceleration();
  view_.dimension = e.dimension();
  view_.worst_case = e.worst_case();
  view_.block_path = e.block_path();
  view_.needs = e.needs();
}

Problem::~Problem() = default;

std::shared_ptr<const Problem> Problem::with_objectives(std::vector<Objective> objectives) const {
  return impl_->with_objectives(std::move(objectives));
}
std::shared_ptr<const Problem> Problem::with_design_space(DesignSpace space) const {
  return impl_->with_design_space(std::move(space));
}

double Problem::block_score_bound(const double* full_design, int component, double lower, double upper,
                                  int sample) const {
  return impl_->block_score_bound(full_design, component, lower, upper, sample);
}
bool Problem::reachable_interval(const double* full_design, int component, int sample, double& lower,
                                 double& upper) const {
  return impl_->reachable_interval(full_design, component, sample, lower, upper);
}
void Problem::bind_sample(SampleQuantities& q, int sample) const { impl_->bind_sample(q, sample); }

Problem::EvalScratch::EvalScratch() = default;
Problem::EvalScratch::~EvalScratch() = default;
const Evaluation& Problem::EvalScratch::last() const { return data_->result; }

std::unique_ptr<Problem::EvalScratch> Problem::make_eval_scratch() const {
  auto scratch = std::make_unique<EvalScratch>();
  scratch->data_ = impl_->make_eval_data();
  return scratch;
}

const Evaluation& Problem::evaluate(const double* free_design, EvalScratch& eval_scratch,
                                    const EvalOptions& options) const {
  return impl_->evaluate(free_design, *eval_scratch.data_, options);
}
void Problem::evaluate_designs(const double* const* free_designs, int count, EvalScratch& eval_scratch,
                               const EvalOptions& options, std::vector<Evaluation>& outs) const {
  impl_->evaluate_designs(free_designs, count, *eval_scratch.data_, options, outs);
}
Evaluation Problem::evaluate_parallel(const double* free_design, int threads, const ParallelOptions& options) const {
  return impl_->evaluate_parallel(free_design, threads, options);
}
bool Problem::constraints(const double* free_design, double* g) const { return impl_->constraints(free_design, g); }
Eigen::VectorXd Problem::full_design(const double* free_design) const { return impl_->full_design(free_design); }
Json Problem::design_to_json(const Eigen::VectorXd& full_design) const { return impl_->design_to_json(full_design); }
double Problem::score(const std::vector<double>& objectives) const { return impl_->score(objectives); }

}  // namespace hapsyn
