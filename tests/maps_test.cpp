// Per-sample records and per-position maps: every position's value is the metric's own
// reduction over that position's samples, checked against the whole-scene evaluation.
#include "test_support.hpp"

#include <hapsyn/internal/maps.hpp>
#include <hapsyn/internal/plot.hpp>

#include <boost/filesystem.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

using hapsyn::Json;
using hapsyn::test::fivebar_study;
using hapsyn::test::registry;

namespace {
Eigen::VectorXd full_design(const hapsyn::Problem& problem, const std::vector<double>& free_design) {
  return problem.full_design(free_design.data());
}

// A small human-arm lattice scene (0.2 m, 101 orientations) with the coverage terms.
hapsyn::Study coverage_study() {
  return hapsyn::load_study(Json::parse(R"({
    "name": "maps", "mechanism": {"plugin": "haptic6r"},
    "scene": {"plugin": "human_arm", "options": {"lattice_step": 0.2, "orientations": 101, "joint3_steps": 5}},
    "design": {"l": {"value": [0.45, 0.45, 0.65, 0.55, 0.15]}, "s": {"value": [3, 3, 2, 2, 1, 1]},
               "r": {"value": [2, 2, 3, 2, 3, 3]}},
    "objectives": [{"metric": "coverage", "name": "J_x", "options": {"terms": ["pose"]}},
                   {"metric": "coverage", "name": "J_v", "options": {"terms": ["velocity"]}},
                   {"metric": "coverage", "name": "J", "options": {}}],
    "solver": {"plugin": "evaluate"}})"),
                            registry());
}
}  // namespace

TEST(Maps, EverySampleOfAPlanarSceneIsItsOwnPositionWithItsLocalValue) {
  Json doc = fivebar_study();
  doc["objectives"] = Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  const hapsyn::Study study = hapsyn::load_study(doc, registry());
  const hapsyn::Problem& problem = *study.problem;
  const Eigen::VectorXd full = full_design(problem, {0.0004, 0.2997, 0.3, 0.4196});
  const hapsyn::SampleRecords records = hapsyn::record_samples(problem, full);
  const hapsyn::PositionMaps maps = hapsyn::position_maps(problem, records);
  ASSERT_EQ(static_cast<int>(maps.position.size()), problem.samples().size());
  EXPECT_EQ(maps.lattice_per_axis, 0);
  // The worst case over the positions is the design's GII and GDI.
  auto ws = problem.make_eval_scratch();
  const std::vector<double> free_design = {0.0004, 0.2997, 0.3, 0.4196};
  const hapsyn::Evaluation& e = problem.evaluate(free_design.data(), *ws);
  ASSERT_EQ(e.status, hapsyn::EvalStatus::kFeasible);
  EXPECT_DOUBLE_EQ(maps.values.col(0).minCoeff(), e.objectives[0]);
  EXPECT_DOUBLE_EQ(maps.values.col(1).minCoeff(), e.objectives[1]);
  for (std::size_t g = 0; g < maps.position.size(); ++g) {
    EXPECT_EQ(maps.samples[g], 1);
    EXPECT_EQ(maps.lattice_index[g], -1);
    EXPECT_DOUBLE_EQ(maps.position[g][0], problem.samples().poses(static_cast<Eigen::Index>(g), 0));
  }
}

TEST(Maps, UnreachableSampleLeavesItsWorstCasePositionUndefined) {
  Json doc = fivebar_study();
  const hapsyn::Study study = hapsyn::load_study(doc, registry());
  const hapsyn::Problem& problem = *study.problem;
  // A design that passes the design constraints but misses some samples: searched, not assumed.
  hapsyn::PositionMaps maps;
  bool found = false;
  for (double l1 = 0.05; l1 <= 0.3 && !found; l1 += 0.05) {
    for (double r = 0.0; r <= 0.6 && !found; r += 0.05) {
      const hapsyn::SampleRecords records = hapsyn::record_samples(problem, full_design(problem, {0.1, l1, 0.1, r}));
      int with = 0;
      for (char c : records.has_locals) with += c;
      if (with > 0 && with < problem.samples().size()) {
        maps = hapsyn::position_maps(problem, records);
        found = true;
      }
    }
  }
  ASSERT_TRUE(found);
  int undefined = 0, defined = 0;
  for (Eigen::Index g = 0; g < maps.values.rows(); ++g) {
    if (std::isnan(maps.values(g, 0))) {
      ++undefined;
    } else {
      ++defined;
    }
  }
  EXPECT_GT(undefined, 0);
  EXPECT_GT(defined, 0);
  // Undefined values are empty cells, never "nan", in maps.csv.
  const std::string csv = hapsyn::maps_csv(maps);
  EXPECT_EQ(csv.find("nan"), std::string::npos);
  EXPECT_NE(csv.find(",\n"), std::string::npos);
}

