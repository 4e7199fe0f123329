#pragma once
// A problem built in code (no plugin) whose mechanism counts its model builds and sample solves
// and whose samples are unreachable, singular or invalid by a fixed pattern; and the per-sample
// records of a design computed sample by sample, the reference of record_samples and of the
// solve's recording (sample_records_test, solve_recording_test).
#include <hapsyn/internal/maps.hpp>
#include <hapsyn/problem.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace hapsyn::test {

using hapsyn::SampleStatus;


using hapsyn::SampleStatus;

// Sample k of the scene (pose k) is unreachable, singular or invalid by a fixed pattern, and
// reachable otherwise.
inline SampleStatus status_of(int k) {
  if (k % 7 == 3) return SampleStatus::kUnreachable;
  if (k % 11 == 5) return SampleStatus::kSingular;
  if (k % 13 == 8) return SampleStatus::kInvalid;
  return SampleStatus::kReachable;
}

// A mechanism that counts its model builds and sample solves (from any thread).
struct Counts {
  std::atomic<long long> builds{0}, solves{0};
};

class CountingMechanism : public hapsyn::Mechanism {
 public:
  explicit CountingMechanism(Counts& counts) : counts_(counts) {}
  class Model : public hapsyn::MechanismModel {
   public:
    Model(double x, Counts& counts) : x_(x), counts_(counts) {}
    void solve(const double* pose, hapsyn::Needs, hapsyn::MechanismScratch&, hapsyn::SampleQuantities& out) const override {
      ++counts_.solves;
      out.status = status_of(static_cast<int>(pose[0]));
      out.q.resize(1);
      out.q[0] = x_ * std::sin(0.37 * pose[0]);
    }

   private:
    double x_;
    Counts& counts_;
  };
  std::unique_ptr<const hapsyn::MechanismModel> build(const double* design) const override {
    ++counts_.builds;
    return std::make_unique<Model>(design[0], counts_);
  }
  hapsyn::MechanismSpecs specs() const override { return {hapsyn::kNeedJacobian, {}}; }

 private:
  Counts& counts_;
};

// local = q + pose / 1000 (so every sample's value differs), reduced by min (worst case) or sum;
// NaN at samples `nan_at` and `nan_at` + 2000.
class SampleMetric : public hapsyn::Metric {
 public:
  SampleMetric(hapsyn::Reduction reduction, int nan_at) : reduction_(reduction), nan_at_(nan_at) {}
  void local(const hapsyn::SampleQuantities& q, double* out) const override {
    out[0] = nan_at_ >= 0 && (q.sample == nan_at_ || q.sample == nan_at_ + 2000) ? std::numeric_limits<double>::quiet_NaN() : q.q[0] + q.scene->pose(q.sample)[0] / 1000.0;
    out[1] = -out[0];
  }
  std::vector<hapsyn::LocalValue> locals() const override {
    return {{"a", reduction_, ""}, {"b", reduction_ == hapsyn::Reduction::kSum ? reduction_ : hapsyn::Reduction::kMax, ""}};
  }
  double combine(const double* reduced, int samples) const override {
    return reduction_ == hapsyn::Reduction::kSum ? reduced[0] / std::max(1, samples) : reduced[0];
  }
  hapsyn::MetricSpecs specs() const override { return {hapsyn::kNeedJacobian, {}}; }

 private:
  hapsyn::Reduction reduction_;
  int nan_at_;
};

// `n` samples at poses 0..n-1, one fixed design component x = 0.8, one metric.
inline std::shared_ptr<hapsyn::Problem> counting_problem(Counts& counts, int n, hapsyn::Reduction reduction, int nan_at = -1) {
  hapsyn::DesignComponent c;
  c.name = c.variable = "x";
  c.lower = 0.0;
  c.upper = 2.0;
  auto samples = std::make_shared<hapsyn::SampleSet>();
  samples->coordinates = {"k"};
  samples->poses.resize(n, 1);
  for (int k = 0; k < n; ++k) samples->poses(k, 0) = k;
  samples->cache_bounds();
  std::vector<hapsyn::MetricEntry> metrics = {{"sample_metric", std::make_shared<SampleMetric>(reduction, nan_at)}};
  hapsyn::Objective o;
  o.name = "m";
  return std::make_shared<hapsyn::Problem>("counting", std::make_shared<CountingMechanism>(counts), samples, metrics,
                                           std::vector<hapsyn::Objective>{o}, hapsyn::DesignSpace({c}));
}

// The reference: every sample evaluated on its own (a subset of one), as the outputs phase did
// before it took one pass.
inline hapsyn::SampleRecords records_one_by_one(const hapsyn::Problem& problem, const Eigen::VectorXd& full) {
  const int n = problem.samples().size();
  hapsyn::SampleRecords records;
  records.status.resize(static_cast<std::size_t>(n));
  records.has_locals.assign(static_cast<std::size_t>(n), 0);
  records.locals.setZero(n, 2);
  auto ws = problem.make_eval_scratch();
  std::vector<int> one(1);
  const hapsyn::SampleCallback record = [&](int sample, const hapsyn::SampleQuantities& q,
                                            const std::vector<std::vector<double>>& locals) {
    records.status[static_cast<std::size_t>(sample)] = hapsyn::to_string(q.status);
    records.locals(sample, 0) = locals[0][0];
    records.locals(sample, 1) = locals[0][1];
    records.has_locals[static_cast<std::size_t>(sample)] = 1;
  };
  hapsyn::EvalOptions options;
  options.subset = &one;
  options.on_sample = &record;
  Eigen::VectorXd free_design = full;  // every component is free
  for (int k = 0; k < n; ++k) {
    one[0] = k;
    const hapsyn::Evaluation& e = problem.evaluate(free_design.data(), *ws, options);
    if (!records.has_locals[static_cast<std::size_t>(k)]) {
      records.status[static_cast<std::size_t>(k)] = e.status == hapsyn::EvalStatus::kSampleFailed
                                                        ? hapsyn::to_string(e.failed_status)
                                                        : hapsyn::to_string(e.status);
    }
  }
  return records;
}

inline void expect_same_records(const hapsyn::SampleRecords& a, const hapsyn::SampleRecords& b) {
  ASSERT_EQ(a.status.size(), b.status.size());
  for (std::size_t i = 0; i < a.status.size(); ++i) {
    EXPECT_EQ(a.status[i], b.status[i]) << "sample " << i;
    ASSERT_EQ(a.has_locals[i], b.has_locals[i]) << "sample " << i;
    if (!a.has_locals[i]) continue;
    for (Eigen::Index c = 0; c < a.locals.cols(); ++c) {
      EXPECT_EQ(a.locals(static_cast<Eigen::Index>(i), c), b.locals(static_cast<Eigen::Index>(i), c)) << "sample " << i;
    }
  }
}

inline int count_failed(int n) {
  int failed = 0;
  for (int k = 0; k < n; ++k) failed += status_of(k) != SampleStatus::kReachable;
  return failed;
}

}  // namespace hapsyn::test
