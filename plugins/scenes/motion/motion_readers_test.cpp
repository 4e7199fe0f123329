// Tests of the motion readers: the hapsyn-motion CSV format (both orientation forms, units,
// labels, every refused file with its message), BVH files (poses against closed-form
// kinematics, channel order, the shoulder frame's independence of body and clavicle motion,
// refused files) and folders (order, labels, empty folders).
#include "motion_recording.hpp"

#include <hapsyn/error.hpp>

#include <Eigen/Geometry>
#include <boost/filesystem.hpp>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

namespace {

namespace fs = boost::filesystem;
using hapsyn::plugins::motion::BvhOptions;
using hapsyn::plugins::motion::read_bvh;
using hapsyn::plugins::motion::read_motion_csv;
using hapsyn::plugins::motion::read_recordings;
using hapsyn::plugins::motion::Recording;
using ::testing::HasSubstr;
using Eigen::Matrix3d;
using Eigen::Vector3d;

// A fresh directory, removed afterwards.
class TempDir {
 public:
  TempDir() : root_(fs::temp_directory_path() / fs::unique_path("hapsyn-motion-%%%%-%%%%-%%%%")) {
    fs::create_directories(root_);
  }
  ~TempDir() {
    boost::system::error_code ec;
    fs::remove_all(root_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  std::string path(const std::string& name = "") const { return name.empty() ? root_.string() : (root_ / name).string(); }
  std::string write(const std::string& name, const std::string& text) const {
    const fs::path file = root_ / name;
    fs::create_directories(file.parent_path());
    std::ofstream(file.string(), std::ios::binary) << text;
    return file.string();
  }

 private:
  fs::path root_;
};

std::string error_of(const std::function<void()>& read) {
  try {
    read();
  } catch (const hapsyn::Error& e) {
    return e.what();
  }
  return "no error";
}

std::string csv_error(const TempDir& dir, const std::string& text, const std::string& name = "m.csv") {
  const std::string path = dir.write(name, text);
  return error_of([&] { read_motion_csv(path); });
}

std::string number(double value) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

// Rotations written out from their definitions (angles in degrees), independent of the readers.
Matrix3d rx(double degrees) {
  const double c = std::cos(degrees * M_PI / 180), s = std::sin(degrees * M_PI / 180);
  return (Matrix3d() << 1, 0, 0, 0, c, -s, 0, s, c).finished();
}
Matrix3d ry(double degrees) {
  const double c = std::cos(degrees * M_PI / 180), s = std::sin(degrees * M_PI / 180);
  return (Matrix3d() << c, 0, s, 0, 1, 0, -s, 0, c).finished();
}
Matrix3d rz(double degrees) {
  const double c = std::cos(degrees * M_PI / 180), s = std::sin(degrees * M_PI / 180);
  return (Matrix3d() << c, -s, 0, s, c, 0, 0, 0, 1).finished();
}

Matrix3d rotation_of(const Recording& r, int row) {
  const Eigen::Quaterniond q(r.quaternion(row, 0), r.quaternion(row, 1), r.quaternion(row, 2), r.quaternion(row, 3));
  return q.toRotationMatrix();
}

void expect_pose(const Recording& r, int row, const Vector3d& position, const Matrix3d& rotation) {
  SCOPED_TRACE("row " + std::to_string(row));
  EXPECT_LT((r.position.row(row).transpose() - position).cwiseAbs().maxCoeff(), 1e-12)
      << r.position.row(row) << " vs " << position.transpose();
  EXPECT_LT((rotation_of(r, row) - rotation).cwiseAbs().maxCoeff(), 1e-12) << rotation_of(r, row) << "\nvs\n" << rotation;
  EXPECT_NEAR(r.quaternion.row(row).norm(), 1.0, 1e-15);
}

// ---------------------------------------------------------------- CSV

const char* const kQuaternionHeader = "time,x,y,z,qw,qx,qy,qz\n";

TEST(MotionCsv, QuaternionAndMatrixFormsGiveTheSamePoses) {
  TempDir dir;
  const std::vector<Matrix3d> rotations = {Matrix3d::Identity(), rz(90), rz(30) * rx(-50) * ry(120),
                                           rx(179) * ry(10), rz(-170) * rx(20), ry(181)};
  std::string quaternions = "# hapsyn-motion 1\n" + std::string(kQuaternionHeader);
  // Matrix form with columns in another order: order is free.
  std::string matrices = "r33,r32,r31,r23,r22,r21,r13,r12,r11, z ,y,x,time\n";
  for (std::size_t i = 0; i < rotations.size(); ++i) {
    const Matrix3d& r = rotations[i];
    const Eigen::Quaterniond q(r);
    const double x = 0.1 * i, y = -0.2, z = 0.3 + 0.01 * i, t = 0.01 * i;
    quaternions += number(t) + "," + number(x) + "," + number(y) + "," + number(z) + "," + number(q.w()) + "," +
                   number(q.x()) + "," + number(q.y()) + "," + number(q.z()) + "\n";
    for (int k = 8; k >= 0; --k) matrices += number(r(k / 3, k % 3)) + ",";
    matrices += number(z) + "\t, " + number(y) + "," + number(x) + "," + number(t) + "\r\n";
  }
  const Recording a = read_motion_csv(dir.write("quaternion.csv", quaternions));
  const Recording b = read_motion_csv(dir.write("matrix.csv", matrices));
  ASSERT_EQ(a.time.size(), 6);
  ASSERT_EQ(b.time.size(), 6);
  EXPECT_EQ(a.line, (std::vector<int>{3, 4, 5, 6, 7, 8}));
  EXPECT_EQ(b.line, (std::vector<int>{2, 3, 4, 5, 6, 7}));
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(a.time[i], 0.01 * i);
    EXPECT_EQ(b.time[i], a.time[i]);
    EXPECT_EQ(a.position.row(i), b.position.row(i));
    expect_pose(a, i, a.position.row(i).transpose(), rotations[i]);
    expect_pose(b, i, a.position.row(i).transpose(), rotations[i]);
    // Quaternions from matrices continue the previous row's sign.
    if (i > 0) {
      EXPECT_GE(b.quaternion.row(i).dot(b.quaternion.row(i - 1)), 0.0);
    }
  }
  EXPECT_GE(b.quaternion(0, 0), 0.0);
}

TEST(MotionCsv, NormalisesQuaternionsWithinTolerance) {
  TempDir dir;
  const Recording r = read_motion_csv(dir.write("q.csv", std::string(kQuaternionHeader) +
                                                             "0,0,0,0,1.0009,0,0,0\n1,0,0,0,0,0,0,-0.9995\n"));
  EXPECT_EQ(r.quaternion.row(0), Eigen::RowVector4d(1, 0, 0, 0));
  EXPECT_EQ(r.quaternion.row(1), Eigen::RowVector4d(0, 0, 0, -1));  // the recorded sign is kept
}

TEST(MotionCsv, ConvertsMillimetresAndMilliseconds) {
  TempDir dir;
  const std::string text = "# unit: mm\n# time_unit: ms\n" + std::string(kQuaternionHeader) +
                           "0,100,-250,300,1,0,0,0\n"
                           "# a comment after the column row\n\n"
                           "10,101,-250,300,1,0,0,0\n"
                           "25.5,102,-250,300,1,0,0,0\n";
  const Recording r = read_motion_csv(dir.write("mm.csv", text));
  ASSERT_EQ(r.time.size(), 3);
  EXPECT_DOUBLE_EQ(r.time[1], 0.010);
  EXPECT_DOUBLE_EQ(r.time[2], 0.0255);
  EXPECT_DOUBLE_EQ(r.position(0, 0), 0.1);
  EXPECT_DOUBLE_EQ(r.position(0, 1), -0.25);
  EXPECT_DOUBLE_EQ(r.position(2, 2), 0.3);
  EXPECT_EQ(r.line, (std::vector<int>{4, 7, 8}));

  const Recording cm = read_motion_csv(dir.write("cm.csv", "# unit: cm\n" + std::string(kQuaternionHeader) +
                                                               "0,10,0,0,1,0,0,0\n1,20,0,0,1,0,0,0\n"));
  EXPECT_DOUBLE_EQ(cm.position(1, 0), 0.2);
  EXPECT_EQ(cm.time[1], 1.0);
}

TEST(MotionCsv, LabelsFromHeaderElseStem) {
  TempDir dir;
  const std::string rows = std::string(kQuaternionHeader) + "0,0,0,0,1,0,0,0\n1,0,0,0,1,0,0,0\n";
  const Recording labelled =
      read_motion_csv(dir.write("S09/take3.csv", "# subject: S01\n# activity: reaching\n" + rows));
  EXPECT_EQ(labelled.subject, "S01");
  EXPECT_EQ(labelled.activity, "reaching");
  EXPECT_EQ(labelled.file, dir.path("S09/take3.csv"));
  // Read alone (not from a folder): the stem, also for a nested file.
  const Recording bare = read_motion_csv(dir.write("S09/take4.csv", rows));
  EXPECT_EQ(bare.subject, "take4");
  EXPECT_EQ(bare.activity, "take4");
  // From a folder: the subject is the first folder below the root unless the header names one.
  const std::vector<Recording> all = read_recordings(dir.path(), BvhOptions{});
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0].subject, "S01");
  EXPECT_EQ(all[0].activity, "reaching");
  EXPECT_EQ(all[1].subject, "S09");
  EXPECT_EQ(all[1].activity, "take4");
}

