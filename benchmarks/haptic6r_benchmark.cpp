// LIBRARIES: hapsyn_haptic6r_model hapsyn_coverage_model hapsyn_human_arm_model orocos-kdl
//
// Cost of the haptic6r + coverage study (Fennel 2022) at the paper's resolution (0.1 m lattice,
// 505 orientations, 17 joint-3 steps: ~35k human poses; the scene is cached on disk after the
// first build), for one plausible design, single thread unless stated:
//   per pose, IK + the quantities + coverage local() for the terms
//     pose only | pose + velocity | + acceleration | + force (all four)
//   the same four terms on the block path (solve_block + local_block, 8 samples per call)
//   one full four-term design evaluation through Problem::evaluate_parallel (1 and 2 threads,
//   block path, M_v and M_a from the evaluator's block copy), with M_v and M_a gathered lane by
//   lane (1 thread), and through the per-sample loop (1 thread)  [ms/design]
//   the GA study's four one-term coverage objectives per design (1 and 2 threads)
//   per configuration: J, H, gravity and the 6-column solve J^-1 M_a, ours (scalar and block) vs KDL's
//     ChainJntToJacSolver + ChainDynParam (JntToMass, JntToGravity) + Eigen LU on the same q
// Read the ratios printed at the end (same run, same machine), not bare times.
#include "common.hpp"

#include <coverage.hpp>
#include <haptic6r.hpp>
#include <human_arm.hpp>

#include <hapsyn/accel/mechanism_acceleration.hpp>
#include <hapsyn/accel/metric_acceleration.hpp>
#include <hapsyn/accel/vector_dispatch.hpp>
#include <hapsyn/problem.hpp>
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/study.hpp>

#include <benchmark/benchmark.h>
#include <kdl/chain.hpp>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainjnttojacsolver.hpp>

#include <Eigen/LU>
#include <map>
#include <utility>
#include <vector>

