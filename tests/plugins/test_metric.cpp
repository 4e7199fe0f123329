// A metric used only by the registry and evaluator tests; macros select how it misbehaves.
#include <hapsyn/plugin.hpp>

#include <atomic>
#include <chrono>
#include <limits>
#include <stdexcept>
#include <thread>

namespace {
struct TestOptions {
  double x{};
  static void declare(hapsyn::OptionDeclarations<TestOptions>& d) {
#ifdef TEST_PLUGIN_BAD_DECLARATION
    // A default its own rule refuses: the registry must refuse the plugin when loading it.
    d.add(&TestOptions::x, "x", -1.0, "a number that must not be negative").minimum(0);
#else
    d.add(&TestOptions::x, "x", 0.0, "unused");
#endif
  }
};

class TestMetric : public hapsyn::Metric {
 public:
  using Options = TestOptions;
#ifdef TEST_PLUGIN_SERIALIZED
  static constexpr hapsyn::ThreadSafety thread_safety = hapsyn::ThreadSafety::kSerialized;
#endif
  explicit TestMetric(const TestOptions&) {
#ifdef TEST_PLUGIN_THROWS
    throw std::runtime_error("deliberate failure in the factory");
#endif
  }
#ifdef TEST_PLUGIN_SUM
  // An averaging metric: reduced by a sum.
  std::vector<hapsyn::LocalValue> locals() const override { return {{"one", hapsyn::Reduction::kSum, ""}}; }
#endif
  void local(const hapsyn::SampleQuantities&, double* out) const override {
#ifdef TEST_PLUGIN_OVERLAP
    // Reports 0 once two calls of local() have ever overlapped in time, else 1.
    static std::atomic<int> inside{0};
    static std::atomic<bool> overlapped{false};
    if (inside.fetch_add(1) > 0) overlapped = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    inside.fetch_sub(1);
    out[0] = overlapped ? 0.0 : 1.0;
    return;
#endif
#ifdef TEST_PLUGIN_NAN
    out[0] = std::numeric_limits<double>::quiet_NaN();
#else
    out[0] = 1.0;
#endif
  }
};
}  // namespace

HAPSYN_METRIC_PLUGIN(TestMetric, TEST_PLUGIN_NAME, "0.0.1", "test metric")
