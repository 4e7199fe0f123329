// Tests of the point_list scene: positions, units, orientations (quaternions, rotation matrices
// against an independent angle-axis construction), weights and attributes, file resolution, and
// every refused file with its message (naming the file, line, column, value and rule).
#include "point_list.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/schema.hpp>

#include <Eigen/Geometry>
#include <boost/filesystem.hpp>
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <string>
#include <vector>

namespace {

namespace fs = boost::filesystem;
using hapsyn::Json;
using hapsyn::SampleSet;
using hapsyn::plugins::PointList;
using hapsyn::plugins::PointListOptions;
using hapsyn::plugins::read_point_list;

// A fresh directory per test, removed afterwards.
class PointListFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / fs::unique_path("hapsyn-point-list-%%%%-%%%%-%%%%");
    fs::create_directories(dir_);
  }
  void TearDown() override {
    boost::system::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& name, const std::string& text) const {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }
  // The error of reading `text` as a file named `name`, with the file's path replaced by "F".
  std::string error_of(const std::string& text, const std::string& name = "points.csv") const {
    const std::string path = write(name, text);
    return error_of_path(path);
  }
  static std::string error_of_path(const std::string& path) {
    try {
      read_point_list(path);
    } catch (const hapsyn::Error& e) {
      std::string message = e.what();
      const std::size_t at = message.find(path);
      if (at != std::string::npos) message.replace(at, path.size(), "F");
      return message;
    }
    return "no error";
  }
  fs::path dir_;
};

PointList scene_of(const std::string& file) {
  return PointList(hapsyn::make_options<PointListOptions>(Json{{"file", file}}));
}

TEST_F(PointListFiles, ReadsPlanarPositionsInFileOrder) {
  const SampleSet set = read_point_list(write("p.csv", "x,y\n0.1,0.2\n-0.3, 0.4\n\n0,0\n"));
  EXPECT_EQ(set.coordinates, (std::vector<std::string>{"x", "y"}));
  EXPECT_EQ(set.unit, "m");
  ASSERT_EQ(set.size(), 3);
  const double expected[3][2] = {{0.1, 0.2}, {-0.3, 0.4}, {0.0, 0.0}};
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(set.pose(i)[0], expected[i][0]);
    EXPECT_EQ(set.pose(i)[1], expected[i][1]);
  }
  EXPECT_TRUE(set.weights.empty());
  EXPECT_TRUE(set.attributes.empty());
  EXPECT_EQ(set.info.at("samples"), 3);
  EXPECT_EQ(set.info.at("length_unit"), "m");
}

TEST_F(PointListFiles, CommentsCrlfAndAByteOrderMarkAreAccepted) {
  const SampleSet set = read_point_list(write("p.csv", "\xEF\xBB\xBF# a comment\r\n  # indented comment\r\nx,y,z\r\n1,2,3\r\n"));
  ASSERT_EQ(set.size(), 1);
  EXPECT_EQ(set.coordinates, (std::vector<std::string>{"x", "y", "z"}));
  EXPECT_EQ(set.pose(0)[2], 3.0);
}

TEST_F(PointListFiles, UnitsLineConvertsPositionsToMetres) {
  const SampleSet metres = read_point_list(write("m.csv", "x,y,z,size\n0.012,-0.25,1.5,7\n"));
  const SampleSet mm = read_point_list(write("mm.csv", "# units: length=mm\nx,y,z,size\n12,-250,1500,7\n"));
  const SampleSet cm = read_point_list(write("cm.csv", "x,y,z,size\n# units: length=cm\n1.2,-25,150,7\n"));
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(mm.pose(0)[c], metres.pose(0)[c], 1e-15) << c;
    EXPECT_NEAR(cm.pose(0)[c], metres.pose(0)[c], 1e-15) << c;
  }
  EXPECT_EQ(mm.attributes.at("size")(0, 0), 7.0);  // attributes are not lengths: unchanged
  EXPECT_EQ(mm.info.at("length_unit"), "mm");
  EXPECT_EQ(mm.unit, "m");
}

