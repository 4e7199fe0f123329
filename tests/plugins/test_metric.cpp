// A metric used only by the registry and evaluator tests; macros select how it misbehaves.
#include <hapsyn/plugin.hpp>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace {
#ifdef TEST_PLUGIN_OPTION_KINDS
// The kinds of option besides scalars and groups, loaded and created through the registry.
struct Stage {
  std::string kind;
  static void declare(hapsyn::OptionDeclarations<Stage>& d) {
    d.add(&Stage::kind, "kind", {}, "what the stage does").required();
  }
};
struct TestOptions {
  std::string label;
  std::optional<double> limit;
  std::vector<Stage> stages;
  hapsyn::Json extra;
  std::uint64_t seed{};
  static void declare(hapsyn::OptionDeclarations<TestOptions>& d) {
    d.add(&TestOptions::label, "label", {}, "a label").required();
    d.add(&TestOptions::limit, "limit", "a limit (default: none)");
    d.add(&TestOptions::stages, "stages", "the stages");
    d.add(&TestOptions::extra, "extra", "anything");
    d.add(&TestOptions::seed, "seed", 1, "a seed");
  }
};
#else
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
#endif

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