// Issue 53, cause 6: labels that are not UTF-8 (a header value, a subject folder, a file name)
// are refused where they are read, naming the file: they once passed `validate` and failed the
// run only when result.json was written.
TEST(MotionCsv, LabelsThatAreNotUtf8AreRefusedWhereTheyAreRead) {
  TempDir dir;
  const std::string rows = std::string(kQuaternionHeader) + "0,0,0,0,1,0,0,0\n1,0,0,0,1,0,0,0\n";
  EXPECT_EQ(csv_error(dir, "# subject: S\xff" "1\n" + rows),
            "motion: " + dir.path("m.csv") + ":1: header key subject = \"S\\xff1\": invalid UTF-8 at byte 1 (labels are "
            "written into result.json: they must be UTF-8)");
  TempDir folder;
  folder.write("S\xfe/reach.csv", rows);
  EXPECT_NE(error_of([&] { read_recordings(folder.path(), BvhOptions{}); })
                .find("the file's path is not valid UTF-8 (at byte " + std::to_string(folder.path().size() + 2) + ")"),
            std::string::npos)
      << error_of([&] { read_recordings(folder.path(), BvhOptions{}); });
}

TEST(MotionCsv, RefusesTimeThatIsNotStrictlyIncreasing) {
  TempDir dir;
  const std::string header = kQuaternionHeader;
  std::string message = csv_error(dir, header + "0,0,0,0,1,0,0,0\n0.2,0,0,0,1,0,0,0\n0.1,0,0,0,1,0,0,0\n");
  EXPECT_THAT(message, HasSubstr("motion: " + dir.path("m.csv") + ":4: time 0.1 is not after the previous row's 0.2 "
                                 "(line 3): time must be strictly increasing"));
  message = csv_error(dir, header + "0,0,0,0,1,0,0,0\n\n0.50,0,0,0,1,0,0,0\n0.5,0,0,0,1,0,0,0\n");
  EXPECT_THAT(message, HasSubstr(dir.path("m.csv") + ":5: time 0.5 is not after the previous row's 0.50 (line 4)"));
}

