// LIBRARIES: hapsyn_serial_chain_model orocos-kdl
//
// The serial_chain IK (chain_ik.hpp) against KDL's ChainIkSolverPos_LMA and
// ChainIkSolverPos_NR_JL (ChainFkSolverPos_recursive + ChainIkSolverVel_pinv), per pose, on
// 10,000 random reachable poses (FK of seeded random in-limit q) of the three shipped URDFs
// (share/serial_chain: ur5_like.urdf and haptic6r.urdf full pose, phantom_3r.urdf position only)
// and a KUKA-iiwa-like 7R built in code (chain_test_chains.hpp; full pose).
//   cold: from home, then the IK's 8 seeded restarts (ik_random_start, seed 1) until success;
//         every solver gets the same starts in the same order (KDL stops at its own success)
//   warm: the poses of a joint-space random walk (steps uniform in +-0.05 rad per joint), each
//         started from the solver's own answer to the previous pose (restarts as cold on failure)
// Success is one criterion for all: FK of the answer within 1e-6 m and 1e-6 rad of the target
// in the task's rows ("in limits" also counts it inside the joint limits: LMA ignores limits).
// Ours: default tolerances (1e-10), closest-to-home (all starts) or first converged, and first
// converged at 1e-7 (KDL's eps here). Times are per pose, the thread's CPU time around one solve
// (CLOCK_THREAD_CPUTIME_ID: preemption on a shared machine is not counted): median and 99th
// percentile. The table is printed after the runs.
#include "common.hpp"
#include "kdl_chain.hpp"

#include <chain_ik.hpp>
#include <chain_template.hpp>
#include <chain_test_chains.hpp>

#include <benchmark/benchmark.h>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>
#include <kdl/chainiksolverpos_nr_jl.hpp>
#include <kdl/chainiksolvervel_pinv.hpp>

#include <algorithm>
#include <ctime>
#include <cstdio>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace {

using namespace hapsyn::plugins;
using namespace hapsyn::plugins::test_chains;

constexpr int kPoses = 10000;
constexpr double kCriterion = 1e-6;  // [m] and [rad], every solver
constexpr double kKdlEps = 1e-7;
constexpr double kWalkStep = 0.05;  // [rad]

struct Case {
  std::string name;
  Chain chain;
  IkTask task;
  std::vector<double> home;
  bool nr_jl = true;  // NR_JL solves full poses only
};

// A shipped URDF (share/serial_chain) at its file's values, as the serial_chain mechanism reads it.
Chain shipped(const char* file, const char* base, const char* tip) {
  const ChainTemplate t =
      ChainTemplate::from_urdf(std::string(HAPSYN_SOURCE_DIR) + "/share/serial_chain/" + file, base, tip);
  std::vector<double> values;
  for (const ChainParameter& p : t.parameters()) values.push_back(p.nominal);
  Chain chain;
  t.instantiate(values.data(), nullptr, chain);
  return chain;
}

// The shipped chains; no 7-DOF file is shipped, so the redundant case is a KUKA-iiwa-like chain
// built in code (chain_test_chains.hpp).
std::vector<Case> cases() {
  return {{"ur5_like.urdf", shipped("ur5_like.urdf", "base_link", "tool0"), full_task(), {0.0, -1.2, 1.5, -1.9, -1.57, 0.0}},
          {"haptic6r.urdf", shipped("haptic6r.urdf", "base_link", "ee_link"), full_task(),
           {0.0, deg(90), 0.0, deg(90), deg(90), 0.0}},
          {"phantom_3r.urdf", shipped("phantom_3r.urdf", "world", "stylus_tip"), position_task(), {0.0, 0.3, 0.0}, false},
          {"iiwa_7r", iiwa_7r(), full_task(), {0.0, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0}}};
}

Eigen::Isometry3d fk(const Chain& chain, const double* q) {
  ChainFrames f;
  chain_frames(chain, q, f);
  return f.tip;
}

// The poses of one case: random (cold) and a random walk (warm).
struct Poses {
  std::vector<Eigen::Isometry3d> random, walk;
};

Poses make_poses(const Chain& chain) {
  Poses p;
  std::vector<double> q(static_cast<std::size_t>(chain.dof()));
  for (int k = 0; k < kPoses; ++k) {
    ik_random_start(chain, 4242, k, q.data());
    p.random.push_back(fk(chain, q.data()));
  }
  std::mt19937_64 rng(4243);  // fully specified engine: the same walk everywhere
  ik_random_start(chain, 4244, 0, q.data());
  for (int k = 0; k < kPoses; ++k) {
    for (int i = 0; i < chain.dof(); ++i) {
      const ChainJoint& j = chain.joints[static_cast<std::size_t>(i)];
      const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;
      q[static_cast<std::size_t>(i)] = std::clamp(q[static_cast<std::size_t>(i)] + kWalkStep * (2 * u - 1), j.lower, j.upper);
    }
    p.walk.push_back(fk(chain, q.data()));
  }
  return p;
}

