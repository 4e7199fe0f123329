#pragma once
// Problems with known Pareto fronts, built in code (no plugin): a "mechanism" whose model hands
// the design to the metrics as q, and worst-case metrics given as functions of (design, sample).
// Used by the Pareto solver tests (nbi, weighted_sum) to check fronts against closed forms.
#include <hapsyn/problem.hpp>

#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace hapsyn::test {

/// Local value of one sample: f(design, pose).
using AnalyticLocal = std::function<double(const double* design, const double* pose)>;

class AnalyticMechanism : public Mechanism {
 public:
  explicit AnalyticMechanism(int n) : n_(n) {}
  class Model : public MechanismModel {
   public:
    Model(const double* design, int n) : design_(design, design + n) {}
    void solve(const double* pose, Needs, MechanismScratch&, SampleQuantities& out) const override {
      out.status = SampleStatus::kReachable;
      out.q.resize(static_cast<Eigen::Index>(design_.size()));
      for (std::size_t i = 0; i < design_.size(); ++i) out.q[static_cast<Eigen::Index>(i)] = design_[i];
    }

   private:
    std::vector<double> design_;
  };
  std::unique_ptr<const MechanismModel> build(const double* design) const override {
    return std::make_unique<Model>(design, n_);
  }
  MechanismSpecs specs() const override { return {kNeedJacobian, {}}; }

 private:
  int n_;
};

/// A worst-case metric: min over the samples of local(q, pose).
class AnalyticMetric : public Metric {
 public:
  explicit AnalyticMetric(AnalyticLocal local) : local_(std::move(local)) {}
  void local(const SampleQuantities& q, double* out) const override {
    out[0] = local_(q.q.data(), q.scene->pose(q.sample));
  }
  MetricSpecs specs() const override { return {kNeedPose, {}}; }

 private:
  AnalyticLocal local_;
};

/// A problem over design components named x0, x1, ... with the given bounds and grid step,
/// samples at the given 1-D poses, and one maximized objective per local function.
inline std::shared_ptr<Problem> analytic_problem(const std::vector<std::pair<double, double>>& bounds, double step,
                                                 const std::vector<double>& poses,
                                                 const std::vector<AnalyticLocal>& objectives) {
  std::vector<DesignComponent> components;
  for (std::size_t i = 0; i < bounds.size(); ++i) {
    DesignComponent c;
    c.name = c.variable = "x" + std::to_string(i);
    c.lower = bounds[i].first;
    c.upper = bounds[i].second;
    c.step = step;
    components.push_back(c);
  }
  auto samples = std::make_shared<SampleSet>();
  samples->coordinates = {"s"};
  samples->poses.resize(static_cast<Eigen::Index>(poses.size()), 1);
  for (std::size_t i = 0; i < poses.size(); ++i) samples->poses(static_cast<Eigen::Index>(i), 0) = poses[i];
  samples->cache_bounds();
  std::vector<MetricEntry> metrics;
  std::vector<Objective> objs;
  for (std::size_t i = 0; i < objectives.size(); ++i) {
    metrics.push_back({"f" + std::to_string(i + 1), std::make_shared<AnalyticMetric>(objectives[i])});
    Objective o;
    o.name = "f" + std::to_string(i + 1);
    o.metric = static_cast<int>(i);
    objs.push_back(o);
  }
  return std::make_shared<Problem>("analytic", std::make_shared<AnalyticMechanism>(static_cast<int>(bounds.size())),
                                   samples, metrics, objs, DesignSpace(components));
}

/// Two objectives, design (x0, x1) in [0, 1] x [-1, 1], samples s in {-1, 0, 1}:
///   f1 = x0 - 0.1 x1^2,   f2 = min_s h(x0) - 0.5 (x1 - 0.3 s)^2 = h(x0) - 0.5 (|x1| + 0.3)^2,
///   h(u) = 1 - u + 0.1 sin(2 pi u).
/// f2 has a kink at x1 = 0 (the critical sample switches), where both objectives peak, so the
/// front is x1 = 0: f2 = front_f2(f1) for f1 in [0, 1]; concave (weighted sums reach it) for
/// f1 < 0.5, convex (weighted sums miss it) for f1 > 0.5.
inline double two_objective_h(double u) { return 1.0 - u + 0.1 * std::sin(2.0 * M_PI * u); }
inline double two_objective_front_f2(double f1) { return two_objective_h(f1) - 0.5 * 0.09; }
inline std::shared_ptr<Problem> two_objective_problem(double step = 0.05) {
  return analytic_problem({{0.0, 1.0}, {-1.0, 1.0}}, step, {-1.0, 0.0, 1.0},
                          {[](const double* x, const double*) { return x[0] - 0.1 * x[1] * x[1]; },
                           [](const double* x, const double* s) {
                             return two_objective_h(x[0]) - 0.5 * (x[1] - 0.3 * s[0]) * (x[1] - 0.3 * s[0]);
                           }});
}

/// Three objectives (DTLZ2-like), design (a, b, r) in [0, 1]^3, one sample:
///   f = (1 - 0.5 r) (cos(a pi/2) cos(b pi/2), cos(a pi/2) sin(b pi/2), sin(a pi/2)).
/// The front is the unit sphere's positive octant (r = 0): |f| = 1.
inline std::shared_ptr<Problem> three_objective_problem(double step = 0.05) {
  const double h = M_PI / 2;
  return analytic_problem(
      {{0.0, 1.0}, {0.0, 1.0}, {0.0, 1.0}}, step, {0.0},
      {[h](const double* x, const double*) { return (1 - 0.5 * x[2]) * std::cos(h * x[0]) * std::cos(h * x[1]); },
       [h](const double* x, const double*) { return (1 - 0.5 * x[2]) * std::cos(h * x[0]) * std::sin(h * x[1]); },
       [h](const double* x, const double*) { return (1 - 0.5 * x[2]) * std::sin(h * x[0]); }});
}

}  // namespace hapsyn::test
