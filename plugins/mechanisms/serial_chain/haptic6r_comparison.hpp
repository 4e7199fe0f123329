#pragma once
// The cross-check of serial_chain against the closed-form haptic6r, shared by serial_chain_test
// (coarse workspace) and serial_chain_slow_test (the paper's): sample by sample, where both pick
// the same configuration, q, the Jacobian, inertia, gravity, actuator limits and the coverage
// metric's per-sample values agree to 1e-9; where they differ, the generic pick is never closer
// to home (the closed form sees every solution).
#include "haptic6r.hpp"
#include "serial_chain.hpp"
#include "test_support.hpp"

#include <hapsyn/metric.hpp>
#include <hapsyn/options.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace hapsyn::plugins::test_support {

inline constexpr double kPi = 3.14159265358979323846;

// The haptic 6R as a DH table, with the haptic6r-evaluate design's actuators.
inline Json haptic6r_dh_options() {
  return Json{{"dh_file", "serial_chain/haptic6r_dh.json"},
              {"actuator_file", "haptic6r/actuators_assumed.json"},
              {"actuator_size", {3, 3, 2, 2, 1, 1}},
              {"actuator_gear", {2, 2, 3, 2, 3, 3}},
              {"home", {0, 90, 0, 90, 90, 0}}};
}

// The same manipulator as a URDF (its inertials are those of the same design).
inline Json haptic6r_urdf_options() {
  Json o = haptic6r_dh_options();
  o.erase("dh_file");
  o["urdf"] = "serial_chain/haptic6r.urdf";
  o["base_link"] = "base_link";
  o["tip_link"] = "ee_link";
  return o;
}

inline SerialChain serial_chain(const Json& options) { return SerialChain(make_options<SerialChainOptions>(options)); }

// The full design vector at the file's values (each variable's default bounds coincide).
inline std::vector<double> nominal_design(const Mechanism& m) {
  std::vector<double> d;
  for (const VariableDecl& v : m.variables()) {
    for (int i = 0; i < v.size; ++i) d.push_back(v.default_lower.size() == 1 ? v.default_lower[0] : v.default_lower[static_cast<std::size_t>(i)]);
  }
  return d;
}

inline SampleSet one_pose_scene(const Eigen::Isometry3d& t) {
  SampleSet s;
  s.coordinates = {"x", "y", "z", "qw", "qx", "qy", "qz"};
  s.poses.resize(1, 7);
  const Eigen::Quaterniond q(t.linear());
  s.poses << t.translation().x(), t.translation().y(), t.translation().z(), q.w(), q.x(), q.y(), q.z();
  return s;
}

inline SampleQuantities solve_one(const MechanismModel& model, const Mechanism& mech, const SampleSet& scene, int i,
                           Needs needs = kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits) {
  SampleQuantities q;
  q.scene = &scene;
  q.sample = i;
  const auto scratch = mech.make_scratch();
  model.solve(scene.pose(i), needs, *scratch, q);
  return q;
}

inline double wrapped_distance(const JointVector& a, const JointVector& b) {
  double m = 0.0;
  for (int i = 0; i < a.size(); ++i) m = std::max(m, std::abs(std::remainder(a(i) - b(i), 2.0 * kPi)));
  return m;
}

inline double home_distance(const JointVector& q, const JointVector& home) {
  double s = 0.0;
  for (int i = 0; i < q.size(); ++i) s += std::pow(std::remainder(q(i) - home(i), 2.0 * kPi), 2);
  return s;
}


/// The coarse human-arm workspace (811 poses) and the paper's (34,548 poses, cached).
inline Json coarse_human_arm() {
  return Json{{"lattice_step", 0.2}, {"orientations", 101}, {"joint3_steps", 9}, {"cache", false}};
}
inline Json paper_human_arm() { return Json{{"lattice_step", 0.1}, {"orientations", 505}, {"joint3_steps", 17}}; }

/// Counts of one comparison.
struct Haptic6RComparison {
  int same = 0;            ///< both reachable, same configuration
  int both_reachable = 0;  ///< both classify the sample reachable
  int farther = 0;         ///< both reachable, the generic IK picked a configuration farther from home
  int missed = 0;          ///< reachable in closed form only
  double same_share() const { return both_reachable > 0 ? static_cast<double>(same) / both_reachable : 0.0; }
};