TEST(MotionCsv, RefusesFieldsThatAreNotFiniteNumbers) {
  TempDir dir;
  const std::string header = kQuaternionHeader;
  const std::string f = dir.path("m.csv");
  EXPECT_THAT(csv_error(dir, header + "0,0,0,0,1,0,0,0\n1,nan,0,0,1,0,0,0\n"),
              HasSubstr(f + ":3: column x = \"nan\": not finite: every field must be a finite number"));
  EXPECT_THAT(csv_error(dir, header + "0,0,0,-inf,1,0,0,0\n"), HasSubstr(f + ":2: column z = \"-inf\": not finite"));
  EXPECT_THAT(csv_error(dir, header + "0,0,,0,1,0,0,0\n"),
              HasSubstr(f + ":2: column y is empty: every field must be a finite number"));
  EXPECT_THAT(csv_error(dir, header + "0,0,0,0,1,0,0,0\n1,0,0,0,1,0.0x,0,0\n"),
              HasSubstr(f + ":3: column qx = \"0.0x\": not a number"));
  EXPECT_THAT(csv_error(dir, header + "0,0,0,0,1,0,0,0\n1,0,0,0,1,0,0,1e999\n"),
              HasSubstr(f + ":3: column qz = \"1e999\": not finite"));
}

TEST(MotionCsv, RefusesBadColumnRows) {
  TempDir dir;
  const std::string f = dir.path("m.csv");
  EXPECT_THAT(csv_error(dir, "time,x,z,qw,qx,qy\n"),
              HasSubstr(f + ":1: column row: missing column(s) y, qz: the columns are time, x, y, z and either qw, qx, "
                            "qy, qz or r11 .. r33"));
  EXPECT_THAT(csv_error(dir, "time,x,y,z\n"), HasSubstr(f + ":1: column row: missing column(s) qw, qx, qy, qz (or r11 .. r33)"));
  EXPECT_THAT(csv_error(dir, "time,x,y,z,r11,r12,r13,r21,r22,r23,r31,r32\n"), HasSubstr("missing column(s) r33"));
  EXPECT_THAT(csv_error(dir, "# subject: a\ntime,x,y,z,qw,qx,qy,qz,speed\n"),
              HasSubstr(f + ":2: column row: unknown column \"speed\": the known columns are time, x, y, z, qw"));
  EXPECT_THAT(csv_error(dir, "time,x,y,z,qw,qx,qy,qz,x\n"),
              HasSubstr(f + ":1: column row: column \"x\" appears twice (fields 2 and 9)"));
  EXPECT_THAT(csv_error(dir, "time,x,y,z,qw,qx,qy,qz,r11,r12,r13,r21,r22,r23,r31,r32,r33\n"),
              HasSubstr(f + ":1: column row: both orientation forms"));
  EXPECT_THAT(csv_error(dir, "# subject: a\n\n"), HasSubstr(f + ": has no column row"));
}

TEST(MotionCsv, RefusesRowsOfTheWrongLength) {
  TempDir dir;
  const std::string f = dir.path("m.csv");
  EXPECT_THAT(csv_error(dir, std::string(kQuaternionHeader) + "0,0,0,0,1,0,0,0\n1,0,0,0,1,0,0\n"),
              HasSubstr(f + ":3: 7 fields, the column row (line 1) has 8: every row needs one field per column"));
  EXPECT_THAT(csv_error(dir, std::string(kQuaternionHeader) + "0,0,0,0,1,0,0,0,\n"),
              HasSubstr(f + ":2: 9 fields, the column row (line 1) has 8"));
}