// Issue 53, cause 3: a units line after data rows, or at the end, applies to every row (rows
// read before it were once taken in metres, mixing metres and millimetres in one scene).
TEST_F(PointListFiles, UnitsLineAnywhereAppliesToEveryRow) {
  const SampleSet first = read_point_list(write("first.csv", "# units: length=mm\nx,y,z\n100,200,300\n400,500,600\n"));
  const SampleSet middle = read_point_list(write("middle.csv", "x,y,z\n100,200,300\n# units: length=mm\n400,500,600\n"));
  const SampleSet last = read_point_list(write("last.csv", "x,y,z\n100,200,300\n400,500,600\n# units: length=mm\n"));
  ASSERT_EQ(first.size(), 2);
  for (const SampleSet* s : {&middle, &last}) {
    ASSERT_EQ(s->size(), 2);
    EXPECT_TRUE(s->poses == first.poses) << s->poses;
  }
  EXPECT_DOUBLE_EQ(last.pose(0)[0], 0.1);
  EXPECT_DOUBLE_EQ(last.pose(1)[2], 0.6);
}

// A units line in another spelling was read as a plain comment (millimetres as metres), and a
// length given twice in one line was resolved by the last; both are refused, other comments pass.
TEST_F(PointListFiles, UnitsLinesInAnotherSpellingOrWithALengthTwiceAreRefused) {
  EXPECT_EQ(error_of("# Units: length=mm\nx,y\n180,0\n"),
            "point_list: F:1: comment \"# Units: length=mm\" reads like a units line: write it '# units: length=mm' "
            "(lower case, \"units:\" with the colon right after it), or reword the comment");
  EXPECT_NE(error_of("x,y\n180,0\n# unit: mm\n").find("F:3: comment \"# unit: mm\" reads like a units line"), std::string::npos);
  EXPECT_NE(error_of("# units : mm\nx,y\n180,0\n").find("F:1: comment \"# units : mm\" reads like a units line"),
            std::string::npos);
  EXPECT_EQ(error_of("# units: length=mm, length=cm\nx,y\n180,0\n"),
            "point_list: F:1: units line \"# units: length=mm, length=cm\": length is given twice; give it once");
  const SampleSet commented = read_point_list(write("commented.csv", "# unit conversions: none\n# units are metres\nx,y\n1,2\n"));
  EXPECT_DOUBLE_EQ(commented.pose(0)[0], 1.0);
}

// Finite weights whose sum overflows were refused by the framework without the file or column.
TEST_F(PointListFiles, WeightsWhoseSumOverflowsAreRefusedWithTheColumn) {
  EXPECT_EQ(error_of("x,y,weight\n0.18,0,1e308\n0.2,0.03,1e308\n"),
            "point_list: F: column \"weight\": the weights sum beyond the range of doubles (to inf): scale them down "
            "(only their ratios matter)");
}

// Issue 53, cause 6: bytes that are not UTF-8 in a column name or a field are refused by the
// reader with the file, line and bytes (they once reached a JSON library exception).
TEST_F(PointListFiles, BytesThatAreNotUtf8AreRefusedWithTheFileAndLine) {
  EXPECT_EQ(error_of("x,y,s\xff\n0.1,0.2,3\n"),
            "point_list: F:1: header: column \"s\\xff\": invalid UTF-8 at byte 1 (column names become attribute names "
            "written into result.json: they must be UTF-8)");
  EXPECT_EQ(error_of("x,y\n0.1,0.2\xff\n"), "point_list: F:2: column \"y\" = \"0.2\\xff\": must be a number");
}

TEST_F(PointListFiles, QuaternionColumnsGiveNormalizedFullPoses) {
  const SampleSet set = read_point_list(write("q.csv", "qx,x,y,z,qw,qy,qz\n0,1,2,3,1.0000005,0,0\n0.5,0,0,0,0.5,0.5,-0.5\n"));
  EXPECT_EQ(set.coordinates, (std::vector<std::string>{"x", "y", "z", "qw", "qx", "qy", "qz"}));
  ASSERT_EQ(set.size(), 2);
  EXPECT_EQ(set.pose(0)[0], 1.0);
  EXPECT_EQ(set.pose(0)[3], 1.0);  // 1.0000005 / 1.0000005
  EXPECT_EQ(set.pose(1)[4], 0.5);
  EXPECT_EQ(set.pose(1)[6], -0.5);
}

