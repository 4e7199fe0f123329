// The lattice slice plots: slices are level in the plot frame (heights above the lattice's
// origin), whatever signed permutation turns the lattice frame into it, and a lattice turned
// by a general rotation is cut along its axis nearest the vertical.
#include <hapsyn/plot.hpp>

#include <Eigen/Geometry>
#include <boost/filesystem.hpp>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = boost::filesystem;

// One slice of a written .dat file: its title line and its rows (u, v, value).
struct Slice {
  std::string title;
  std::vector<Eigen::Vector3d> rows;
};

std::vector<Slice> read_slices(const fs::path& dat) {
  std::ifstream in(dat.string());
  std::vector<Slice> slices;
  std::string line;
  int header_lines = 2;  // the title and the column description
  while (std::getline(in, line)) {
    if (line.rfind("# ", 0) == 0) {
      if (header_lines > 0) {
        --header_lines;
        continue;
      }
      slices.push_back({line.substr(2), {}});
    } else if (!line.empty()) {
      std::istringstream s(line);
      Eigen::Vector3d row;
      std::string value;
      s >> row(0) >> row(1) >> value;
      row(2) = value == "NaN" ? std::nan("") : std::stod(value);
      slices.back().rows.push_back(row);
    }
  }
  return slices;
}

// A field on a 5^3 lattice of 0.1 m whose value at each point is a coordinate of the point in the
// plot frame, C p.
hapsyn::LatticeField coordinate_field(const Eigen::Matrix3d& C, int coordinate) {
  hapsyn::LatticeField field;
  field.per_axis = 5;
  field.step = 0.1;
  field.lattice_to_plot = C;
  field.origin = "the shoulder";
  field.lattice_frame = "S";
  for (int iz = 0; iz < 5; ++iz) {
    for (int iy = 0; iy < 5; ++iy) {
      for (int ix = 0; ix < 5; ++ix) {
        const Eigen::Vector3d p = 0.1 * Eigen::Vector3d(ix - 2, iy - 2, iz - 2);
        field.values.push_back((C * p)(coordinate));
      }
    }
  }
  return field;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / fs::unique_path("hapsyn-plot-" + name + "-%%%%-%%%%");
  fs::create_directories(dir);
  return dir;
}

Eigen::Matrix3d upright() {
  Eigen::Matrix3d C;
  C << 0, 0, -1, -1, 0, 0, 0, 1, 0;  // the human_arm default: S -> B for an upright user
  return C;
}

TEST(Plot, LatticeSlicesAreLevelInThePlotFrameHighestFirst) {
  const fs::path dir = fresh_dir("level");
  hapsyn::plot_lattice_slices(dir.string(), "height", "height", coordinate_field(upright(), 2), 1.0);
  const std::vector<Slice> slices = read_slices(dir / "height.dat");
  ASSERT_EQ(slices.size(), 5u);
  for (std::size_t k = 0; k < slices.size(); ++k) {
    const double height = 0.2 - 0.1 * static_cast<double>(k);
    std::ostringstream title;
    title.setf(std::ios::fixed);
    title.precision(2);
    title << "height above the shoulder: " << height + 0.0 << " m";
    EXPECT_EQ(slices[k].title, title.str());
    ASSERT_EQ(slices[k].rows.size(), 25u);
    for (const Eigen::Vector3d& row : slices[k].rows) EXPECT_NEAR(row(2), height, 1e-12) << slices[k].title;
  }
  fs::remove_all(dir);
}

TEST(Plot, PanelsAreDrawnInThePlotFramesHorizontalAxes) {
  const fs::path dir = fresh_dir("axes");
  for (int coordinate : {0, 1}) {
    const std::string name = "c" + std::to_string(coordinate);
    hapsyn::plot_lattice_slices(dir.string(), name, name, coordinate_field(upright(), coordinate), 1.0);
    for (const Slice& slice : read_slices(dir / (name + ".dat"))) {
      for (const Eigen::Vector3d& row : slice.rows) EXPECT_NEAR(row(2), row(coordinate), 1e-12) << slice.title;
    }
  }
  std::ifstream script((dir / "c0.gp").string());
  const std::string text((std::istreambuf_iterator<char>(script)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("set xlabel 'x [m]'"), std::string::npos) << text;
  EXPECT_NE(text.find("set ylabel 'y [m]'"), std::string::npos) << text;
  fs::remove_all(dir);
}

TEST(Plot, TiltedLatticeIsCutAlongItsAxisNearestTheVertical) {
  const Eigen::Matrix3d tilted = Eigen::AngleAxisd(30.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const hapsyn::LatticeSlicing slicing = hapsyn::lattice_slicing(tilted);
  EXPECT_FALSE(slicing.by_height);
  EXPECT_EQ(slicing.slice_axis, 2);
  EXPECT_NEAR(slicing.tilt_degrees, 30.0, 1e-9);
  EXPECT_TRUE(hapsyn::lattice_slicing(upright()).by_height);
  const fs::path dir = fresh_dir("tilted");
  hapsyn::plot_lattice_slices(dir.string(), "t", "t", coordinate_field(tilted, 2), 1.0);
  const std::vector<Slice> slices = read_slices(dir / "t.dat");
  ASSERT_EQ(slices.size(), 5u);
  EXPECT_EQ(slices.front().title, "z_S = 0.20 m (30 deg from the vertical)");
  EXPECT_EQ(slices.back().title, "z_S = -0.20 m (30 deg from the vertical)");
  fs::remove_all(dir);
}

}  // namespace
