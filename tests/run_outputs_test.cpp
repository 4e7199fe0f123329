// The run's contract around the solve: unique samples.csv columns, warnings on bounds, the
// output-directory checks shared by `run` and `validate`, and the thread cap.
#include "analytic_problems.hpp"
#include "test_support.hpp"

#include <hapsyn/internal/maps.hpp>
#include <hapsyn/internal/plot.hpp>
#include <hapsyn/internal/study_runner.hpp>

#include <boost/filesystem.hpp>

#include <fstream>
#include <thread>

#include <unistd.h>

namespace fs = boost::filesystem;
using hapsyn::Json;
using hapsyn::test::error_of;

namespace {

// The analytic two-objective problem with both objectives from one metric plugin "m" (as a
// study with two coverage objectives has), and integer components when asked.
std::shared_ptr<const hapsyn::Problem> same_metric_twice(bool integer = false) {
  const auto local = [](const double* x, const double*) { return x[0]; };
  std::vector<hapsyn::DesignComponent> components(2);
  for (int i = 0; i < 2; ++i) {
    components[i].name = components[i].variable = "x" + std::to_string(i);
    components[i].lower = -1.0;
    components[i].upper = 1.0;
    components[i].integer = integer;
  }
  auto samples = std::make_shared<hapsyn::SampleSet>();
  samples->coordinates = {"s"};
  samples->poses = Eigen::MatrixXd::Zero(1, 1);
  samples->cache_bounds();
  std::vector<hapsyn::MetricEntry> metrics;
  std::vector<hapsyn::Objective> objectives;
  for (int i = 0; i < 2; ++i) {
    metrics.push_back({"m", std::make_shared<hapsyn::test::AnalyticMetric>(local)});
    hapsyn::Objective o;
    o.name = "o" + std::to_string(i);
    o.metric = i;
    objectives.push_back(o);
  }
  return std::make_shared<hapsyn::Problem>("analytic", std::make_shared<hapsyn::test::AnalyticMechanism>(2), samples,
                                           metrics, objectives, hapsyn::DesignSpace(components));
}

hapsyn::SolutionPoint point(double x0, double x1) {
  hapsyn::SolutionPoint p;
  p.design = Eigen::Vector2d(x0, x1);
  p.objectives = {0.0, 0.0};
  return p;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("hapsyn-run-outputs-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}

}  // namespace

TEST(RunOutputs, RepeatedLocalColumnNamesGetTheirIndex) {
  EXPECT_EQ(hapsyn::local_columns(*hapsyn::test::two_objective_problem()),
            (std::vector<std::string>{"f1.value", "f2.value"}));
  EXPECT_EQ(hapsyn::local_columns(*same_metric_twice()), (std::vector<std::string>{"m.value[0]", "m.value[1]"}));
}

TEST(RunOutputs, ABestDesignOnABoundIsWarnedAbout) {
  const auto problem = hapsyn::test::two_objective_problem();  // x0 in [0, 1], x1 in [-1, 1], step 0.05
  hapsyn::SolverResult result;
  result.best = point(1.0 - 0.02, 0.1);  // within half a step of the upper end
  EXPECT_EQ(hapsyn::bound_warnings(*problem, result),
            (std::vector<std::string>{"design.x0 = 0.98 is at its upper bound: the optimum may lie beyond it; widen "
                                      "design.x0.upper to check"}));
  result.best = point(0.5, 0.0);
  EXPECT_TRUE(hapsyn::bound_warnings(*problem, result).empty());
  result.front = {point(0.5, -1.0), point(0.6, -1.0), point(0.7, 0.0)};
  EXPECT_EQ(hapsyn::bound_warnings(*problem, result),
            (std::vector<std::string>{"design.x1 is at its lower bound in 2 of 3 front points: the front may extend "
                                      "beyond it; widen design.x1.lower to check"}));
}

TEST(RunOutputs, IntegerComponentsOnABoundAreNotWarnedAbout) {
  hapsyn::SolverResult result;
  result.best = point(1.0, -1.0);
  EXPECT_TRUE(hapsyn::bound_warnings(*same_metric_twice(true), result).empty());
}

TEST(RunOutputs, OutputDirectoryChecksChangeNothing) {
  const fs::path dir = fresh_dir("check");
  hapsyn::RunOptions options;
  EXPECT_EQ(error_of([&] { hapsyn::check_output_directory((dir / "a" / "b").string(), options); }), "(no error)");
  EXPECT_FALSE(fs::exists(dir)) << "checking creates nothing";
  fs::create_directories(dir);
  std::ofstream((dir / "file").string()) << "x";
  EXPECT_EQ(error_of([&] { hapsyn::check_output_directory((dir / "file" / "out").string(), options); }),
            "output: the output directory " + (dir / "file" / "out").string() + ": Not a directory");
  const std::string long_name(300, 'x');
  EXPECT_EQ(error_of([&] { hapsyn::check_output_directory((dir / long_name).string(), options); }),
            "output: the output directory " + (dir / long_name).string() + ": File name too long");
  fs::remove_all(dir);
}

TEST(RunOutputs, FinishedAndStoppedStudiesNeedTheirFlags) {
  const fs::path dir = fresh_dir("finished");
  fs::create_directories(dir);
  const std::string out = dir.string(), result = (dir / "result.json").string();
  hapsyn::RunOptions plain, resume, force;
  resume.resume = true;
  force.force = true;
  std::ofstream(result) << R"({"status": "converged"})";
  EXPECT_EQ(error_of([&] { hapsyn::check_output_directory(out, plain); }),
            "output: " + out + " already holds a finished study (" + result +
                "); pass --force to overwrite it, or --out for another directory");
  EXPECT_EQ(error_of([&] { hapsyn::check_output_directory(out, resume); }),
            "output: " + result + ": the study in " + out + " has finished; there is nothing to resume (pass --force to run it again)");
  EXPECT_EQ(error_of([&] { hapsyn::check_output_directory(out, force); }), "(no error)");
  std::ofstream(result) << R"({"status": "stopped"})";
  EXPECT_EQ(error_of([&] { hapsyn::check_output_directory(out, plain); }),
            "output: " + out + " holds a stopped study (" + result +
                " has status \"stopped\"); pass --resume to continue it, or --force to start over");
  EXPECT_EQ(error_of([&] { hapsyn::check_output_directory(out, resume); }), "(no error)");
  fs::remove_all(dir);
}

TEST(RunOutputs, ThreadsAreCappedWithAWarningAndRangeChecked) {
  const int hardware = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int cap = std::min(1024, 4 * hardware);
  std::vector<std::string> warnings;
  hapsyn::RunOptions options;
  options.threads = 100000;
  EXPECT_EQ(hapsyn::run_threads(Json::object(), options, warnings), cap);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], "--threads 100000: capped to " + std::to_string(cap) + " (4 x the " + std::to_string(hardware) +
                             " hardware threads)");
  options.threads = 0;
  warnings.clear();
  EXPECT_EQ(hapsyn::run_threads(Json{{"threads", 100000}}, options, warnings), cap);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].rfind("threads = 100000 (problem file): capped to ", 0), 0u) << warnings[0];
  EXPECT_EQ(error_of([&] { hapsyn::run_threads(Json{{"threads", 3000000000LL}}, options, warnings); }),
            "problem: threads = 3000000000: must be an integer in [0, 2147483647] (0 = all cores)");
  EXPECT_EQ(error_of([&] { hapsyn::run_threads(Json{{"threads", -2}}, options, warnings); }),
            "problem: threads = -2: must be an integer in [0, 2147483647] (0 = all cores)");
  EXPECT_EQ(hapsyn::run_threads(Json{{"threads", 1}}, options, warnings), 1);
}

