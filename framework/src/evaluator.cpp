#include <hapsyn/accel/mechanism_acceleration.hpp>
#include <hapsyn/accel/metric_acceleration.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/parallel.hpp>
#include <hapsyn/problem.hpp>

#include "evaluator.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <sstream>

namespace hapsyn {


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

std::string format_design(const Evaluator& problem, const Eigen::VectorXd& full) {
  return problem.design_to_json(full).dump();
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

// An evaluation's verdict before its design is looked at: feasible until shown otherwise.
void reset_evaluation(Evaluation& out) {
  out.status = EvalStatus::kFeasible;
  out.failed_constraint = -1;
  out.failed_sample = -1;
  out.failed_status = SampleStatus::kReachable;
  out.samples_evaluated = 0;
  out.score = -std::numeric_limits<double>::infinity();
}

bool better(Reduction r, double value, int index, double current, int current_index) {
  switch (r) {
    case Reduction::kMin: return value < current || (value == current && index < current_index);
    case Reduction::kMax: return value > current || (value == current && index < current_index);
    case Reduction::kSum: return false;
  }
  return false;
}
}  // namespace

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

namespace {
// The message of an out-of-bounds or non-finite design component. Out of line and cold: inlined,
// its stream set-up made check_design, which runs for every design, spill and save registers.
[[noreturn, gnu::cold, gnu::noinline]] void throw_bad_component(const DesignComponent& c, double v) {
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
}  // namespace

void Evaluator::check_design(const double* free_design) const {
  for (std::size_t k = 0; k < free_lower_.size(); ++k) {
    const double v = free_design[k];
    if (v >= free_lower_[k] && v <= free_upper_[k]) continue;  // false for NaN too
    throw_bad_component(space_.components()[static_cast<std::size_t>(space_.free_indices()[k])], v);
  }
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

bool Evaluator::front_dominates(const std::vector<double>& front, const double* accumulator, double* bound) const {
  // Upper bounds of the objectives from the reductions so far (samples seen: a count is only
  // needed by sum reductions, which worst-case metrics do not have).
  const std::size_t m = objectives_.size();
  for (std::size_t o = 0; o < m; ++o) {
    const std::size_t metric = static_cast<std::size_t>(objectives_[o].metric);
    bound[o] = metrics_[metric].metric->combine(accumulator + local_offset_[metric], 1);
  }
  const std::size_t points = front.size() / m;
  if (m == 2) {
    // Sorted by the first objective, descending (second ascending): the points with q0 >= b0 are
    // a prefix, and the last of them has the largest q1.
    std::size_t lo = 0, hi = points;  // first index with q0 < b0
    while (lo < hi) {
      const std::size_t mid = (lo + hi) / 2;
      if (front[2 * mid] >= bound[0]) lo = mid + 1; else hi = mid;
    }
    if (lo == 0) return false;
    const double q0 = front[2 * (lo - 1)], q1 = front[2 * (lo - 1) + 1];
    return q1 > bound[1] || (q1 == bound[1] && q0 > bound[0]);
  }
  for (std::size_t p = 0; p < points; ++p) {
    const double* q = front.data() + p * m;
    bool at_least = true, better = false;
    for (std::size_t o = 0; o < m && at_least; ++o) {
      at_least = q[o] >= bound[o];
      better = better || q[o] > bound[o];
    }
    if (at_least && better) return true;
  }
  return false;
}

// evaluate() in named steps. Each returns early the way evaluate() does; the per-sample steps are
// in this file so that the compiler can inline them into the sample loop.

bool Evaluator::constraints_hold(const double* full, EvalData& ws, Evaluation& out) const {
  if (constraint_names_.empty()) return true;
  mechanism_->evaluate_constraints(full, *samples_, ws.g.data());
  for (std::size_t i = 0; i < constraint_names_.size(); ++i) {
    if (std::isnan(ws.g[i])) {
      throw Error("problem", "mechanism '" + mechanism_plugin_ + "' returned constraint '" + constraint_names_[i] +
                                 "' = nan for design " +
                                 format_design(*this, Eigen::Map<const Eigen::VectorXd>(full, static_cast<Eigen::Index>(space_.size()))));
    }
    if (ws.g[i] > 0.0) {
      out.status = EvalStatus::kConstraintViolated;
      out.failed_constraint = static_cast<int>(i);
      return false;
    }
  }
  return true;
}

void Evaluator::accumulate_locals(int sample, EvalData& ws, bool keep_locals) const {
  for (std::size_t m = 0; m < metrics_.size(); ++m) {
    ws.quantities.attributes = metric_attributes_[m].data();
    ws.quantities.attribute_count = static_cast<int>(metric_attributes_[m].size());
    metrics_[m].metric->local(ws.quantities, ws.locals.data() + local_offset_[m]);
  }
  fold_locals(sample, ws, keep_locals, ws.quantities);
}

// The first quantity the mechanism filled (those the metrics need) that is not finite, or null.
// Only called once a local value came out non-finite: the per-sample loop pays nothing for it.
static const char* non_finite_quantity(const SampleQuantities& q, Needs needs) {
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

void Evaluator::fold_locals(int sample, EvalData& ws, bool keep_locals, const SampleQuantities& q) const {
  // The sample's weight factor for sum reductions (1 when unweighted: v * 1.0 is v exactly).
  const double scale = sample_scale_.empty() ? 1.0 : sample_scale_[static_cast<std::size_t>(sample)];
  for (std::size_t m = 0; m < metrics_.size(); ++m) {
    const int begin = local_offset_[m];
    const int end = local_offset_[m + 1];
    for (int i = begin; i < end; ++i) {
      const double v = ws.locals[static_cast<std::size_t>(i)];
      if (!std::isfinite(v)) refuse_non_finite_local(m, i - begin, sample, ws, q);
      const std::size_t ui = static_cast<std::size_t>(i);
      if (local_reduction_[ui] == Reduction::kSum) {
        ws.accumulator[ui] += v * scale;
      } else if (better(local_reduction_[ui], v, sample, ws.accumulator[ui], ws.argument[ui])) {
        ws.accumulator[ui] = v;
        ws.argument[ui] = sample;
      }
    }
    if (keep_locals) std::copy(ws.locals.begin() + begin, ws.locals.begin() + end, ws.nested_locals[m].begin());
  }
}

double Evaluator::score_bound(const double* accumulator, long long samples) const {
  // The metrics over the samples seen so far bound their final values from above.
  double bound = 0.0;
  for (std::size_t o = 0; o < objectives_.size(); ++o) {
    const std::size_t m = static_cast<std::size_t>(objectives_[o].metric);
    bound += objectives_[o].weight *
             metrics_[m].metric->combine(accumulator + local_offset_[m], static_cast<int>(samples));
  }
  return bound;
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

void Evaluator::mark_pruned(const int* argument, Evaluation& out) const {
  // The samples attaining the reductions so far are what made the bound fall: culling collects
  // them as critical samples.
  out.critical_samples.resize(metrics_.size());  // a no-op but for a caller's unsized evaluation
  for (std::size_t m = 0; m < metrics_.size(); ++m) {
    std::vector<int>& critical = out.critical_samples[m];
    const std::size_t n = static_cast<std::size_t>(local_offset_[m + 1] - local_offset_[m]);
    critical.resize(n);  // a no-op on a reused evaluation: the samples are written in place
    for (std::size_t j = 0; j < n; ++j) critical[j] = argument[static_cast<std::size_t>(local_offset_[m]) + j];
  }
  out.status = EvalStatus::kPruned;
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

const Evaluation& Evaluator::evaluate(const double* free_design, EvalData& ws, const EvalOptions& options) const {
  check_design(free_design);
  Evaluation& out = ws.result;
  reset_evaluation(out);

  space_.expand(free_design, ws.full.data());
  if (!constraints_hold(ws.full.data(), ws, out)) return out;

  std::unique_ptr<const MechanismModel> owned;
  const MechanismModel* model = mechanism_accel_->build_in(ws.full.data(), *ws.scratch);
  if (!model) {
    owned = mechanism_->build(ws.full.data());
    model = owned.get();
  }
  std::copy(identity_accumulator_.begin(), identity_accumulator_.end(), ws.accumulator.begin());
  std::fill(ws.argument.begin(), ws.argument.end(), -1);
  const bool prune = std::isfinite(options.prune_below) && prunable_;
  const std::vector<double>* front = options.prune_dominated_by;
  const bool prune_front = front && !front->empty() && worst_case_ && all_maximized_;
  if (batch_ > 0) return evaluate_batched(*model, ws, options, prune, prune_front);
  if (block_path_ && !options.per_sample && !options.on_sample) {
    return evaluate_blocks(*model, ws, options, prune, prune_front);
  }
  const std::vector<int>& indices = options.subset ? *options.subset : order_;
  for (const int sample : indices) {
    // Set before solve(): a mechanism may read the scene (its dimension, its attributes).
    bind_sample(ws.quantities, sample);
    model->solve(samples_->pose(sample), needs_, *ws.scratch, ws.quantities);
    ++out.samples_evaluated;
    if (ws.quantities.status != SampleStatus::kReachable && any_worst_case_) {
      out.status = EvalStatus::kSampleFailed;
      out.failed_sample = sample;
      out.failed_status = ws.quantities.status;
      return out;
    }
    accumulate_locals(sample, ws, options.on_sample != nullptr);
    if (options.on_sample) (*options.on_sample)(sample, ws.quantities, ws.nested_locals);
    if ((prune_front && front_dominates(*front, ws.accumulator.data(), ws.objective_bound.data())) ||
        (prune && score_bound(ws.accumulator.data(), out.samples_evaluated) < options.prune_below)) {
      mark_pruned(ws.argument.data(), out);
      return out;
    }
  }
  combine_objectives(ws, out);
  return out;
}

// The per-sample loop of evaluate() for studies with a batched metric (Metric::batch_size()):
// up to batch_ samples are solved, their local values computed with one local_batch() call per
// metric, then reduced one by one exactly as the per-sample loop does (same order, same checks,
// same pruning decisions after each sample). Kept apart so that the per-sample loop is untouched.
const Evaluation& Evaluator::evaluate_batched(const MechanismModel& model, EvalData& ws, const EvalOptions& options,
                                            bool prune, bool prune_front) const {
  Evaluation& out = ws.result;
  const std::vector<int>& indices = options.subset ? *options.subset : order_;
  const std::size_t n = indices.size();
  long long folded = 0;  // samples reduced so far (the per-sample loop's samples_evaluated)
  for (std::size_t first = 0; first < n; first += static_cast<std::size_t>(batch_)) {
    const int capacity = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(batch_), n - first));
    int count = 0;
    bool failed = false;
    for (; count < capacity; ++count) {
      const int sample = indices[first + static_cast<std::size_t>(count)];
      SampleQuantities& q = ws.batch_quantities[static_cast<std::size_t>(count)];
      bind_sample(q, sample);
      model.solve(samples_->pose(sample), needs_, *ws.scratch, q);
      ++out.samples_evaluated;
      if (q.status != SampleStatus::kReachable && any_worst_case_) {
        failed = true;  // the samples before it are reduced first, as the per-sample loop would
        break;
      }
    }
    for (std::size_t m = 0; m < metrics_.size(); ++m) {
      for (int i = 0; i < count; ++i) {
        SampleQuantities& q = ws.batch_quantities[static_cast<std::size_t>(i)];
        q.attributes = metric_attributes_[m].data();
        q.attribute_count = static_cast<int>(metric_attributes_[m].size());
      }
      if (count > 0) {
        // A batch_size() > 0 without a local_batch() override writes nothing: the NaN left
        // here is then reported as the metric's, not reduced as a stale value.
        std::fill_n(ws.batch_locals.data() + static_cast<std::size_t>(batch_) * local_offset_[m],
                    static_cast<std::size_t>(count) * static_cast<std::size_t>(local_offset_[m + 1] - local_offset_[m]),
                    std::numeric_limits<double>::quiet_NaN());
        metric_accel_[m]->local_batch(ws.batch_pointers.data(), count,
                                        ws.batch_locals.data() + static_cast<std::size_t>(batch_) * local_offset_[m]);
      }
    }
    for (int i = 0; i < count; ++i) {
      const SampleQuantities& q = ws.batch_quantities[static_cast<std::size_t>(i)];
      for (std::size_t m = 0; m < metrics_.size(); ++m) {
        const int k = local_offset_[m + 1] - local_offset_[m];
        const double* block = ws.batch_locals.data() + static_cast<std::size_t>(batch_) * local_offset_[m];
        std::copy(block + i * k, block + (i + 1) * k, ws.locals.begin() + local_offset_[m]);
      }
      fold_locals(q.sample, ws, options.on_sample != nullptr, q);
      ++folded;
      if (options.on_sample) (*options.on_sample)(q.sample, q, ws.nested_locals);
      if ((prune_front && front_dominates(*options.prune_dominated_by, ws.accumulator.data(), ws.objective_bound.data())) ||
          (prune && score_bound(ws.accumulator.data(), folded) < options.prune_below)) {
        mark_pruned(ws.argument.data(), out);
        return out;
      }
    }
    if (failed) {
      const SampleQuantities& q = ws.batch_quantities[static_cast<std::size_t>(count)];
      out.status = EvalStatus::kSampleFailed;
      out.failed_sample = q.sample;
      out.failed_status = q.status;
      return out;
    }
  }
  combine_objectives(ws, out);
  return out;
}

// The per-sample loop of evaluate() on the block path: kBlockLanes samples are solved and their
// local values computed per call, then reduced lane by lane in sample order with the per-sample
// loop's tie rule. Pruning is decided once per block: the bounds only fall as samples are added
// (worst-case metrics), so a block whose end is not pruned had no pruned prefix; a block whose
// end is pruned is replayed lane by lane from the reductions before it, to stop at the very
// sample the per-sample loop stops at. A failing sample ends the evaluation after the lanes
// before it, as in the per-sample loop; samples_evaluated counts the same samples.
const Evaluation& Evaluator::evaluate_blocks(const MechanismModel& model, EvalData& ws, const EvalOptions& options,
                                           bool prune, bool prune_front) const {
  Evaluation& out = ws.result;
  const std::vector<int>* subset = options.subset;
  const std::size_t n = subset ? subset->size() : order_.size();
  const int dimension = samples_->dimension();
  QuantityBlock& q = *ws.block;
  PoseBlock poses;
  poses.dimension = dimension;
  // ws.block_first says which block of order_ the metrics see (their attributes' block copy);
  // other paths share the scratch, so it is reset however this function ends.
  struct ResetBlockFirst {
    std::size_t& first;
    ~ResetBlockFirst() { first = SIZE_MAX; }
  } reset{ws.block_first};
  // A subset that is a run of order_ on block boundaries reads the blocks of the full order.
  const std::size_t run = subset ? order_run(*subset) : 0;
  const bool in_order = run != SIZE_MAX;
  for (std::size_t first = 0; first < n; first += kBlockLanes) {
    const int count = static_cast<int>(std::min<std::size_t>(kBlockLanes, n - first));
    ws.block_first = in_order ? run + first : SIZE_MAX;
    poses.count = count;
    const int* lane_sample = in_order ? order_.data() + run + first : subset->data() + first;
    for (int c = 0; c < dimension; ++c) {
      if (!in_order) {
        double* lane = ws.gathered.data() + static_cast<std::size_t>(c) * kBlockLanes;
        for (int i = 0; i < kBlockLanes; ++i) lane[i] = samples_->pose(lane_sample[std::min(i, count - 1)])[c];
        poses.coordinate[c] = lane;
      } else {
        poses.coordinate[c] = block_poses_.data() + static_cast<std::size_t>(c) * block_stride_ + run + first;
      }
    }
    // The lanes' samples, padded with the last one (a kernel reads every lane).
    for (int i = 0; i < kBlockLanes; ++i) q.samples[i] = lane_sample[std::min(i, count - 1)];
    mechanism_accel_->solve_block(model, poses, needs_, *ws.scratch, q);
    if (!worst_case_) {  // averaging: every lane counts, whatever its status; nothing to prune
      fold_block_sums(model, ws, lane_sample, count);
      continue;
    }
    int valid = 0;  // reachable lanes before the first failing one
    while (valid < count && q.lane_status(valid) == SampleStatus::kReachable) ++valid;
    if (valid > 0 && fold_block(model, ws, options, lane_sample, valid, prune, prune_front)) {
      mark_pruned(ws.argument.data(), out);
      return out;
    }
    if (valid < count) {
      ++out.samples_evaluated;
      out.status = EvalStatus::kSampleFailed;
      out.failed_sample = lane_sample[valid];
      out.failed_status = q.lane_status(valid);
      return out;
    }
  }
  combine_objectives(ws, out);
  return out;
}

// Whether one of the first `lanes` values v[0..kBlockLanes) of local i may move its worst-case
// reduction from `current`: a value not strictly worse, or not finite (NaN, or an infinity that
// compares as worse). The lanes are tested without branches or early exit (one vector compare
// per lane group: the scan ran once per block and cost a sixth of an unpruned five-bar grid).
bool Evaluator::block_moves(std::size_t i, const double* v, double current, int lanes) const {
  const bool min = local_reduction_[i] == Reduction::kMin;
  if (lanes < kBlockLanes) {  // a block's last lanes: rare, lane by lane
    for (int lane = 0; lane < lanes; ++lane) {
      if (!std::isfinite(v[lane]) || !(min ? v[lane] > current : v[lane] < current)) return true;
    }
    return false;
  }
  // Pairs of lanes as vectors of the baseline instruction set (SSE2: a wider GCC vector was
  // compared lane by lane), one comparison per pair: y = v + (v - v) is v where v is finite and
  // NaN elsewhere, and a NaN is never strictly worse.
  typedef double Pair __attribute__((vector_size(2 * sizeof(double))));
  typedef std::int64_t Truths __attribute__((vector_size(2 * sizeof(double))));
  Truths worse = {-1, -1};
  for (int lane = 0; lane < kBlockLanes; lane += 2) {
    Pair x;
    std::memcpy(&x, v + lane, sizeof x);
    const Pair y = x + (x - x);
    if (min) {
      worse &= y > current;
    } else {
      worse &= y < current;
    }
  }
  return (worse[0] & worse[1]) == 0;
}

// Reduces the first `lanes` lanes of the block in ws (all reachable) into the accumulators and
// counts them in samples_evaluated; true when the evaluation is pruned, with the reductions and
// the count where the per-sample loop would have stopped.
bool Evaluator::fold_block(const MechanismModel& model, EvalData& ws, const EvalOptions& options,
                         const int* lane_sample, int lanes, bool prune, bool prune_front) const {
  Evaluation& out = ws.result;
  block_locals(ws);
  const bool check = prune || prune_front;
  const std::size_t k = local_reduction_.size();
  // Most blocks do not move a worst-case reduction: when no lane reaches a reduction's current
  // value (its block extreme is strictly worse), the lane-by-lane scan of that value is skipped;
  // a lane that ties or beats it goes through the per-sample tie rule below.
  bool moves = false;
  for (std::size_t i = 0; i < k && !moves; ++i) moves = block_moves(i, ws.block_locals.data() + i * kBlockLanes, ws.accumulator[i], lanes);
  if (!moves) {  // the reductions, hence the bounds, are those after the previous block: not pruned
    out.samples_evaluated += lanes;
    return false;
  }
  if (check) {  // element by element: a few values, no memmove call per block
    for (std::size_t i = 0; i < k; ++i) {
      ws.saved_accumulator[i] = ws.accumulator[i];
      ws.saved_argument[i] = ws.argument[i];
    }
  }
  const auto fold_lane = [&](int lane) {
    const int sample = lane_sample[lane];
    for (std::size_t i = 0; i < k; ++i) {
      const double v = ws.block_locals[i * kBlockLanes + static_cast<std::size_t>(lane)];
      if (!std::isfinite(v)) refuse_non_finite_block_local(model, ws, sample);
      if (better(local_reduction_[i], v, sample, ws.accumulator[i], ws.argument[i])) {
        ws.accumulator[i] = v;
        ws.argument[i] = sample;
      }
    }
    ++out.samples_evaluated;
  };
  const auto pruned = [&] {
    return (prune_front && front_dominates(*options.prune_dominated_by, ws.accumulator.data(), ws.objective_bound.data())) ||
           (prune && score_bound(ws.accumulator.data(), out.samples_evaluated) < options.prune_below);
  };
  for (int lane = 0; lane < lanes; ++lane) fold_lane(lane);
  if (!check || !pruned()) return false;
  for (std::size_t i = 0; i < k; ++i) {
    ws.accumulator[i] = ws.saved_accumulator[i];
    ws.argument[i] = ws.saved_argument[i];
  }
  out.samples_evaluated -= lanes;
  for (int lane = 0; lane < lanes; ++lane) {
    fold_lane(lane);
    if (pruned()) return true;
  }
  assert(false && "a worst-case bound rose within a block");
  return true;
}

// Every metric's local values of the block in ws (its samples set), each metric with the scene
// attributes it listed, and their block copy when the block is one of order_'s.
void Evaluator::block_locals(EvalData& ws) const {
  QuantityBlock& q = *ws.block;
  for (std::size_t m = 0; m < metrics_.size(); ++m) {
    q.attributes = metric_attributes_[m].data();
    q.attribute_count = static_cast<int>(metric_attributes_[m].size());
    q.attribute_lane_data = nullptr;
    if (ws.block_first != SIZE_MAX && !metric_attributes_[m].empty()) {
      for (std::size_t k = 0; k < metric_attributes_[m].size(); ++k) {
        const double* start = metric_attribute_blocks_[m][k];
        ws.attribute_lane_pointers[k] =
            start ? start + ws.block_first * static_cast<std::size_t>(metric_attributes_[m][k]->cols()) : nullptr;
      }
      q.attribute_lane_data = ws.attribute_lane_pointers.data();
    }
    metric_accel_[m]->local_block(q, ws.block_locals.data() + static_cast<std::size_t>(local_offset_[m]) * kBlockLanes);
  }
}

// The block path of an averaging study: the first `lanes` lanes are reduced in sample order
// exactly as fold_locals() reduces them one by one (sums weighted, extremes by the tie rule).
void Evaluator::fold_block_sums(const MechanismModel& model, EvalData& ws, const int* lane_sample, int lanes) const {
  block_locals(ws);
  const std::size_t k = local_reduction_.size();
  for (int lane = 0; lane < lanes; ++lane) {
    const int sample = lane_sample[lane];
    const double scale = sample_scale_.empty() ? 1.0 : sample_scale_[static_cast<std::size_t>(sample)];
    for (std::size_t i = 0; i < k; ++i) {
      const double v = ws.block_locals[i * kBlockLanes + static_cast<std::size_t>(lane)];
      if (!std::isfinite(v)) refuse_non_finite_block_local(model, ws, sample);
      if (local_reduction_[i] == Reduction::kSum) {
        ws.accumulator[i] += v * scale;
      } else if (better(local_reduction_[i], v, sample, ws.accumulator[i], ws.argument[i])) {
        ws.accumulator[i] = v;
        ws.argument[i] = sample;
      }
    }
  }
  ws.result.samples_evaluated += lanes;
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

// Design lanes (evaluate_designs). Lane i's design is lane_design[i]: the caller's free vector
// when every component is free, else its expansion at ws.lane_full[i * size]. Its reductions are
// kept lane-minor, local j of lane i at ws.lane_accumulator / lane_argument[j * kBlockLanes + i],
// so that starting and folding a group are loops over the lanes that compile to vector code.
// Most designs here are decided at their first sample: what a design costs is this bookkeeping,
// not the arithmetic, so a lane's Evaluation is written only when the lane is decided
// (docs/design.md section 13.4).
void Evaluator::evaluate_designs(const double* const* free_designs, int count, EvalData& ws,
                               const EvalOptions& options, std::vector<Evaluation>& outs) const {
  assert(count >= 1 && count <= kBlockLanes);
  size_evaluations(outs, count);
  const auto one_by_one = [&](int from, const bool* pending) {
    for (int i = from; i < count; ++i) {
      if (!pending || pending[i]) outs[static_cast<std::size_t>(i)] = evaluate(free_designs[i], ws, options);
    }
  };
  // Design lanes serve worst-case studies (their first samples decide most designs).
  if (!block_path_ || !worst_case_ || options.per_sample || options.on_sample || count == 1) {
    return one_by_one(0, nullptr);
  }
  bool active[kBlockLanes] = {};
  const double* lane_design[kBlockLanes];
  int left = start_lanes(free_designs, count, options.constraints_verified, ws, outs, active, lane_design);
  if (left == 0) return;
  int any = 0;
  while (!active[any]) ++any;
  const bool prune = std::isfinite(options.prune_below) && prunable_;
  const std::vector<double>* front = options.prune_dominated_by;
  const bool prune_front = front && !front->empty() && worst_case_ && all_maximized_;
  const std::vector<int>& indices = options.subset ? *options.subset : order_;
  const std::size_t lane_samples = std::min<std::size_t>(indices.size(), kBlockLanes);
  const double* designs[kBlockLanes];
  for (std::size_t t = 0; t < lane_samples && left > 0; ++t) {
    for (int i = 0; i < kBlockLanes; ++i) {  // decided and unused lanes repeat a live design
      designs[i] = lane_design[i < count && active[i] ? i : any];
    }
    const int sample = indices[t];
    if (!mechanism_accel_->solve_designs(designs, count, samples_->pose(sample), needs_, *ws.scratch, *ws.block)) {
      return one_by_one(0, active);  // these designs cannot share a vector: from scratch, one by one
    }
    std::fill_n(ws.block->samples, kBlockLanes, sample);
    const int non_finite = fold_lanes(sample, count, ws, options, prune, prune_front, outs, active, left);
    if (non_finite >= 0) {
      // The per-sample loop meets the same value and reports it with the design and sample.
      EvalOptions alone = options;
      alone.per_sample = true;
      (void)evaluate(free_designs[non_finite], ws, alone);
      throw Error("problem", "sample " + std::to_string(sample) +
                                 " gave a non-finite local value in a design lane but not alone (docs/design.md section 13.4)");
    }
    for (any = 0; left > 0 && !active[any];) ++any;
  }
  if (left == 0) return;
  if (lane_samples == indices.size()) {  // every sample seen: the surviving designs are complete
    const std::size_t size = space_.size(), k = local_reduction_.size();
    for (int i = 0; i < count; ++i) {
      if (!active[i]) continue;
      for (std::size_t j = 0; j < k; ++j) {
        ws.accumulator[j] = ws.lane_accumulator[j * kBlockLanes + static_cast<std::size_t>(i)];
        ws.argument[j] = ws.lane_argument[j * kBlockLanes + static_cast<std::size_t>(i)];
      }
      std::copy_n(lane_design[i], size, ws.full.data());
      combine_objectives(ws, outs[static_cast<std::size_t>(i)]);
    }
    return;
  }
  one_by_one(0, active);  // undecided after the first samples: the block path finishes them
}

// Makes outs hold at least `count` evaluations, new ones sized for the study. Existing ones are
// not checked per call (that cost as much as a lane's fold): the lanes' writers size what they
// write (mark_pruned, combine_objectives), and whole evaluations are assigned.
void Evaluator::size_evaluations(std::vector<Evaluation>& outs, int count) const {
  const std::size_t old = outs.size();
  if (old >= static_cast<std::size_t>(count)) return;
  outs.resize(static_cast<std::size_t>(count));
  for (std::size_t i = old; i < outs.size(); ++i) {
    outs[i].objectives.resize(objectives_.size());
    outs[i].critical_samples.resize(metrics_.size());
    outs[i].reduced.resize(metrics_.size());
  }
}

// Each lane's evaluate() up to its first sample: bounds, constraints (unless the caller verified
// them), identity reductions. Sets active[i] for the designs that go on to their samples and
// returns how many do; their outs hold a reset evaluation, the others a constraint violation.
int Evaluator::start_lanes(const double* const* free_designs, int count, bool constraints_verified, EvalData& ws,
                         std::vector<Evaluation>& outs, bool* active, const double** lane_design) const {
  const std::size_t free = free_lower_.size(), size = space_.size(), k = local_reduction_.size();
  // Component by component over all the lanes (unused lanes repeat the last design), so that
  // the comparisons are vector ones; a design out of bounds is then named by check_design.
  bool inside = true;
  for (std::size_t c = 0; c < free; ++c) {
    double v[kBlockLanes];
    for (int i = 0; i < kBlockLanes; ++i) v[i] = free_designs[std::min(i, count - 1)][c];
    const double lower = free_lower_[c], upper = free_upper_[c];
    bool in = true;
    for (int i = 0; i < kBlockLanes; ++i) in &= (v[i] >= lower) & (v[i] <= upper);
    inside &= in;
  }
  if (!inside) {
    for (int i = 0; i < count; ++i) check_design(free_designs[i]);  // throws with the component named
  }
  for (std::size_t j = 0; j < k; ++j) {
    for (int i = 0; i < kBlockLanes; ++i) {
      ws.lane_accumulator[j * kBlockLanes + static_cast<std::size_t>(i)] = identity_accumulator_[j];
      ws.lane_argument[j * kBlockLanes + static_cast<std::size_t>(i)] = -1;
    }
  }
  int live = 0;
  for (int i = 0; i < count; ++i) {
    Evaluation& out = outs[static_cast<std::size_t>(i)];
    reset_evaluation(out);
    if (free == size) {
      lane_design[i] = free_designs[i];
    } else {
      double* full = ws.lane_full.data() + static_cast<std::size_t>(i) * size;
      space_.expand(free_designs[i], full);
      lane_design[i] = full;
    }
    if (!constraints_verified) {
      if (!constraints_hold(lane_design[i], ws, out)) continue;
    } else {
      // The caller's line bound checked the run's ends under the mechanism's quasiconvexity
      // promise; a broken promise is a plugin bug that builds with assertions catch here.
      assert(constraints_hold(lane_design[i], ws, out) &&
             "EvalOptions::constraints_verified for a design that violates a constraint");
    }
    active[i] = true;
    ++live;
  }
  return live;
}

// One sample of every active lane (solved into ws.block), as the per-sample loop takes it: the
// metrics' local values are computed for the lanes that reach it; a failing sample ends the
// design, the local values are reduced with the tie rule, and the bound may prune it. Clears
// active[i] and decrements `left` for each lane decided here. Returns the first lane with a
// non-finite local value (the caller reports it), else -1.
int Evaluator::fold_lanes(int sample, int count, EvalData& ws, const EvalOptions& options, bool prune,
                        bool prune_front, std::vector<Evaluation>& outs, bool* active, int& left) const {
  const std::size_t k = local_reduction_.size();
  constexpr std::size_t L = kBlockLanes;
  // Which lanes fold this sample: active and reachable. The reductions of all lanes are updated
  // together under that mask (lane-minor: a vector per local value).
  bool folds[L] = {};
  bool any_folds = false;
  for (int i = 0; i < count; ++i) {
    folds[i] = active[i] && ws.block->lane_status(i) == SampleStatus::kReachable;
    any_folds |= folds[i];
  }
  // Where the sample fails for every design (often: a line's neighbours share their failures),
  // there are no local values to compute.
  if (any_folds) block_locals(ws);
  const double* locals = ws.block_locals.data();
  for (std::size_t j = 0; j < k; ++j) {
    bool finite = true;
    for (std::size_t i = 0; i < L; ++i) finite &= !folds[i] || std::isfinite(locals[j * L + i]);
    if (!finite) {
      for (int i = 0; i < count; ++i) {
        if (folds[i] && !std::isfinite(locals[j * L + static_cast<std::size_t>(i)])) return i;
      }
    }
    double* acc = ws.lane_accumulator.data() + j * L;
    int* arg = ws.lane_argument.data() + j * L;
    const Reduction reduction = local_reduction_[j];
    for (std::size_t i = 0; i < L; ++i) {
      const double v = locals[j * L + i];
      const bool take = folds[i] && better(reduction, v, sample, acc[i], arg[i]);
      acc[i] = take ? v : acc[i];
      arg[i] = take ? sample : arg[i];
    }
  }
  // Every active lane has seen the same samples (they start together and fold each one).
  const int seen = outs[static_cast<std::size_t>(std::find(active, active + count, true) - active)].samples_evaluated + 1;
  double bound[L];
  const bool bounded = prune && !prune_front && score_bound_lanes(ws.lane_accumulator.data(), seen, bound);
  double* lane_acc = ws.accumulator.data();  // one lane's reductions, for the helpers (free here)
  int* lane_arg = ws.argument.data();
  for (int i = 0; i < count; ++i) {
    if (!active[i]) continue;
    Evaluation& out = outs[static_cast<std::size_t>(i)];
    out.samples_evaluated = seen;
    if (!folds[i]) {
      out.status = EvalStatus::kSampleFailed;
      out.failed_sample = sample;
      out.failed_status = ws.block->lane_status(i);
      active[i] = false;
      --left;
      continue;
    }
    if (!prune && !prune_front) continue;
    if (bounded && !(bound[i] < options.prune_below)) continue;
    for (std::size_t j = 0; j < k; ++j) {
      lane_acc[j] = ws.lane_accumulator[j * L + static_cast<std::size_t>(i)];
      lane_arg[j] = ws.lane_argument[j * L + static_cast<std::size_t>(i)];
    }
    if (bounded || (prune_front && front_dominates(*options.prune_dominated_by, lane_acc, ws.objective_bound.data())) ||
        (prune && score_bound(lane_acc, seen) < options.prune_below)) {
      mark_pruned(lane_arg, out);
      active[i] = false;
      --left;
    }
  }
  return -1;
}

// score_bound() of every lane at once (lane-minor reductions), bit for bit: each objective's
// combined values added in objective order from 0. False when a metric has no combine_block.
bool Evaluator::score_bound_lanes(const double* lane_accumulator, int samples, double* bound) const {
  constexpr std::size_t L = kBlockLanes;
  std::fill_n(bound, L, 0.0);
  double combined[L];
  for (std::size_t o = 0; o < objectives_.size(); ++o) {
    const std::size_t m = static_cast<std::size_t>(objectives_[o].metric);
    if (!metric_accel_[m]->combine_block(lane_accumulator + static_cast<std::size_t>(local_offset_[m]) * L, samples,
                                           combined)) {
      return false;
    }
    const double weight = objectives_[o].weight;
    for (std::size_t i = 0; i < L; ++i) bound[i] += weight * combined[i];
  }
  return true;
}

Evaluation Evaluator::evaluate_parallel(const double* free_design, int threads, const ParallelOptions& options) const {
  check_design(free_design);
  const std::vector<int>& indices = options.subset ? *options.subset : order_;
  const long long n = static_cast<long long>(indices.size());
  const int chunk_count = static_cast<int>(std::max(1LL, std::min<long long>(options.chunks > 0 ? options.chunks : threads, n)));
  threads = std::max(1, std::min(threads, chunk_count));
  if (chunk_count == 1) {
    auto ws = make_eval_data();
    EvalOptions o;
    o.subset = options.subset;
    return evaluate(free_design, *ws, o);
  }
  // Each chunk is a contiguous piece of the sample order; the reductions are merged in chunk
  // order with the same tie rule (lower sample index wins) as a sequential run, so the result
  // does not depend on the thread count.
  // Chunks of the full order start on whole blocks, so that the block path reads them from its
  // block copies (order_run) instead of gathering each block.
  const auto boundary = [&](int t) -> long long {
    const long long b = n * t / chunk_count;
    return t == chunk_count ? n : (block_path_ && !options.subset ? b / kBlockLanes * kBlockLanes : b);
  };
  std::vector<std::unique_ptr<EvalData>> spaces(static_cast<std::size_t>(chunk_count));
  std::vector<std::vector<int>> chunks(static_cast<std::size_t>(chunk_count));
  for (int t = 0; t < chunk_count; ++t) {
    chunks[static_cast<std::size_t>(t)].assign(indices.begin() + boundary(t), indices.begin() + boundary(t + 1));
  }
  parallel_for_dynamic(chunk_count, threads, 1, [&](long long t, int) {
    // Made by the thread that fills it (docs/design.md section 1.5).
    spaces[static_cast<std::size_t>(t)] = make_eval_data();
    EvalOptions o;
    o.subset = &chunks[static_cast<std::size_t>(t)];
    evaluate(free_design, *spaces[static_cast<std::size_t>(t)], o);
  });
  Evaluation merged = spaces[0]->result;
  merged.samples_evaluated = 0;
  for (const auto& ws : spaces) merged.samples_evaluated += ws->result.samples_evaluated;
  for (const auto& ws : spaces) {
    if (ws->result.status != EvalStatus::kFeasible) {
      Evaluation failed = ws->result;  // the first chunk (in sample order) that failed
      failed.samples_evaluated = merged.samples_evaluated;
      return failed;
    }
  }
  std::vector<double> acc = identity_accumulator_;
  std::vector<int> arg(local_reduction_.size(), -1);
  for (const auto& ws : spaces) {
    for (std::size_t m = 0; m < metrics_.size(); ++m) {
      for (std::size_t j = 0; j < ws->result.reduced[m].size(); ++j) {
        const std::size_t i = static_cast<std::size_t>(local_offset_[m]) + j;
        const double v = ws->result.reduced[m][j];
        const int a = ws->result.critical_samples[m][j];
        if (local_reduction_[i] == Reduction::kSum) {
          acc[i] += v;
        } else if (better(local_reduction_[i], v, a, acc[i], arg[i])) {
          acc[i] = v;
          arg[i] = a;
        }
      }
    }
  }
  for (std::size_t m = 0; m < metrics_.size(); ++m) {
    merged.reduced[m].assign(acc.begin() + local_offset_[m], acc.begin() + local_offset_[m + 1]);
    merged.critical_samples[m].assign(arg.begin() + local_offset_[m], arg.begin() + local_offset_[m + 1]);
  }
  for (std::size_t o = 0; o < objectives_.size(); ++o) {
    const std::size_t m = static_cast<std::size_t>(objectives_[o].metric);
    merged.objectives[o] = metrics_[m].metric->combine(merged.reduced[m].data(), static_cast<int>(merged.samples_evaluated));
  }
  merged.score = score(merged.objectives);
  return merged;
}

}  // namespace hapsyn