TEST_F(PointListFiles, RotationMatrixBecomesTheQuaternionOfThatRotation) {
  // Rotations built independently from angle and axis; 170 and 180 degrees take Eigen's
  // non-trace branch, where the sign of qw is arbitrary unless fixed.
  const std::vector<std::pair<double, Eigen::Vector3d>> rotations = {
      {0.3, Eigen::Vector3d(0, 0, 1)}, {1.2, Eigen::Vector3d(1, 2, 3).normalized()},
      {170.0 * M_PI / 180.0, Eigen::Vector3d(-1, 0.5, 0.2).normalized()}, {M_PI, Eigen::Vector3d(0, 1, 0)}};
  std::string text = "x,y,z,r11,r12,r13,r21,r22,r23,r31,r32,r33\n";
  char buffer[64];
  for (const auto& [angle, axis] : rotations) {
    const Eigen::Matrix3d r = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    text += "0,0,0";
    for (int k = 0; k < 9; ++k) {
      std::snprintf(buffer, sizeof buffer, ",%.17g", r(k / 3, k % 3));
      text += buffer;
    }
    text += "\n";
  }
  const SampleSet set = read_point_list(write("r.csv", text));
  ASSERT_EQ(set.size(), 4);
  EXPECT_EQ(set.info.at("orientation"), "matrix");
  for (int i = 0; i < 4; ++i) {
    const auto& [angle, axis] = rotations[static_cast<std::size_t>(i)];
    const double* q = set.pose(i) + 3;
    EXPECT_GE(q[0], 0.0) << i;
    EXPECT_NEAR(q[0], std::cos(angle / 2), 1e-12) << i;
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(q[1 + a], axis[a] * std::sin(angle / 2), 1e-12) << i << " " << a;
  }
}

TEST_F(PointListFiles, WeightAndOtherColumnsBecomeWeightsAndAttributes) {
  const std::string path = write("w.csv", "x,y,weight,stiffness,label_id\n0,0,2,100,1\n0.1,0,0,200,2\n0,0.1,0.5,300,3\n");
  const SampleSet set = read_point_list(path);
  EXPECT_EQ(set.weights, (std::vector<double>{2.0, 0.0, 0.5}));
  ASSERT_EQ(set.attributes.size(), 2u);
  EXPECT_EQ(set.attributes.at("stiffness")(2, 0), 300.0);
  EXPECT_EQ(set.info.at("attributes"), Json({"label_id", "stiffness"}));
  EXPECT_EQ(set.info.at("weighted"), true);
  // The scene hands out exactly the requested attributes.
  const PointList scene = scene_of(path);
  EXPECT_EQ(scene.attribute_names(), (std::vector<std::string>{"label_id", "stiffness"}));
  EXPECT_TRUE(scene.build({}).attributes.empty());
  hapsyn::SceneRequest request;
  request.attributes = {"stiffness"};
  const SampleSet built = scene.build(request);
  ASSERT_EQ(built.attributes.size(), 1u);
  EXPECT_EQ(built.attributes.at("stiffness")(1, 0), 200.0);
  EXPECT_EQ(built.weights, set.weights);
  request.attributes = {"M_v"};
  try {
    scene.build(request);
    FAIL() << "no error";
  } catch (const hapsyn::Error& e) {
    EXPECT_EQ(std::string(e.what()), "point_list: per-sample attribute 'M_v' requested: " + scene.path() +
                                         " has no such column (attribute columns: label_id, stiffness)");
  }
}

TEST_F(PointListFiles, DefaultFileIsTheSharedPlanarExample) {
  const PointList scene(hapsyn::default_options<PointListOptions>());
  const SampleSet set = scene.build({});
  ASSERT_EQ(set.size(), 9);
  EXPECT_EQ(set.pose(0)[0], -0.05);  // -50 mm
  EXPECT_EQ(std::accumulate(set.weights.begin(), set.weights.end(), 0.0), 16.0);
}

TEST_F(PointListFiles, RelativePathsResolveAgainstTheCurrentDirectory) {
  write("here.csv", "x,y\n1,2\n");
  const fs::path before = fs::current_path();
  fs::current_path(dir_);
  const PointList scene = scene_of("here.csv");
  fs::current_path(before);
  EXPECT_EQ(scene.path(), (dir_ / "here.csv").string());
  EXPECT_EQ(scene.build({}).pose(0)[1], 2.0);
}

TEST_F(PointListFiles, RefusesAMissingOrUnnamedFile) {
  try {
    scene_of("no_such_points.csv");
    FAIL() << "no error";
  } catch (const hapsyn::Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("point_list: options.file = \"no_such_points.csv\": no such file (tried ", 0), 0u)
        << e.what();
  }
  const std::string absent = (dir_ / "absent.csv").string();
  try {
    scene_of(absent);
    FAIL() << "no error";
  } catch (const hapsyn::Error& e) {
    EXPECT_EQ(std::string(e.what()), "point_list: options.file = \"" + absent + "\": no such file");
  }
  try {
    scene_of("");
    FAIL() << "no error";
  } catch (const hapsyn::Error& e) {
    EXPECT_STREQ(e.what(), "point_list: options.file = \"\": must name a file");
  }
  EXPECT_EQ(error_of_path(absent), "point_list: F: no such file");
}

