// The motion scene end to end on analytic trajectories written as hapsyn-motion CSV: the samples
// and the demanded twist against closed-form values (position, velocity and acceleration of a
// sinusoid; a rotation about a fixed axis), the mapping into the manipulator base against an
// independent construction, trim and stride, the groupings, and the refused inputs.
#include "motion_scene.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/options.hpp>
#include <hapsyn/quantities.hpp>

#include <Eigen/Geometry>
#include <boost/filesystem.hpp>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <iomanip>
#include <sstream>

namespace {

namespace fs = boost::filesystem;
using hapsyn::Json;
using hapsyn::SampleSet;
using hapsyn::plugins::MotionOptions;
using hapsyn::plugins::MotionScene;
using ::testing::HasSubstr;

constexpr double kPi = 3.14159265358979323846;

// The analytic palm motion in S: p(t) = p0 + A sin(w t) (per axis), orientation a rotation of
// angle b sin(w t) about a fixed unit axis u, so omega = b w cos(w t) u, alpha = -b w^2 sin(w t) u.
struct Analytic {
  Eigen::Vector3d p0{0.3, -0.1, 0.2}, A{0.10, 0.05, -0.08};
  Eigen::Vector3d u = Eigen::Vector3d(1, 2, 2).normalized();
  double b = 0.6, w = 2 * kPi * 0.5;  // 0.5 Hz, well below the 5 Hz cut-off
  Eigen::Vector3d p(double t) const { return p0 + A * std::sin(w * t); }
  Eigen::Vector3d v(double t) const { return A * w * std::cos(w * t); }
  Eigen::Vector3d a(double t) const { return -A * w * w * std::sin(w * t); }
  Eigen::Quaterniond q(double t) const { return Eigen::Quaterniond(Eigen::AngleAxisd(b * std::sin(w * t), u)); }
  Eigen::Vector3d omega(double t) const { return b * w * std::cos(w * t) * u; }
  Eigen::Vector3d alpha(double t) const { return -b * w * w * std::sin(w * t) * u; }
};

std::string csv_of(const Analytic& m, double rate, double seconds, const std::string& header = "") {
  std::ostringstream s;
  s << "# hapsyn-motion 1\n" << header << "time,x,y,z,qw,qx,qy,qz\n" << std::setprecision(17);
  const int n = static_cast<int>(std::lround(seconds * rate)) + 1;
  for (int i = 0; i < n; ++i) {
    const double t = i / rate;
    const Eigen::Vector3d p = m.p(t);
    const Eigen::Quaterniond q = m.q(t);
    s << t << "," << p.x() << "," << p.y() << "," << p.z() << "," << q.w() << "," << q.x() << "," << q.y() << ","
      << q.z() << "\n";
  }
  return s.str();
}

class MotionScenes : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / fs::unique_path("hapsyn-motion-%%%%-%%%%-%%%%");
    fs::create_directories(dir_);
  }
  void TearDown() override {
    boost::system::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& name, const std::string& text) const {
    const fs::path path = dir_ / name;
    fs::create_directories(path.parent_path());
    std::ofstream(path.string(), std::ios::binary) << text;
    return path.string();
  }
  static SampleSet build(const Json& options) {
    const MotionOptions o = hapsyn::make_options<MotionOptions>(options, "scene.options");
    return MotionScene(o).build({});
  }
  // Identity placement: B = S, E = P, so samples and twists are the palm's in S.
  static Json identity_placement(Json options) {
    options["x_S_B"] = {0, 0, 0};
    options["C_S_B"] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    options["C_E_P"] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    return options;
  }
  static std::string error_of(const std::function<void()>& f) {
    try {
      f();
    } catch (const hapsyn::Error& e) {
      return e.what();
    }
    return "(no error)";
  }
  fs::path dir_;
};