TEST(MotionCsv, RefusesOrientationsThatAreNotRotations) {
  TempDir dir;
  const std::string f = dir.path("m.csv");
  const std::string matrix = "time,x,y,z,r11,r12,r13,r21,r22,r23,r31,r32,r33\n";
  EXPECT_THAT(csv_error(dir, matrix + "0,0,0,0,1,0,0,0,1,0,0,0,1\n1,0,0,0,1,0.001,0,0,1,0,0,0,1\n"),
              HasSubstr(f + ":3: rotation matrix (r11 .. r33) = (1, 0.001, 0, 0, 1, 0, 0, 0, 1) is not a rotation: "
                            "max |R^T R - I| = 0.001, det = 1: must be orthonormal with det +1 within 0.0001"));
  // A reflection is orthonormal but has det -1.
  EXPECT_THAT(csv_error(dir, matrix + "0,0,0,0,-1,0,0,0,1,0,0,0,1\n"),
              HasSubstr(f + ":2: rotation matrix (r11 .. r33) = (-1, 0, 0, 0, 1, 0, 0, 0, 1) is not a rotation: max "
                            "|R^T R - I| = 0, det = -1"));
  EXPECT_THAT(csv_error(dir, std::string(kQuaternionHeader) + "0,0,0,0,1,0,0,0\n1,0,0,0,1,0.1,0,0\n"),
              HasSubstr(f + ":3: quaternion (qw, qx, qy, qz) = (1, 0.1, 0, 0) has norm 1.00498756: must be 1 within 0.001"));
  EXPECT_THAT(csv_error(dir, std::string(kQuaternionHeader) + "0,0,0,0,0,0,0,0\n"), HasSubstr(f + ":2: quaternion"));
}

TEST(MotionCsv, RefusesBadHeaderComments) {
  TempDir dir;
  const std::string f = dir.path("m.csv");
  const std::string rest = std::string(kQuaternionHeader) + "0,0,0,0,1,0,0,0\n1,0,0,0,1,0,0,0\n";
  EXPECT_THAT(csv_error(dir, "# hapsyn-motion 1\n# subjekt: S01\n" + rest),
              HasSubstr(f + ":2: unknown header key \"subjekt\": the known keys are subject, activity, unit, time_unit"));
  EXPECT_THAT(csv_error(dir, "# hapsyn-motion 2\n" + rest),
              HasSubstr(f + ":1: format version \"2\" (\"# hapsyn-motion N\"): this reader reads version 1 only"));
  EXPECT_THAT(csv_error(dir, "# unit: km\n" + rest), HasSubstr(f + ":1: unit = \"km\": must be m, cm or mm"));
  EXPECT_THAT(csv_error(dir, "# time_unit: min\n" + rest), HasSubstr(f + ":1: time_unit = \"min\": must be s or ms"));
  EXPECT_THAT(csv_error(dir, "# unit: mm\n# unit: m\n" + rest),
              HasSubstr(f + ":2: header key unit given again (first on line 1)"));
  EXPECT_THAT(csv_error(dir, "# recorded in the lab\n" + rest),
              HasSubstr(f + ":1: header comment \"# recorded in the lab\": before the column row"));
}

TEST(MotionCsv, RefusesTooFewRows) {
  TempDir dir;
  EXPECT_THAT(csv_error(dir, std::string(kQuaternionHeader) + "0,0,0,0,1,0,0,0\n"),
              HasSubstr(dir.path("m.csv") + ": has 1 data row(s): at least 2 are required"));
}

TEST(MotionCsv, RefusesLinesLongerThanOneMebibyte) {
  TempDir dir;
  const std::string long_line = std::string(hapsyn::plugins::motion::kMotionMaxLineBytes + 1, '1');
  EXPECT_THAT(csv_error(dir, std::string(kQuaternionHeader) + long_line + "\n"),
              HasSubstr(dir.path("m.csv") + ":2: line longer than 1048576 bytes"));
  // Exactly at the limit, the line is read (and then refused for its content).
  const std::string at_limit = std::string(hapsyn::plugins::motion::kMotionMaxLineBytes, '1');
  EXPECT_THAT(csv_error(dir, std::string(kQuaternionHeader) + at_limit), HasSubstr(":2: 1 fields"));
}

TEST(MotionCsv, RefusesDirectoriesFifosAndMissingFiles) {
  TempDir dir;
  fs::create_directories(dir.path("folder.csv"));
  EXPECT_EQ(error_of([&] { read_motion_csv(dir.path("folder.csv")); }),
            "motion: " + dir.path("folder.csv") + ": is a directory: a file was expected");
  const std::string fifo = dir.path("pipe.csv");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  // Nothing writes to the FIFO: opening it for reading would block forever.
  EXPECT_EQ(error_of([&] { read_motion_csv(fifo); }),
            "motion: " + fifo + ": is not a regular file (a FIFO, socket or device): refused, reading it could block "
                                "or never end");
  EXPECT_EQ(error_of([&] { read_recordings(fifo, BvhOptions{}); }), error_of([&] { read_motion_csv(fifo); }));
  EXPECT_EQ(error_of([&] { read_motion_csv(dir.path("none.csv")); }), "motion: " + dir.path("none.csv") + ": no such file");
}

// ---------------------------------------------------------------- BVH

