// nsga2 through the shared pagmo adapter: a known front, determinism, errors.
#include "nsga2.hpp"

#include "analytic_problems.hpp"
#include "test_support.hpp"

#include <hapsyn/checkpoint.hpp>
#include <hapsyn/cluster.hpp>
#include <hapsyn/pareto.hpp>
#include <hapsyn/internal/plot.hpp>
#include <hapsyn/internal/study_runner.hpp>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <streambuf>

#include <cmath>

using hapsyn::Json;

namespace {
Json pareto_study(const Json& options) {
  Json doc = hapsyn::read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/problems/fivebar-pareto-nsga2.json");
  doc["scene"]["options"]["step"] = 0.01;
  doc["solver"]["options"] = options.is_null() ? Json::object() : options;
  return doc;
}

hapsyn::SolverResult solve(const Json& doc, int threads, std::uint64_t seed = 3) {
  hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  hapsyn::SolverContext context;
  context.threads = threads;
  context.seed = seed;
  return study.solver->solve(*study.problem, context);
}
}  // namespace

TEST(Nsga2, FrontIsNonDominatedFeasibleAndSpansTheTradeOff) {
  const auto r = solve(pareto_study({{"population", 32}, {"generations", 40}}), 2);
  ASSERT_FALSE(r.front.empty()) << r.message;
  EXPECT_EQ(r.status, hapsyn::SolverStatus::kBudgetExhausted);
  EXPECT_GE(r.front.size(), 5u);
  for (const auto& a : r.front) {
    for (const auto& b : r.front) {
      const bool dominates = b.objectives[0] >= a.objectives[0] && b.objectives[1] >= a.objectives[1] &&
                             (b.objectives[0] > a.objectives[0] || b.objectives[1] > a.objectives[1]);
      EXPECT_FALSE(dominates);
    }
  }
  // The extremes approach the single-objective optima of Table 2 (GII 0.783, GDI 0.766).
  double best_gii = 0, best_gdi = 0;
  for (const auto& p : r.front) {
    best_gii = std::max(best_gii, p.objectives[0]);
    best_gdi = std::max(best_gdi, p.objectives[1]);
  }
  EXPECT_GT(best_gii, 0.72);
  EXPECT_GT(best_gdi, 0.72);
  EXPECT_LT(best_gii, 0.7835);
  EXPECT_LT(best_gdi, 0.7665);
}

TEST(Nsga2, SameSeedSameFrontWhateverTheThreadCount) {
  const Json doc = pareto_study({{"population", 16}, {"generations", 10}});
  const auto a = solve(doc, 2), b = solve(doc, 1);
  ASSERT_EQ(a.front.size(), b.front.size());
  for (std::size_t i = 0; i < a.front.size(); ++i) {
    EXPECT_EQ(a.front[i].objectives, b.front[i].objectives);
    EXPECT_TRUE(a.front[i].design == b.front[i].design);
  }
  EXPECT_NE(solve(doc, 2, 4).front.front().objectives, a.front.front().objectives);
}

namespace {
// Rank 0 of a pretend two-rank job, in one process: each farm runs its even tasks only and
// reports a stop (as a stopped MPI farm leaves tasks out), so the adapter takes its multi-rank
// path (results serialized, collected, broadcast) and evaluates what the farm left out.
class PretendTwoRanks : public hapsyn::LocalCluster {
 public:
  int size() const override { return 2; }
  hapsyn::FarmOutcome run_tasks(const hapsyn::TaskFarm& farm, int threads) override {
    ++farms;
    hapsyn::TaskFarm even = farm;
    even.done = [&farm](long long i) { return i % 2 == 1 || (farm.done && farm.done(i)); };
    hapsyn::FarmOutcome outcome = LocalCluster::run_tasks(even, threads);
    outcome.stopped = farm.count > 1;
    return outcome;
  }
  int farms = 0;
};
}  // namespace