// The largest error of the scene's twist against the analytic one over samples with time in
// [from, to], rows (omega, v) then (alpha, a).
struct TwistErrors {
  double position = 0, orientation = 0, omega = 0, velocity = 0, alpha = 0, acceleration = 0;
};
TwistErrors errors(const SampleSet& s, const Analytic& m, double from, double to) {
  TwistErrors e;
  const auto& twist = s.attributes.at(hapsyn::kTwistAttribute);
  const auto& rate = s.attributes.at(hapsyn::kTwistRateAttribute);
  const auto& time = s.attributes.at("time");
  for (int i = 0; i < s.size(); ++i) {
    const double t = time(i, 0);
    if (t < from || t > to) continue;
    const Eigen::Vector3d p(s.poses(i, 0), s.poses(i, 1), s.poses(i, 2));
    const Eigen::Quaterniond q(s.poses(i, 3), s.poses(i, 4), s.poses(i, 5), s.poses(i, 6));
    e.position = std::max(e.position, (p - m.p(t)).norm());
    e.orientation = std::max(e.orientation, q.angularDistance(m.q(t)));
    e.omega = std::max(e.omega, (twist.row(i).head<3>().transpose() - m.omega(t)).norm());
    e.velocity = std::max(e.velocity, (twist.row(i).tail<3>().transpose() - m.v(t)).norm());
    e.alpha = std::max(e.alpha, (rate.row(i).head<3>().transpose() - m.alpha(t)).norm());
    e.acceleration = std::max(e.acceleration, (rate.row(i).tail<3>().transpose() - m.a(t)).norm());
  }
  return e;
}

TEST_F(MotionScenes, FilteredTwistMatchesTheAnalyticMotionAwayFromTheEnds) {
  const Analytic m;
  const std::string file = write("S01/reaching.csv", csv_of(m, 120.0, 10.0));
  const SampleSet s = build(identity_placement({{"path", file}}));
  ASSERT_EQ(s.size(), 1201);
  // 0.5 Hz under a 5 Hz 4th-order zero-phase low-pass: gain 1 - O(1e-8), no phase. The
  // derivatives' central-difference error is (w h)^2 / 6 = 1.14e-4 relative. The middle 8 s:
  const TwistErrors e = errors(s, m, 1.0, 9.0);
  EXPECT_LT(e.position, 1e-6);
  EXPECT_LT(e.orientation, 1e-6);
  EXPECT_LT(e.velocity, 1.5e-4 * m.A.norm() * m.w);
  EXPECT_LT(e.omega, 1.5e-4 * m.b * m.w);
  EXPECT_LT(e.acceleration, 1e-3 * m.A.norm() * m.w * m.w);
  EXPECT_LT(e.alpha, 1e-3 * m.b * m.w * m.w);
}

TEST_F(MotionScenes, WithoutTheFilterTheDerivativesAreCentralDifferences) {
  const Analytic m;
  const std::string file = write("a.csv", csv_of(m, 120.0, 4.0));
  const SampleSet s = build(identity_placement({{"path", file}, {"filter", false}}));
  const TwistErrors e = errors(s, m, 0.1, 3.9);
  EXPECT_LT(e.position, 1e-12);
  // Central differences of a sinusoid: relative error (w h)^2 / 6 = 1.9e-5 at 120 Hz.
  const double h = 1.0 / 120.0, bound = (m.w * h) * (m.w * h) / 6.0 * 1.5;
  EXPECT_LT(e.velocity, bound * m.A.norm() * m.w);
  EXPECT_LT(e.omega, bound * m.b * m.w);
}

TEST_F(MotionScenes, PlacementMapsPoseAndTwistIntoTheBase) {
  const Analytic m;
  const std::string file = write("a.csv", csv_of(m, 120.0, 6.0));
  // A general placement, built here independently: T_E^B = T_S^B T_P^S T_E^P.
  const Eigen::Matrix3d C = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0, 1, 1).normalized()).toRotationMatrix();
  const Eigen::Matrix3d E = Eigen::AngleAxisd(-1.1, Eigen::Vector3d(1, 0, 1).normalized()).toRotationMatrix();
  const Eigen::Vector3d x(0.1, -0.2, -0.5), r(0.02, -0.03, 0.05);
  const auto rows = [](const Eigen::Matrix3d& c) {
    return Json{{c(0, 0), c(0, 1), c(0, 2)}, {c(1, 0), c(1, 1), c(1, 2)}, {c(2, 0), c(2, 1), c(2, 2)}};
  };
  const SampleSet s = build({{"path", file}, {"x_S_B", {x.x(), x.y(), x.z()}}, {"C_S_B", rows(C)},
                             {"C_E_P", rows(E)}, {"x_E_P", {r.x(), r.y(), r.z()}}});
  const SampleSet palm = build(identity_placement({{"path", file}}));
  ASSERT_EQ(s.size(), palm.size());
  const auto& twist = s.attributes.at(hapsyn::kTwistAttribute);
  const auto& palm_twist = palm.attributes.at(hapsyn::kTwistAttribute);
  for (int i = 0; i < s.size(); i += 37) {
    const Eigen::Vector3d p(palm.poses(i, 0), palm.poses(i, 1), palm.poses(i, 2));
    const Eigen::Matrix3d R =
        Eigen::Quaterniond(palm.poses(i, 3), palm.poses(i, 4), palm.poses(i, 5), palm.poses(i, 6)).toRotationMatrix();
    const Eigen::Vector3d expected_x = x + C * (p + R * r);
    const Eigen::Matrix3d expected_R = C * R * E;
    const Eigen::Vector3d got_x(s.poses(i, 0), s.poses(i, 1), s.poses(i, 2));
    const Eigen::Matrix3d got_R = Eigen::Quaterniond(s.poses(i, 3), s.poses(i, 4), s.poses(i, 5), s.poses(i, 6)).toRotationMatrix();
    EXPECT_LT((got_x - expected_x).norm(), 1e-12);
    EXPECT_LT((got_R - expected_R).norm(), 1e-12);
    EXPECT_GE(s.poses(i, 3), 0.0);
    // The velocity of the point E: v_P + omega x (R r), rotated into B.
    const Eigen::Vector3d w = palm_twist.row(i).head<3>().transpose(), v = palm_twist.row(i).tail<3>().transpose();
    EXPECT_LT((twist.row(i).head<3>().transpose() - C * w).norm(), 1e-12);
    EXPECT_LT((twist.row(i).tail<3>().transpose() - C * (v + w.cross(R * r))).norm(), 1e-12);
  }
}