// A small skeleton: Hips (root; position + rotation), the right clavicle, the shoulder
// (RightArm, rotation channels in `arm_order`), the elbow (one channel), the hand (one channel),
// and a left arm after the right one (its channels come last in a frame line).
std::string skeleton(const std::string& arm_order = "Zrotation Xrotation Yrotation") {
  return "HIERARCHY\n"
         "ROOT Hips\n"
         "{\n"
         "  OFFSET 0.0 0.0 0.0\n"
         "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
         "  JOINT RightShoulder\n"
         "  {\n"
         "    OFFSET -5 20 0\n"
         "    CHANNELS 3 Zrotation Xrotation Yrotation\n"
         "    JOINT RightArm\n"
         "    {\n"
         "      OFFSET -10 0 0\n"
         "      CHANNELS 3 " + arm_order + "\n"
         "      JOINT RightForeArm\n"
         "      {\n"
         "        OFFSET 0 -30 0\n"
         "        CHANNELS 1 Xrotation\n"
         "        JOINT RightHand\n"
         "        {\n"
         "          OFFSET 0 -25 0\n"
         "          CHANNELS 1 Yrotation\n"
         "          End Site\n"
         "          {\n"
         "            OFFSET 0 -8 0\n"
         "          }\n"
         "        }\n"
         "      }\n"
         "    }\n"
         "  }\n"
         "  JOINT LeftArm\n"
         "  {\n"
         "    OFFSET 15 20 0\n"
         "    CHANNELS 3 Zrotation Xrotation Yrotation\n"
         "    End Site\n"
         "    {\n"
         "      OFFSET 0 -30 0\n"
         "    }\n"
         "  }\n"
         "}\n";
}
// The lines of skeleton().
const int kSkeletonLines = [] {
  const std::string text = skeleton();
  return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}();

// The values of one frame: root position and ZXY rotation, clavicle ZXY, arm (in the file's
// order), elbow X, hand Y, left arm ZXY.
struct Frame {
  Vector3d root_position = Vector3d::Zero(), root = Vector3d::Zero(), clavicle = Vector3d::Zero();
  Vector3d arm = Vector3d::Zero();  // in the order of the arm's CHANNELS line
  double elbow = 0, hand = 0;
  Vector3d left = Vector3d::Zero();
};

std::string frame_line(const Frame& f) {
  std::string line;
  for (const Vector3d& v : {f.root_position, f.root, f.clavicle, f.arm}) {
    for (int i = 0; i < 3; ++i) line += number(v[i]) + " ";
  }
  line += number(f.elbow) + "\t" + number(f.hand) + "  ";
  for (int i = 0; i < 3; ++i) line += number(f.left[i]) + " ";
  return line + "\n";
}

std::string bvh(const std::vector<Frame>& frames, const std::string& arm_order = "Zrotation Xrotation Yrotation") {
  std::string text = skeleton(arm_order) + "MOTION\nFrames: " + std::to_string(frames.size()) + "\nFrame Time: 0.01\n";
  for (const Frame& f : frames) text += frame_line(f);
  return text;
}

Frame arm_frame(double z, double x, double y, double elbow, double hand = 0) {
  Frame f;
  f.arm = Vector3d(z, x, y);
  f.elbow = elbow;
  f.hand = hand;
  return f;
}

// The same arm pose with the body and clavicle moved.
Frame moved_body(Frame f) {
  f.root_position = Vector3d(100, 50, -20);
  f.root = Vector3d(30, 10, -20);
  f.clavicle = Vector3d(15, -5, 40);
  f.left = Vector3d(10, 20, 30);
  return f;
}

const Vector3d kElbow(0, -30, 0), kWrist(0, -25, 0);  // the forearm's and hand's OFFSETs [cm]

TEST(MotionBvh, HandPoseInTheShoulderFrameMatchesClosedForm) {
  TempDir dir;
  const std::vector<Frame> frames = {arm_frame(0, 0, 0, 0), arm_frame(90, 0, 0, 0), arm_frame(90, 0, 0, 90),
                                     moved_body(arm_frame(90, 0, 0, 90)), moved_body(arm_frame(25, -40, 70, 35, -50))};
  const std::string path = dir.write("walk.bvh", bvh(frames));
  const Recording r = read_bvh(path, BvhOptions{});
  ASSERT_EQ(r.time.size(), 5);
  EXPECT_EQ(r.file, path);
  EXPECT_EQ(r.subject, "walk");
  EXPECT_EQ(r.activity, "walk");
  for (int i = 0; i < 5; ++i) {
    EXPECT_DOUBLE_EQ(r.time[i], 0.01 * i);
    EXPECT_EQ(r.line[i], kSkeletonLines + 4 + i);
  }
  // At rest the arm hangs: elbow 30 cm and wrist 25 cm below the shoulder.
  expect_pose(r, 0, Vector3d(0, -0.55, 0), Matrix3d::Identity());
  // 90 deg about z swings the hanging arm to +x: (0, -55, 0) -> (55, 0, 0).
  Matrix3d z90;
  z90 << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  expect_pose(r, 1, Vector3d(0.55, 0, 0), z90);
  // Then the elbow flexes 90 deg about its x: the forearm (0, -25, 0) -> (0, 0, -25) in the upper
  // arm's frame, which z90 leaves in place; the hand's rotation is z90 * x90.
  Matrix3d z90x90;
  z90x90 << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  expect_pose(r, 2, Vector3d(0.30, 0, -0.25), z90x90);
  // Moving the body and the clavicle moves the shoulder in the world, but the shoulder frame moves
  // with it (it is oriented like the clavicle): the same result.
  expect_pose(r, 3, Vector3d(0.30, 0, -0.25), z90x90);
  // General angles; the hand's own rotation turns the hand but does not move it.
  const Matrix3d arm = rz(25) * rx(-40) * ry(70);
  expect_pose(r, 4, 0.01 * arm * (kElbow + rx(35) * kWrist), arm * rx(35) * ry(-50));
}

