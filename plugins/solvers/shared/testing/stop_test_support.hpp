#pragma once
// Test helpers for stop, checkpoint and resume of the grid-based solvers (grid_test and
// culling_test include it): analytic problems whose metric requests a stop after a given number
// of samples (deterministic, whatever the threads), a metric that breaks the worst-case
// monotonicity rule, and checkpoint edits (with and without a recomputed checksum).
#include "analytic_problems.hpp"
#include "test_support.hpp"

#include <hapsyn/checkpoint.hpp>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace hapsyn::test {

/// Sets *stop once `limit` local values have been computed (limit < 0: never); counts them all.
struct StopAfter {
  std::atomic<bool> stop{false};
  std::atomic<long long> calls{0};
  long long limit = -1;
  void tick() {
    if (calls.fetch_add(1, std::memory_order_relaxed) + 1 == limit) stop.store(true);
  }
};

/// A worst-case metric min_s local(x, s) that ticks a StopAfter per sample.
class StoppingMetric : public Metric {
 public:
  StoppingMetric(AnalyticLocal local, StopAfter* counter) : local_(std::move(local)), counter_(counter) {}
  void local(const SampleQuantities& q, double* out) const override {
    counter_->tick();
    out[0] = local_(q.q.data(), q.scene->pose(q.sample));
  }
  MetricSpecs specs() const override { return {kNeedPose, {}}; }

 private:
  AnalyticLocal local_;
  StopAfter* counter_;
};

/// A metric that breaks the worst-case monotonicity rule: min-reduced, but combine() = -min, so
/// a subset of samples gives a value below the whole scene's.
class NonMonotoneMetric : public Metric {
 public:
  void local(const SampleQuantities& q, double* out) const override {
    out[0] = 1.0 + q.q[0] + 0.1 * q.q[1] * q.scene->pose(q.sample)[0];
  }
  MetricSpecs specs() const override { return {kNeedPose, {}}; }
  double combine(const double* reduced, int) const override { return -reduced[0]; }
};

/// Design (x0, x1) on [0, 1]^2 with `step`, samples s in 8 points of [-1, 1], and the given
/// metrics (one maximized objective each, named after `names`).
inline std::shared_ptr<Problem> metric_problem(double step, std::vector<std::shared_ptr<const Metric>> metrics,
                                               const std::vector<std::string>& names) {
  std::vector<DesignComponent> components;
  for (int i = 0; i < 2; ++i) {
    DesignComponent c;
    c.name = c.variable = "x" + std::to_string(i);
    c.lower = 0.0;
    c.upper = 1.0;
    c.step = step;
    components.push_back(c);
  }
  auto samples = std::make_shared<SampleSet>();
  samples->coordinates = {"s"};
  samples->poses.resize(8, 1);
  for (int i = 0; i < 8; ++i) samples->poses(i, 0) = -1.0 + 2.0 * i / 7.0;
  samples->cache_bounds();
  std::vector<MetricEntry> entries;
  std::vector<Objective> objectives;
  for (std::size_t i = 0; i < metrics.size(); ++i) {
    entries.push_back({names[i], metrics[i]});
    Objective o;
    o.name = names[i];
    o.metric = static_cast<int>(i);
    objectives.push_back(o);
  }
  return std::make_shared<Problem>("analytic", std::make_shared<AnalyticMechanism>(2), samples, entries, objectives,
                                   DesignSpace(components));
}

/// One objective with a unique grid optimum near (0.37, 0.61), or (two) a trade-off front.
inline std::shared_ptr<Problem> stopping_problem(StopAfter& counter, double step = 0.02, bool two = false) {
  std::vector<std::shared_ptr<const Metric>> metrics = {std::make_shared<StoppingMetric>(
      [](const double* x, const double* s) {
        return 1.0 - (x[0] - 0.37) * (x[0] - 0.37) - (x[1] - 0.61) * (x[1] - 0.61) - 0.05 * (x[1] - 0.2 * s[0]) * (x[1] - 0.2 * s[0]);
      },
      &counter)};
  std::vector<std::string> names = {"f1"};
  if (two) {
    metrics.push_back(std::make_shared<StoppingMetric>(
        [](const double* x, const double* s) { return x[0] - 0.3 * x[1] * x[1] + 0.01 * s[0] * x[1]; }, &counter));
    names.push_back("f2");
  }
  return metric_problem(step, metrics, names);
}

inline std::shared_ptr<Problem> non_monotone_problem() {
  return metric_problem(0.1, {std::make_shared<NonMonotoneMetric>()}, {"bad"});
}

/// A fresh, empty directory under the temporary directory.
inline std::string fresh_directory(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("hapsyn-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

inline Json read_json_file(const std::string& file) {
  std::ifstream in(file);
  return Json::parse(in);
}

/// Writes `document`, with its checksum recomputed as the framework does when `rechecksum`.
inline void write_json_file(const std::string& file, Json document, bool rechecksum) {
  if (rechecksum) {
    document.erase("checksum");
    document["checksum"] = fnv1a_hex(document.dump());
  }
  std::ofstream(file) << document.dump();
}

/// Truncates a file to half its size.
inline void truncate_file(const std::string& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  const std::string all = text.str();
  std::ofstream(file) << all.substr(0, all.size() / 2);
}

}  // namespace hapsyn::test