using hapsyn::bench::to_kdl;

Eigen::Isometry3d from_kdl(const KDL::Frame& f) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) t.linear()(r, c) = f.M(static_cast<unsigned>(r), static_cast<unsigned>(c));
    t.translation()(r) = f.p(r);
  }
  return t;
}

// A solver from one start: true when it reports success by its own criterion.
using Solver = std::function<bool(const Eigen::Isometry3d& target, const double* start, double* q)>;

struct Row {
  std::string chain, solver, mode;
  double success = 0, in_limits = 0, median_us = 0, p99_us = 0;
};
std::vector<Row>& table() {
  static std::vector<Row> rows;
  return rows;
}

// The calling thread's CPU time [us].
double thread_cpu_us() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e6 * static_cast<double>(t.tv_sec) + 1e-3 * static_cast<double>(t.tv_nsec);
}

bool inside(const Chain& chain, const double* q) {
  for (int i = 0; i < chain.dof(); ++i) {
    const ChainJoint& j = chain.joints[static_cast<std::size_t>(i)];
    if (!(q[i] >= j.lower && q[i] <= j.upper)) return false;
  }
  return true;
}

// Runs one solver over the poses of a case; `restarts`: retry from the IK's seeded starts.
void run_case(benchmark::State& state, const Case& c, const std::vector<Eigen::Isometry3d>& targets, bool warm,
              const Solver& solve, bool restarts, const std::string& solver_name) {
  const int n = c.chain.dof();
  std::vector<double> times;
  times.reserve(targets.size());
  int success = 0, in_limits = 0;
  std::vector<double> q(static_cast<std::size_t>(n)), previous = c.home, start(static_cast<std::size_t>(n));
  for (auto _ : state) {
    times.clear();
    success = in_limits = 0;
    previous = c.home;
    for (const Eigen::Isometry3d& target : targets) {
      const double t0 = thread_cpu_us();
      bool ok = solve(target, warm ? previous.data() : c.home.data(), q.data());
      for (int k = 0; restarts && !ok && k < IkSettings().restarts; ++k) {
        ik_random_start(c.chain, IkSettings().seed, k, start.data());
        ok = solve(target, start.data(), q.data());
      }
      times.push_back(thread_cpu_us() - t0);
      const IkResidual r = task_residual(c.task, fk(c.chain, q.data()), target);
      const bool good = r.position < kCriterion && r.orientation < kCriterion;
      success += good;
      in_limits += good && inside(c.chain, q.data());
      if (good || !warm) previous = q;  // a warm run continues from its last good answer
    }
  }
  std::sort(times.begin(), times.end());
  Row row{c.name, solver_name, warm ? "warm" : "cold"};
  row.success = 100.0 * success / static_cast<double>(targets.size());
  row.in_limits = 100.0 * in_limits / static_cast<double>(targets.size());
  row.median_us = times[times.size() / 2];
  row.p99_us = times[static_cast<std::size_t>(0.99 * static_cast<double>(times.size()))];
  table().push_back(row);
  state.counters["success_pct"] = row.success;
  state.counters["in_limits_pct"] = row.in_limits;
  state.counters["median_us"] = row.median_us;
  state.counters["p99_us"] = row.p99_us;
}

// Everything one case needs, kept alive for the registered lambdas.
struct CaseData {
  Case c;
  Poses poses;
  KDL::Chain kdl;
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
  std::unique_ptr<KDL::ChainIkSolverVel_pinv> vel;
  std::unique_ptr<KDL::ChainIkSolverPos_NR_JL> nr_jl;
  std::unique_ptr<KDL::ChainIkSolverPos_LMA> lma;
  IkScratch scratch;
  KDL::JntArray kq, kout;
};

std::vector<std::unique_ptr<CaseData>>& data() {
  static std::vector<std::unique_ptr<CaseData>> d;
  return d;
}

void check_kdl_fk(CaseData& d) {
  const int n = d.c.chain.dof();
  std::vector<double> q(static_cast<std::size_t>(n));
  for (int k = 0; k < 10; ++k) {
    ik_random_start(d.c.chain, 99, k, q.data());
    KDL::JntArray kq(static_cast<unsigned>(n));
    for (int i = 0; i < n; ++i) kq(static_cast<unsigned>(i)) = q[static_cast<std::size_t>(i)];
    KDL::Frame f;
    d.fk->JntToCart(kq, f);
    const Eigen::Isometry3d a = from_kdl(f), b = fk(d.c.chain, q.data());
    if ((a.matrix() - b.matrix()).norm() > 1e-12) {
      std::fprintf(stderr, "KDL FK of %s differs from ours\n", d.c.name.c_str());
      std::abort();
    }
  }
}