TEST(Nsga2, BatchesOverRanksGiveTheSingleProcessFront) {
  const Json doc = pareto_study({{"population", 16}, {"generations", 6}});
  const auto plain = solve(doc, 2);
  hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  EXPECT_TRUE(study.solver->specs().distributed);
  EXPECT_FALSE(study.solver->specs().shardable);
  PretendTwoRanks ranks;
  hapsyn::SolverContext context;
  context.threads = 2;
  context.seed = 3;
  context.ranks = &ranks;
  const auto r = study.solver->solve(*study.problem, context);
  EXPECT_EQ(ranks.farms, 7);  // the initial population and one batch per generation
  EXPECT_EQ(r.status, plain.status);
  EXPECT_EQ(r.design_evaluations, plain.design_evaluations);
  ASSERT_EQ(r.front.size(), plain.front.size());
  for (std::size_t i = 0; i < r.front.size(); ++i) {
    EXPECT_EQ(r.front[i].objectives, plain.front[i].objectives);
    EXPECT_TRUE(r.front[i].design == plain.front[i].design);
  }
}

TEST(Nsga2, BadInputNamesThePathTheValueAndTheRule) {
  using hapsyn::test::expect_error;
  expect_error([] { solve(pareto_study({{"population", 18}}), 1); },
               {"nsga2: options.population = 18", "must be a multiple of 4"});
  Json single = pareto_study({});
  single["objectives"] = Json::array({{{"metric", "gii"}}});
  expect_error([&] { solve(single, 1); }, {"nsga2: objectives: 1 objective(s)", "at least two"});
  Json repair = pareto_study({{"sort_descending", {"l9"}}});
  expect_error([&] { solve(repair, 1); }, {"nsga2: options.sort_descending[0] = \"l9\": no such design variable"});
}

namespace {
// A log stream that requests a stop once it has received `limit` lines (nsga2 logs a line per
// generation, so the stop falls between the same generations whatever the threads).
class StopAfterLines : public std::streambuf {
 public:
  explicit StopAfterLines(int limit) : limit_(limit) {}
  std::atomic<bool> stop{false};

 protected:
  int overflow(int c) override {
    if (c == '\n' && ++lines_ >= limit_ && limit_ > 0) stop = true;
    return c;
  }