namespace {

using hapsyn::Json;
using hapsyn::SampleQuantities;
using hapsyn::SampleSet;
using namespace hapsyn::plugins;

const std::vector<double> kDesign{0.45, 0.45, 0.65, 0.55, 0.15, 3, 3, 2, 2, 1, 1, 2, 2, 3, 2, 3, 3};

const SampleSet& scene() {
  static const SampleSet set = [] {
    hapsyn::SceneRequest request;
    request.attributes = {"M_v", "M_a"};
    return HumanArmScene(hapsyn::make_options<HumanArmOptions>(
                             Json{{"lattice_step", 0.1}, {"orientations", 505}, {"joint3_steps", 17}}))
        .build(request);
  }();
  return set;
}

const Haptic6R& mechanism() {
  static const Haptic6R m(hapsyn::default_options<Haptic6ROptions>());  // plugins are not copyable
  static const bool checked = (m.check_scene(scene()), true);
  (void)checked;
  return m;
}

const Haptic6RModel& model() {
  static const std::unique_ptr<const hapsyn::MechanismModel> m = mechanism().build(kDesign.data());
  return static_cast<const Haptic6RModel&>(*m);
}

void run_terms(benchmark::State& state, const Json& terms) {
  const Coverage metric(hapsyn::make_options<CoverageOptions>(Json{{"terms", terms}}));
  const SampleSet& s = scene();
  const Haptic6RModel& m = model();
  auto scratch = mechanism().make_scratch();
  SampleQuantities q;
  // The metric reads the sample's M_v / M_a through these, resolved once as the evaluator does.
  q.scene = &s;
  std::vector<const hapsyn::AttributeMatrix*> attributes;
  for (const std::string& name : metric.scene_attributes()) attributes.push_back(&s.attributes.at(name));
  q.attributes = attributes.data();
  q.attribute_count = static_cast<int>(attributes.size());
  std::vector<double> out(metric.locals().size());
  double sum = 0.0;
  for (auto _ : state) {
    for (int i = 0; i < s.size(); ++i) {
      q.sample = i;
      m.solve(s.pose(i), metric.needs(), *scratch, q);
      metric.local(q, out.data());
      sum += out[1];
    }
  }
  benchmark::DoNotOptimize(sum);
  state.counters["poses"] = s.size();
  state.counters["per_pose"] = benchmark::Counter(static_cast<double>(s.size()) * static_cast<double>(state.iterations()),
                                                  benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["poses_per_s"] = benchmark::Counter(static_cast<double>(s.size()) * static_cast<double>(state.iterations()),
                                                     benchmark::Counter::kIsRate);
}

void BM_CoveragePoseOnly(benchmark::State& state) { run_terms(state, Json::array({"pose"})); }
void BM_CoveragePoseVelocity(benchmark::State& state) { run_terms(state, Json::array({"pose", "velocity"})); }
void BM_CoveragePoseVelocityAcceleration(benchmark::State& state) {
  run_terms(state, Json::array({"pose", "velocity", "acceleration"}));
}
void BM_CoverageAllFourTerms(benchmark::State& state) {
  run_terms(state, Json::array({"pose", "velocity", "acceleration", "force"}));
}

// The same four terms on the block path: solve_block + local_block per 8 samples, scene order,
// the poses laid out as the evaluator lays them out (structure of arrays, once).
void BM_CoverageAllFourTermsBlock(benchmark::State& state) {
  const Coverage metric(hapsyn::make_options<CoverageOptions>(Json::object()));
  const SampleSet& s = scene();
  const Haptic6RModel& m = model();
  auto scratch = mechanism().make_scratch();
  const int n = s.size();
  const int padded = (n + hapsyn::kBlockLanes - 1) / hapsyn::kBlockLanes * hapsyn::kBlockLanes;
  std::vector<double> poses(static_cast<std::size_t>(7 * padded));
  for (int i = 0; i < padded; ++i) {
    for (int c = 0; c < 7; ++c) poses[static_cast<std::size_t>(c * padded + i)] = s.pose(std::min(i, n - 1))[c];
  }
  std::vector<const hapsyn::AttributeMatrix*> attributes;
  for (const std::string& name : metric.scene_attributes()) attributes.push_back(&s.attributes.at(name));
  auto q = std::make_unique<hapsyn::QuantityBlock>();
  q->attributes = attributes.data();
  q->attribute_count = static_cast<int>(attributes.size());
  std::vector<double> out(metric.locals().size() * hapsyn::kBlockLanes);
  double sum = 0.0;
  for (auto _ : state) {
    for (int first = 0; first < n; first += hapsyn::kBlockLanes) {
      hapsyn::PoseBlock block;
      block.dimension = 7;
      block.count = std::min(hapsyn::kBlockLanes, n - first);
      for (int c = 0; c < 7; ++c) block.coordinate[c] = poses.data() + static_cast<std::size_t>(c * padded + first);
      for (int lane = 0; lane < hapsyn::kBlockLanes; ++lane) q->samples[lane] = first + std::min(lane, block.count - 1);
      m.solve_block(block, metric.needs(), *scratch, *q);
      metric.local_block(*q, out.data());
      for (int lane = 0; lane < block.count; ++lane) sum += out[static_cast<std::size_t>(hapsyn::kBlockLanes + lane)];
    }
  }
  benchmark::DoNotOptimize(sum);
  state.counters["poses"] = n;
  state.counters["per_pose"] = benchmark::Counter(static_cast<double>(n) * static_cast<double>(state.iterations()),
                                                  benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// BM_CoverageAllFourTermsBlock with the block kernels compiled for one instruction set
// (hapsyn/accel/vector_dispatch.hpp; 0 = SSE2, 1 = AVX2, 2 = AVX-512), as on a CPU whose widest
// it is: the kernels' cost per instruction set on this machine.
void BM_CoverageAllFourTermsBlockOnTarget(benchmark::State& state) {
  const auto target = static_cast<hapsyn::VectorTarget>(state.range(0));
  if (!hapsyn::vector_target_available(target)) {
    state.SkipWithError("this CPU lacks the instruction set");
    return;
  }
  state.SetLabel(hapsyn::vector_target_name(target));
  hapsyn::force_vector_target(target);
  BM_CoverageAllFourTermsBlock(state);
  hapsyn::force_vector_target(std::nullopt);
}

hapsyn::Study& full_study() {
  static hapsyn::Registry registry({HAPSYN_PLUGIN_DIR});
  static hapsyn::Study study = hapsyn::load_study(Json::parse(R"({
    "name": "bench", "mechanism": {"plugin": "haptic6r"},
    "scene": {"plugin": "human_arm", "options": {"lattice_step": 0.1, "orientations": 505, "joint3_steps": 17}},
    "design": {"l": {"value": [0.45, 0.45, 0.65, 0.55, 0.15]}, "s": {"value": [3, 3, 2, 2, 1, 1]}, "r": {"value": [2, 2, 3, 2, 3, 3]}},
    "objectives": [{"metric": "coverage"}], "solver": {"plugin": "evaluate"}})"), registry);
  return study;
}

// The full objective J through the framework's evaluator, as a solver sees it (the block path:
// docs/design.md section 14).
void BM_FullObjectivePerDesign(benchmark::State& state) {
  const hapsyn::Study& study = full_study();
  const int threads = static_cast<int>(state.range(0));
  double j = 0.0;
  for (auto _ : state) j += study.problem->evaluate_parallel(nullptr, threads).objectives[0];
  benchmark::DoNotOptimize(j);
  state.counters["poses"] = study.problem->samples().size();
}

// The GA study's objectives (problems/haptic6r-ga-paper.json): J_x, J_v, J_a, J_f as four
// one-term coverage objectives, as a GA evaluates each design (1 and 2 threads, block path).
void BM_GaObjectivesPerDesign(benchmark::State& state) {
  static hapsyn::Registry registry({HAPSYN_PLUGIN_DIR});
  static hapsyn::Study study = hapsyn::load_study(Json::parse(R"({
    "name": "bench-ga", "mechanism": {"plugin": "haptic6r"},
    "scene": {"plugin": "human_arm", "options": {"lattice_step": 0.1, "orientations": 505, "joint3_steps": 17}},
    "design": {"l": {"value": [0.45, 0.45, 0.65, 0.55, 0.15]}, "s": {"value": [3, 3, 2, 2, 1, 1]}, "r": {"value": [2, 2, 3, 2, 3, 3]}},
    "objectives": [{"metric": "coverage", "name": "J_x", "options": {"terms": ["pose"]}},
                   {"metric": "coverage", "name": "J_v", "options": {"terms": ["velocity"]}},
                   {"metric": "coverage", "name": "J_a", "options": {"terms": ["acceleration"]}},
                   {"metric": "coverage", "name": "J_f", "options": {"terms": ["force"]}}],
    "solver": {"plugin": "evaluate"}})"), registry);
  const int threads = static_cast<int>(state.range(0));
  double j = 0.0;
  for (auto _ : state) j += study.problem->evaluate_parallel(nullptr, threads).objectives[1];
  benchmark::DoNotOptimize(j);
  state.counters["poses"] = study.problem->samples().size();
}

// Scaling: the full objective of the same design against the scene's lattice step [mm] and
// orientation count, on 1 and 2 threads (block path). Each scene is built once (and cached on
// disk by the human_arm scene, like any study's).
void BM_FullObjectiveScaling(benchmark::State& state) {
  static hapsyn::Registry registry({HAPSYN_PLUGIN_DIR});
  static std::map<std::pair<long, long>, hapsyn::Study> studies;
  const long step_mm = static_cast<long>(state.range(0)), orientations = static_cast<long>(state.range(1));
  auto it = studies.find({step_mm, orientations});
  if (it == studies.end()) {
    Json doc = Json::parse(R"({
      "name": "bench-scaling", "mechanism": {"plugin": "haptic6r"},
      "scene": {"plugin": "human_arm", "options": {"joint3_steps": 17}},
      "design": {"l": {"value": [0.45, 0.45, 0.65, 0.55, 0.15]}, "s": {"value": [3, 3, 2, 2, 1, 1]}, "r": {"value": [2, 2, 3, 2, 3, 3]}},
      "objectives": [{"metric": "coverage"}], "solver": {"plugin": "evaluate"}})");
    doc["scene"]["options"]["lattice_step"] = static_cast<double>(step_mm) / 1000.0;
    doc["scene"]["options"]["orientations"] = orientations;
    it = studies.emplace(std::make_pair(step_mm, orientations), hapsyn::load_study(doc, registry)).first;
  }
  const hapsyn::Problem& problem = *it->second.problem;
  const int threads = static_cast<int>(state.range(2));
  double j = 0.0;
  for (auto _ : state) j += problem.evaluate_parallel(nullptr, threads).objectives[0];
  benchmark::DoNotOptimize(j);
  state.counters["poses"] = problem.samples().size();
  state.counters["per_pose"] = benchmark::Counter(static_cast<double>(problem.samples().size()) * static_cast<double>(state.iterations()),
                                                     benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// The same evaluation, one thread, with the scene attributes M_v and M_a gathered lane by lane
// from their rows instead of read from the evaluator's block copy: the samples in the study's
// order rotated by one (not a run of whole blocks, so the block path gathers; the same samples
// and work, the sums in another order).
void BM_FullObjectivePerDesignGathered(benchmark::State& state) {
  const hapsyn::Study& study = full_study();
  auto ws = study.problem->make_eval_scratch();
  std::vector<int> rotated = study.problem->sample_order();
  std::rotate(rotated.begin(), rotated.begin() + 1, rotated.end());
  hapsyn::EvalOptions options;
  options.subset = &rotated;
  double j = 0.0;
  for (auto _ : state) j += study.problem->evaluate(nullptr, *ws, options).objectives[0];
  benchmark::DoNotOptimize(j);
  state.counters["poses"] = study.problem->samples().size();
}

// The baseline: the same evaluation, one thread, forced onto the per-sample loop.
void BM_FullObjectivePerDesignPerSample(benchmark::State& state) {
  const hapsyn::Study& study = full_study();
  auto ws = study.problem->make_eval_scratch();
  hapsyn::EvalOptions options;
  options.per_sample = true;
  double j = 0.0;
  for (auto _ : state) j += study.problem->evaluate(nullptr, *ws, options).objectives[0];
  benchmark::DoNotOptimize(j);
  state.counters["poses"] = study.problem->samples().size();
}

// The configurations of the reachable samples, for the per-configuration comparison.
const std::vector<Vector6d>& configurations() {
  static const std::vector<Vector6d> qs = [] {
    std::vector<Vector6d> out;
    auto scratch = mechanism().make_scratch();
    SampleQuantities q;
    for (int i = 0; i < scene().size() && out.size() < 4096; i += 7) {
      model().solve(scene().pose(i), hapsyn::kNeedPose, *scratch, q);
      if (q.status == hapsyn::SampleStatus::kReachable) out.push_back(Vector6d(q.q));
    }
    return out;
  }();
  return qs;
}

void BM_OursJacobianInertiaGravitySolve(benchmark::State& state) {
  const auto& qs = configurations();
  const Haptic6RModel& m = model();
  const Matrix6d rhs = Matrix6d::Identity() * 3.0;
  double sum = 0.0;
  for (auto _ : state) {
    for (const Vector6d& q : qs) {
      Matrix6d j, h;
      Vector6d g;
      m.quantities(q, &j, &h, &g);
      Matrix6d x = rhs;
      Coverage::solve_jacobian(j, x);
      const Matrix6d a = h * x;
      sum += a(0, 0) + g(3);
    }
  }
  benchmark::DoNotOptimize(sum);
  state.counters["per_pose"] = benchmark::Counter(static_cast<double>(qs.size()) * static_cast<double>(state.iterations()),
                                                  benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// KDL's solvers for J, H and gravity on the same configurations; the 6-column solve either as a
// KDL user writes it (Eigen's PartialPivLU) or with coverage's fixed-size elimination (`our_solve`),
// so that the second ratio compares the kinematics and dynamics alone.
void run_kdl(benchmark::State& state, bool our_solve) {
  const auto& qs = configurations();
  const Haptic6RModel& m = model();
  KDL::Chain chain;
  for (int i = 0; i < 6; ++i) {
    const Eigen::Vector4d row = m.dh_row(i);
    const Haptic6RBody& b = m.bodies()[static_cast<std::size_t>(i)];
    const KDL::RotationalInertia ic(b.inertia(0, 0), b.inertia(1, 1), b.inertia(2, 2), b.inertia(0, 1), b.inertia(0, 2),
                                    b.inertia(1, 2));
    chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotZ), KDL::Frame::DH(row(2), row(3), row(1), 0.0),
                                  KDL::RigidBodyInertia(b.mass, KDL::Vector(b.com.x(), b.com.y(), b.com.z()), ic)));
  }
  KDL::ChainDynParam dyn(chain, KDL::Vector(0, 0, -9.81));
  KDL::ChainJntToJacSolver jac(chain);
  KDL::JntArray kq(6), kg(6);
  KDL::JntSpaceInertiaMatrix kh(6);
  KDL::Jacobian kj(6);
  const Matrix6d rhs = Matrix6d::Identity() * 3.0;
  double sum = 0.0;
  for (auto _ : state) {
    for (const Vector6d& q : qs) {
      for (unsigned i = 0; i < 6; ++i) kq(i) = q(static_cast<int>(i)) + m.dh_row(static_cast<int>(i))(0);
      jac.JntToJac(kq, kj);
      dyn.JntToMass(kq, kh);
      dyn.JntToGravity(kq, kg);
      const Matrix6d j = kj.data, h = kh.data;
      Matrix6d a;
      if (our_solve) {
        Matrix6d x = rhs;
        Coverage::solve_jacobian(j, x);
        a = h * x;
      } else {
        a = h * Eigen::PartialPivLU<Matrix6d>(j).solve(rhs);
      }
      sum += a(0, 0) + kg(3);
    }
  }
  benchmark::DoNotOptimize(sum);
  state.counters["per_pose"] = benchmark::Counter(static_cast<double>(qs.size()) * static_cast<double>(state.iterations()),
                                                  benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
// The block kernels on the same configurations, 8 per call: Haptic6RModel::quantities_block,
// then Coverage::acceleration_torque_block (the 6-column solve and H X per lane, as above).
void BM_OursBlockJacobianInertiaGravitySolve(benchmark::State& state) {
  constexpr int L = hapsyn::kBlockLanes;
  const auto& qs = configurations();
  const Haptic6RModel& m = model();
  auto q = std::make_unique<hapsyn::QuantityBlock>();
  alignas(64) double x[36][L], regular[L];
  const hapsyn::Needs needs = hapsyn::kNeedJacobian | hapsyn::kNeedInertia | hapsyn::kNeedGravity;
  double sum = 0.0;
  for (auto _ : state) {
    for (std::size_t first = 0; first < qs.size(); first += L) {
      const int count = static_cast<int>(std::min<std::size_t>(L, qs.size() - first));
      m.quantities_block(qs.data() + first, count, needs, *q);
      for (int e = 0; e < 36; ++e) {
        for (int lane = 0; lane < L; ++lane) x[e][lane] = e / 6 == e % 6 ? 3.0 : 0.0;
      }
      Coverage::acceleration_torque_block(*q, x, regular);
      for (int lane = 0; lane < count; ++lane) sum += x[0][lane] + q->gravity[3][lane];
      benchmark::DoNotOptimize(x);
    }
  }
  benchmark::DoNotOptimize(sum);
  state.counters["per_pose"] = benchmark::Counter(static_cast<double>(qs.size()) * static_cast<double>(state.iterations()),
                                                  benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_KdlJacobianInertiaGravitySolve(benchmark::State& state) { run_kdl(state, false); }
void BM_KdlJacobianInertiaGravityOurSolve(benchmark::State& state) { run_kdl(state, true); }

}  // namespace

BENCHMARK(BM_CoveragePoseOnly)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CoveragePoseVelocity)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CoveragePoseVelocityAcceleration)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CoverageAllFourTerms)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CoverageAllFourTermsBlock)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CoverageAllFourTermsBlockOnTarget)->ArgName("target")->DenseRange(0, 2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FullObjectivePerDesignPerSample)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FullObjectivePerDesignGathered)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FullObjectivePerDesign)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GaObjectivesPerDesign)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FullObjectiveScaling)
    ->ArgNames({"step_mm", "orientations", "threads"})
    ->ArgsProduct({{200, 100, 50}, {505}, {1, 2}})
    ->ArgsProduct({{100}, {101, 2000}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_OursJacobianInertiaGravitySolve)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_OursBlockJacobianInertiaGravitySolve)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_KdlJacobianInertiaGravitySolve)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_KdlJacobianInertiaGravityOurSolve)->Unit(benchmark::kMicrosecond);

