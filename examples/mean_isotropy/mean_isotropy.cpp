// mean_isotropy: an example hapsyn metric plugin built out of tree (see README.md).
//
// The averaging counterpart of the worst-case global isotropy index (GII):
//
//   mean_isotropy = (1 / N_r) * sum over reachable samples of (sigma_min(J) / sigma_max(J))^e
//
// J the mechanism's task Jacobian at the sample, N_r the number of reachable samples and
// e the "exponent" option. Dimensionless, in [0, 1]; 0 when no sample is reachable.
//
// How it maps onto hapsyn::Metric: two local values, both reduced by sum over the samples,
//   out[0] "isotropy"  = (sigma_min / sigma_max)^e at a reachable sample, else 0
//   out[1] "reachable" = 1 at a reachable sample, else 0
// and combine() divides the first sum by the second. Because every reduction is a sum, the
// metric's aggregation is kAveraging (the default rule of Metric::aggregation()), so the
// framework passes unreachable / singular / invalid samples to local() as well, with
// q.status telling which; their Jacobian is not meaningful and must not be read.
#include <hapsyn/plugin.hpp>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace mean_isotropy_example {

using hapsyn::LocalValue;
using hapsyn::Needs;
using hapsyn::Reduction;
using hapsyn::SampleQuantities;
using hapsyn::SampleStatus;
using hapsyn::TaskJointMatrix;

/// The options, declared once: the framework derives the schema from this (`hapsyn describe
/// mean_isotropy`), checks the problem file against it (unknown keys, types, the minimum) and
/// fills the struct before the constructor runs. Member initialisers stay `{}`: the declared
/// default is the only one.
struct MeanIsotropyOptions {
  double exponent{};

  static void declare(hapsyn::OptionDeclarations<MeanIsotropyOptions>& d) {
    d.describe(
        "Mean isotropy: the average over the reachable samples of (sigma_min(J) / sigma_max(J))^exponent, J the "
        "task Jacobian (averaging counterpart of the worst-case GII). Unreachable, singular and invalid samples "
        "are left out of the average; 0 when no sample is reachable. Dimensionless, in [0, 1].");
    d.add(&MeanIsotropyOptions::exponent, "exponent", 1.0,
          "Each sample contributes (sigma_min / sigma_max)^exponent; 1 averages the inverse condition number "
          "itself, larger values penalise poorly conditioned samples more.")
        .minimum(0.1);
  }
};

/// The "mean_isotropy" metric. Thread safety: immutable after construction; local() is
/// const, allocation-free and safe to call from several threads at once.
class MeanIsotropy final : public hapsyn::Metric {
 public:
  using Options = MeanIsotropyOptions;
  /// \param options validated against the declarations, defaults filled in by the framework
  ///        (in a test: hapsyn::make_options<MeanIsotropyOptions>(json)).
  explicit MeanIsotropy(const MeanIsotropyOptions& options) : exponent_(options.exponent) {}

  void local(const SampleQuantities& q, double* out) const override {
    if (q.status != SampleStatus::kReachable) {
      out[0] = 0.0;  // contributes to neither the sum nor the count
      out[1] = 0.0;
      return;
    }
    const double ratio = isotropy(q.jacobian);
    out[0] = exponent_ == 1.0 ? ratio : std::pow(ratio, exponent_);
    out[1] = 1.0;
  }

  hapsyn::MetricSpecs specs() const override { return {hapsyn::kNeedJacobian, {}}; }

  std::vector<LocalValue> locals() const override {
    return {LocalValue{"isotropy", Reduction::kSum, ""}, LocalValue{"reachable", Reduction::kSum, ""}};
  }

  /// reduced[0] / reduced[1]: the mean over reachable samples; 0 when none is reachable.
  double combine(const double* reduced, int /*samples*/) const override {
    return reduced[1] > 0.0 ? reduced[0] / reduced[1] : 0.0;
  }

  /// sigma_min(J) / sigma_max(J) in [0, 1]; 0 for a zero, empty or non-finite Jacobian
  /// (never NaN). No heap allocation: the SVDs work on fixed-capacity matrices.
  static double isotropy(const TaskJointMatrix& j) {
    if (j.rows() == 0 || j.cols() == 0 || !j.allFinite()) return 0.0;
    double sigma_min = 0.0;
    double sigma_max = 0.0;
    if (j.rows() == 2 && j.cols() == 2) {
      const Eigen::Matrix2d m = j;  // fixed 2 x 2 copy
      const Eigen::Vector2d s = Eigen::JacobiSVD<Eigen::Matrix2d>(m).singularValues();
      sigma_max = s(0);
      sigma_min = s(1);
    } else {
      const Eigen::JacobiSVD<TaskJointMatrix> svd(j);
      const auto& s = svd.singularValues();
      sigma_max = s(0);
      sigma_min = s(s.size() - 1);
    }
    if (!(sigma_max > 0.0) || !std::isfinite(sigma_max)) return 0.0;
    return std::clamp(sigma_min / sigma_max, 0.0, 1.0);
  }

 private:
  double exponent_;
};

}  // namespace mean_isotropy_example

HAPSYN_METRIC_PLUGIN(mean_isotropy_example::MeanIsotropy, "mean_isotropy", "1.0.0",
                     "Mean isotropy: average over reachable samples of (sigma_min(J) / sigma_max(J))^exponent")