 private:
  int limit_;
  int lines_ = 0;
};

hapsyn::SolverResult solve_with(const hapsyn::Study& study, const std::string& checkpoint, bool resume,
                                int stop_after_lines) {
  StopAfterLines lines(stop_after_lines);
  std::ostream log(&lines);
  hapsyn::SolverContext context;
  context.threads = 2;
  context.seed = 3;
  context.stop = &lines.stop;
  context.log = &log;
  context.checkpoint_file = checkpoint;
  context.resume = resume;
  return study.solver->solve(*study.problem, context);
}

void expect_same_front(const hapsyn::SolverResult& a, const hapsyn::SolverResult& b) {
  ASSERT_EQ(a.front.size(), b.front.size());
  for (std::size_t i = 0; i < a.front.size(); ++i) {
    EXPECT_EQ(a.front[i].objectives, b.front[i].objectives);
    EXPECT_TRUE(a.front[i].design == b.front[i].design);
  }
}

Json read_json(const std::string& file) {
  std::ifstream in(file);
  return Json::parse(in);
}

void write_document(const std::string& file, Json document, bool rechecksum) {
  if (rechecksum) {
    document.erase("checksum");
    document["checksum"] = hapsyn::fnv1a_hex(document.dump());
  }
  std::ofstream(file) << document.dump();
}

std::string fresh_checkpoint(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("hapsyn-nsga2-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return (dir / "checkpoint.json").string();
}

// Two integer variables in 0..3 with x0 + x1 <= 0.5: (0, 0) is the one feasible design.
class OneFeasibleMechanism : public hapsyn::test::AnalyticMechanism {
 public:
  OneFeasibleMechanism() : AnalyticMechanism(2) {}
  std::vector<hapsyn::ConstraintDecl> constraints() const override { return {{"sum", ""}}; }
  void evaluate_constraints(const double* d, const hapsyn::SampleSet&, double* g) const override { g[0] = d[0] + d[1] - 0.5; }
};

std::shared_ptr<hapsyn::Problem> one_feasible_problem() {
  std::vector<hapsyn::DesignComponent> components;
  for (int i = 0; i < 2; ++i) {
    hapsyn::DesignComponent c;
    c.name = c.variable = "x" + std::to_string(i);
    c.lower = 0;
    c.upper = 3;
    c.step = 1;
    c.integer = true;
    components.push_back(c);
  }
  auto samples = std::make_shared<hapsyn::SampleSet>();
  samples->coordinates = {"s"};
  samples->poses = Eigen::MatrixXd::Zero(2, 1);
  samples->poses(1, 0) = 1.0;
  samples->cache_bounds();
  std::vector<hapsyn::MetricEntry> metrics = {
      {"f1", std::make_shared<hapsyn::test::AnalyticMetric>([](const double* x, const double* s) { return 1 - x[0] + s[0]; })},
      {"f2", std::make_shared<hapsyn::test::AnalyticMetric>([](const double* x, const double* s) { return 2 - x[1] - s[0]; })}};
  std::vector<hapsyn::Objective> objectives = {{"f1", 0, hapsyn::Sense::kMaximize, 1.0},
                                               {"f2", 1, hapsyn::Sense::kMaximize, 1.0}};
  return std::make_shared<hapsyn::Problem>("one", std::make_shared<OneFeasibleMechanism>(), samples, metrics, objectives,
                                           hapsyn::DesignSpace(components));
}
}  // namespace

TEST(Nsga2, StopMidRunCheckpointsAndResumeGivesTheUninterruptedFront) {
  for (const char* over : {"individuals", "samples"}) {
    const hapsyn::Study study = hapsyn::load_study(
        pareto_study({{"population", 16}, {"generations", 12}, {"checkpoint_every", 4}, {"parallel_over", over}}),
        hapsyn::test::registry());
    const std::string file = fresh_checkpoint("stop");
    const auto uninterrupted = solve_with(study, "", false, 0);
    ASSERT_EQ(uninterrupted.status, hapsyn::SolverStatus::kBudgetExhausted) << uninterrupted.message;
    const auto stopped = solve_with(study, file, false, 6);
    EXPECT_EQ(stopped.status, hapsyn::SolverStatus::kStopped);
    EXPECT_FALSE(stopped.front.empty());
    EXPECT_NE(stopped.message.find("stopped on request after 6 of 12 generations; front so far: "), std::string::npos)
        << stopped.message;
    EXPECT_NE(stopped.message.find("checkpoint " + file + " written, resume with --resume"), std::string::npos)
        << stopped.message;
    const Json checkpoint = read_json(file);
    EXPECT_EQ(checkpoint["solver"], "nsga2");
    EXPECT_EQ(checkpoint["state"]["generation"], 6);
    const auto resumed = solve_with(study, file, true, 0);
    ASSERT_EQ(resumed.status, hapsyn::SolverStatus::kBudgetExhausted) << resumed.message;
    expect_same_front(resumed, uninterrupted);
    std::filesystem::remove_all(std::filesystem::path(file).parent_path());
  }
}

TEST(Nsga2, DamagedEditedAndForeignCheckpointsAreRefused) {
  const Json options = {{"population", 16}, {"generations", 12}, {"checkpoint_every", 4}};
  const hapsyn::Study study = hapsyn::load_study(pareto_study(options), hapsyn::test::registry());
  const std::string file = fresh_checkpoint("bad");
  auto stop_midway = [&] {
    EXPECT_EQ(solve_with(study, file, false, 6).status, hapsyn::SolverStatus::kStopped);
    return read_json(file);
  };
  auto resume = [&] { solve_with(study, file, true, 0); };
  using hapsyn::test::expect_error;

  Json c = stop_midway();
  std::ofstream(file) << c.dump().substr(0, c.dump().size() / 2);
  expect_error(resume, {"checkpoint: " + file + ": not valid JSON (truncated or damaged); delete it, or run without --resume"});

  c = stop_midway();
  c["state"]["f"][0][0] = 99.0;
  write_document(file, c, false);
  expect_error(resume, {"checkpoint: " + file + ": damaged or edited (its checksum does not match its content)"});
  write_document(file, c, true);
  expect_error(resume, {"checkpoint: " + file + ": state.f[0]: individual 0 has fitness [",
                        "on re-evaluation, the checkpoint claims [99", "; delete it, or run without --resume"});

  c = stop_midway();
  c["state"].erase("algorithm");
  write_document(file, c, true);
  expect_error(resume, {"checkpoint: " + file + ": state: ", "algorithm"});

  c = stop_midway();
  c["state"]["x"].erase(0);
  write_document(file, c, true);
  expect_error(resume, {"checkpoint: " + file + ": state: 15 decision and 16 fitness vectors for a population of 16"});

  c = stop_midway();
  c["state"]["generation"] = "six";
  write_document(file, c, true);
  expect_error(resume, {"checkpoint: " + file + ": state: ", "type must be number"});

  c = stop_midway();
  c["solver"] = "ga";
  write_document(file, c, true);
  expect_error(resume, {"checkpoint: " + file + ": written by solver \"ga\", this study's solver is \"nsga2\""});

  (void)stop_midway();
  const hapsyn::Study other = hapsyn::load_study(pareto_study({{"population", 20}, {"generations", 12}}), hapsyn::test::registry());
  expect_error([&] { solve_with(other, file, true, 0); }, {"checkpoint: " + file + ": written for another study"});
  std::filesystem::remove_all(std::filesystem::path(file).parent_path());
}

// One feasible individual used to reach pagmo's non-dominated sorting, which wants two points
// (an internal error); now it is a front of one point.
TEST(Nsga2, OneFeasibleDesignIsAFrontOfOnePoint) {
  const auto problem = one_feasible_problem();
  const hapsyn::plugins::Nsga2Solver solver(
      hapsyn::make_options<hapsyn::plugins::Nsga2Options>({{"population", 8}, {"generations", 3}}));
  int feasible_runs = 0;
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    hapsyn::SolverContext context;
    context.seed = seed;
    const auto r = solver.solve(*problem, context);
    if (r.front.empty()) {
      EXPECT_EQ(r.status, hapsyn::SolverStatus::kInfeasible) << r.message;
      continue;
    }
    ++feasible_runs;
    EXPECT_EQ(r.status, hapsyn::SolverStatus::kBudgetExhausted) << r.message;
    ASSERT_EQ(r.front.size(), 1u);
    EXPECT_EQ(r.front[0].design, Eigen::Vector2d(0, 0));
    EXPECT_EQ(r.front[0].objectives, (std::vector<double>{1.0, 1.0}));
  }
  EXPECT_GT(feasible_runs, 10);
}