// The shipped recordings as every shipped motion study places them: the user is upright, so
// every seated activity starts and ends with the hand resting on the table, which lies below the
// shoulder in B and in front of the user (+x_B), and no seated motion takes the hand far above
// the shoulder. A user lying on their side (the paper's printed C_S^B taken as S -> B) would
// have the table beside the shoulder, at its height.
TEST_F(MotionScenes, SeatedActivitiesStartAndEndOnATableBelowTheShoulder) {
  int studies = 0;
  for (const auto& entry : fs::directory_iterator(HAPSYN_SOURCE_DIR "/problems")) {
    if (entry.path().extension() != ".json") continue;
    std::ifstream in(entry.path().string());
    const Json problem = Json::parse(in);
    if (problem.at("scene").at("plugin") != "motion") continue;
    const std::string label = entry.path().filename().string();
    const Json options = problem.at("scene").value("options", Json::object());
    const SampleSet s = build(options);
    const double shoulder_z = hapsyn::make_options<MotionOptions>(options, "scene.options").x_S_B[2];
    const hapsyn::SampleGrouping& activity = s.groups[1];
    const hapsyn::SampleGrouping& trajectory = s.groups[2];
    ASSERT_EQ(activity.name, "activity") << label;
    ASSERT_EQ(trajectory.name, "trajectory") << label;
    const auto seated = [&](int i) {
      return activity.labels[static_cast<std::size_t>(activity.of_sample[static_cast<std::size_t>(i)])] != "side_reach";
    };
    const auto on_the_table = [&](int i, const char* when) {
      const std::string& name =
          trajectory.labels[static_cast<std::size_t>(trajectory.of_sample[static_cast<std::size_t>(i)])];
      EXPECT_LT(s.poses(i, 2), shoulder_z - 0.15) << label << " " << name << " " << when << ": not below the shoulder";
      EXPECT_GT(s.poses(i, 0), 0.1) << label << " " << name << " " << when << ": not in front of the user";
    };
    int trajectories = 0;
    for (int i = 0; i < s.size(); ++i) {
      if (!seated(i)) continue;
      EXPECT_LT(s.poses(i, 2), shoulder_z + 0.15) << label << " sample " << i << " far above the shoulder";
      const bool first = i == 0 || trajectory.of_sample[static_cast<std::size_t>(i - 1)] != trajectory.of_sample[static_cast<std::size_t>(i)];
      const bool last = i + 1 == s.size() ||
                        trajectory.of_sample[static_cast<std::size_t>(i + 1)] != trajectory.of_sample[static_cast<std::size_t>(i)];
      if (first) ++trajectories, on_the_table(i, "start");
      if (last) on_the_table(i, "end");
    }
    EXPECT_EQ(trajectories, 24) << label << ": 6 subjects x 4 seated activities";
    ++studies;
  }
  EXPECT_GE(studies, 2) << "the shipped motion studies";
}