void register_case(const Case& c) {
  data().push_back(std::make_unique<CaseData>());
  CaseData& d = *data().back();
  d.c = c;
  d.poses = make_poses(c.chain);
  d.kdl = to_kdl(c.chain);
  const unsigned n = d.kdl.getNrOfJoints();
  KDL::JntArray lower(n), upper(n);
  for (unsigned i = 0; i < n; ++i) {
    lower(i) = c.chain.joints[i].lower;
    upper(i) = c.chain.joints[i].upper;
  }
  d.fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(d.kdl);
  d.vel = std::make_unique<KDL::ChainIkSolverVel_pinv>(d.kdl);
  d.nr_jl = std::make_unique<KDL::ChainIkSolverPos_NR_JL>(d.kdl, lower, upper, *d.fk, *d.vel, 100, kKdlEps);
  Eigen::Matrix<double, 6, 1> weights = Eigen::Matrix<double, 6, 1>::Ones();
  if (c.task.orientation == IkTask::Orientation::kNone) weights.tail<3>().setZero();
  d.lma = std::make_unique<KDL::ChainIkSolverPos_LMA>(d.kdl, weights, kKdlEps, 500, 1e-15);
  d.kq.resize(n);
  d.kout.resize(n);
  check_kdl_fk(d);

  auto ours = [&d](bool first, double tolerance) -> Solver {
    return [&d, first, tolerance](const Eigen::Isometry3d& target, const double* start, double* q) {
      IkSettings s;
      s.position_tolerance = s.orientation_tolerance = tolerance;
      const double* starts[] = {start};
      return solve_ik(d.c.chain, d.c.task, s, target, starts, 1, d.c.home.data(), first, q, d.scratch) ==
             IkStatus::kConverged;
    };
  };
  auto kdl = [&d](bool lma) -> Solver {
    return [&d, lma](const Eigen::Isometry3d& target, const double* start, double* q) {
      const unsigned joints = d.kdl.getNrOfJoints();
      for (unsigned i = 0; i < joints; ++i) d.kq(i) = start[i];
      const KDL::Frame f = to_kdl(target);
      const int rc = lma ? d.lma->CartToJnt(d.kq, f, d.kout) : d.nr_jl->CartToJnt(d.kq, f, d.kout);
      for (unsigned i = 0; i < joints; ++i) q[i] = d.kout(i);
      return rc >= 0;
    };
  };
  struct Entry {
    std::string solver;
    Solver solve;
    bool restarts;  // ours restarts inside solve_ik
    bool warm_too;
  };
  std::vector<Entry> entries{{"ours closest-to-home", ours(false, 1e-10), false, false},
                             {"ours first", ours(true, 1e-10), false, true},
                             {"ours first tol 1e-7", ours(true, kKdlEps), false, true},
                             {"KDL LMA", kdl(true), true, true}};
  if (c.nr_jl) entries.push_back({"KDL NR_JL", kdl(false), true, true});
  for (const Entry& e : entries) {
    for (bool warm : {false, true}) {
      if (warm && !e.warm_too) continue;
      const std::string name = "BM_" + c.name + "/" + e.solver + "/" + (warm ? "warm" : "cold");
      benchmark::RegisterBenchmark(name.c_str(), [&d, e, warm](benchmark::State& state) {
        run_case(state, d.c, warm ? d.poses.walk : d.poses.random, warm, e.solve, e.restarts, e.solver);
      })->Iterations(1)->Unit(benchmark::kMillisecond);
    }
  }
}

void print_table() {
  std::printf("\n%-11s %-22s %-5s %9s %10s %11s %10s\n", "chain", "solver", "mode", "success%", "in-limits%",
              "median[us]", "p99[us]");
  for (const Row& r : table()) {
    std::printf("%-11s %-22s %-5s %9.2f %10.2f %11.2f %10.2f\n", r.chain.c_str(), r.solver.c_str(), r.mode.c_str(),
                r.success, r.in_limits, r.median_us, r.p99_us);
  }
}

}  // namespace

int main(int argc, char** argv) {
  hapsyn::bench::record_context(hapsyn::Json{{"poses_per_chain", kPoses}, {"criterion", kCriterion},
                                             {"kdl_eps", kKdlEps}, {"walk_step_rad", kWalkStep}},
                                4242);
  for (const Case& c : cases()) register_case(c);
  const int rc = hapsyn::bench::run_main(argc, argv);
  print_table();
  return rc;
}
