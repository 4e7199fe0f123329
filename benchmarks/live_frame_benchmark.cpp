// LIBRARIES: hapsyn_view_prototype
// The virtual prototype's live frame (`hapsyn view`, WebSocket /live; docs/virtual-prototype.md):
// the server's time to answer one pose message of the shipped motion study
// (problems/haptic6r-motion-validation.json), i.e. what a tracker streaming at 120 Hz asks of it.
//   BM_LiveFrame        -- the whole answer: parse the message, keep the window, filter and
//                          differentiate the last 2 s of poses (motion_signal), IK, joint rates,
//                          full inverse dynamics, motion_feasibility's values, the drawing, the
//                          JSON frame; with the window full (240 poses at 120 Hz).
//   BM_LiveFramePoseOnly -- the same before the window holds the filter's minimum (IK and drawing,
//                          no rates): what the derivatives and dynamics add.
// Counter: frames_per_s (the rate one server thread sustains).
#include "common.hpp"

#include <live_session.hpp>
#include <view_source.hpp>

#include <hapsyn/data_file.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/study.hpp>

#include <benchmark/benchmark.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace {

const std::string kProblem = std::string(HAPSYN_SOURCE_DIR) + "/problems/haptic6r-motion-validation.json";

hapsyn::Registry& registry() {
  static hapsyn::Registry r({HAPSYN_PLUGIN_DIR});
  return r;
}

// The study (its design: every variable fixed) and the first recording's poses as messages.
struct Fixture {
  std::shared_ptr<const hapsyn_cli::ViewSource> source;
  std::vector<double> time;
  std::vector<std::string> poses;  // the message bodies without "t"
  double duration = 0.0;
};

const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture out;
    hapsyn::Json doc = hapsyn::read_problem_file(kProblem);
    const hapsyn::ProblemDirectoryScope scope(kProblem);
    auto source = std::make_shared<hapsyn_cli::ViewSource>(
        hapsyn_cli::ViewSource{hapsyn::load_study(doc, registry()), {}, "problem file", {}});
    source->design = source->study.problem->full_design(nullptr);
    const hapsyn::SampleSet& samples = source->study.problem->samples();
    const auto& shoulder = samples.attributes.at("shoulder_pose");
    const auto& time = samples.attributes.at("time");
    for (int i = 0; i < samples.size() && (i == 0 || time(i, 0) > time(i - 1, 0)); ++i) {
      const hapsyn::Json pose = {{"position", {shoulder(i, 0), shoulder(i, 1), shoulder(i, 2)}},
                                 {"orientation", {shoulder(i, 3), shoulder(i, 4), shoulder(i, 5), shoulder(i, 6)}}};
      out.time.push_back(time(i, 0));
      out.poses.push_back(pose.dump());
    }
    out.duration = out.time.back() - out.time.front() + (out.time[1] - out.time[0]);
    out.source = std::move(source);
    return out;
  }();
  return f;
}

// The message of pose k of an endless stream (the recording repeated, time stamps increasing).
std::string message(const Fixture& f, long long k) {
  const std::size_t n = f.poses.size();
  const double t = f.time[static_cast<std::size_t>(k) % n] + static_cast<double>(k / static_cast<long long>(n)) * f.duration;
  std::string body = f.poses[static_cast<std::size_t>(k) % n];
  return "{\"t\":" + std::to_string(t) + "," + body.substr(1);
}

void BM_LiveFrame(benchmark::State& state) {
  const Fixture& f = fixture();
  const hapsyn_cli::LiveModel model(f.source);
  std::optional<hapsyn_cli::LiveSession> session;
  std::vector<std::string> messages;
  // A stream whose window is full (2 s at 120 Hz), and its next 4096 messages.
  const auto restart = [&] {
    session.emplace(model);
    for (long long j = 0; j < 240; ++j) session->answer(message(f, j));
    messages.clear();
    for (long long j = 0; j < 4096; ++j) messages.push_back(message(f, 240 + j));
  };
  restart();
  std::size_t next = 0;
  bool frames = true;
  for (auto _ : state) {
    bool is_frame = false;
    benchmark::DoNotOptimize(session->answer(messages[next], &is_frame));
    frames = frames && is_frame;
    if (++next == messages.size()) {  // a new stream: the time stamps would repeat
      state.PauseTiming();
      restart();
      next = 0;
      state.ResumeTiming();
    }
  }
  if (!frames) state.SkipWithError("a message was answered with an error frame");
  state.counters["frames_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_LiveFrame)->Unit(benchmark::kMicrosecond)->UseRealTime();

void BM_LiveFramePoseOnly(benchmark::State& state) {
  const Fixture& f = fixture();
  const hapsyn_cli::LiveModel model(f.source);
  long long k = 0;
  for (auto _ : state) {
    state.PauseTiming();
    hapsyn_cli::LiveSession session(model);  // an empty window: no rates
    const std::string m = message(f, k++ % static_cast<long long>(f.poses.size()));
    state.ResumeTiming();
    benchmark::DoNotOptimize(session.answer(m));
  }
  state.counters["frames_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_LiveFramePoseOnly)->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  hapsyn::bench::record_context(hapsyn::read_problem_file(kProblem));
  return hapsyn::bench::run_main(argc, argv);
}
