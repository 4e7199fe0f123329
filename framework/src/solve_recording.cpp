// SolveRecording: the solve's per-sample records of a fixed design, kept for the outputs phase.
#include <hapsyn/internal/solve_recording.hpp>

#include <algorithm>
#include <mutex>

namespace hapsyn {

namespace {

// The live recordings (several studies may run in one process: sweeps, tests).
std::mutex registry_mutex;
std::vector<SolveRecording*>& registry() {
  static std::vector<SolveRecording*> live;
  return live;
}

}  // namespace

std::atomic<int> SolveRecording::live_{0};

SampleRecords blank_records(const Problem& problem) {
  const Eigen::Index n = problem.samples().size();
  Eigen::Index total_locals = 0;
  for (const MetricEntry& m : problem.metrics()) total_locals += static_cast<Eigen::Index>(m.metric->locals().size());
  SampleRecords records;
  records.status.resize(static_cast<std::size_t>(n));
  records.has_locals.assign(static_cast<std::size_t>(n), 0);
  records.locals.setZero(n, total_locals);
  return records;
}

SampleCallback record_into(SampleRecords& records) {
  return [&records](int sample, const SampleQuantities& q, const std::vector<std::vector<double>>& locals) {
    const std::size_t i = static_cast<std::size_t>(sample);
    records.status[i] = to_string(q.status);
    Eigen::Index c = 0;
    for (const auto& metric_locals : locals) {
      for (double v : metric_locals) records.locals(sample, c++) = v;
    }
    records.has_locals[i] = 1;
  };
}

SolveRecording::SolveRecording(const Problem& problem, const Eigen::VectorXd& full_design)
    : mechanism_(&problem.mechanism()),
      samples_(&problem.samples()),
      design_(full_design),
      records_(blank_records(problem)),
      callback_(record_into(records_)) {
  for (const MetricEntry& m : problem.metrics()) metrics_.push_back(m.metric.get());
  const std::lock_guard<std::mutex> lock(registry_mutex);
  registry().push_back(this);
  live_.fetch_add(1, std::memory_order_relaxed);
}

SolveRecording::~SolveRecording() {
  const std::lock_guard<std::mutex> lock(registry_mutex);
  auto& live = registry();
  live.erase(std::remove(live.begin(), live.end(), this), live.end());
  live_.fetch_sub(1, std::memory_order_relaxed);
}

SolveRecording* SolveRecording::claim(const Mechanism* mechanism, const SampleSet* samples,
                                      const std::vector<MetricEntry>& metrics, const Eigen::VectorXd& full_design) {
  const std::lock_guard<std::mutex> lock(registry_mutex);
  for (SolveRecording* r : registry()) {
    if (r->claimed_ || r->complete_ || r->mechanism_ != mechanism || r->samples_ != samples ||
        r->metrics_.size() != metrics.size() || r->design_.size() != full_design.size() || r->design_ != full_design) {
      continue;
    }
    bool same_metrics = true;
    for (std::size_t m = 0; m < metrics.size(); ++m) same_metrics = same_metrics && r->metrics_[m] == metrics[m].metric.get();
    if (!same_metrics) continue;
    r->claimed_ = true;
    return r;
  }
  return nullptr;
}

void SolveRecording::finish(bool feasible) {
  const std::lock_guard<std::mutex> lock(registry_mutex);
  claimed_ = false;
  complete_ = feasible;
}

}  // namespace hapsyn