TEST(MotionBvh, TheShoulderParentOrientsTheFrame) {
  TempDir dir;
  const Frame f = moved_body(arm_frame(25, -40, 70, 35, -50));
  const std::string path = dir.write("t.bvh", bvh({f, f}));
  const Matrix3d root = rz(30) * rx(10) * ry(-20), clavicle = rz(15) * rx(-5) * ry(40);
  const Matrix3d arm = rz(25) * rx(-40) * ry(70), hand = rx(35) * ry(-50);
  const Vector3d below_arm = arm * (kElbow + rx(35) * kWrist);
  const Vector3d clavicle_offset(-5, 20, 0), arm_offset(-10, 0, 0);
  // The root as "shoulder": its parent is the world, so the root's rotation enters, its
  // translation does not.
  BvhOptions options;
  options.shoulder_joint = "Hips";
  Recording r = read_bvh(path, options);
  expect_pose(r, 1, 0.01 * root * (clavicle_offset + clavicle * (arm_offset + below_arm)),
              root * clavicle * arm * hand);
  // The clavicle as "shoulder": oriented like the root, so the clavicle's rotation enters.
  options.shoulder_joint = "RightShoulder";
  r = read_bvh(path, options);
  expect_pose(r, 1, 0.01 * clavicle * (arm_offset + below_arm), clavicle * arm * hand);
  // The elbow as shoulder, the hand's frame at metres scale.
  options.shoulder_joint = "RightForeArm";
  options.scale = 1;
  r = read_bvh(path, options);
  expect_pose(r, 0, rx(35) * kWrist, rx(35) * ry(-50));
}

TEST(MotionBvh, ChannelOrderMatters) {
  TempDir dir;
  // The same values, 90 deg about z and about x: Rz * Rx for ZXY, Rx * Rz for XYZ.
  const Recording zxy = read_bvh(dir.write("zxy.bvh", bvh({arm_frame(90, 90, 0, 0), arm_frame(90, 90, 0, 0)})),
                                 BvhOptions{});
  const Recording xyz = read_bvh(
      dir.write("xyz.bvh", bvh({arm_frame(90, 0, 90, 0), arm_frame(90, 0, 90, 0)}, "Xrotation Yrotation Zrotation")),
      BvhOptions{});
  Matrix3d z90x90, x90z90;
  z90x90 << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  x90z90 << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  // The hanging arm (0, -55, 0) goes to -55 times the rotation's second column.
  expect_pose(zxy, 1, Vector3d(0, 0, -0.55), z90x90);
  expect_pose(xyz, 1, Vector3d(0.55, 0, 0), x90z90);
}

TEST(MotionBvh, ToleratesTabsCrlfAndExtraSpaces) {
  TempDir dir;
  const std::vector<Frame> frames = {arm_frame(0, 0, 0, 0), moved_body(arm_frame(25, -40, 70, 35, -50))};
  std::string messy;
  for (char c : bvh(frames)) {
    if (c == '\n') {
      messy += " \t\r\n";
    } else if (c == ' ') {
      messy += "\t  ";
    } else {
      messy += c;
    }
  }
  const Recording clean = read_bvh(dir.write("clean.bvh", bvh(frames)), BvhOptions{});
  const Recording read = read_bvh(dir.write("messy.bvh", messy + "\r\n\r\n"), BvhOptions{});
  EXPECT_EQ(read.position, clean.position);
  EXPECT_EQ(read.quaternion, clean.quaternion);
  EXPECT_EQ(read.line, clean.line);
}

std::string bvh_error(const TempDir& dir, const std::string& text, const BvhOptions& options = BvhOptions{}) {
  const std::string path = dir.write("e.bvh", text);
  return error_of([&] { read_bvh(path, options); });
}

TEST(MotionBvh, RefusesMissingJointsListingTheFilesJoints) {
  TempDir dir;
  const std::string text = bvh({Frame{}, Frame{}});
  BvhOptions options;
  options.shoulder_joint = "Rightarm";
  EXPECT_THAT(bvh_error(dir, text, options),
              HasSubstr(dir.path("e.bvh") + ": shoulder joint \"Rightarm\" not found (did you mean \"RightArm\"?): the "
                                            "file's joints are Hips, RightShoulder, RightArm, RightForeArm, RightHand, "
                                            "LeftArm"));
  options = BvhOptions{};
  options.hand_joint = "Head";
  EXPECT_THAT(bvh_error(dir, text, options),
              HasSubstr(": hand joint \"Head\" not found: the file's joints are Hips, RightShoulder"));
}

