// The validation on motion end to end (motion scene -> haptic6r -> motion_feasibility): on
// noise-free synthetic arm motion, the twist the scene estimates is the exact twist of the
// generator; motion inside a design's capability is 100 % feasible; played k times faster,
// exactly the samples predicted from the k = 1 quantities become infeasible (joint rates scale by
// k, accelerations and the velocity torque by k^2, gravity not at all); and the shares per subject
// are the evaluations of each subject's own samples.
#include "synthetic_motion.hpp"

#include <hapsyn/internal/groups.hpp>
#include <hapsyn/internal/maps.hpp>
#include <hapsyn/mechanism.hpp>
#include <hapsyn/internal/study.hpp>

#include "shared/human_arm_model/human_arm_model.hpp"

#include "test_support.hpp"

#include <Eigen/Geometry>
#include <boost/filesystem.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace {

namespace fs = boost::filesystem;
using hapsyn::Json;
using hapsyn::plugins::motion::SyntheticTrajectory;

const Json kDesign = {{"l", {{"value", {0.45, 0.45, 0.65, 0.55, 0.15}}}},
                      {"s", {{"value", {3, 3, 2, 2, 1, 1}}}},
                      {"r", {{"value", {2, 2, 3, 2, 3, 3}}}}};

// Two subjects' noise-free synthetic seated motion (exact poses, uniform time stamps).
const std::vector<SyntheticTrajectory>& trajectories() {
  static const std::vector<SyntheticTrajectory> t = [] {
    const hapsyn::plugins::HumanArmData arm = hapsyn::plugins::load_human_arm(
        std::string(HAPSYN_SOURCE_DIR) + "/share/human_arm/fennel2022_right_arm.json");
    hapsyn::plugins::motion::SyntheticOptions o;
    o.subjects = 2;
    o.position_noise_m = 0.0;
    o.orientation_noise_deg = 0.0;
    // The activities at the table: inside the capability of the design below. side_reach leaves
    // its workspace on purpose; drinking takes the upright user's hand to the mouth, where the
    // design's SCARA is nearly stretched (q2 within a few degrees of 0) and its joint 4 holds the
    // arm against gravity at its torque limit, so no speed makes every sample feasible.
    std::vector<SyntheticTrajectory> all = hapsyn::plugins::motion::make_synthetic_motion(arm, o), seated;
    for (SyntheticTrajectory& trajectory : all) {
      if (trajectory.activity != "side_reach" && trajectory.activity != "drinking") seated.push_back(std::move(trajectory));
    }
    return seated;
  }();
  return t;
}

// Writes the noise-free poses at full precision, time stamps divided by `k` (played k times faster).
void write_csv(const SyntheticTrajectory& t, double k, const fs::path& file) {
  fs::create_directories(file.parent_path());
  std::ofstream out(file.string());
  out << std::setprecision(17) << "# subject: " << t.subject << "\n# activity: " << t.activity
      << "\ntime,x,y,z,qw,qx,qy,qz\n";
  for (Eigen::Index i = 0; i < t.time.size(); ++i) {
    out << t.time(i) / k;
    for (int c = 0; c < 3; ++c) out << "," << t.position(i, c);
    for (int c = 0; c < 4; ++c) out << "," << t.quaternion(i, c);
    out << "\n";
  }
}

