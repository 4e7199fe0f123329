// Tests of the view's mesh files (framework/app/view/view_meshes.hpp) with a mechanism written
// here: each distinct file read once onto a numbered route, the list's poses and scales, and the
// warning of each file left out (over a limit, unreadable) and of the mechanism's own.
#include "view_meshes.hpp"

#include <hapsyn/mesh_drawing.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace hapsyn;
using hapsyn_cli::load_view_meshes;
using hapsyn_cli::MeshLimits;
namespace fs = std::filesystem;

namespace {

class MeshModel final : public MechanismModel, public MeshDrawing {
 public:
  explicit MeshModel(std::vector<MeshVisual> visuals) : visuals_(std::move(visuals)) {}
  void solve(const double*, Needs, MechanismScratch&, SampleQuantities& out) const override {
    out.status = SampleStatus::kReachable;
  }
  std::vector<MeshVisual> mesh_visuals(const SampleSet&, int, MechanismScratch&) const override { return visuals_; }
  std::vector<std::string> mesh_warnings() const override { return {"robot.urdf: link \"c\" visual box: not drawn"}; }

 private:
  std::vector<MeshVisual> visuals_;
};

class PlainModel final : public MechanismModel {
 public:
  void solve(const double*, Needs, MechanismScratch&, SampleQuantities& out) const override {
    out.status = SampleStatus::kReachable;
  }
};

class TestMechanism final : public Mechanism {
 public:
  explicit TestMechanism(std::vector<MeshVisual> visuals, bool meshes = true) : visuals_(std::move(visuals)), meshes_(meshes) {}
  std::unique_ptr<const MechanismModel> build(const double*) const override {
    if (!meshes_) return std::make_unique<PlainModel>();
    return std::make_unique<MeshModel>(visuals_);
  }

 private:
  std::vector<MeshVisual> visuals_;
  bool meshes_;
};

// A folder with files of the given sizes, named f<size>.stl (or .dae).
struct Files {
  fs::path root = fs::path(HAPSYN_BINARY_DIR) / "view_meshes_test" /
                  ::testing::UnitTest::GetInstance()->current_test_info()->name();
  Files() {
    fs::remove_all(root);
    fs::create_directories(root);
  }
  std::string make(const std::string& name, std::size_t size) const {
    const fs::path p = root / name;
    std::ofstream(p, std::ios::binary) << std::string(size, static_cast<char>('a' + size % 26));
    return p.string();
  }
};

MeshVisual visual(const std::string& link, const std::string& file, double x = 0.0) {
  MeshVisual v;
  v.link = link;
  v.file = file;
  v.pose = Eigen::Translation3d(x, 2.0, 3.0) * Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ());
  v.scale = Eigen::Vector3d(1.0, 2.0, 0.5);
  return v;
}

std::string read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

SampleSet one_sample() {
  SampleSet s;
  s.coordinates = {"x", "y", "z"};
  s.poses = Eigen::MatrixXd::Zero(1, 3);
  return s;
}

