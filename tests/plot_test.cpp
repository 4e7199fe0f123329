// The lattice slice plots: slices are level in the plot frame (heights above the lattice's
// origin), whatever signed permutation turns the lattice frame into it, and a lattice turned
// by a general rotation is cut along its axis nearest the vertical.
#include <hapsyn/internal/plot.hpp>

#include <Eigen/Geometry>
#include <boost/filesystem.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
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

namespace {

std::string read_text(const fs::path& file) {
  std::ifstream in(file.string(), std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Every figure helper leaves `<name>.png` (a PNG) and `<name>.svg` (an SVG) side by side.
void expect_png_and_svg(const fs::path& dir, const std::string& name) {
  const std::string png = read_text(dir / (name + ".png")), svg = read_text(dir / (name + ".svg"));
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << name;
  EXPECT_NE(svg.find("<svg"), std::string::npos) << name;
}

hapsyn::ConvergenceFigure two_panel_figure() {
  hapsyn::ConvergenceFigure figure;
  figure.title = "convergence of run_1";
  figure.panels = {"best_score", "hypervolume"};
  figure.curves.push_back({"run_1", 0, 0, false, {10, 20, 30}, {0.1, std::nan(""), 0.3}});
  figure.curves.push_back({"", 1, 1, true, {10, 20, 30}, {1, 2, 3}});
  return figure;
}

}  // namespace

TEST(Plot, NamesWithUnderscoresArePrintedAsWritten) {
  EXPECT_EQ(hapsyn::gnuplot_quote("it's a_b"), "'it''s a_b'");
  const std::string script = hapsyn::figure_script("map_J_x", "J_x per position", hapsyn::FigureStyle{}, "plot x\n");
  EXPECT_NE(script.find("set terminal pngcairo noenhanced"), std::string::npos) << script;
  EXPECT_NE(script.find("set terminal svg noenhanced"), std::string::npos) << script;
  EXPECT_NE(script.find("set termoption noenhanced"), std::string::npos) << script;
  EXPECT_NE(script.find("set output 'map_J_x.'.format"), std::string::npos) << script;
  EXPECT_NE(script.find("unset key"), std::string::npos) << "one series, no key: " << script;
  hapsyn::FigureStyle keyed;
  keyed.key = true;
  EXPECT_NE(hapsyn::figure_script("f", "f", keyed, "").find("set key outside right top"), std::string::npos);
}

TEST(Plot, EveryFigureHasAnSvgTwin) {
  const fs::path dir = fresh_dir("twins");
  const std::vector<std::string> messages = {
      hapsyn::plot_lattice_slices(dir.string(), "lattice_slices", "height_above", coordinate_field(upright(), 2), 1.0),
      hapsyn::plot_front(dir.string(), {"g_ii", "g_di"}, {"maximize", "minimize"}, {{0.1, 0.2}, {0.2, 0.3}}),
      hapsyn::plot_convergence(dir.string(), two_panel_figure())};
  const std::string convergence = read_text(dir / "convergence.gp");
  EXPECT_NE(convergence.find("title 'run_1'"), std::string::npos) << convergence;
  EXPECT_NE(convergence.find("set ylabel 'best_score'"), std::string::npos) << convergence;
  EXPECT_NE(convergence.find("set key outside right top"), std::string::npos) << convergence;
  EXPECT_NE(read_text(dir / "front.gp").find("set xlabel 'g_ii (maximize)'"), std::string::npos);
  EXPECT_NE(read_text(dir / "lattice_slices.gp").find("set termoption noenhanced"), std::string::npos);
  if (!hapsyn::gnuplot_available()) GTEST_SKIP() << "gnuplot is not installed";
  for (const std::string& m : messages) EXPECT_EQ(m, "");
  std::size_t pngs = 0;
  for (const fs::directory_entry& f : fs::directory_iterator(dir)) {
    if (f.path().extension() != ".png") continue;
    ++pngs;
    expect_png_and_svg(dir, f.path().stem().string());
  }
  EXPECT_EQ(pngs, 3u);
  fs::remove_all(dir);
}

TEST(Plot, HistoryKeepsEveryKthGenerationAndTheLatest) {
  hapsyn::ConvergenceHistory history(100);
  for (int g = 0; g <= 4999; ++g) history.add(g, {{"best", g * 0.5}, {"ideal", {{"a_b", -g}}}});
  const hapsyn::Json& h = history.json();
  const long long stride = h["stride"];
  EXPECT_GT(stride, 1);
  EXPECT_LE(history.size(), 101u);
  EXPECT_GE(history.size(), 50u);
  EXPECT_EQ(h["generation"].back(), 4999);
  EXPECT_EQ(h["ideal"]["a_b"].size(), history.size());
  for (std::size_t i = 0; i < history.size(); ++i) {
    const long long g = h["generation"][i];
    if (i + 1 < history.size()) {
      EXPECT_EQ(g % stride, 0) << g;
    }
    EXPECT_EQ(h["best"][i], g * 0.5);
    EXPECT_EQ(h["ideal"]["a_b"][i], -g);
  }
}

TEST(Plot, HistoryContinuedFromItsJsonKeepsWhatAnUninterruptedOneKeeps) {
  hapsyn::ConvergenceHistory whole(64), first(64);
  for (int g = 0; g < 1000; ++g) whole.add(g, {{"v", g}});
  for (int g = 0; g < 437; ++g) first.add(g, {{"v", g}});
  hapsyn::ConvergenceHistory resumed = hapsyn::ConvergenceHistory::from_json(first.json(), 64);
  for (int g = 437; g < 1000; ++g) resumed.add(g, {{"v", g}});
  EXPECT_EQ(resumed.json(), whole.json());
  hapsyn::ConvergenceHistory again = resumed;
  again.add(999, {{"v", -1}});  // a second entry of the last generation (a final ranking)
  const hapsyn::Json& g = again.json()["generation"];
  ASSERT_GE(g.size(), 2u);
  EXPECT_EQ(g[g.size() - 2], 999);
  EXPECT_EQ(g.back(), 999);
  EXPECT_EQ(again.json()["v"].back(), -1);
  EXPECT_THROW(again.add(998, {{"v", 0}}), std::invalid_argument);
  EXPECT_THROW(again.add(1000, {{"w", 0}}), std::invalid_argument);
  hapsyn::Json bad = whole.json();
  bad["v"].erase(0);
  EXPECT_THROW(hapsyn::ConvergenceHistory::from_json(bad), std::invalid_argument);
  bad = whole.json();
  bad["stride"] = 0;
  EXPECT_THROW(hapsyn::ConvergenceHistory::from_json(bad), std::invalid_argument);
  bad = whole.json();
  std::swap(bad["generation"][0], bad["generation"][1]);
  EXPECT_THROW(hapsyn::ConvergenceHistory::from_json(bad), std::invalid_argument);
}