TEST(MotionBvh, RefusesAHandNotBelowTheShoulder) {
  TempDir dir;
  const std::string text = bvh({Frame{}, Frame{}});
  BvhOptions options;
  options.hand_joint = "LeftArm";
  EXPECT_THAT(bvh_error(dir, text, options),
              HasSubstr(dir.path("e.bvh") + ": hand joint \"LeftArm\" is not below the shoulder joint \"RightArm\": "
                                            "the hand must be a descendant of the shoulder (the hand's chain is Hips > "
                                            "LeftArm)"));
  options.hand_joint = "RightArm";
  EXPECT_THAT(bvh_error(dir, text, options), HasSubstr("hand joint \"RightArm\" is not below the shoulder joint \"RightArm\""));
}

TEST(MotionBvh, RefusesBadFrames) {
  TempDir dir;
  const std::string f = dir.path("e.bvh");
  const std::string good = frame_line(Frame{});
  const std::string motion = "MOTION\nFrames: 2\nFrame Time: 0.01\n";
  const int first = kSkeletonLines + 4;
  EXPECT_THAT(bvh_error(dir, skeleton() + motion + good + "0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n"),
              HasSubstr(f + ":" + std::to_string(first + 1) + ": 16 values on the frame line: the HIERARCHY declares 17 "
                                                              "channels"));
  EXPECT_THAT(bvh_error(dir, skeleton() + motion + good + "0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n"),
              HasSubstr(f + ":" + std::to_string(first + 1) + ": 18 values"));
  EXPECT_THAT(bvh_error(dir, skeleton() + "MOTION\nFrames: 3\nFrame Time: 0.01\n" + good + good),
              HasSubstr(f + ":" + std::to_string(kSkeletonLines + 2) + ": Frames: 3 but 2 frame line(s) follow: the "
                                                                       "count must match the lines present"));
  EXPECT_THAT(bvh_error(dir, skeleton() + motion + good + good + good),
              HasSubstr(f + ":" + std::to_string(first + 2) + ": frame line beyond the 2 frames that Frames: (line " +
                        std::to_string(kSkeletonLines + 2) + ") announces"));
  EXPECT_THAT(bvh_error(dir, skeleton() + motion + good + "0 0 nan 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n"),
              HasSubstr(f + ":" + std::to_string(first + 1) + ": value 3 (Hips Zposition) = \"nan\": every value must "
                                                              "be a finite number"));
  EXPECT_THAT(bvh_error(dir, skeleton() + motion + good + "0 0 0 0 0 0 0 0 0 0 0 0 0 1e400 0 0 0\n"),
              HasSubstr(": value 14 (RightHand Yrotation) = \"1e400\""));
  // strtod read hexadecimal floats; no BVH writer prints them (found by the bvh attack class).
  EXPECT_THAT(bvh_error(dir, skeleton() + motion + good + "0 0 0 0 0 0 0 0 0 0 0 0 0 0x1p3 0 0 0\n"),
              HasSubstr(": value 14 (RightHand Yrotation) = \"0x1p3\": every value must be a finite number"));
  EXPECT_THAT(bvh_error(dir, skeleton() + "MOTION\nFrames: 2\nFrame Time: 0\n" + good + good),
              HasSubstr(f + ":" + std::to_string(kSkeletonLines + 3) + ": Frame Time: \"0\": must be a finite number > 0"));
  EXPECT_THAT(bvh_error(dir, skeleton() + "MOTION\nFrames: 1\nFrame Time: 0.01\n" + good),
              HasSubstr(":" + std::to_string(kSkeletonLines + 2) + ": Frames: 1: at least 2 frames are required"));
  EXPECT_THAT(bvh_error(dir, skeleton() + "MOTION\nFrames: two\n"), HasSubstr("Frames: \"two\": must be a whole number"));
}

TEST(MotionBvh, RefusesBadHierarchies) {
  TempDir dir;
  const std::string f = dir.path("e.bvh");
  const std::string motion = "MOTION\nFrames: 2\nFrame Time: 0.01\n0\n0\n";
  EXPECT_THAT(bvh_error(dir, "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Xrot\n}\n" + motion),
              HasSubstr(f + ":5: unknown channel \"Xrot\" of Hips: the channels are Xposition, Yposition, Zposition, "
                            "Xrotation, Yrotation, Zrotation"));
  EXPECT_THAT(bvh_error(dir, "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Xrotation\n" + motion),
              HasSubstr(f + ":6: MOTION before joint Hips (line 2) is closed: unbalanced braces"));
  EXPECT_THAT(bvh_error(dir, "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Xrotation\n}\n}\n" + motion),
              HasSubstr(f + ":7: \"}\": expected ROOT (a skeleton) or MOTION at the top level"));
  EXPECT_THAT(bvh_error(dir, "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Xrotation\n  JOINT A\n  {\n"),
              HasSubstr(f + ": joint A (line 6) is not closed (the file ends): unbalanced braces"));
  EXPECT_THAT(bvh_error(dir, "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 nan 0\n}\n" + motion),
              HasSubstr(f + ":4: OFFSET of Hips: value \"nan\": must be a finite number"));
  EXPECT_THAT(bvh_error(dir, "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 2 Xrotation Xrotation\n}\n" + motion),
              HasSubstr(f + ":5: channel Xrotation of Hips given twice"));
  EXPECT_THAT(bvh_error(dir, "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 7\n}\n" + motion),
              HasSubstr(f + ":5: CHANNELS count of Hips = \"7\": must be an integer 0 to 6"));
  EXPECT_THAT(bvh_error(dir, "ROOT Hips\n"), HasSubstr(f + ":1: \"ROOT\": a BVH file starts with HIERARCHY"));
  EXPECT_THAT(bvh_error(dir, "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Xrotation\n  JOINT Hips\n  {\n"),
              HasSubstr(f + ":6: joint name \"Hips\" used again (first on line 2): joint names must be unique"));
  // Issue 53: 100,000 nested JOINT blocks once took 15 s (every name compared with every other);
  // the joint count is bounded where the 1,001st begins.
  std::string deep = "HIERARCHY\nROOT J0\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Xrotation\n";
  for (int k = 1; k <= 100000; ++k) deep += "JOINT J" + std::to_string(k) + "\n{\nOFFSET 0 0 0\n";
  const auto started = std::chrono::steady_clock::now();
  EXPECT_THAT(bvh_error(dir, deep), HasSubstr(f + ":3003: JOINT J1000: more than 1000 joints"));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), 5.0);
}