class MotionValidation : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / fs::unique_path("hapsyn-motion-validation-%%%%-%%%%");
  }
  void TearDown() override {
    boost::system::error_code ec;
    fs::remove_all(dir_, ec);
  }
  // The data set played k times faster, in its own folder; only the subjects' uniform recordings.
  std::string data(double k) const {
    const fs::path folder = dir_ / ("k" + std::to_string(k));
    for (const SyntheticTrajectory& t : trajectories()) write_csv(t, k, folder / t.subject / (t.activity + ".csv"));
    return folder.string();
  }
  static hapsyn::Study study(const std::string& path, bool filter, const std::string& share = "all") {
    return hapsyn::load_study(Json{{"name", "validation"},
                                   {"mechanism", {{"plugin", "haptic6r"}}},
                                   {"scene", {{"plugin", "motion"}, {"options", {{"path", path}, {"filter", filter}}}}},
                                   {"design", kDesign},
                                   {"objectives", {{{"metric", "motion_feasibility"}, {"options", {{"share", share}}}}}},
                                   {"solver", {{"plugin", "evaluate"}}}},
                              hapsyn::test::registry());
  }
  static Eigen::VectorXd full_design(const hapsyn::Problem& p) { return p.full_design(nullptr); }
  fs::path dir_;
};

// The exact twist of the generator, mapped into B as the scene maps poses (the defaults:
// C_S_B of an upright user, E at the palm, C_E_P of the paper).
TEST_F(MotionValidation, EstimatedTwistIsTheGeneratorsExactTwist) {
  const hapsyn::Study s = study(data(1.0), true);
  const hapsyn::SampleSet& scene = s.problem->samples();
  Eigen::Matrix3d C_S_B;
  C_S_B << 0, 0, -1, -1, 0, 0, 0, 1, 0;
  const auto& twist = scene.attributes.at(hapsyn::kTwistAttribute);
  const auto& rate = scene.attributes.at(hapsyn::kTwistRateAttribute);
  double peak_v = 0, err_v = 0, peak_w = 0, err_w = 0, peak_a = 0, err_a = 0, square_a = 0;
  // The scene orders recordings by path (S01/lifting.csv first): find each one's first row.
  const hapsyn::SampleGrouping& trajectory = scene.groups[2];
  ASSERT_EQ(trajectory.name, "trajectory");
  Eigen::Index compared = 0;
  for (const SyntheticTrajectory& t : trajectories()) {
    const auto label = std::find(trajectory.labels.begin(), trajectory.labels.end(), t.subject + "/" + t.activity);
    ASSERT_NE(label, trajectory.labels.end());
    const auto first = std::find(trajectory.of_sample.begin(), trajectory.of_sample.end(),
                                 static_cast<int>(label - trajectory.labels.begin()));
    Eigen::Index row = first - trajectory.of_sample.begin();
    for (Eigen::Index i = 0; i < t.time.size(); ++i, ++row, ++compared) {
      const Eigen::Vector3d w = C_S_B * t.twist.row(i).head<3>().transpose();
      const Eigen::Vector3d v = C_S_B * t.twist.row(i).tail<3>().transpose();
      const Eigen::Vector3d a = C_S_B * t.twist_rate.row(i).tail<3>().transpose();
      peak_v = std::max(peak_v, v.norm());
      peak_w = std::max(peak_w, w.norm());
      peak_a = std::max(peak_a, a.norm());
      err_v = std::max(err_v, (twist.row(row).tail<3>().transpose() - v).norm());
      err_w = std::max(err_w, (twist.row(row).head<3>().transpose() - w).norm());
      square_a += (rate.row(row).tail<3>().transpose() - a).squaredNorm();
      err_a = std::max(err_a, (rate.row(row).tail<3>().transpose() - a).norm());
    }
  }
  ASSERT_EQ(compared, scene.size());
  // Quintic rest-to-rest moves low-passed at 5 Hz: the velocities follow the exact twist to 2 % of
  // their peak. The acceleration of the short wiping strokes (a few tenths of a second) has
  // content above 5 Hz that the paper's filter removes: at stroke reversals the estimate is off
  // by up to a quarter of the peak (measured 26 %), in the mean square by a few percent.
  const double rms_a = std::sqrt(square_a / static_cast<double>(compared));
  std::cout << "max errors / peak: v " << err_v / peak_v << ", omega " << err_w / peak_w << ", a " << err_a / peak_a
            << "; rms a / peak " << rms_a / peak_a << "\n";
  EXPECT_LT(err_v, 0.02 * peak_v) << "peak " << peak_v;
  EXPECT_LT(err_w, 0.02 * peak_w) << "peak " << peak_w;
  EXPECT_LT(err_a, 0.30 * peak_a) << "peak " << peak_a;
  EXPECT_LT(rms_a, 0.05 * peak_a) << "peak " << peak_a;
}