TEST_F(PointListFiles, RefusesEmptyFilesAndFilesWithoutData) {
  EXPECT_EQ(error_of(""), "point_list: F: is empty: a header row of column names is required");
  EXPECT_EQ(error_of("# only\n\n# comments\n"),
            "point_list: F: has no header row (only comments and blank lines): a header row of column names is "
            "required");
  EXPECT_EQ(error_of("# c\nx,y\n"), "point_list: F: has a header row (line 2) but no data rows");
}

TEST_F(PointListFiles, RefusesRaggedRowsNonNumbersAndNonFiniteValues) {
  EXPECT_EQ(error_of("x,y,weight\n1,2,1\n3,4\n"),
            "point_list: F:3: 2 fields for 3 columns (x, y, weight): every row needs one value per column");
  EXPECT_EQ(error_of("x,y\n1,2,3\n"), "point_list: F:2: 3 fields for 2 columns (x, y): every row needs one value per column");
  EXPECT_EQ(error_of("x,y\n1,abc\n"), "point_list: F:2: column \"y\" = \"abc\": must be a number");
  EXPECT_EQ(error_of("x,y\n1.5e,2\n"), "point_list: F:2: column \"x\" = \"1.5e\": must be a number");
  EXPECT_EQ(error_of("x,y\n1,\n"), "point_list: F:2: column \"y\" = \"\": must be a number");
  EXPECT_EQ(error_of("x,y\n# c\n1,nan\n"), "point_list: F:3: column \"y\" = \"nan\": must be finite");
  EXPECT_EQ(error_of("x,y\n-inf,1\n"), "point_list: F:2: column \"x\" = \"-inf\": must be finite");
  EXPECT_EQ(error_of("x,y\n1e999,1\n"), "point_list: F:2: column \"x\" = \"1e999\": must be finite");
}

TEST_F(PointListFiles, RefusesDuplicateEmptyAndUnknownShapedColumnSets) {
  EXPECT_EQ(error_of("x,y,x\n1,2,3\n"), "point_list: F:1: header: column \"x\" appears twice (fields 1 and 3)");
  EXPECT_EQ(error_of("x,,y\n1,2,3\n"), "point_list: F:1: header: field 2 has an empty column name");
  EXPECT_EQ(error_of("X,Y\n1,2\n"),
            "point_list: F:1: header \"X,Y\": needs position columns x and y (then optionally z); the first row that "
            "is not a comment is the header");
  EXPECT_EQ(error_of("0.1,0.2\n0.3,0.4\n"),
            "point_list: F:1: header \"0.1,0.2\": needs position columns x and y (then optionally z); the first row "
            "that is not a comment is the header");
  EXPECT_EQ(error_of("x,y,z,qw,qx,qy\n0,0,0,1,0,0\n"),
            "point_list: F:1: header \"x,y,z,qw,qx,qy\": a quaternion needs all of qw, qx, qy, qz (missing qz)");
  EXPECT_EQ(error_of("x,y,z,r11,r22,r33\n0,0,0,1,1,1\n"),
            "point_list: F:1: header \"x,y,z,r11,r22,r33\": a rotation matrix needs all of r11, r12, r13, r21, r22, "
            "r23, r31, r32, r33 (missing r12, r13, r21, r23, r31, r32)");
  EXPECT_EQ(error_of("x,y,z,qw,qx,qy,qz,r11,r12,r13,r21,r22,r23,r31,r32,r33\n"),
            "point_list: F:1: header \"x,y,z,qw,qx,qy,qz,r11,r12,r13,r21,r22,r23,r31,r32,r33\": has both a quaternion "
            "(qw, qx, qy, qz) and a rotation matrix (r11 .. r33): give one orientation");
  EXPECT_EQ(error_of("x,y,qw,qx,qy,qz\n0,0,1,0,0,0\n"),
            "point_list: F:1: header \"x,y,qw,qx,qy,qz\": an orientation needs a z column (a full pose is x, y, z, qw, "
            "qx, qy, qz)");
}

