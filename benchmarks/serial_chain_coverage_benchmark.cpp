// LIBRARIES: hapsyn_serial_chain_model orocos-kdl
//
// Coverage per design of a UR-class arm read from a URDF (share/serial_chain/ur5_like.urdf, the
// mechanism options of problems/ur5like-coverage-ga.json at the file's design) on the paper's
// human-arm workspace (0.1 m lattice, 505 orientations, 17 joint-3 steps: 34,548 poses; the scene
// is cached on disk after the first build), the four-term objective J through the framework's
// evaluator on 2 threads, with serial_chain's closed-form IK (ik.solver closed_form) and its
// numerical IK (ik.solver numerical, 8 restarts, closest to home), against the haptic6r
// mechanism's own closed form on the same workspace (problems/haptic6r-evaluate.json's design),
// all in the same run. Also the IK alone per pose on the same arm (chain_ik.hpp and
// chain_closed_form_ik.hpp, single thread, 1,000 poses from random in-limit configurations):
// closed form (all solutions, closest to home) against the numerical IK (home + 8 restarts,
// closest to home; and first found) and KDL's Levenberg-Marquardt position IK
// (ChainIkSolverPos_LMA, from home, pose tolerance 1e-10) on the same chain and targets. Read
// the ratios printed at the end, not bare times.
#include "common.hpp"
#include "kdl_chain.hpp"

#include <chain_closed_form_ik.hpp>
#include <chain_ik.hpp>
#include <chain_template.hpp>

#include <hapsyn/problem.hpp>
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/study.hpp>

#include <benchmark/benchmark.h>

#include <kdl/chainiksolverpos_lma.hpp>

#include <map>
#include <string>
#include <vector>

namespace {

using hapsyn::Json;

constexpr int kThreads = 2;

hapsyn::Registry& registry() {
  static hapsyn::Registry r({HAPSYN_PLUGIN_DIR});
  return r;
}

const char* kScene = R"("scene": {"plugin": "human_arm", "options": {"lattice_step": 0.1, "orientations": 505, "joint3_steps": 17}},
    "objectives": [{"metric": "coverage"}], "solver": {"plugin": "evaluate"})";

const hapsyn::Problem& ur_study(const std::string& solver) {
  static std::map<std::string, hapsyn::Study> studies;
  auto it = studies.find(solver);
  if (it == studies.end()) {
    Json doc = Json::parse(std::string(R"({"name": "bench-ur", "mechanism": {"plugin": "serial_chain", "options": {
      "urdf": "serial_chain/ur5_like.urdf", "base_link": "base_link", "tip_link": "tool0",
      "base_xyz": [0.2, -0.1, -0.1], "base_rpy": [180, 0, 0], "home": [0, -90, 90, -90, -90, 0]}},)") + kScene + "}");
    doc["mechanism"]["options"]["ik"]["solver"] = solver;
    it = studies.emplace(solver, hapsyn::load_study(doc, registry())).first;
  }
  return *it->second.problem;
}

const hapsyn::Problem& haptic6r_study() {
  static hapsyn::Study study = hapsyn::load_study(
      Json::parse(std::string(R"({"name": "bench-haptic6r", "mechanism": {"plugin": "haptic6r", "options": {"selection": "closest_to_home"}},
    "design": {"l": {"value": [0.45, 0.45, 0.65, 0.55, 0.15]}, "s": {"value": [3, 3, 2, 2, 1, 1]}, "r": {"value": [2, 2, 3, 2, 3, 3]}},)") +
                  kScene + "}"),
      registry());
  return *study.problem;
}

void run(benchmark::State& state, const hapsyn::Problem& problem) {
  double j = 0.0;
  for (auto _ : state) j = problem.evaluate_parallel(nullptr, kThreads).objectives[0];
  state.counters["J"] = j;
  state.counters["poses"] = problem.samples().size();
}

void BM_Haptic6RCoveragePerDesign(benchmark::State& state) { run(state, haptic6r_study()); }
void BM_UrUrdfClosedFormCoveragePerDesign(benchmark::State& state) { run(state, ur_study("closed_form")); }
void BM_UrUrdfNumericalCoveragePerDesign(benchmark::State& state) { run(state, ur_study("numerical")); }

// ur5_like.urdf at its file's values, and 1,000 targets from random in-limit configurations.
struct IkCase {
  hapsyn::plugins::Chain chain;
  std::vector<Eigen::Isometry3d> targets;
  std::vector<double> home{0.0, -1.5707963267948966, 1.5707963267948966, -1.5707963267948966, -1.5707963267948966, 0.0};
};