TEST_F(MotionValidation, MotionInsideTheCapabilityIsFullyFeasibleAndSpeedUpFailsExactlyThePredictedSamples) {
  // Played at half speed, the design serves every sample (at full speed the wiping strokes
  // exceed its torque limits): every share 100 %.
  const double base = 0.5;
  const hapsyn::Study slow = study(data(base), false);
  const hapsyn::Problem& p1 = *slow.problem;
  const hapsyn::SampleRecords r1 = hapsyn::record_samples(p1, full_design(p1));
  for (Eigen::Index i = 0; i < r1.locals.rows(); ++i) {
    ASSERT_EQ(r1.locals.row(i).minCoeff(), 1.0) << "sample " << i << " is not feasible at half speed";
  }
  // The quantities at half speed, from the mechanism directly.
  const std::unique_ptr<const hapsyn::MechanismModel> model = p1.mechanism().build(full_design(p1).data());
  const std::unique_ptr<hapsyn::MechanismScratch> scratch = p1.mechanism().make_scratch();
  const hapsyn::Needs needs = hapsyn::kNeedJointVelocity | hapsyn::kNeedJointAcceleration |
                              hapsyn::kNeedVelocityTorque | hapsyn::kNeedInertia | hapsyn::kNeedGravity |
                              hapsyn::kNeedActuatorLimits;
  const double k = 10.0;
  const hapsyn::Study fast = study(data(base * k), false);
  const hapsyn::Problem& pk = *fast.problem;
  ASSERT_EQ(pk.samples().size(), p1.samples().size());
  const hapsyn::SampleRecords rk = hapsyn::record_samples(pk, full_design(pk));
  int velocity_failures = 0, torque_failures = 0;
  for (int i = 0; i < p1.samples().size(); ++i) {
    hapsyn::SampleQuantities q;
    p1.bind_sample(q, i);
    model->solve(p1.samples().pose(i), needs, *scratch, q);
    ASSERT_EQ(q.status, hapsyn::SampleStatus::kReachable);
    // Predicted k times faster: qdot * k; tau = k^2 (H qddot + c) + g. Keep clear of the thresholds so that
    // rounding cannot decide (the derivatives of time / k agree with k x those of time to ~1e-15).
    bool velocity_ok = true, torque_ok = true;
    double closest = 1.0;
    for (Eigen::Index j = 0; j < q.joint_velocity.size(); ++j) {
      const double v = k * std::abs(q.joint_velocity(j)) / q.max_velocity(j);
      const Eigen::VectorXd h_qdd = q.inertia.row(j) * q.joint_acceleration;
      const double tau = std::abs(k * k * (h_qdd(0) + q.velocity_torque(j)) + q.gravity(j)) / q.max_torque(j);
      velocity_ok = velocity_ok && v <= 1.0;
      torque_ok = torque_ok && tau <= 1.0;
      closest = std::min({closest, std::abs(v - 1.0), std::abs(tau - 1.0)});
    }
    ASSERT_GT(closest, 1e-9) << "sample " << i << " sits on a limit: choose another k";
    EXPECT_EQ(rk.locals(i, 1), velocity_ok ? 1.0 : 0.0) << "sample " << i;
    EXPECT_EQ(rk.locals(i, 2), torque_ok ? 1.0 : 0.0) << "sample " << i;
    velocity_failures += !velocity_ok;
    torque_failures += !torque_ok;
  }
  // The test decides something: samples of both kinds fail at k, and others do not.
  EXPECT_GT(velocity_failures, p1.samples().size() / 100);
  EXPECT_GT(torque_failures, p1.samples().size() / 100);
  EXPECT_LT(std::max(velocity_failures, torque_failures), p1.samples().size());
  std::cout << "k = " << k << ": " << velocity_failures << " velocity and " << torque_failures
            << " torque failures of " << p1.samples().size() << " samples\n";
}

