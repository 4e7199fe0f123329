#include "replay_data.hpp"

#include <hapsyn/internal/maps.hpp>
#include <hapsyn/mechanism.hpp>
#include <hapsyn/parallel.hpp>
#include <hapsyn/quantities.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

namespace hapsyn_cli {
namespace {

using hapsyn::Json;

constexpr const char* kFeasibilityMetric = "motion_feasibility";
constexpr hapsyn::Needs kRateNeeds = hapsyn::kNeedJointVelocity | hapsyn::kNeedActuatorLimits;
constexpr hapsyn::Needs kTorqueNeeds = hapsyn::kNeedJointAcceleration | hapsyn::kNeedVelocityTorque |
                                       hapsyn::kNeedInertia | hapsyn::kNeedGravity | hapsyn::kNeedActuatorLimits;

// What the evaluator handed out for one sample.
struct FrameRecord {
  std::string status;
  bool has_locals = false;  // the evaluator handed the sample to the metrics
  bool reachable = false;   // q and the ratios are set
  std::vector<double> q, qdot_ratio, tau_ratio, locals;
};

// The frames' order: by trajectory (label order), then by time, then by sample index.
std::vector<int> frame_order(const hapsyn::SampleSet& samples) {
  const auto& time = samples.attributes.at("time");
  std::vector<int> trajectory(static_cast<std::size_t>(samples.size()), 0);
  for (const hapsyn::SampleGrouping& g : samples.groups) {
    if (g.name == "trajectory") trajectory = g.of_sample;
  }
  std::vector<int> order(static_cast<std::size_t>(samples.size()));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    const auto ta = trajectory[static_cast<std::size_t>(a)], tb = trajectory[static_cast<std::size_t>(b)];
    return ta != tb ? ta < tb : time(a, 0) < time(b, 0);
  });
  return order;
}

// Every sample through the evaluator once (record_samples' pass, on every core: the records do not
// depend on the thread count).
std::vector<FrameRecord> evaluate_samples(const hapsyn::Problem& problem, const Eigen::VectorXd& full, bool with_ratios) {
  std::vector<FrameRecord> records(static_cast<std::size_t>(problem.samples().size()));
  const hapsyn::SampleCallback record = [&](int sample, const hapsyn::SampleQuantities& q,
                                            const std::vector<std::vector<double>>& locals) {
    FrameRecord& r = records[static_cast<std::size_t>(sample)];
    r.status = hapsyn::to_string(q.status);
    r.has_locals = true;
    // An averaging metric sees unreachable samples too; their quantities are stale.
    r.reachable = q.status == hapsyn::SampleStatus::kReachable;
    if (r.reachable) r.q.assign(q.q.data(), q.q.data() + q.q.size());
    if (r.reachable && with_ratios) {
      r.qdot_ratio.resize(static_cast<std::size_t>(q.joint_velocity.size()));
      r.tau_ratio.resize(r.qdot_ratio.size());
      limit_ratios(q, r.qdot_ratio.data(), r.tau_ratio.data());
    }
    for (const auto& metric_locals : locals) r.locals.insert(r.locals.end(), metric_locals.begin(), metric_locals.end());
  };
  hapsyn::evaluate_each_sample(problem, full, hapsyn::hardware_threads(), record, [&](int sample, const std::string& status) {
    records[static_cast<std::size_t>(sample)].status = status;
  });
  return records;
}

// The positions of motion_feasibility's locals among all metrics' locals.
std::vector<std::size_t> feasibility_locals(const hapsyn::Problem& problem, Json& names) {
  const std::vector<std::string> columns = hapsyn::local_columns(problem);
  std::vector<std::size_t> at;
  std::size_t c = 0;
  for (const hapsyn::MetricEntry& m : problem.metrics()) {
    for (std::size_t k = 0; k < m.metric->locals().size(); ++k, ++c) {
      if (m.plugin != kFeasibilityMetric) continue;
      at.push_back(c);
      names.push_back(columns[c]);
    }
  }
  return at;
}

double micrometres(double x) { return std::round(x * 1e6) / 1e6; }

// The drawing of every frame, flat (see replay_json).
void add_drawing(const hapsyn::Problem& problem, const Eigen::VectorXd& full, const std::vector<int>& order, Json& doc) {
  const hapsyn::Mechanism& mechanism = problem.mechanism();
  const auto model = mechanism.build(full.data());
  const auto scratch = mechanism.make_scratch();
  Json points = Json::array(), sizes = Json::array(), names = Json::array(), offsets = Json::array();
  int polylines = 0;
  for (const int sample : order) {
    offsets.push_back(polylines);
    for (const hapsyn::Segment& s : model->segments(problem.samples(), sample, *scratch)) {
      for (const Eigen::Vector3d& p : s.points) {
        points.push_back(micrometres(p.x()));
        points.push_back(micrometres(p.y()));
        points.push_back(micrometres(p.z()));
      }
      sizes.push_back(s.points.size());
      names.push_back(s.name);
      ++polylines;
    }
  }
  offsets.push_back(polylines);
  doc["points"] = std::move(points);
  doc["polyline_sizes"] = std::move(sizes);
  doc["polyline_names"] = std::move(names);
  doc["frame_polylines"] = std::move(offsets);
}