// statistics.history: one entry per generation from the initial population, evaluations rising
// to the reported count, and the last entry the final front's: its size, its ideal point and,
// with the study's reference point, its hypervolume (as indicators.hypervolume computes it).
TEST(Nsga2, HistoryEndsAtTheFinalFrontsIdealAndHypervolume) {
  const hapsyn::Study study = hapsyn::load_study(pareto_study({{"population", 16}, {"generations", 12}}),
                                                 hapsyn::test::registry());
  hapsyn::SolverContext context;
  context.threads = 2;
  context.seed = 3;
  context.reference_point = {0.0, 0.0};
  const auto r = study.solver->solve(*study.problem, context);
  ASSERT_FALSE(r.front.empty()) << r.message;
  const Json& h = r.statistics["history"];
  ASSERT_EQ(h["generation"].size(), 13u);
  EXPECT_EQ(h["generation"].front(), 0);
  for (std::size_t i = 1; i < h["evaluations"].size(); ++i) {
    EXPECT_LT(h["evaluations"][i - 1].get<long long>(), h["evaluations"][i].get<long long>()) << i;
  }
  EXPECT_EQ(h["evaluations"].back(), r.design_evaluations);
  EXPECT_EQ(h["front_size"].back(), r.front.size());
  std::vector<hapsyn::ObjectivePoint> points;
  std::vector<hapsyn::Sense> senses;
  for (std::size_t k = 0; k < study.problem->objectives().size(); ++k) {
    const hapsyn::Objective& o = study.problem->objectives()[k];
    senses.push_back(o.sense);
    double ideal = r.front.front().objectives[k];
    for (const auto& p : r.front) ideal = o.sense == hapsyn::Sense::kMinimize ? std::min(ideal, p.objectives[k]) : std::max(ideal, p.objectives[k]);
    EXPECT_EQ(h["ideal"][o.name].back(), ideal) << o.name;
  }
  for (const auto& p : r.front) points.push_back(p.objectives);
  EXPECT_EQ(h["hypervolume"].back(), hapsyn::hypervolume(points, context.reference_point, senses));
  context.reference_point.clear();  // none in the study: none made up
  EXPECT_FALSE(study.solver->solve(*study.problem, context).statistics["history"].contains("hypervolume"));
}