/// Compares the two on the human_arm scene of `scene_options` with serial_chain's IK `solver`
/// ("auto": the closed form; "numerical" with `restarts` restarts).
inline Haptic6RComparison compare_with_haptic6r(Json options, const char* solver, int restarts, const Json& scene_options,
                                                const char* form) {
  options["ik"]["solver"] = solver;
  options["ik"]["restarts"] = restarts;
  const SerialChain chain = serial_chain(options);
  const Haptic6R closed(make_options<Haptic6ROptions>(Json{{"selection", "closest_to_home"}}));
  const std::vector<double> closed_design = {0.45, 0.45, 0.65, 0.55, 0.15, 3, 3, 2, 2, 1, 1, 2, 2, 3, 2, 3, 3};
  const auto chain_model = chain.build(nominal_design(chain).data());
  const auto closed_model = closed.build(closed_design.data());
  const auto coverage = test::registry().create_metric(
      "coverage", Json{{"terms", {"pose", "velocity", "acceleration", "force"}}}, "objectives[0]");
  const auto scene_plugin = test::registry().create_scene("human_arm", scene_options, "scene");
  const SampleSet scene = scene_plugin->build(SceneRequest{coverage->specs().scene_attributes});
  const std::vector<std::string> names = coverage->specs().scene_attributes;
  std::vector<const AttributeMatrix*> attributes;
  for (const std::string& n : names) attributes.push_back(&scene.attributes.at(n));
  const std::size_t local_count = coverage->locals().size();
  std::vector<double> local_a(local_count), local_b(local_count);
  const Needs all = kNeedJacobian | kNeedInertia | kNeedGravity | kNeedActuatorLimits;
  const auto cs = chain.make_scratch();
  const auto hs = closed.make_scratch();
  Haptic6RComparison r;
  int& same = r.same;
  int& both_reachable = r.both_reachable;
  int& closer = r.farther;
  int& missed = r.missed;
  double max_generic = 0, max_closed = 0;
  for (int i = 0; i < scene.size(); ++i) {
    SampleQuantities a, b;
    a.scene = b.scene = &scene;
    a.sample = b.sample = i;
    a.attributes = b.attributes = attributes.data();
    a.attribute_count = b.attribute_count = static_cast<int>(attributes.size());
    chain_model->solve(scene.pose(i), all, *cs, a);
    closed_model->solve(scene.pose(i), all, *hs, b);
    if (b.status == SampleStatus::kReachable && a.status != SampleStatus::kReachable) ++missed;
    if (a.status != SampleStatus::kReachable || b.status != SampleStatus::kReachable) continue;
    ++both_reachable;
    const JointVector& home = chain.setup().home;
    if (wrapped_distance(a.q, b.q) > 1e-6) {
      // The closed form sees every solution, so a different generic pick is never closer to home.
      EXPECT_GE(home_distance(a.q, home), home_distance(b.q, home)) << "sample " << i;
      ++closer;
      continue;
    }
    {
      const Chain& c = static_cast<const SerialChainModel&>(*chain_model).chain();
      ChainFrames fa, fb;
      chain_frames(c, a.q.data(), fa);
      chain_frames(c, b.q.data(), fb);
      const Eigen::Isometry3d t = static_cast<const SerialChainModel&>(*chain_model).target(scene.pose(i), 7);
      max_generic = std::max(max_generic, (fa.tip.translation() - t.translation()).norm() + (fa.tip.linear() - t.linear()).norm());
      max_closed = std::max(max_closed, (fb.tip.translation() - t.translation()).norm() + (fb.tip.linear() - t.linear()).norm());
    }
    ++same;
    EXPECT_LT(wrapped_distance(a.q, b.q), 1e-9) << "sample " << i;
    EXPECT_LT((a.jacobian - b.jacobian).norm(), 1e-9 * (1 + b.jacobian.norm())) << "sample " << i;
    EXPECT_LT((a.inertia - b.inertia).norm(), 1e-9 * (1 + b.inertia.norm())) << "sample " << i;
    EXPECT_LT((a.gravity - b.gravity).norm(), 1e-9 * (1 + b.gravity.norm())) << "sample " << i;
    EXPECT_LT((a.max_velocity - b.max_velocity).norm(), 1e-12);
    EXPECT_LT((a.max_torque - b.max_torque).norm(), 1e-12);
    // The coverage terms' per-sample values (eta_v, eta_a, eta_f and the reach flag).
    coverage->local(a, local_a.data());
    coverage->local(b, local_b.data());
    for (std::size_t k = 0; k < local_count; ++k) {
      EXPECT_NEAR(local_a[k], local_b[k], 1e-9 * (1 + std::abs(local_b[k]))) << "sample " << i << " local " << k;
    }
  }
  std::printf("[ serial_chain vs haptic6r (%s) ] %d samples: %d both reachable, %d same configuration, %d a farther "
              "one, %d reachable only in closed form; largest pose residual %.3g (closed form %.3g)\n",
              form, scene.size(), both_reachable, same, closer, missed, max_generic, max_closed);
  EXPECT_GT(both_reachable, scene.size() / 4);
  EXPECT_LT(max_generic, 1e-13);
  EXPECT_LE(missed, scene.size() / 100);
  return r;
}

}  // namespace hapsyn::plugins::test_support
