// Tests of a URDF chain's mesh visuals (chain_meshes.hpp, urdf_meshes.hpp, serial_chain_meshes.cpp):
// each form of a mesh file name resolved, the warning of each visual left out, and the meshes'
// poses against forward kinematics written out here from the file's numbers.
#include "chain_meshes.hpp"
#include "serial_chain.hpp"

#include <hapsyn/mesh_drawing.hpp>
#include <hapsyn/options.hpp>

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

using namespace hapsyn;
using namespace hapsyn::plugins;
namespace fs = std::filesystem;

namespace {

// A folder of robot files for the tests: robots/my_pkg/urdf/robot.urdf (with parts/rel.stl
// beside it), robots/my_pkg/meshes/a.stl, robots/other_pkg/meshes/b.stl, ros/third_pkg/c.dae
// (for ROS_PACKAGE_PATH), abs/d.STL. One folder per test: ctest runs them in parallel.
struct RobotFolder {
  fs::path root = fs::path(HAPSYN_BINARY_DIR) / "chain_meshes_test" /
                  ::testing::UnitTest::GetInstance()->current_test_info()->name();
  fs::path urdf_dir = root / "robots/my_pkg/urdf";
  fs::path urdf = urdf_dir / "robot.urdf";

  RobotFolder() {
    fs::remove_all(root);
    for (const fs::path& f : {urdf_dir / "parts/rel.stl", root / "robots/my_pkg/meshes/a.stl",
                              root / "robots/other_pkg/meshes/b.stl", root / "ros/third_pkg/c.dae", root / "abs/d.STL"}) {
      fs::create_directories(f.parent_path());
      std::ofstream(f) << "solid x\nendsolid x\n";
    }
  }
  std::string at(const std::string& relative) const { return (root / relative).lexically_normal().string(); }
  MeshFileLookup resolve(const std::string& name, const std::string& ros = "") const {
    return resolve_mesh_file(name, urdf.string(), ros);
  }
};

TEST(ChainMeshes, ResolvesPathsFileUrisAndPackageUris) {
  const RobotFolder r;
  EXPECT_EQ(r.resolve(r.at("abs/d.STL")).path, r.at("abs/d.STL"));
  EXPECT_EQ(r.resolve("file://" + r.at("abs/d.STL")).path, r.at("abs/d.STL"));
  EXPECT_EQ(r.resolve("file://parts/rel.stl").path, r.at("robots/my_pkg/urdf/parts/rel.stl"));
  EXPECT_EQ(r.resolve("parts/rel.stl").path, r.at("robots/my_pkg/urdf/parts/rel.stl"));
  EXPECT_EQ(r.resolve("../urdf/./parts/rel.stl").path, r.at("robots/my_pkg/urdf/parts/rel.stl"));
  // An ancestor named as the package, and a folder of that name inside an ancestor.
  EXPECT_EQ(r.resolve("package://my_pkg/meshes/a.stl").path, r.at("robots/my_pkg/meshes/a.stl"));
  EXPECT_EQ(r.resolve("package://other_pkg/meshes/b.stl").path, r.at("robots/other_pkg/meshes/b.stl"));
  // ROS_PACKAGE_PATH: a folder inside an entry, or the entry itself; empty and missing entries skipped.
  EXPECT_EQ(r.resolve("package://third_pkg/c.dae", "/nonexistent::" + r.at("ros")).path, r.at("ros/third_pkg/c.dae"));
  EXPECT_EQ(r.resolve("package://third_pkg/c.dae", r.at("ros/third_pkg")).path, r.at("ros/third_pkg/c.dae"));
  for (const char* name : {"parts/rel.stl", "package://my_pkg/meshes/a.stl"}) EXPECT_EQ(r.resolve(name).problem, "") << name;
}

TEST(ChainMeshes, UnresolvedNamesSayWhatWasSearched) {
  const RobotFolder r;
  EXPECT_EQ(r.resolve("parts/missing.stl").problem,
            "no such file (relative to the URDF's folder: " + r.at("robots/my_pkg/urdf/parts/missing.stl") + ")");
  EXPECT_EQ(r.resolve(r.at("abs/missing.stl")).problem, "no such file (" + r.at("abs/missing.stl") + ")");
  EXPECT_EQ(r.resolve("package://third_pkg/c.dae").problem,
            "package \"third_pkg\" not found (searched the URDF's folder and its ancestors, ROS_PACKAGE_PATH not set)");
  EXPECT_EQ(r.resolve("package://third_pkg/c.dae", "/nonexistent").problem,
            "package \"third_pkg\" not found (searched the URDF's folder and its ancestors, and ROS_PACKAGE_PATH)");
  EXPECT_EQ(r.resolve("package://my_pkg/meshes/missing.stl").problem,
            "no file meshes/missing.stl in package \"my_pkg\" (" + r.at("robots/my_pkg") + ")");
  EXPECT_EQ(r.resolve("package://my_pkg").problem, "a package:// URI must be package://NAME/PATH");
  EXPECT_EQ(r.resolve("http://example.com/a.stl").problem,
            "URI scheme \"http://\" not supported (absolute or relative paths, file:// and package:// are)");
  EXPECT_EQ(r.resolve("").problem, "an empty file name");
  for (const char* name : {"parts/missing.stl", "http://example.com/a.stl"}) EXPECT_EQ(r.resolve(name).path, "") << name;
}

TEST(ChainMeshes, DrawsStlAndDaeInAnyCaseOnly) {
  for (const char* yes : {"a.stl", "a.STL", "dir.x/a.dae", "package://p/a.Dae"}) EXPECT_TRUE(drawable_mesh_format(yes)) << yes;
  for (const char* no : {"a.obj", "a.stl.gz", "a", "a.ply", "stl"}) EXPECT_FALSE(drawable_mesh_format(no)) << no;
}

#ifdef HAPSYN_HAVE_URDFDOM

// base -j1 (revolute z)-> l1 -j2 (revolute y)-> l2 -j3 (revolute x)-> l3 -jf (fixed)-> tip, and
// off the path: cover
// fixed to l2 (drawn), flap on a revolute joint (not drawn, no warning).
std::string robot_urdf(const RobotFolder& r) {
  const char* limit = R"(<limit lower="-3" upper="3" effort="1" velocity="1"/>)";
  return std::string(R"(<?xml version="1.0"?>
<robot name="t">
  <link name="base">
    <visual><geometry><mesh filename="parts/missing.stl"/></geometry></visual>
    <visual><origin xyz="0 0 0.01"/><geometry><mesh filename="package://my_pkg/meshes/a.stl"/></geometry></visual>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1" rpy="0 0 0.3"/><axis xyz="0 0 1"/>)") + limit + R"(</joint>
  <link name="l1">
    <visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual>
    <visual><origin xyz="0.1 0 0" rpy="0 1.2 0"/><geometry><mesh filename="parts/rel.stl" scale="2 3 4"/></geometry></visual>
    <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.2 0 0" rpy="0.2 0 0"/><axis xyz="0 1 0"/>)" + limit + R"(</joint>
  <link name="l2">
    <visual><geometry><mesh filename="package://other_pkg/meshes/b.stl"/></geometry></visual>
    <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.1 0 0"/><axis xyz="1 0 0"/>)" + limit + R"(</joint>
  <link name="l3">
    <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <joint name="jf" type="fixed"><parent link="l3"/><child link="tip"/><origin xyz="0.15 0 -0.05" rpy="0 0.4 0"/></joint>
  <link name="tip">
    <visual><origin xyz="0 0 0.02" rpy="0.1 0.2 0.3"/><geometry><mesh filename="file://)" + r.at("abs/d.STL") + R"("/></geometry></visual>
    <visual><geometry><mesh filename="meshes/thing.obj"/></geometry></visual>
  </link>
  <joint name="cover_joint" type="fixed"><parent link="l2"/><child link="cover"/><origin xyz="0 0.03 0" rpy="0 0 1.0"/></joint>
  <link name="cover"><visual><origin xyz="0.01 0 0"/><geometry><mesh filename="package://third_pkg/c.dae"/></geometry></visual></link>
  <joint name="branch" type="revolute"><parent link="l2"/><child link="flap"/><axis xyz="1 0 0"/>)" + limit + R"(</joint>
  <link name="flap"><visual><geometry><mesh filename="nothere.stl"/></geometry></visual></link>
</robot>
)";
}