TEST(RunOutputs, AnOutputNameTakenByADirectoryIsRefusedBeforeTheSolve) {
  const fs::path dir = fresh_dir("occupied");
  fs::create_directories(dir / "samples.csv");
  hapsyn::RunOptions force;
  force.force = true;  // also with --force: the move into place would fail after the whole solve
  EXPECT_EQ(error_of([&] { hapsyn::check_output_directory(dir.string(), force); }),
            "output: " + (dir / "samples.csv").string() +
                " is a directory, where a run writes a file; remove it, or choose another --out");
  fs::remove_all(dir);
}

TEST(RunOutputs, AnOutputDirectoryThatIsNotUtf8IsRefused) {
  // result.json records the directory; a name it cannot hold fails before the solve, not after.
  const std::string out = fresh_dir("utf8").string() + "\xff";
  EXPECT_EQ(error_of([&] { hapsyn::check_output_directory(out, hapsyn::RunOptions()); }).rfind(
                "output: output directory = ", 0),
            0u);
  EXPECT_NE(error_of([&] { hapsyn::check_output_directory(out, hapsyn::RunOptions()); }).find("invalid UTF-8"),
            std::string::npos);
}

// Every figure a run with plots: true writes (the map of a grid study's best design, the front
// of a two-objective one) is a PNG with an SVG of the same name beside it, drawn with names as
// written.
TEST(RunOutputs, EveryPngFigureHasAnSvgTwin) {
  for (const bool pareto : {false, true}) {
    Json doc = hapsyn::test::fivebar_study("grid");
    doc["objectives"] = Json::parse(R"([{"metric": "gii", "name": "g_ii"}, {"metric": "gdi", "name": "g_di"}])");
    if (pareto) {
      doc["solver"]["options"] = {{"pareto", true}};
    } else {
      doc["objectives"].erase(1);
    }
    hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
    study.resolved["output"]["plots"] = true;
    const fs::path dir = fresh_dir(pareto ? "svg-twins-front" : "svg-twins-map");
    hapsyn::RunOptions options;
    options.output_directory = dir.string();
    options.quiet = true;
    (void)hapsyn::run_study(study, options);
    std::size_t scripts = 0;
    for (const fs::directory_entry& f : fs::directory_iterator(dir)) {
      if (f.path().extension() != ".gp") continue;
      ++scripts;
      std::ifstream in(f.path().string());
      const std::string script((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      EXPECT_NE(script.find("noenhanced"), std::string::npos) << f.path();
    }
    EXPECT_TRUE(fs::exists(dir / (pareto ? "front.gp" : "map_g_ii.gp")));
    if (!hapsyn::gnuplot_available()) GTEST_SKIP() << "gnuplot is not installed";
    std::size_t pngs = 0;
    for (const fs::directory_entry& f : fs::directory_iterator(dir)) {
      if (f.path().extension() != ".png") continue;
      ++pngs;
      fs::path svg = f.path();
      svg.replace_extension(".svg");
      ASSERT_TRUE(fs::exists(svg)) << f.path();
      EXPECT_GT(fs::file_size(svg), 1000u) << svg;
    }
    EXPECT_EQ(pngs, scripts) << "a picture per script";
    fs::remove_all(dir);
  }
}