TEST_F(PointListFiles, RefusesQuaternionsAndMatricesThatAreNoRotations) {
  EXPECT_EQ(error_of("x,y,z,qw,qx,qy,qz\n0,0,0,1,0,0,0\n0,0,0,1,1,0,0\n"),
            "point_list: F:3: quaternion (qw, qx, qy, qz) = (1.0, 1.0, 0.0, 0.0) has norm 1.4142135623730951: must be "
            "1 within 1e-6");
  EXPECT_EQ(error_of("x,y,z,qw,qx,qy,qz\n0,0,0,1.00001,0,0,0\n"),
            "point_list: F:2: quaternion (qw, qx, qy, qz) = (1.00001, 0.0, 0.0, 0.0) has norm 1.00001: must be 1 "
            "within 1e-6");
  const std::string header = "x,y,z,r11,r12,r13,r21,r22,r23,r31,r32,r33\n";
  EXPECT_EQ(error_of(header + "0,0,0,1,0,0,0,1,0,0,0.01,1\n"),
            "point_list: F:2: rotation matrix (r11 .. r33) = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.01, 1.0]]: "
            "must be orthonormal within 1e-6 (max |R^T R - I| = 0.01)");
  EXPECT_EQ(error_of(header + "0,0,0,-1,0,0,0,1,0,0,0,1\n"),
            "point_list: F:2: rotation matrix (r11 .. r33) = [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]: det "
            "= -1.0: must be +1 (a rotation, not a reflection)");
}

TEST_F(PointListFiles, RefusesNegativeOrAllZeroWeights) {
  EXPECT_EQ(error_of("x,y,weight\n0,0,1\n1,1,-0.5\n"), "point_list: F:3: column \"weight\" = \"-0.5\": must be >= 0");
  EXPECT_EQ(error_of("x,y,weight\n0,0,0\n1,1,0\n"), "point_list: F: column \"weight\": every weight is 0: at least one must be > 0");
  EXPECT_EQ(error_of("x,y,weight\n0,0,inf\n"), "point_list: F:2: column \"weight\" = \"inf\": must be finite");
}

TEST_F(PointListFiles, RefusesMalformedOrRepeatedUnitsLines) {
  EXPECT_EQ(error_of("# units: length=inch\nx,y\n1,2\n"),
            "point_list: F:1: units line \"# units: length=inch\": length = \"inch\": must be m, cm or mm");
  EXPECT_EQ(error_of("# units: angle=deg\nx,y\n1,2\n"),
            "point_list: F:1: units line \"# units: angle=deg\": unknown quantity \"angle\" (only length=m|cm|mm)");
  EXPECT_EQ(error_of("# units:\nx,y\n1,2\n"),
            "point_list: F:1: units line \"# units:\": names no unit; write e.g. '# units: length=mm'");
  EXPECT_EQ(error_of("# units: length=mm\nx,y\n# units: length=m\n1,2\n"),
            "point_list: F:3: units line \"# units: length=m\": the units were already given on line 1; give them once");
}

TEST_F(PointListFiles, RefusesDirectoriesAndFifosWithoutBlocking) {
  EXPECT_EQ(error_of_path(dir_.string()), "point_list: F: is a directory, not a regular file");
  const std::string fifo = (dir_ / "pipe.csv").string();
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  // Nothing writes to the FIFO: opening it for reading would block forever.
  EXPECT_EQ(error_of_path(fifo),
            "point_list: F: is not a regular file (a FIFO, socket or device): refused, reading it could block or never end");
  fs::create_directory(dir_ / "sub");
  const fs::path before = fs::current_path();
  fs::current_path(dir_);
  try {
    scene_of("sub");
    ADD_FAILURE() << "no error";
  } catch (const hapsyn::Error& e) {
    EXPECT_EQ(std::string(e.what()), "point_list: " + (dir_ / "sub").string() + ": is a directory, not a regular file");
  }
  fs::current_path(before);
}

TEST_F(PointListFiles, RefusesAFileLargerThanTheCap) {
  // A sparse file one byte above the cap: refused from its size, before a byte is read.
  const std::string path = write("huge.csv", "x,y\n");
  fs::resize_file(path, hapsyn::plugins::kPointListMaxBytes + 1);
  EXPECT_EQ(error_of_path(path), "point_list: F: 1073741825 bytes: larger than the 1 GiB cap (1073741824 bytes)");
}

TEST(PointList, DeclaredSchemaHasTheSharedExampleAsDefault) {
  const Json schema = hapsyn::options_schema<PointListOptions>();
  EXPECT_NO_THROW(hapsyn::check_schema(schema, "point_list"));
  const Json filled = hapsyn::validate_and_fill(schema, Json::object(), "scene.options");
  EXPECT_EQ(filled.at("file"), "point_list/example_planar.csv");
  EXPECT_THROW(hapsyn::validate_and_fill(schema, Json{{"file", 3}}, "scene.options"), hapsyn::Error);
}

}  // namespace