struct TestRobot : RobotFolder {
  TestRobot() {
    std::ofstream(urdf) << robot_urdf(*this);
    setenv("ROS_PACKAGE_PATH", at("ros").c_str(), 1);
  }
  ~TestRobot() { unsetenv("ROS_PACKAGE_PATH"); }
  SerialChain mechanism() const {
    const Json o = {{"urdf", urdf.string()}, {"base_link", "base"},         {"tip_link", "tip"},
                    {"task", "position"},   {"base_xyz", {0.1, -0.2, 0.3}}, {"base_rpy", {10, -20, 30}}};
    return SerialChain(make_options<SerialChainOptions>(o));
  }
};

Eigen::Isometry3d pose(double x, double y, double z, const Eigen::Matrix3d& r = Eigen::Matrix3d::Identity()) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = r;
  t.translation() << x, y, z;
  return t;
}
Eigen::Matrix3d rot(double angle, const Eigen::Vector3d& axis) { return Eigen::AngleAxisd(angle, axis).toRotationMatrix(); }
Eigen::Matrix3d rpy(double r, double p, double y) {
  return rot(y, Eigen::Vector3d::UnitZ()) * rot(p, Eigen::Vector3d::UnitY()) * rot(r, Eigen::Vector3d::UnitX());
}

TEST(ChainMeshes, CollectsThePathsAndFixedLinksMeshesAndWarnsOfTheRest) {
  const TestRobot r;
  // A package found through a folder whose name is Latin-1, not UTF-8 (the view's JSON needs it).
  const std::string latin1 = r.at("ros") + "\xe9";
  fs::create_directories(fs::path(latin1) / "third_pkg");
  fs::copy_file(r.at("ros/third_pkg/c.dae"), fs::path(latin1) / "third_pkg/c.dae");
  setenv("ROS_PACKAGE_PATH", latin1.c_str(), 1);
  const ChainTemplate t = ChainTemplate::from_urdf(r.urdf.string(), "base", "tip");
  const ChainMeshes& m = t.meshes();
  const std::string u = r.urdf.string();
  const std::vector<std::string> warnings = {
      u + ": link \"base\" visual mesh \"parts/missing.stl\": no such file (relative to the URDF's folder: " +
          r.at("robots/my_pkg/urdf/parts/missing.stl") + "); not drawn",
      u + ": link \"l1\" visual box: a primitive shape, not drawn (only .stl and .dae meshes are)",
      u + ": link \"cover\" visual mesh \"package://third_pkg/c.dae\": the link's or the file's name is not UTF-8; not drawn",
      u + ": link \"tip\" visual mesh \"meshes/thing.obj\": not drawn (only .stl and .dae files are)"};
  EXPECT_EQ(m.warnings, warnings);
  std::vector<std::pair<std::string, std::string>> drawn;
  for (const ChainMeshVisual& v : m.visuals) drawn.emplace_back(v.link, v.file);
  const std::vector<std::pair<std::string, std::string>> want = {{"base", r.at("robots/my_pkg/meshes/a.stl")},
                                                                 {"l1", r.at("robots/my_pkg/urdf/parts/rel.stl")},
                                                                 {"l2", r.at("robots/other_pkg/meshes/b.stl")},
                                                                 {"tip", r.at("abs/d.STL")}};
  EXPECT_EQ(drawn, want);
  EXPECT_EQ(m.visuals[1].scale, Eigen::Vector3d(2, 3, 4));
  // A DH table has none.
  const ChainTemplate dh = ChainTemplate::from_dh_file(std::string(HAPSYN_SOURCE_DIR) + "/share/serial_chain/haptic6r_dh.json");
  EXPECT_TRUE(dh.meshes().visuals.empty());
  EXPECT_TRUE(dh.meshes().warnings.empty());
}

