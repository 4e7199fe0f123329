// A metric used only by the registry and evaluator tests; macros select how it misbehaves.
#include <hapsyn/plugin.hpp>

#include <limits>
#include <stdexcept>

namespace {
class TestMetric : public hapsyn::Metric {
 public:
  explicit TestMetric(const hapsyn::Json&) {
#ifdef TEST_PLUGIN_THROWS
    throw std::runtime_error("deliberate failure in the factory");
#endif
  }
#ifdef TEST_PLUGIN_SUM
  // An averaging metric: reduced by a sum.
  std::vector<hapsyn::LocalValue> locals() const override { return {{"one", hapsyn::Reduction::kSum, ""}}; }
#endif
  void local(const hapsyn::SampleQuantities&, double* out) const override {
#ifdef TEST_PLUGIN_NAN
    out[0] = std::numeric_limits<double>::quiet_NaN();
#else
    out[0] = 1.0;
#endif
  }
};
}  // namespace

HAPSYN_METRIC_PLUGIN(TestMetric, TEST_PLUGIN_NAME, "0.0.1", "test metric")