// Appends `values` (or `joints` nulls when there are none) to `out`.
void append(Json& out, const std::vector<double>& values, bool present, int joints) {
  for (int j = 0; j < joints; ++j) {
    const std::size_t k = static_cast<std::size_t>(j);
    out.push_back(present && k < values.size() ? Json(values[k]) : Json(nullptr));
  }
}

}  // namespace

void limit_ratios(const hapsyn::SampleQuantities& q, double* qdot, double* tau) {
  const Eigen::Index n = q.joint_velocity.size();
  for (Eigen::Index i = 0; i < n; ++i) {
    qdot[i] = std::abs(q.joint_velocity(i)) / q.max_velocity(i);
    double t = q.velocity_torque(i) + q.gravity(i);
    for (Eigen::Index j = 0; j < n; ++j) t += q.inertia(i, j) * q.joint_acceleration(j);
    tau[i] = std::abs(t) / q.max_torque(i);
  }
}

std::string replay_unavailable(const hapsyn::Problem& problem) {
  const auto& attributes = problem.samples().attributes;
  const auto time = attributes.find("time");
  if (time == attributes.end() || time->second.cols() != 1 || !attributes.count(hapsyn::kTwistAttribute)) {
    return "the scene gives its samples no time stamps and demanded motion (attributes \"time\" and \"twist\"): "
           "only a motion scene's study can be replayed";
  }
  return "";
}

Json replay_json(const hapsyn::Problem& problem, const Eigen::VectorXd& full_design) {
  if (const std::string why = replay_unavailable(problem); !why.empty()) return {{"available", false}, {"reason", why}};
  const hapsyn::SampleSet& samples = problem.samples();
  const bool with_ratios = (problem.needs() & (kRateNeeds | kTorqueNeeds)) == (kRateNeeds | kTorqueNeeds);
  const std::vector<FrameRecord> records = evaluate_samples(problem, full_design, with_ratios);
  const std::vector<int> order = frame_order(samples);
  int joints = 0;
  for (const FrameRecord& r : records) joints = std::max(joints, static_cast<int>(r.q.size()));
  Json checks = Json::array();
  const std::vector<std::size_t> check_at = feasibility_locals(problem, checks);

  Json sample = Json::array(), time = Json::array(), trajectory = Json::array(), status = Json::array();
  Json q = Json::array(), qdot = Json::array(), tau = Json::array(), feasible = Json::array();
  const hapsyn::SampleGrouping* trajectories = nullptr;
  for (const hapsyn::SampleGrouping& g : samples.groups) {
    if (g.name == "trajectory") trajectories = &g;
  }
  for (const int i : order) {
    const FrameRecord& r = records[static_cast<std::size_t>(i)];
    sample.push_back(i);
    time.push_back(samples.attributes.at("time")(i, 0));
    trajectory.push_back(trajectories ? trajectories->of_sample[static_cast<std::size_t>(i)] : 0);
    status.push_back(r.status);
    append(q, r.q, r.reachable, joints);
    append(qdot, r.qdot_ratio, r.reachable && with_ratios, joints);
    append(tau, r.tau_ratio, r.reachable && with_ratios, joints);
    bool ok = r.has_locals;
    for (const std::size_t c : check_at) ok = ok && r.locals[c] == 1.0;
    feasible.push_back(ok ? 1 : 0);
  }
  Json doc = {{"available", true},
              {"frames", order.size()},
              {"joints", joints},
              {"sample", std::move(sample)},
              {"time", std::move(time)},
              {"trajectory", std::move(trajectory)},
              {"trajectories", trajectories ? Json(trajectories->labels) : Json::array({"all samples"})},
              {"status", std::move(status)},
              {"q", std::move(q)},
              {"qdot_ratio", std::move(qdot)},
              {"tau_ratio", std::move(tau)},
              {"checks", checks},
              {"feasible", check_at.empty() ? Json(nullptr) : std::move(feasible)}};
  if (!with_ratios) {
    doc["ratios_missing"] = "the study's metrics do not ask the mechanism for the joint rates and the dynamics "
                            "(motion_feasibility with share \"all\" or \"velocity\" and \"acceleration\" does)";
  }
  add_drawing(problem, full_design, order, doc);
  return doc;
}

}  // namespace hapsyn_cli
