// LIBRARIES: hapsyn_haptic6r_model hapsyn_coverage_model hapsyn_human_arm_model orocos-kdl
//
// Cost of the haptic6r + coverage study (Fennel 2022) at the paper's resolution (0.1 m lattice,
// 505 orientations, 17 joint-3 steps: ~35k human poses; the scene is cached on disk after the
// first build), for one plausible design, single thread unless stated:
//   per pose, IK + the quantities + coverage local() for the terms
//     pose only | pose + velocity | + acceleration | + force (all four)
//   one full four-term design evaluation through Problem::evaluate_parallel (2 threads)  [ms/design]
//   per configuration: J, H, gravity and the 6-column solve J^-1 M_a, ours vs KDL's
//     ChainJntToJacSolver + ChainDynParam (JntToMass, JntToGravity) + Eigen LU on the same q
// Read the ratios printed at the end (same run, same machine), not bare times.
#include "common.hpp"

#include <coverage.hpp>
#include <haptic6r.hpp>
#include <human_arm.hpp>

#include <hapsyn/problem.hpp>
#include <hapsyn/registry.hpp>
#include <hapsyn/study.hpp>

#include <benchmark/benchmark.h>
#include <kdl/chain.hpp>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainjnttojacsolver.hpp>

#include <Eigen/LU>
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
  static const Haptic6R m = [] {
    Haptic6R h(hapsyn::default_options<Haptic6ROptions>());
    h.check_scene(scene());
    return h;
  }();
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

// The full objective J through the framework's evaluator, as a solver sees it.
void BM_FullObjectivePerDesign(benchmark::State& state) {
  static hapsyn::Registry registry({HAPSYN_PLUGIN_DIR});
  static hapsyn::Study study = hapsyn::load_study(Json::parse(R"({
    "name": "bench", "mechanism": {"plugin": "haptic6r"},
    "scene": {"plugin": "human_arm", "options": {"lattice_step": 0.1, "orientations": 505, "joint3_steps": 17}},
    "design": {"l": {"value": [0.45, 0.45, 0.65, 0.55, 0.15]}, "s": {"value": [3, 3, 2, 2, 1, 1]}, "r": {"value": [2, 2, 3, 2, 3, 3]}},
    "objectives": [{"metric": "coverage"}], "solver": {"plugin": "evaluate"}})"), registry);
  const int threads = static_cast<int>(state.range(0));
  double j = 0.0;
  for (auto _ : state) j += study.problem->evaluate_parallel(nullptr, threads).objectives[0];
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
void BM_KdlJacobianInertiaGravitySolve(benchmark::State& state) { run_kdl(state, false); }
void BM_KdlJacobianInertiaGravityOurSolve(benchmark::State& state) { run_kdl(state, true); }

}  // namespace

BENCHMARK(BM_CoveragePoseOnly)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CoveragePoseVelocity)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CoveragePoseVelocityAcceleration)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CoverageAllFourTerms)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FullObjectivePerDesign)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_OursJacobianInertiaGravitySolve)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_KdlJacobianInertiaGravitySolve)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_KdlJacobianInertiaGravityOurSolve)->Unit(benchmark::kMicrosecond);

int main(int argc, char** argv) {
  hapsyn::bench::record_context(Json{{"mechanism", "haptic6r"}, {"metric", "coverage"},
                                     {"scene", "human_arm 0.1 m, 505 orientations, 17 joint-3 steps"},
                                     {"design", kDesign}});
  hapsyn::bench::compare("BM_CoveragePoseVelocity", "BM_CoveragePoseOnly");
  hapsyn::bench::compare("BM_CoveragePoseVelocityAcceleration", "BM_CoveragePoseOnly");
  hapsyn::bench::compare("BM_CoverageAllFourTerms", "BM_CoveragePoseOnly");
  hapsyn::bench::compare("BM_OursJacobianInertiaGravitySolve", "BM_KdlJacobianInertiaGravitySolve");
  hapsyn::bench::compare("BM_OursJacobianInertiaGravitySolve", "BM_KdlJacobianInertiaGravityOurSolve");
  return hapsyn::bench::run_main(argc, argv);
}