TEST(ChainMeshes, MeshPosesFollowTheLinkFramesOfTheDrawnConfiguration) {
  const TestRobot r;
  const SerialChain m = r.mechanism();
  std::vector<double> design;
  int jf_x = -1;
  for (const VariableDecl& v : m.variables()) {
    if (v.name == "jf:x") jf_x = static_cast<int>(design.size());
    for (int i = 0; i < v.size; ++i) design.push_back(v.default_lower[static_cast<std::size_t>(i)]);
  }
  ASSERT_GE(jf_x, 0);
  design[static_cast<std::size_t>(jf_x)] = 0.18;  // a design value, not the file's 0.15
  const auto model = m.build(design.data());
  const auto* drawing = dynamic_cast<const MeshDrawing*>(model.get());
  ASSERT_NE(drawing, nullptr);
  EXPECT_EQ(drawing->mesh_warnings(), r.mechanism().setup().chain_template.meshes().warnings);

  // The forward kinematics written out from the file's numbers: the link frames in the scene
  // frame (base, l1, l2, cover, tip), then each visual's <origin>.
  const Eigen::Isometry3d scene_base = pose(0.1, -0.2, 0.3, rpy(10 * M_PI / 180, -20 * M_PI / 180, 30 * M_PI / 180));
  const auto link_frames = [&](double q1, double q2, double q3) {
    const Eigen::Isometry3d l1 = pose(0, 0, 0.1, rot(0.3, Eigen::Vector3d::UnitZ())) * pose(0, 0, 0, rot(q1, Eigen::Vector3d::UnitZ()));
    const Eigen::Isometry3d l2 = l1 * pose(0.2, 0, 0, rot(0.2, Eigen::Vector3d::UnitX())) * pose(0, 0, 0, rot(q2, Eigen::Vector3d::UnitY()));
    const Eigen::Isometry3d cover = l2 * pose(0, 0.03, 0, rot(1.0, Eigen::Vector3d::UnitZ()));
    const Eigen::Isometry3d l3 = l2 * pose(0.1, 0, 0) * pose(0, 0, 0, rot(q3, Eigen::Vector3d::UnitX()));
    const Eigen::Isometry3d tip = l3 * pose(0.18, 0, -0.05, rot(0.4, Eigen::Vector3d::UnitY()));
    return std::vector<Eigen::Isometry3d>{scene_base, scene_base * l1, scene_base * l2, scene_base * cover, scene_base * tip};
  };
  const std::vector<Eigen::Isometry3d> visual_origins = {pose(0, 0, 0.01), pose(0.1, 0, 0, rot(1.2, Eigen::Vector3d::UnitY())),
                                                         pose(0, 0, 0), pose(0.01, 0, 0), pose(0, 0, 0.02, rpy(0.1, 0.2, 0.3))};
  // A sample the tip reaches at q = (0.5, -0.4, 0.7); the IK may pick another configuration that
  // reaches it: the expected poses are those of the one it picks.
  SampleSet scene;
  scene.coordinates = {"x", "y", "z"};
  scene.poses.resize(1, 3);
  const Eigen::Vector3d tip_point = link_frames(0.5, -0.4, 0.7)[4].translation();
  scene.poses.row(0) = tip_point.transpose();
  auto scratch = m.make_scratch();
  SampleQuantities q;
  q.scene = &scene;
  q.sample = 0;
  model->solve(scene.pose(0), kNeedPose, *scratch, q);
  ASSERT_EQ(q.status, SampleStatus::kReachable);
  const std::vector<Eigen::Isometry3d> frames = link_frames(q.q(0), q.q(1), q.q(2));
  EXPECT_LT((frames[4].translation() - tip_point).norm(), 1e-9) << "the configuration reaches the sample";
  std::vector<Eigen::Isometry3d> want;
  for (std::size_t k = 0; k < frames.size(); ++k) want.push_back(frames[k] * visual_origins[k]);
  const std::vector<MeshVisual> drawn = drawing->mesh_visuals(scene, 0, *scratch);
  ASSERT_EQ(drawn.size(), want.size());
  const std::vector<std::string> links = {"base", "l1", "l2", "cover", "tip"};
  for (std::size_t k = 0; k < drawn.size(); ++k) {
    EXPECT_EQ(drawn[k].link, links[k]);
    EXPECT_LT((drawn[k].pose.matrix() - want[k].matrix()).norm(), 1e-9) << links[k] << "\n"
                                                                        << drawn[k].pose.matrix() << "\n"
                                                                        << want[k].matrix();
  }
  EXPECT_EQ(drawn[1].scale, Eigen::Vector3d(2, 3, 4));
  EXPECT_EQ(drawn[0].scale, Eigen::Vector3d(1, 1, 1));
  // Nothing for a sample out of reach, as segments().
  scene.poses.row(0) << 5.0, 5.0, 5.0;
  EXPECT_TRUE(model->segments(scene, 0, *scratch).empty());
  EXPECT_TRUE(drawing->mesh_visuals(scene, 0, *scratch).empty());
}

#endif  // HAPSYN_HAVE_URDFDOM

}  // namespace