TEST_F(MotionScenes, FolderGivesSubjectsActivitiesAndTrajectories) {
  const Analytic m;
  write("S01/reaching.csv", csv_of(m, 100.0, 1.0));
  write("S01/wiping.csv", csv_of(m, 100.0, 1.5));
  write("S02/reaching.csv", csv_of(m, 100.0, 2.0));
  const SampleSet s = build({{"path", dir_.string()}});
  ASSERT_EQ(s.groups.size(), 3u);
  EXPECT_EQ(s.groups[0].name, "subject");
  EXPECT_EQ(s.groups[0].labels, (std::vector<std::string>{"S01", "S02"}));
  EXPECT_EQ(s.groups[1].labels, (std::vector<std::string>{"reaching", "wiping"}));
  EXPECT_EQ(s.groups[2].labels, (std::vector<std::string>{"S01/reaching", "S01/wiping", "S02/reaching"}));
  EXPECT_EQ(s.size(), 101 + 151 + 201);
  EXPECT_EQ(s.groups[2].of_sample[101], 1);
  EXPECT_EQ(s.groups[0].of_sample[101 + 151], 1);
  EXPECT_EQ(s.info["recordings"], 3);
}

TEST_F(MotionScenes, TrimAndStrideDropSamples) {
  const Analytic m;
  const std::string file = write("a.csv", csv_of(m, 100.0, 3.0));
  const SampleSet s = build({{"path", file}, {"trim", 0.5}, {"stride", 4}});
  // 301 samples, 50 trimmed at each end: 201, every 4th kept: 51.
  EXPECT_EQ(s.size(), 51);
  const auto& time = s.attributes.at("time");
  EXPECT_NEAR(time(0, 0), 0.5, 1e-12);
  EXPECT_NEAR(time(1, 0), 0.54, 1e-12);
}

TEST_F(MotionScenes, JitteredTimeStampsAreResampled) {
  const Analytic m;
  std::ostringstream s;
  s << "time,x,y,z,qw,qx,qy,qz\n" << std::setprecision(17);
  for (int i = 0; i <= 600; ++i) {
    const double t = i / 120.0 + (i % 2 ? 0.9e-3 : -0.7e-3) * (i > 0 && i < 600);
    const Eigen::Vector3d p = m.p(t);
    const Eigen::Quaterniond q = m.q(t);
    s << t << "," << p.x() << "," << p.y() << "," << p.z() << "," << q.w() << "," << q.x() << "," << q.y() << ","
      << q.z() << "\n";
  }
  const SampleSet set = build(identity_placement({{"path", write("j.csv", s.str())}}));
  const auto& time = set.attributes.at("time");
  for (int i = 1; i < set.size(); ++i) EXPECT_NEAR(time(i, 0) - time(i - 1, 0), 1.0 / 120.0, 1e-9);
  // Linear interpolation between jittered samples: error ~ (w dt)^2 / 8 of the amplitude.
  EXPECT_LT(errors(set, m, 1.0, 4.0).position, 2e-4);
}

TEST_F(MotionScenes, TooShortARecordingIsRefusedWithItsFile) {
  const Analytic m;
  const std::string file = write("short.csv", csv_of(m, 120.0, 0.05));
  const std::string e = error_of([&] { build({{"path", file}}); });
  EXPECT_THAT(e, HasSubstr("motion: " + file + ": 7 samples"));
  EXPECT_THAT(e, HasSubstr("the filter and derivatives need at least 16 samples"));
  const std::string trimmed = error_of([&] { build({{"path", write("t.csv", csv_of(m, 120.0, 0.5))}, {"trim", 0.3}}); });
  EXPECT_THAT(trimmed, HasSubstr("trimmed (trim = 0.3"));
}

TEST_F(MotionScenes, BadOptionsAreRefusedWithTheRule) {
  const Analytic m;
  const std::string file = write("a.csv", csv_of(m, 120.0, 1.0));
  EXPECT_THAT(error_of([&] { build({{"path", (dir_ / "nowhere").string()}}); }),
              HasSubstr("options.path = \"" + (dir_ / "nowhere").string() + "\": no such file or folder"));
  EXPECT_THAT(error_of([&] { build({{"path", file}, {"recording_rotation", {{1, 0, 0}, {0, 1, 0}, {0, 0, 2}}}}); }),
              HasSubstr("options.recording_rotation = [[1.0,0.0,0.0],[0.0,1.0,0.0],[0.0,0.0,2.0]]: must be a rotation matrix"));
  EXPECT_THAT(error_of([&] { build({{"path", file}, {"cutoff", 70}}); }),
              HasSubstr("options.cutoff = 70 Hz: must be below half the sampling rate of " + file + " (120 Hz)"));
  EXPECT_THAT(error_of([&] { build({{"path", file}, {"stride", 0}}); }), HasSubstr("scene.options.stride"));
  EXPECT_THAT(error_of([&] { build({{"path", file}, {"trim", 1e300}}); }), HasSubstr("scene.options.trim"));
  EXPECT_THAT(error_of([&] { build({{"path", file}, {"rate", 1e300}}); }), HasSubstr("scene.options.rate"));
  const std::string long_file = write("long.csv", "time,x,y,z,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n1000,0,0,0,1,0,0,0\n");
  EXPECT_THAT(error_of([&] { build({{"path", long_file}, {"rate", 100000}}); }),
              HasSubstr(long_file + ": resampling 1000 s at 100000 Hz (options.rate) gives 1e+08 samples: more than "
                                    "options.max_samples = 10000000 (lower options.rate, or raise max_samples deliberately)"));
}