TEST(Maps, CoveragePerLatticePointAveragesBackToTheWholeSceneTerms) {
  const hapsyn::Study study = coverage_study();
  const hapsyn::Problem& problem = *study.problem;
  const Eigen::VectorXd full = problem.full_design(nullptr);
  const hapsyn::Evaluation e = problem.evaluate_parallel(nullptr, 1);
  const hapsyn::SampleRecords records = hapsyn::record_samples(problem, full);
  const hapsyn::PositionMaps maps = hapsyn::position_maps(problem, records);
  ASSERT_GT(maps.lattice_per_axis, 0);
  ASSERT_GT(maps.position.size(), 10u);
  // J_x(p) = reach_m(p) / n(p), so sum_p n(p) J_x(p) = n_reach^m; J_v(p) = sum eta_v(p) / reach_m(p),
  // so sum_p reach_m(p) J_v(p) = sum eta_v.
  double reach_m = 0.0, eta_v = 0.0, n = 0.0;
  for (std::size_t g = 0; g < maps.position.size(); ++g) {
    const double here = maps.samples[g] * maps.values(static_cast<Eigen::Index>(g), 0);
    reach_m += here;
    eta_v += here * maps.values(static_cast<Eigen::Index>(g), 1);
    n += maps.samples[g];
    EXPECT_GE(maps.lattice_index[g], 0);
    for (Eigen::Index o = 0; o < 3; ++o) EXPECT_TRUE(std::isfinite(maps.values(static_cast<Eigen::Index>(g), o)));
  }
  EXPECT_EQ(n, problem.samples().size());
  EXPECT_NEAR(reach_m / n, e.objectives[0], 1e-12);
  EXPECT_NEAR(eta_v / reach_m, e.objectives[1], 1e-12);
  // Positions of one lattice point coincide (palm positions in B).
  const auto& index = problem.samples().attributes.at("lattice_index");
  for (int i = 0; i < problem.samples().size(); ++i) {
    if (index(i, 0) != maps.lattice_index[0]) continue;
    EXPECT_NEAR(problem.samples().poses(i, 0), maps.position[0][0], 1e-12);
    EXPECT_NEAR(problem.samples().poses(i, 2), maps.position[0][2], 1e-12);
  }
}

TEST(Maps, RunStudyWritesMapsAndPlotsWhenAsked) {
  namespace fs = boost::filesystem;
  hapsyn::Study study = coverage_study();
  const fs::path dir = fs::temp_directory_path() / fs::unique_path("hapsyn-maps-%%%%%%");
  study.resolved["output"]["plots"] = true;
  hapsyn::RunOptions options;
  options.output_directory = dir.string();
  options.quiet = true;
  const Json result = hapsyn::run_study(study, options);
  EXPECT_EQ(result["files"]["maps"], "maps.csv");
  EXPECT_EQ(hapsyn::test::count_lines((dir / "maps.csv").string()),
            1 + static_cast<int>(hapsyn::position_maps(*study.problem, hapsyn::record_samples(*study.problem, study.problem->full_design(nullptr))).position.size()));
  for (const char* name : {"map_J_x", "map_J_v", "map_J"}) {
    EXPECT_TRUE(fs::exists(dir / (std::string(name) + ".dat"))) << name;
    EXPECT_TRUE(fs::exists(dir / (std::string(name) + ".gp"))) << name;
  }
  if (hapsyn::gnuplot_available()) {
    EXPECT_EQ(result["files"]["plots"].size(), 3u) << result.dump();
    EXPECT_GT(fs::file_size(dir / "map_J_v.png"), 10000u);
  } else {
    EXPECT_TRUE(result.contains("plot_message"));
  }
  fs::remove_all(dir);
}

// Issue 51: the map of a 3-D box or point list drew every position in one x-y plot, its layers
// overprinted. Each z layer is a panel (highest first); many layers are banded, every position
// in exactly one band.
TEST(Maps, ScatteredThreeDimensionalMapsArePlottedPerHeight) {
  namespace fs = boost::filesystem;
  const auto maps_with = [](const std::vector<double>& zs) {
    hapsyn::PositionMaps maps;
    maps.objectives = {"gii"};
    for (double z : zs) {
      for (double x : {0.0, 0.1}) maps.position.emplace_back(x, 0.2, z);
    }
    maps.samples.assign(maps.position.size(), 1);
    maps.lattice_index.assign(maps.position.size(), -1);
    maps.values = Eigen::MatrixXd::Constant(static_cast<Eigen::Index>(maps.position.size()), 1, 0.5);
    return maps;
  };
  const fs::path dir = fs::temp_directory_path() / fs::unique_path("hapsyn-maps3d-%%%%%%");
  fs::create_directories(dir);
  const auto read = [&](const std::string& file) {
    std::ifstream in((dir / file).string());
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const auto count = [](const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  const auto data_lines = [](const std::string& text) {
    std::size_t n = 0;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) n += !line.empty() && line[0] != '#';
    return n;
  };
  std::string message;
  hapsyn::plot_maps(maps_with({-0.04, 0.0, 0.04}), dir.string(), message);
  std::string script = read("map_gii.gp"), data = read("map_gii.dat");
  EXPECT_EQ(count(script, "plot 'map_gii.dat' index "), 3u) << script;
  EXPECT_NE(script.find("set multiplot layout 2,2"), std::string::npos) << script;
  EXPECT_LT(script.find("set title 'z = 0.04'"), script.find("set title 'z = -0.04'")) << "highest first: " << script;
  EXPECT_EQ(data_lines(data), 6u) << data;

  std::vector<double> many;
  for (int k = 0; k < 30; ++k) many.push_back(0.01 * k);
  hapsyn::plot_maps(maps_with(many), dir.string(), message);
  script = read("map_gii.gp");
  data = read("map_gii.dat");
  EXPECT_EQ(count(script, "plot 'map_gii.dat' index "), 12u) << script;
  EXPECT_EQ(data_lines(data), 60u) << "every position in exactly one band: " << data;

  hapsyn::plot_maps(maps_with({0.0}), dir.string(), message);  // planar: one plot, no panels
  script = read("map_gii.gp");
  EXPECT_EQ(script.find("multiplot"), std::string::npos) << script;
  EXPECT_EQ(count(script, "plot 'map_gii.dat' index 0"), 1u) << script;
  if (hapsyn::gnuplot_available()) {
    EXPECT_TRUE(fs::exists(dir / "map_gii.png"));
  }
  fs::remove_all(dir);
}