const IkCase& ik_case() {
  static const IkCase c = [] {
    IkCase k;
    const auto t = hapsyn::plugins::ChainTemplate::from_urdf(std::string(HAPSYN_SOURCE_DIR) + "/share/serial_chain/ur5_like.urdf",
                                                             "base_link", "tool0");
    std::vector<double> values;
    for (const auto& p : t.parameters()) values.push_back(p.nominal);
    t.instantiate(values.data(), nullptr, k.chain);
    std::vector<double> q(6);
    for (int i = 0; i < 1000; ++i) {
      hapsyn::plugins::ik_random_start(k.chain, 4242, i, q.data());
      hapsyn::plugins::ChainFrames f;
      hapsyn::plugins::chain_frames(k.chain, q.data(), f);
      k.targets.push_back(f.tip);
    }
    return k;
  }();
  return c;
}

// Per pose: the IK alone. Counter "solved": the share of poses solved inside the limits.
void BM_UrIkClosedFormPerPose(benchmark::State& state) {
  const IkCase& c = ik_case();
  const hapsyn::plugins::ChainClosedFormIk ik(c.chain);
  hapsyn::plugins::ClosedFormScratch scratch;
  double q[6];
  std::size_t k = 0;
  long solved = 0;
  for (auto _ : state) {
    solved += ik.solve(c.chain, c.targets[k], c.home.data(), false, q, scratch) == hapsyn::plugins::IkStatus::kConverged;
    k = (k + 1) % c.targets.size();
  }
  state.counters["solved"] = static_cast<double>(solved) / static_cast<double>(state.iterations());
}

void BM_UrIkNumericalPerPose(benchmark::State& state) {
  const IkCase& c = ik_case();
  const bool first_found = state.range(0) != 0;
  hapsyn::plugins::IkScratch scratch;
  const hapsyn::plugins::IkSettings settings;
  const double* starts[] = {c.home.data()};
  double q[6];
  std::size_t k = 0;
  long solved = 0;
  for (auto _ : state) {
    solved += hapsyn::plugins::solve_ik(c.chain, hapsyn::plugins::IkTask{}, settings, c.targets[k], starts, 1, c.home.data(),
                                       first_found, q, scratch) == hapsyn::plugins::IkStatus::kConverged;
    k = (k + 1) % c.targets.size();
  }
  state.counters["solved"] = static_cast<double>(solved) / static_cast<double>(state.iterations());
}

// KDL's LMA from home. Counter "solved": the share of poses it reports solved (error < 1e-10).
void BM_UrIkKdlLmaPerPose(benchmark::State& state) {
  const IkCase& c = ik_case();
  const KDL::Chain chain = hapsyn::bench::to_kdl(c.chain);
  KDL::ChainIkSolverPos_LMA solver(chain, 1e-10, 500, 1e-15);
  KDL::JntArray home(6), q(6);
  for (int i = 0; i < 6; ++i) home(static_cast<unsigned>(i)) = c.home[static_cast<std::size_t>(i)];
  std::vector<KDL::Frame> targets;
  for (const Eigen::Isometry3d& t : c.targets) targets.push_back(hapsyn::bench::to_kdl(t));
  std::size_t k = 0;
  long solved = 0;
  for (auto _ : state) {
    solved += solver.CartToJnt(home, targets[k], q) >= 0;
    k = (k + 1) % targets.size();
  }
  state.counters["solved"] = static_cast<double>(solved) / static_cast<double>(state.iterations());
}

}  // namespace

BENCHMARK(BM_UrIkClosedFormPerPose)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_UrIkNumericalPerPose)->ArgName("first_found")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_UrIkKdlLmaPerPose)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Haptic6RCoveragePerDesign)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_UrUrdfClosedFormCoveragePerDesign)->Unit(benchmark::kMillisecond)->UseRealTime();
// About 5 s per design: one evaluation.
BENCHMARK(BM_UrUrdfNumericalCoveragePerDesign)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

int main(int argc, char** argv) {
  hapsyn::bench::record_context(Json{{"mechanism", "serial_chain ur5_like.urdf / haptic6r"}, {"metric", "coverage (J)"},
                                     {"scene", "human_arm 0.1 m, 505 orientations, 17 joint-3 steps"},
                                     {"threads", kThreads}});
  hapsyn::bench::compare("BM_UrUrdfClosedFormCoveragePerDesign/real_time", "BM_UrUrdfNumericalCoveragePerDesign/iterations:1/real_time");
  hapsyn::bench::compare("BM_Haptic6RCoveragePerDesign/real_time", "BM_UrUrdfClosedFormCoveragePerDesign/real_time");
  hapsyn::bench::compare("BM_UrIkClosedFormPerPose", "BM_UrIkNumericalPerPose/first_found:0");
  hapsyn::bench::compare("BM_UrIkClosedFormPerPose", "BM_UrIkNumericalPerPose/first_found:1");
  hapsyn::bench::compare("BM_UrIkClosedFormPerPose", "BM_UrIkKdlLmaPerPose");
  return hapsyn::bench::run_main(argc, argv);
}