int main(int argc, char** argv) {
  hapsyn::bench::record_context(Json{{"mechanism", "haptic6r"}, {"metric", "coverage"},
                                     {"scene", "human_arm 0.1 m, 505 orientations, 17 joint-3 steps"},
                                     {"design", kDesign}});
  hapsyn::bench::compare("BM_CoveragePoseVelocity", "BM_CoveragePoseOnly");
  hapsyn::bench::compare("BM_CoveragePoseVelocityAcceleration", "BM_CoveragePoseOnly");
  hapsyn::bench::compare("BM_CoverageAllFourTerms", "BM_CoveragePoseOnly");
  hapsyn::bench::compare("BM_CoverageAllFourTermsBlock", "BM_CoverageAllFourTerms");
  hapsyn::bench::compare("BM_FullObjectivePerDesign/1/real_time", "BM_FullObjectivePerDesignPerSample/real_time");
  hapsyn::bench::compare("BM_FullObjectivePerDesign/2/real_time", "BM_FullObjectivePerDesignPerSample/real_time");
  hapsyn::bench::compare("BM_GaObjectivesPerDesign/1/real_time", "BM_FullObjectivePerDesign/1/real_time");
  hapsyn::bench::compare("BM_FullObjectivePerDesign/1/real_time", "BM_FullObjectivePerDesignGathered/real_time");
  hapsyn::bench::compare("BM_OursJacobianInertiaGravitySolve", "BM_KdlJacobianInertiaGravitySolve");
  hapsyn::bench::compare("BM_OursBlockJacobianInertiaGravitySolve", "BM_KdlJacobianInertiaGravitySolve");
  hapsyn::bench::compare("BM_OursJacobianInertiaGravitySolve", "BM_KdlJacobianInertiaGravityOurSolve");
  return hapsyn::bench::run_main(argc, argv);
}