// Issue 53, cause 1: a small recording whose time stamps have a tiny step (its median rate
// 1 MHz) and one long gap would be resampled to 5e7 samples (the process then died of memory);
// the count is decided from the duration and rate before any sample is made, for the whole scene.
TEST_F(MotionScenes, SampleCountIsBoundedBeforeAnyWork) {
  std::ostringstream tiny;
  tiny << "# hapsyn-motion 1\ntime,x,y,z,qw,qx,qy,qz\n" << std::setprecision(17);
  for (int i = 0; i < 40; ++i) tiny << i * 1e-6 << ",0,0,0,1,0,0,0\n";
  tiny << "50,0,0,0,1,0,0,0\n";
  const std::string file = write("tiny/S01/tiny.csv", tiny.str());
  const auto started = std::chrono::steady_clock::now();
  EXPECT_THAT(error_of([&] { build({{"path", file}}); }),
              HasSubstr(file + ": resampling 50 s at 1e+06 Hz (its median rate) gives 5e+07 samples: more than "
                               "options.max_samples = 10000000 (check the time stamps, or raise max_samples deliberately)"));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), 5.0);
  // The budget is the whole scene's: the second recording is refused with the first one's count.
  const Analytic m;
  write("two/S01/a.csv", csv_of(m, 120.0, 2.0));
  write("two/S01/b.csv", csv_of(m, 120.0, 2.0));
  EXPECT_THAT(error_of([&] { build({{"path", (dir_ / "two").string()}, {"max_samples", 300}}); }),
              HasSubstr("b.csv: 241 samples, with the 241 of the recordings before it: more than options.max_samples = 300"));
  EXPECT_EQ(build({{"path", (dir_ / "two").string()}, {"max_samples", 482}}).size(), 482);
}

// A recording whose time stamps step by 1e-9 s (nanoseconds read as seconds) once gave 50
// samples at 1 GHz whose filtered velocities were off by 10^3: a cut-off at 1e-8 of the Nyquist
// frequency is beyond what the low-pass computes accurately, and is refused with the file.
TEST_F(MotionScenes, ACutOffFarBelowTheNyquistFrequencyIsRefused) {
  std::ostringstream ns;
  ns << "# hapsyn-motion 1\ntime,x,y,z,qw,qx,qy,qz\n" << std::setprecision(17);
  for (int i = 0; i < 50; ++i) ns << i * 1e-9 << "," << 0.3 + 3.5e-12 * i << ",0,0,1,0,0,0\n";
  const std::string file = write("ns/S01/ns.csv", ns.str());
  EXPECT_THAT(error_of([&] { build({{"path", file}}); }),
              HasSubstr("motion: options.cutoff = 5 Hz is 1e-08 of the Nyquist frequency of " + file +
                        " (sampled at 1e+09 Hz): the low-pass is accurate down to 0.0001 of it; check the time stamps"));
  // Without the filter the derivatives are differences of the data as given: 3.5 mm/s.
  const hapsyn::SampleSet unfiltered = build({{"path", file}, {"filter", false}});
  EXPECT_NEAR(unfiltered.attributes.at("twist").row(25).tail<3>().norm(), 3.5e-3, 1e-8);  // (omega, v)
}

TEST_F(MotionScenes, UnknownAttributeIsRefused) {
  const Analytic m;
  const std::string file = write("a.csv", csv_of(m, 120.0, 1.0));
  hapsyn::SceneRequest request;
  request.attributes = {"M_v"};
  const MotionOptions o = hapsyn::make_options<MotionOptions>(Json{{"path", file}}, "scene.options");
  EXPECT_THAT(error_of([&] { MotionScene(o).build(request); }),
              HasSubstr("attribute 'M_v' is not provided (motion provides twist, twist_rate, time, shoulder_pose)"));
}

}  // namespace