TEST(ViewMeshes, ReadsEachDistinctFileOnceOntoNumberedRoutes) {
  const Files f;
  const std::string a = f.make("a.stl", 100), b = f.make("b.DAE", 50);
  const TestMechanism m({visual("l1", a, 1.0), visual("l2", b, 2.0), visual("l3", a, 3.0)});
  std::ostringstream warnings;
  const auto meshes = load_view_meshes(m, nullptr, one_sample(), 0, MeshLimits{}, &warnings);
  ASSERT_EQ(meshes.files.size(), 2u);
  EXPECT_EQ(meshes.files[0].route, "/api/mesh/0");
  EXPECT_EQ(meshes.files[0].bytes, read(a));
  EXPECT_EQ(meshes.files[0].content_type, "model/stl");
  EXPECT_EQ(meshes.files[1].route, "/api/mesh/1");
  EXPECT_EQ(meshes.files[1].bytes, read(b));
  EXPECT_EQ(meshes.files[1].content_type, "model/vnd.collada+xml");
  ASSERT_EQ(meshes.list.size(), 3u);
  const std::vector<std::string> routes = {"/api/mesh/0", "/api/mesh/1", "/api/mesh/0"};
  for (std::size_t k = 0; k < 3; ++k) {
    const Json& e = meshes.list[k];
    EXPECT_EQ(e["link"], "l" + std::to_string(k + 1));
    EXPECT_EQ(e["route"], routes[k]);
    EXPECT_EQ(e["format"], k == 1 ? "dae" : "stl");
    EXPECT_EQ(e["name"], k == 1 ? "b.DAE" : "a.stl");
    const Eigen::Matrix4d want = visual("", "", static_cast<double>(k + 1)).pose.matrix();
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) EXPECT_EQ(e["pose"][r][c].get<double>(), want(r, c)) << k << " " << r << " " << c;
    }
    EXPECT_EQ(e["scale"], Json({1.0, 2.0, 0.5}));
  }
  EXPECT_EQ(warnings.str(), "hapsyn view: warning: robot.urdf: link \"c\" visual box: not drawn\n");
}

TEST(ViewMeshes, LeavesOutFilesOverTheLimitsOrUnreadableWithAWarning) {
  const Files f;
  const std::string small = f.make("small.stl", 8), big = f.make("big.stl", 12), fits = f.make("fits.stl", 9),
                    over = f.make("over.stl", 9), gone = (f.root / "gone.stl").string();
  const TestMechanism m({visual("a", small), visual("b", big), visual("c", fits), visual("d", over), visual("e", gone),
                         visual("caf\xe9", "x.stl")});
  std::ostringstream warnings;
  MeshLimits limits;
  limits.per_file = 10;
  limits.total = 25;
  const auto meshes = load_view_meshes(m, nullptr, one_sample(), 0, limits, &warnings);
  ASSERT_EQ(meshes.files.size(), 2u);
  EXPECT_EQ(meshes.files[0].bytes, read(small));
  EXPECT_EQ(meshes.files[1].bytes, read(fits));
  ASSERT_EQ(meshes.list.size(), 2u);
  EXPECT_EQ(meshes.list[0]["link"], "a");
  EXPECT_EQ(meshes.list[1]["link"], "c");
  EXPECT_EQ(warnings.str(), "hapsyn view: warning: robot.urdf: link \"c\" visual box: not drawn\n"
                            "hapsyn view: warning: link \"caf\\xe9\": mesh file \"x.stl\": not UTF-8 (the page's documents are JSON); not drawn\n"
                                "hapsyn view: warning: link b: view: mesh file " + big +
                                " is 12 bytes, more than the 10 this reader accepts; not drawn\n"
                                "hapsyn view: warning: link d: mesh file " + over +
                                ": 9 bytes would take the meshes over 25 bytes in all; not drawn\n"
                                "hapsyn view: warning: link e: view: cannot read mesh file " + gone +
                                ": No such file or directory; not drawn\n");
}

TEST(ViewMeshes, NoneForAModelWithoutMeshesOrWithoutADrawnSample) {
  const Files f;
  const std::string a = f.make("a.stl", 10);
  std::ostringstream warnings;
  EXPECT_TRUE(load_view_meshes(TestMechanism({visual("l", a)}, false), nullptr, one_sample(), 0, MeshLimits{}, &warnings).list.empty());
  const auto none = load_view_meshes(TestMechanism({visual("l", a)}), nullptr, one_sample(), -1, MeshLimits{}, &warnings);
  EXPECT_TRUE(none.list.empty());
  EXPECT_TRUE(none.files.empty());
  EXPECT_EQ(warnings.str(), "");
  EXPECT_EQ(MeshLimits{}.per_file, 32u << 20);
  EXPECT_EQ(MeshLimits{}.total, 128u << 20);
}

}  // namespace