// ---------------------------------------------------------------- folders

TEST(MotionFolder, ReadsNestedCsvAndBvhFilesInPathOrderWithLabels) {
  TempDir dir;
  const std::string rows = std::string(kQuaternionHeader) + "0,0,0,0,1,0,0,0\n1,0,0,0,1,0,0,0\n";
  const std::string motion = bvh({Frame{}, arm_frame(90, 0, 0, 0)});
  dir.write("top.csv", rows);
  dir.write("S02/b.bvh", motion);
  dir.write("S01/reach.csv", rows);
  dir.write("S01/sub/deep.csv", "# subject: P7\n# activity: pour\n" + rows);
  dir.write("S01/Z.BVH", motion);
  dir.write("S01/notes.txt", "not read");
  fs::create_directories(dir.path("S03/empty"));
  // A link loop: not followed, so it neither hangs nor repeats files.
  fs::create_directory_symlink(dir.path(), dir.path("S01/loop"));
  const std::vector<Recording> all = read_recordings(dir.path(), BvhOptions{});
  ASSERT_EQ(all.size(), 5u);
  const std::vector<std::string> files = {"S01/Z.BVH", "S01/reach.csv", "S01/sub/deep.csv", "S02/b.bvh", "top.csv"};
  const std::vector<std::string> subjects = {"S01", "S01", "P7", "S02", "top"};
  const std::vector<std::string> activities = {"Z", "reach", "pour", "b", "top"};
  for (std::size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all[i].file, (fs::path(dir.path()) / files[i]).string());
    EXPECT_EQ(all[i].subject, subjects[i]) << files[i];
    EXPECT_EQ(all[i].activity, activities[i]) << files[i];
  }
  expect_pose(all[3], 1, Vector3d(0.55, 0, 0), rz(90));
  EXPECT_EQ(all[1].line, (std::vector<int>{2, 3}));
}

TEST(MotionFolder, ReadsOneFileByItsExtension) {
  TempDir dir;
  const std::string rows = std::string(kQuaternionHeader) + "0,0,0,0,1,0,0,0\n1,0,0,0,1,0,0,0\n";
  const std::vector<Recording> one = read_recordings(dir.write("S05/Take.CSV", rows), BvhOptions{});
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].subject, "Take");
  const std::string txt = dir.write("take.txt", rows);
  EXPECT_EQ(error_of([&] { read_recordings(txt, BvhOptions{}); }),
            "motion: " + txt + ": extension \".txt\": must be .csv (hapsyn-motion) or .bvh (case ignored)");
  EXPECT_EQ(error_of([&] { read_recordings(dir.path("nothing"), BvhOptions{}); }),
            "motion: " + dir.path("nothing") + ": no such file or folder");
}

TEST(MotionFolder, RefusesAFolderWithoutRecordings) {
  TempDir dir;
  EXPECT_EQ(error_of([&] { read_recordings(dir.path(), BvhOptions{}); }),
            "motion: " + dir.path() + ": is a folder without .csv or .bvh files (searched recursively): nothing to read");
  dir.write("a/readme.txt", "text");
  EXPECT_THAT(error_of([&] { read_recordings(dir.path(), BvhOptions{}); }), HasSubstr("is a folder without .csv or .bvh"));
}

TEST(MotionFolder, ReportsTheFirstBadFileByName) {
  TempDir dir;
  dir.write("S01/a.csv", std::string(kQuaternionHeader) + "0,0,0,0,1,0,0,0\n1,0,0,0,1,0,0,0\n");
  dir.write("S01/b.csv", std::string(kQuaternionHeader) + "0,0,0,0,1,0,0,0\n0,0,0,0,1,0,0,0\n");
  EXPECT_THAT(error_of([&] { read_recordings(dir.path(), BvhOptions{}); }),
              HasSubstr((fs::path(dir.path()) / "S01/b.csv").string() + ":3: time 0 is not after"));
}

}  // namespace