TEST(Nsga2, HistoryContinuesAcrossAResume) {
  const hapsyn::Study study = hapsyn::load_study(
      pareto_study({{"population", 16}, {"generations", 12}, {"checkpoint_every", 4}}), hapsyn::test::registry());
  const std::string file = fresh_checkpoint("history");
  const auto uninterrupted = solve_with(study, "", false, 0);
  EXPECT_EQ(solve_with(study, file, false, 6).status, hapsyn::SolverStatus::kStopped);
  const Json saved = read_json(file)["state"]["history"];
  EXPECT_EQ(saved["generation"].back(), 6);
  const auto resumed = solve_with(study, file, true, 0);
  Json a = resumed.statistics["history"], b = uninterrupted.statistics["history"];
  // Up to the stop, the checkpoint's entries; after it, the resumed process's (which re-evaluates
  // the population once: its counts rise by that).
  for (std::size_t g = 0; g <= 6; ++g) EXPECT_EQ(a["evaluations"][g], saved["evaluations"][g]);
  EXPECT_EQ(a["evaluations"].back(), resumed.design_evaluations);
  a.erase("evaluations");
  b.erase("evaluations");
  EXPECT_EQ(a, b);
  std::filesystem::remove_all(std::filesystem::path(file).parent_path());
}

TEST(Nsga2, RunWithPlotsWritesItsFrontAndConvergenceFigures) {
  const Json doc = Json::parse(pareto_study({{"population", 16}, {"generations", 6}}).dump());
  hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  study.resolved["output"]["plots"] = true;
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("hapsyn-nsga2-plots-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  hapsyn::RunOptions options;
  options.output_directory = dir.string();
  options.quiet = true;
  const Json result = hapsyn::run_study(study, options);
  EXPECT_TRUE(std::filesystem::exists(dir / "front.gp"));
  EXPECT_TRUE(std::filesystem::exists(dir / "convergence.gp"));
  if (!hapsyn::gnuplot_available()) GTEST_SKIP() << "gnuplot is not installed";
  EXPECT_EQ(result["files"]["front_plot"], "front.png, front.svg") << result.dump();
  EXPECT_EQ(result["files"]["convergence_plot"], "convergence.png, convergence.svg") << result.dump();
  for (const char* name : {"front", "convergence"}) {
    std::ifstream png((dir / (std::string(name) + ".png")).string(), std::ios::binary);
    std::string magic(8, '\0');
    png.read(&magic[0], 8);
    EXPECT_EQ(magic, std::string("\x89PNG\r\n\x1a\n", 8)) << name;
    EXPECT_GT(std::filesystem::file_size(dir / (std::string(name) + ".svg")), 1000u) << name;
  }
  std::filesystem::remove_all(dir);
}
