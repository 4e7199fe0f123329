// Problem: the public face of the evaluator (evaluator.hpp). Every method forwards; the
// evaluation paths and their per-thread data stay private to the framework.
#include <hapsyn/problem.hpp>

#include "evaluator.hpp"

namespace hapsyn {

Problem::Problem(std::string mechanism_plugin, std::shared_ptr<const Mechanism> mechanism,
                 std::shared_ptr<const SampleSet> samples, std::vector<MetricEntry> metrics,
                 std::vector<Objective> objectives, DesignSpace space)
    : impl_(std::make_unique<const Evaluator>(std::move(mechanism_plugin), std::move(mechanism), std::move(samples),
                                              std::move(metrics), std::move(objectives), std::move(space))) {}

Problem::~Problem() = default;

std::shared_ptr<const Problem> Problem::with_objectives(std::vector<Objective> objectives) const {
  return impl_->with_objectives(std::move(objectives));
}
std::shared_ptr<const Problem> Problem::with_design_space(DesignSpace space) const {
  return impl_->with_design_space(std::move(space));
}

const DesignSpace& Problem::design_space() const { return impl_->design_space(); }
const SampleSet& Problem::samples() const { return impl_->samples(); }
const Mechanism& Problem::mechanism() const { return impl_->mechanism(); }
const std::vector<MetricEntry>& Problem::metrics() const { return impl_->metrics(); }
const std::vector<Objective>& Problem::objectives() const { return impl_->objectives(); }
std::size_t Problem::dimension() const { return impl_->dimension(); }
std::size_t Problem::constraint_count() const { return impl_->constraint_count(); }
const std::vector<std::string>& Problem::constraint_names() const { return impl_->constraint_names(); }
bool Problem::worst_case() const { return impl_->worst_case(); }
double Problem::block_score_bound(const double* full_design, int component, double lower, double upper,
                                  int sample) const {
  return impl_->block_score_bound(full_design, component, lower, upper, sample);
}
bool Problem::reachable_interval(const double* full_design, int component, int sample, double& lower,
                                 double& upper) const {
  return impl_->reachable_interval(full_design, component, sample, lower, upper);
}
const MechanismAcceleration& Problem::mechanism_acceleration() const { return impl_->mechanism_acceleration(); }
bool Problem::block_path() const { return impl_->block_path(); }
Needs Problem::needs() const { return impl_->needs(); }
const std::vector<int>& Problem::sample_order() const { return impl_->sample_order(); }
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