TEST_F(MotionValidation, SharesPerSubjectAreTheSubjectsOwnEvaluations) {
  const hapsyn::Study s = study(data(3.0), true, "acceleration");
  const hapsyn::Problem& p = *s.problem;
  const hapsyn::SampleRecords records = hapsyn::record_samples(p, full_design(p));
  const std::vector<hapsyn::GroupTable> tables = hapsyn::group_tables(p, records);
  ASSERT_EQ(tables.size(), 3u);
  const hapsyn::GroupTable& subjects = tables[0];
  ASSERT_EQ(subjects.grouping, "subject");
  ASSERT_EQ(subjects.labels.size(), 2u);
  auto ws = p.make_eval_scratch();
  double sum = 0.0;
  for (std::size_t g = 0; g < 2; ++g) {
    std::vector<int> subset;
    for (int i = 0; i < p.samples().size(); ++i) {
      if (p.samples().groups[0].of_sample[static_cast<std::size_t>(i)] == static_cast<int>(g)) subset.push_back(i);
    }
    hapsyn::EvalOptions options;
    options.subset = &subset;
    const hapsyn::Evaluation& e = p.evaluate(nullptr, *ws, options);
    EXPECT_DOUBLE_EQ(subjects.values(static_cast<Eigen::Index>(g), 0), e.objectives[0]);
    sum += e.objectives[0];
  }
  EXPECT_DOUBLE_EQ(subjects.mean(0), sum / 2);
  EXPECT_GT(subjects.standard_deviation(0), 0.0);  // the subjects' arms and motions differ
}

TEST_F(MotionValidation, ASceneWithoutMotionIsRefusedWithTheWayOut) {
  Json doc = {{"name", "no-motion"},
              {"mechanism", {{"plugin", "haptic6r"}}},
              {"scene", {{"plugin", "human_arm"}, {"options", {{"lattice_step", 0.35}, {"orientations", 5}, {"cache", false}}}}},
              {"design", kDesign},
              {"objectives", {{{"metric", "motion_feasibility"}, {"options", {{"share", "velocity"}}}}}},
              {"solver", {{"plugin", "evaluate"}}}};
  EXPECT_NE(hapsyn::test::error_of([&] { hapsyn::load_study(doc, hapsyn::test::registry()); })
                .find("metric 'motion_feasibility' needs the demanded motion of each sample (joint_velocity"),
            std::string::npos);
}

TEST_F(MotionValidation, ABadRecordingStopsTheRunBeforeAnythingIsWritten) {
  const std::string folder = data(1.0);
  // One NaN row in the second subject's lifting recording.
  const fs::path bad = fs::path(folder) / "S02" / "lifting.csv";
  std::ofstream(bad.string(), std::ios::app) << "99,nan,0,0,1,0,0,0\n";
  Json doc = {{"name", "bad-recording"},
              {"mechanism", {{"plugin", "haptic6r"}}},
              {"scene", {{"plugin", "motion"}, {"options", {{"path", folder}}}}},
              {"design", kDesign},
              {"objectives", {{{"metric", "motion_feasibility"}}}},
              {"solver", {{"plugin", "evaluate"}}}};
  const fs::path problem = dir_ / "bad.json", out = dir_ / "out";
  std::ofstream(problem.string()) << doc.dump();
  const hapsyn::test::Output o = hapsyn::test::hapsyn_cli("run " + problem.string() + " --out " + out.string());
  EXPECT_EQ(o.code, 1) << o.out;  // bad input
  EXPECT_NE(o.out.find(bad.string() + ":"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("nan"), std::string::npos) << o.out;
  EXPECT_FALSE(fs::exists(out)) << "the failed run wrote " << out;
}

}  // namespace
