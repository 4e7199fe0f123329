// The evaluator: construction (checks, sample order, the block path's copies), designs, the cold error paths.
#include <hapsyn/accel/mechanism_acceleration.hpp>
#include <hapsyn/accel/lanes.hpp>
#include <hapsyn/accel/metric_acceleration.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/parallel.hpp>
#include <hapsyn/problem.hpp>

#include "evaluator.hpp"
#include "evaluator_steps.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <sstream>

namespace hapsyn {

using namespace evaluator_detail;


namespace {
// Stand-ins for a plugin without a speed layer: their defaults say "not available" (no block
// kernel, no bound, no batch), which is what the evaluator did before the layer existed. The
// evaluator holds one of these instead of a null pointer, so its hot loops need no null checks.
const MechanismAcceleration kNoMechanismAcceleration;
const MetricAcceleration kNoMetricAcceleration;

const MechanismAcceleration* accelerated(const MechanismAcceleration* acceleration) {
  return acceleration != nullptr ? acceleration : &kNoMechanismAcceleration;
}
const MetricAcceleration* accelerated(const MetricAcceleration* acceleration) {
  return acceleration != nullptr ? acceleration : &kNoMetricAcceleration;
}


// The factor w_i N / W of each sample's sum-reduced local values (see SampleSet::weights); empty
// when the weights are absent or all equal, so that equal weights are the unweighted study bit for
// bit (N copies of w need not sum to exactly N w). W is summed in sample order: deterministic.
std::vector<double> weighted_sum_scale(const std::vector<double>& weights) {
  if (std::all_of(weights.begin(), weights.end(), [&](double w) { return w == weights.front(); })) return {};
  const double total = std::accumulate(weights.begin(), weights.end(), 0.0);
  const double n = static_cast<double>(weights.size());
  std::vector<double> scale(weights.size());
  for (std::size_t i = 0; i < weights.size(); ++i) scale[i] = weights[i] * n / total;
  return scale;
}


}  // namespace

namespace evaluator_detail {
// The message of an out-of-bounds or non-finite design component. Out of line and cold: inlined,
// its stream set-up made check_design, which runs for every design, spill and save registers.
void throw_bad_component(const DesignComponent& c, double v) {
  std::ostringstream message;
  message.precision(12);
  message << "design component " << c.name << " = " << v << " from the solver: ";
  if (!std::isfinite(v)) {
    message << "must be finite";
  } else {
    message << "must lie within the bounds [" << c.lower << ", " << c.upper << "]";
  }
  throw Error("problem", message.str());
}

// The first quantity the mechanism filled (those the metrics need) that is not finite, or null.
// Only called once a local value came out non-finite: the per-sample loop pays nothing for it.
const char* non_finite_quantity(const SampleQuantities& q, Needs needs) {
  if (q.status != SampleStatus::kReachable) return nullptr;  // the rest is not meaningful then
  if (!q.q.allFinite()) return "joint angles q";
  if ((needs & kNeedJacobian) && !q.jacobian.allFinite()) return "jacobian";
  if ((needs & kNeedInertia) && !q.inertia.allFinite()) return "inertia";
  if ((needs & kNeedEffectiveMass) && !q.effective_mass.allFinite()) return "effective_mass";
  if ((needs & kNeedGravity) && !q.gravity.allFinite()) return "gravity";
  if ((needs & kNeedActuatorLimits) && !(q.max_velocity.allFinite() && q.max_torque.allFinite()))
    return "actuator limits";
  if ((needs & kNeedJointVelocity) && !q.joint_velocity.allFinite()) return "joint_velocity";
  if ((needs & kNeedJointAcceleration) && !q.joint_acceleration.allFinite()) return "joint_acceleration";
  if ((needs & kNeedVelocityTorque) && !q.velocity_torque.allFinite()) return "velocity_torque";
  return nullptr;
}
}  // namespace evaluator_detail


Evaluator::Evaluator(std::string mechanism_plugin, std::shared_ptr<const Mechanism> mechanism,
                 std::shared_ptr<const SampleSet> samples, std::vector<MetricEntry> metrics,
                 std::vector<Objective> objectives, DesignSpace space)
    : mechanism_plugin_(std::move(mechanism_plugin)),
      mechanism_(std::move(mechanism)),
      samples_(std::move(samples)),
      metrics_(std::move(metrics)),
      objectives_(std::move(objectives)),
      space_(std::move(space)) {
  assert(mechanism_ && samples_);
  if (samples_->size() == 0) throw Error("problem", "scene: the scene has no samples");
  if (!samples_->poses.allFinite()) throw Error("problem", "scene: the scene's samples contain NaN or infinity");
  check_weights(*samples_, "problem");
  sample_scale_ = weighted_sum_scale(samples_->weights);
  mechanism_->check_scene(*samples_);
  if (objectives_.empty()) throw Error("problem", "objectives: at least one objective is required");
  for (const ConstraintDecl& c : mechanism_->constraints()) constraint_names_.push_back(c.name);

  const Needs provided = mechanism_->specs().provides;
  mechanism_accel_ = accelerated(mechanism_->acceleration());
  for (std::size_t m = 0; m < metrics_.size(); ++m) {
    const Metric& metric = *metrics_[m].metric;
    const MetricSpecs specs = metric.specs();
    metric_accel_.push_back(accelerated(metric.acceleration()));
    const Needs missing = specs.needs & ~provided;
    if (missing != 0) {
      throw Error("problem", "objectives: metric '" + metrics_[m].plugin +
                                 "' needs quantities the mechanism '" + mechanism_plugin_ +
                                 "' does not provide: " + need_names(missing));
    }
    needs_ |= specs.needs;
    batch_ = std::max(batch_, metric_accel_.back()->batch_size());
    const bool wc = metric.aggregation() == Aggregation::kWorstCase;
    worst_case_ = worst_case_ && wc;
    any_worst_case_ = any_worst_case_ || wc;
    local_offset_.push_back(static_cast<int>(local_reduction_.size()));
    const std::vector<LocalValue> locals = metric.locals();
    if (locals.empty()) throw Error("problem", "metric '" + metrics_[m].plugin + "' declares no local values");
    for (const LocalValue& l : locals) local_reduction_.push_back(l.reduction);
    std::vector<const AttributeMatrix*> attributes;
    for (const std::string& name : specs.scene_attributes) {
      const auto it = samples_->attributes.find(name);
      attributes.push_back(it == samples_->attributes.end() ? nullptr : &it->second);
    }
    metric_attributes_.push_back(std::move(attributes));
  }
  local_offset_.push_back(static_cast<int>(local_reduction_.size()));
  for (const Reduction r : local_reduction_) {
    identity_accumulator_.push_back(r == Reduction::kMin   ? std::numeric_limits<double>::infinity()
                                    : r == Reduction::kMax ? -std::numeric_limits<double>::infinity()
                                                           : 0.0);
  }
  // Accelerations and the velocity torque are computed at the joint rates: they imply them.
  if (needs_ & (kNeedJointAcceleration | kNeedVelocityTorque)) needs_ |= kNeedJointVelocity;
  resolve_demanded_motion();
  for (const Objective& o : objectives_) {
    if (o.metric < 0 || o.metric >= static_cast<int>(metrics_.size())) {
      throw Error("problem", "objective '" + o.name + "' refers to no metric");
    }
    if (!std::isfinite(o.weight)) throw Error("problem", "objective '" + o.name + "': weight must be finite");
  }

  all_maximized_ = std::all_of(objectives_.begin(), objectives_.end(),
                               [](const Objective& o) { return o.sense == Sense::kMaximize; });
  prunable_ = worst_case_ && std::all_of(objectives_.begin(), objectives_.end(), [](const Objective& o) {
                return o.sense == Sense::kMaximize && o.weight >= 0.0;
              });
  for (int index : space_.free_indices()) {
    const DesignComponent& c = space_.components()[static_cast<std::size_t>(index)];
    const double tol = 1e-9 * std::max(1.0, c.upper - c.lower);  // rounding of lower + i*step
    free_lower_.push_back(c.lower - tol);
    free_upper_.push_back(c.upper + tol);
  }

  order_.resize(static_cast<std::size_t>(samples_->size()));
  std::iota(order_.begin(), order_.end(), 0);
  // Without a worst-case metric nothing is decided early, and the scene's own order keeps the
  // per-sample data (poses, attributes) streaming through the cache: 1.4x faster on the 35k-pose
  // human-arm scene than the scattered order below.
  if (any_worst_case_) order_extremes_first();
  choose_block_path();
}

void Evaluator::order_extremes_first() {
  // Extreme samples first: far from the centroid (corners of a square) is where reach fails
  // and where worst cases usually sit, so infeasible designs and pruning are decided early.
  const Eigen::RowVectorXd centroid = samples_->poses.colwise().mean();
  std::vector<double> distance(static_cast<std::size_t>(samples_->size()));
  for (int i = 0; i < samples_->size(); ++i) {
    distance[static_cast<std::size_t>(i)] = (samples_->poses.row(i) - centroid).squaredNorm();
  }
  std::stable_sort(order_.begin(), order_.end(), [&](int a, int b) {
    return distance[static_cast<std::size_t>(a)] > distance[static_cast<std::size_t>(b)];
  });
}

void Evaluator::choose_block_path() {
  // Worst-case studies reduce per block with pruning (fold_block); averaging ones add every lane
  // (fold_block_sums). A study mixing both kinds keeps the per-sample loop.
  block_path_ = (worst_case_ || !any_worst_case_) && batch_ == 0 && !twist_ && !twist_rate_ &&
                samples_->dimension() <= kBlockMaxCoordinates && mechanism_accel_->solves_blocks(needs_);
  for (std::size_t m = 0; m < metrics_.size() && block_path_; ++m) {
    block_path_ = metric_accel_[m]->has_local_block();
  }
  if (!block_path_) return;
  // The poses in sample order, structure of arrays, padded to whole blocks with the last
  // sample: a block of the full order is then a pointer per coordinate, no copy per design.
  const std::size_t n = order_.size();
  block_stride_ = (n + kBlockLanes - 1) / kBlockLanes * kBlockLanes;
  const int dimension = samples_->dimension();
  block_poses_.assign(static_cast<std::size_t>(dimension) * block_stride_, 0.0);
  for (std::size_t k = 0; k < block_stride_; ++k) {
    const double* pose = samples_->pose(order_[std::min(k, n - 1)]);
    for (int c = 0; c < dimension; ++c) block_poses_[static_cast<std::size_t>(c) * block_stride_ + k] = pose[c];
  }
  order_position_.assign(n, 0);
  for (std::size_t k = 0; k < n; ++k) order_position_[static_cast<std::size_t>(order_[k])] = static_cast<int>(k);
  copy_attribute_blocks();
}

// The position in order_ where `subset` starts when it is a run of order_ that starts on a
// block and ends on one or at the end (evaluate_parallel's chunks of the full order): its blocks
// are then blocks of block_poses_ and of the attribute copies. SIZE_MAX otherwise.
std::size_t Evaluator::order_run(const std::vector<int>& subset) const {
  const std::size_t n = order_.size();
  if (subset.empty() || subset.size() > n) return SIZE_MAX;
  const int first_sample = subset.front();
  if (first_sample < 0 || static_cast<std::size_t>(first_sample) >= n) return SIZE_MAX;
  const std::size_t start = static_cast<std::size_t>(order_position_[static_cast<std::size_t>(first_sample)]);
  const std::size_t end = start + subset.size();
  if (start % kBlockLanes != 0 || end > n || (end % kBlockLanes != 0 && end != n)) return SIZE_MAX;
  return std::equal(subset.begin(), subset.end(), order_.begin() + static_cast<std::ptrdiff_t>(start)) ? start : SIZE_MAX;
}

// The metrics' scene attributes in the same order and padding as block_poses_, structure of
// arrays per block, so that a metric loads an entry of all lanes as one vector: the gather of
// a 36-entry attribute lane by lane was a fifth of the haptic 6R coverage objective.
void Evaluator::copy_attribute_blocks() {
  constexpr std::size_t L = kBlockLanes, kAlign = 64 / sizeof(double);
  const std::size_t n = order_.size();
  std::vector<const AttributeMatrix*> copied;
  for (const auto& attributes : metric_attributes_) {
    std::vector<const double*> starts;
    for (const AttributeMatrix* a : attributes) {
      if (!a || n == 0) {
        starts.push_back(nullptr);
        continue;
      }
      const auto it = std::find(copied.begin(), copied.end(), a);
      if (it != copied.end()) {
        starts.push_back(attribute_block_start(static_cast<std::size_t>(it - copied.begin())));
        continue;
      }
      const std::size_t cols = static_cast<std::size_t>(a->cols());
      std::vector<double>& copy = attribute_blocks_.emplace_back(block_stride_ * cols + kAlign, 0.0);
      copied.push_back(a);
      double* start = copy.data() + (attribute_block_start(attribute_blocks_.size() - 1) - copy.data());
      for (std::size_t k = 0; k < block_stride_; ++k) {
        const double* row = a->row(order_[std::min(k, n - 1)]).data();
        double* block = start + (k / L) * cols * L + k % L;
        for (std::size_t e = 0; e < cols; ++e) block[e * L] = row[e];
      }
      starts.push_back(start);
    }
    metric_attribute_blocks_.push_back(std::move(starts));
  }
}

// Copy i of attribute_blocks_ from its first 64-byte boundary.
const double* Evaluator::attribute_block_start(std::size_t i) const {
  const double* data = attribute_blocks_[i].data();
  const std::size_t misalignment = reinterpret_cast<std::uintptr_t>(data) % 64 / sizeof(double);
  return data + (misalignment == 0 ? 0 : 64 / sizeof(double) - misalignment);
}

// The demanded motion (twist, twist rate) is the scene's business; the metrics that need joint
// rates or accelerations cannot work without it, so a scene lacking it is refused at load
// rather than giving zero rates.
void Evaluator::resolve_demanded_motion() {
  const auto find = [&](const char* name) -> const AttributeMatrix* {
    const auto it = samples_->attributes.find(name);
    if (it == samples_->attributes.end()) return nullptr;
    if (it->second.cols() != 6 || it->second.rows() != samples_->size() || !it->second.allFinite()) {
      throw Error("problem", std::string("scene: attribute '") + name + "' must have 6 finite columns (omega, v) " +
                                 "and one row per sample; it has " + std::to_string(it->second.cols()) + " columns and " +
                                 std::to_string(it->second.rows()) + " rows");
    }
    return &it->second;
  };
  twist_ = find(kTwistAttribute);
  twist_rate_ = find(kTwistRateAttribute);
  const auto require = [&](Needs flag, const AttributeMatrix* attribute, const char* name) {
    if (!(needs_ & flag) || attribute) return;
    std::string metrics;
    for (const MetricEntry& m : metrics_) {
      if (m.metric->specs().needs & flag) metrics += (metrics.empty() ? "'" : ", '") + m.plugin + "'";
    }
    throw Error("problem", "objectives: metric " + metrics + " needs the demanded motion of each sample (" +
                               need_names(flag) + "), but the scene has no '" + name +
                               "' attribute: use a scene of recorded motion such as 'motion'");
  };
  require(kNeedJointVelocity | kNeedVelocityTorque, twist_, kTwistAttribute);
  require(kNeedJointAcceleration, twist_rate_, kTwistRateAttribute);
}

std::shared_ptr<const Problem> Evaluator::with_objectives(std::vector<Objective> objectives) const {
  return std::make_shared<const Problem>(mechanism_plugin_, mechanism_, samples_, metrics_, std::move(objectives), space_);
}

std::shared_ptr<const Problem> Evaluator::with_design_space(DesignSpace space) const {
  bool same = space.size() == space_.size();
  for (std::size_t i = 0; same && i < space.size(); ++i) same = space.components()[i].name == space_.components()[i].name;
  if (!same) throw Error("problem", "with_design_space: the design space must have the same components as the study's");
  return std::make_shared<const Problem>(mechanism_plugin_, mechanism_, samples_, metrics_, objectives_, std::move(space));
}

std::unique_ptr<EvalData> Evaluator::make_eval_data() const {
  auto ws = std::make_unique<EvalData>();
  ws->scratch = mechanism_->make_scratch();
  ws->full.resize(static_cast<Eigen::Index>(space_.size()));
  ws->locals.resize(local_reduction_.size());
  ws->accumulator.resize(local_reduction_.size());
  ws->argument.resize(local_reduction_.size());
  ws->g.resize(constraint_names_.size());
  for (std::size_t m = 0; m < metrics_.size(); ++m) {
    ws->nested_locals.emplace_back(static_cast<std::size_t>(local_offset_[m + 1] - local_offset_[m]));
  }
  if (batch_ > 0) {
    ws->batch_quantities.resize(static_cast<std::size_t>(batch_));
    for (const SampleQuantities& q : ws->batch_quantities) ws->batch_pointers.push_back(&q);
    ws->batch_locals.resize(static_cast<std::size_t>(batch_) * local_reduction_.size());
  }
  if (block_path_) {
    ws->block = std::make_unique<QuantityBlock>();
    ws->block_locals.resize(local_reduction_.size() * kBlockLanes);
    ws->gathered.resize(static_cast<std::size_t>(kBlockMaxCoordinates) * kBlockLanes);
    std::size_t attributes = 0;
    for (const auto& a : metric_attributes_) attributes = std::max(attributes, a.size());
    ws->attribute_lane_pointers.resize(attributes);
    ws->saved_accumulator.resize(local_reduction_.size());
    ws->saved_argument.resize(local_reduction_.size());
    ws->lane_full.resize(static_cast<std::size_t>(kBlockLanes) * space_.size());
    ws->lane_accumulator.resize(static_cast<std::size_t>(kBlockLanes) * local_reduction_.size());
    ws->lane_argument.resize(static_cast<std::size_t>(kBlockLanes) * local_reduction_.size());
  }
  ws->result.objectives.resize(objectives_.size());
  ws->objective_bound.resize(objectives_.size());
  ws->result.critical_samples.resize(metrics_.size());
  ws->result.reduced.resize(metrics_.size());
  return ws;
}

bool Evaluator::constraints(const double* free_design, double* g) const {
  check_design(free_design);
  const Eigen::VectorXd full = full_design(free_design);
  mechanism_->evaluate_constraints(full.data(), *samples_, g);
  bool ok = true;
  for (std::size_t i = 0; i < constraint_names_.size(); ++i) {
    if (std::isnan(g[i])) {
      throw Error("problem", "mechanism '" + mechanism_plugin_ + "' returned constraint '" + constraint_names_[i] +
                                 "' = nan for design " + format_design(*this, full));
    }
    ok = ok && g[i] <= 0.0;
  }
  return ok;
}

Eigen::VectorXd Evaluator::full_design(const double* free_design) const {
  Eigen::VectorXd full(static_cast<Eigen::Index>(space_.size()));
  space_.expand(free_design, full.data());
  return full;
}

Json Evaluator::design_to_json(const Eigen::VectorXd& full) const {
  Json out = Json::object();
  for (std::size_t i = 0; i < space_.size(); ++i) {
    const DesignComponent& c = space_.components()[i];
    const double v = full[static_cast<Eigen::Index>(i)];
    const Json value = c.integer ? Json(static_cast<long long>(std::llround(v))) : Json(v);
    if (c.name == c.variable) {
      out[c.variable] = value;
    } else {
      out[c.variable].push_back(value);
    }
  }
  return out;
}

double Evaluator::score(const std::vector<double>& objectives) const {
  double s = 0.0;
  for (std::size_t i = 0; i < objectives_.size(); ++i) {
    const double sign = objectives_[i].sense == Sense::kMaximize ? 1.0 : -1.0;
    s += objectives_[i].weight * sign * objectives[i];
  }
  return s;
}

// A non-finite local value: the mechanism's fault when its own quantities were not finite (a
// mechanism option such as a bar width of 1e300 overflowing), else the metric's.
void Evaluator::refuse_non_finite_local(std::size_t m, int local, int sample, const EvalData& ws,
                                      const SampleQuantities& q) const {
  std::ostringstream where;
  if (const char* quantity = non_finite_quantity(q, needs_)) {
    where << "mechanism '" << mechanism_plugin_ << "' returned a non-finite " << quantity << " at sample " << sample
          << " of design " << format_design(*this, ws.full) << " (check the mechanism's options and design bounds)";
  } else {
    where << "metric '" << metrics_[m].plugin << "' returned " << ws.locals[static_cast<std::size_t>(local_offset_[m] + local)]
          << " for local value " << local << " at sample " << sample << " (" << to_string(q.status) << ") of design "
          << format_design(*this, ws.full);
  }
  throw Error("problem", where.str());
}

bool Evaluator::reachable_interval(const double* full_design, int component, int sample, double& lower,
                                 double& upper) const {
  return any_worst_case_ &&
         mechanism_accel_->reachable_interval(full_design, component, samples_->pose(sample), lower, upper);
}

double Evaluator::block_score_bound(const double* full_design, int component, double lower, double upper,
                                  int sample) const {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (!prunable_) return kInf;  // the sum of metric bounds bounds the score only for maximized, weight >= 0
  SampleEnvelope envelope;
  if (!mechanism_accel_->sample_envelope(full_design, component, lower, upper, samples_->pose(sample), needs_, envelope)) return kInf;
  if (envelope.all_fail) return -kInf;
  // Added as score_bound adds: each term is an upper bound, and rounded addition is monotone.
  double bound = 0.0;
  for (const Objective& objective : objectives_) {
    const double value = metric_accel_[static_cast<std::size_t>(objective.metric)]->envelope_bound(envelope);
    if (!(value < kInf)) return kInf;
    bound += objective.weight * value;
  }
  return bound;
}

void Evaluator::combine_objectives(const EvalData& ws, Evaluation& out) const {
  // No-ops for the scratch's own evaluation; a design lane's may come from the caller unsized.
  out.objectives.resize(objectives_.size());
  out.reduced.resize(metrics_.size());
  out.critical_samples.resize(metrics_.size());
  for (std::size_t m = 0; m < metrics_.size(); ++m) {
    const int begin = local_offset_[m];
    const int end = local_offset_[m + 1];
    out.reduced[m].assign(ws.accumulator.begin() + begin, ws.accumulator.begin() + end);
    out.critical_samples[m].assign(ws.argument.begin() + begin, ws.argument.begin() + end);
  }
  for (std::size_t o = 0; o < objectives_.size(); ++o) {
    const std::size_t m = static_cast<std::size_t>(objectives_[o].metric);
    const double value = metrics_[m].metric->combine(out.reduced[m].data(), static_cast<int>(out.samples_evaluated));
    if (!std::isfinite(value)) {
      std::ostringstream where;
      where << "metric '" << metrics_[m].plugin << "' combined its local values into " << value << " for design "
            << format_design(*this, ws.full);
      throw Error("problem", where.str());
    }
    out.objectives[o] = value;
  }
  out.score = score(out.objectives);
}

// A non-finite local value on the block path: the sample is solved again on the per-sample path
// (an error path, so its cost does not matter) and reported exactly as the per-sample loop does.
void Evaluator::refuse_non_finite_block_local(const MechanismModel& model, EvalData& ws, int sample) const {
  bind_sample(ws.quantities, sample);
  model.solve(samples_->pose(sample), needs_, *ws.scratch, ws.quantities);
  accumulate_locals(sample, ws, false);
  throw Error("problem", "metric block path: sample " + std::to_string(sample) +
                             " gave a non-finite local value in a block but a finite one alone (docs/design.md section 13)");
}

}  // namespace hapsyn
