// The ga solver and the shared pagmo adapter: known optima of small mixed-integer problems with
// the haptic 6R's constraint structure (s_i >= s_{i+1}), determinism, options errors, runs and
// clusters, multi-fidelity, and (through the hapsyn program) checkpoints, kill -9 and --resume.
#include "ga.hpp"
#include "ga_checkpoint.hpp"
#include "shared/pagmo_adapter.hpp"

#include "test_support.hpp"

#include <hapsyn/checkpoint.hpp>
#include <hapsyn/cluster.hpp>
#include <hapsyn/options.hpp>
#include <hapsyn/internal/plot.hpp>
#include <hapsyn/internal/study_runner.hpp>

#include <hapsyn/problem.hpp>

#include <pagmo/algorithms/sga.hpp>

#include <boost/filesystem.hpp>

#include <array>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <thread>
#include <sys/wait.h>
#include <unistd.h>

using hapsyn::Json;
namespace fs = boost::filesystem;
namespace pa = hapsyn::plugins::pagmo_adapter;

namespace {

// A toy mechanism with the haptic 6R's design structure: x (2 reals), s (4 integers in 1..3,
// constraint s_i >= s_{i+1}), r (2 integers in 1..6). Every sample is reachable and carries
// the design's value f in q(0):
//   f = -(x0 - 0.3)^2 - (x1 - 1.2)^2 - sum_i (s_i - t_i)^2 - |r0 - 4| - |r1 - 2|, t = (1, 3, 1, 3).
// Unconstrained, s = t; under s_i >= s_{i+1} the optimum is s = (2, 2, 2, 2) (isotonic
// regression of t), so the known optimum is x = (0.3, 1.2), s = (2, 2, 2, 2), r = (4, 2), f = -4.
class ToyModel : public hapsyn::MechanismModel {
 public:
  explicit ToyModel(const double* d) {
    const double t[4] = {1, 3, 1, 3};
    value_ = -(d[0] - 0.3) * (d[0] - 0.3) - (d[1] - 1.2) * (d[1] - 1.2) - std::abs(d[6] - 4) - std::abs(d[7] - 2);
    for (int i = 0; i < 4; ++i) value_ -= (d[2 + i] - t[i]) * (d[2 + i] - t[i]);
  }
  void solve(const double*, hapsyn::Needs, hapsyn::MechanismScratch&, hapsyn::SampleQuantities& out) const override {
    out.status = hapsyn::SampleStatus::kReachable;
    out.q.resize(1);
    out.q(0) = value_;
  }

 private:
  double value_ = 0.0;
};

class ToyMechanism : public hapsyn::Mechanism {
 public:
  std::unique_ptr<const hapsyn::MechanismModel> build(const double* design) const override {
    return std::make_unique<ToyModel>(design);
  }
  std::vector<hapsyn::VariableDecl> variables() const override {
    return {{"x", "reals", "m", 2, false, {-1.0}, {2.0}, {-10.0}, {10.0}},
            {"s", "monotone integers", "", 4, true, {1}, {3}, {1}, {3}},
            {"r", "integers", "", 2, true, {1}, {6}, {1}, {6}}};
  }
  std::vector<hapsyn::ConstraintDecl> constraints() const override {
    return {{"s1", ""}, {"s2", ""}, {"s3", ""}};
  }
  void evaluate_constraints(const double* d, const hapsyn::SampleSet&, double* g) const override {
    for (int i = 0; i < 3; ++i) g[i] = d[3 + i] - d[2 + i];
  }
};

class ValueMetric : public hapsyn::Metric {
 public:
  void local(const hapsyn::SampleQuantities& q, double* out) const override { out[0] = q.q(0); }
};

std::shared_ptr<hapsyn::Problem> toy_problem() {
  ToyMechanism mechanism;
  std::vector<hapsyn::DesignComponent> components;
  for (const hapsyn::VariableDecl& v : mechanism.variables()) {
    for (int i = 0; i < v.size; ++i) {
      hapsyn::DesignComponent c;
      c.name = v.name + "[" + std::to_string(i) + "]";
      c.variable = v.name;
      c.index = i;
      c.integer = v.integer;
      c.lower = v.default_lower[0];
      c.upper = v.default_upper[0];
      c.step = v.integer ? 1.0 : 0.0;
      components.push_back(c);
    }
  }
  auto samples = std::make_shared<hapsyn::SampleSet>();
  samples->poses = Eigen::MatrixXd::Zero(8, 1);
  for (int i = 0; i < 8; ++i) samples->poses(i, 0) = i;
  samples->coordinates = {"u"};
  std::vector<hapsyn::MetricEntry> metrics = {{"value", std::make_shared<ValueMetric>()}};
  std::vector<hapsyn::Objective> objectives = {{"f", 0, hapsyn::Sense::kMaximize, 1.0}};
  return std::make_shared<hapsyn::Problem>("toy", std::make_shared<ToyMechanism>(), samples, metrics, objectives,
                                           hapsyn::DesignSpace(components));
}

// Every option at its declared default, with `overrides` applied.
hapsyn::plugins::GaOptions ga_options(const Json& overrides) {
  return hapsyn::make_options<hapsyn::plugins::GaOptions>(overrides, "solver.options");
}

hapsyn::SolverResult solve_toy(const Json& overrides, int threads = 2, std::uint64_t seed = 11) {
  const auto problem = toy_problem();
  hapsyn::plugins::GaSolver solver(ga_options(overrides));
  solver.check(*problem);
  hapsyn::SolverContext context;
  context.threads = threads;
  context.seed = seed;
  return solver.solve(*problem, context);
}

void expect_toy_optimum(const hapsyn::SolverResult& r) {
  ASSERT_TRUE(r.best.has_value()) << r.message;
  const Eigen::VectorXd& d = r.best->design;
  EXPECT_NEAR(d[0], 0.3, 0.03);
  EXPECT_NEAR(d[1], 1.2, 0.03);
  for (int i = 2; i < 6; ++i) EXPECT_EQ(d[i], 2.0) << "s[" << i - 2 << "]";
  EXPECT_EQ(d[6], 4.0);
  EXPECT_EQ(d[7], 2.0);
  EXPECT_NEAR(r.best->score, -4.0, 2e-3);
}

using hapsyn::test::hapsyn_cli;
using hapsyn::test::Output;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("hapsyn-ga-test-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}

Json read_json(const fs::path& p) {
  std::ifstream in(p.string());
  return Json::parse(in);
}

// A run record without its evaluation counts ("designs" and the history's "evaluations"): a
// resumed process starts with an empty cache, so it evaluates again what the cache held.
Json without_counts(Json run) {
  run.erase("designs");
  if (run.contains("history")) run["history"].erase("evaluations");
  return run;
}

// A five-bar GII study for the GA (continuous design, 5 mm workspace).
Json fivebar_ga_study(const Json& options) {
  Json doc = hapsyn::test::fivebar_study("ga");
  for (const char* v : {"l0", "l1", "l2", "r"}) doc["design"][v].erase("step");
  doc["scene"]["options"]["step"] = 0.005;
  doc["solver"]["options"] = options;
  doc["seed"] = 5;
  return doc;
}

// The solver's reported best has the values of a full-scene evaluation of its design.
void expect_full_scene_values(const hapsyn::Study& study, const hapsyn::SolverResult& r) {
  ASSERT_TRUE(r.best.has_value()) << r.message;
  Eigen::VectorXd free(static_cast<Eigen::Index>(study.problem->dimension()));
  for (std::size_t k = 0; k < study.problem->dimension(); ++k) {
    free[static_cast<Eigen::Index>(k)] = r.best->design[study.problem->design_space().free_indices()[k]];
  }
  const hapsyn::Evaluation full = study.problem->evaluate_parallel(free.data(), 1);
  ASSERT_EQ(full.status, hapsyn::EvalStatus::kFeasible);
  EXPECT_DOUBLE_EQ(full.objectives[0], r.best->objectives[0]);
}

}  // namespace

TEST(PagmoAdapter, EncodingPutsIntegersLastAndRepairSortsDescending) {
  const auto problem = toy_problem();
  const pa::Encoding encoding(*problem, {"s"}, {}, "ga");
  EXPECT_EQ(encoding.size(), 8u);
  EXPECT_EQ(encoding.integer_count(), 6u);
  // pagmo order: x0 x1 | s0..s3 r0 r1 (already reals first); unsorted, non-integral s repaired.
  const std::vector<double> free = encoding.decode({0.5, 1.0, 1.2, 2.6, 1.0, 3.0, 4.4, 6.0});
  EXPECT_EQ(free, (std::vector<double>{0.5, 1.0, 3.0, 3.0, 1.0, 1.0, 4.0, 6.0}));
  std::vector<double> g(3);
  EXPECT_TRUE(problem->constraints(free.data(), g.data()));
  const pa::Encoding ascending(*problem, {}, {"s"}, "ga");
  EXPECT_EQ(ascending.decode({0.5, 1.0, 3, 1, 2, 1, 1, 1})[2], 1.0);
  EXPECT_EQ(ascending.decode({0.5, 1.0, 3, 1, 2, 1, 1, 1})[5], 3.0);
}

TEST(PagmoAdapter, InfeasibleDesignsArePenalisedAndFeasibleOnesNegated) {
  const auto problem = toy_problem();
  auto evaluator = std::make_shared<pa::Evaluator>(*problem, pa::Encoding(*problem, {}, {}, "ga"), pa::EvaluationSettings{}, false);
  const auto feasible = evaluator->fitness({0.3, 1.2, 2, 2, 2, 2, 4, 2});
  EXPECT_DOUBLE_EQ(feasible[0], 4.0);  // -score
  const auto violated = evaluator->fitness({0.3, 1.2, 1, 3, 1, 3, 4, 2});
  EXPECT_DOUBLE_EQ(violated[0], pa::kConstraintFitness + 4.0);  // 2 + 2 units of violation
  // The same phenotype again comes from the cache.
  const auto again = evaluator->batch_fitness({0.3, 1.2, 2, 2, 2, 2, 4, 2, 0.3, 1.2, 2, 2, 2, 2, 4, 2});
  EXPECT_EQ(again, (pagmo::vector_double{4.0, 4.0}));
  EXPECT_EQ(evaluator->design_evaluations(), 2);
  EXPECT_EQ(evaluator->cache_hits(), 2);
}

// A batch that mixes cached designs, designs repeated within it and genotypes that decode to one
// phenotype (integers rounded) gives, design for design, what fitness() gives one
// at a time on a fresh evaluator, and counts each distinct new phenotype as one evaluation.
TEST(PagmoAdapter, MixedBatchOfCachedRepeatedAndNewDesignsMatchesOneAtATime) {
  const auto problem = toy_problem();
  const std::vector<pagmo::vector_double> designs = {
      {0.3, 1.2, 2, 2, 2, 2, 4, 2},        // cached before the batch
      {0.1, 0.4, 3, 2, 2, 1, 1, 5},        // new
      {0.1, 0.4, 3, 2, 2, 1, 1, 5},        // repeated in the batch
      {0.1, 0.4, 2.6, 2.2, 1.9, 1, 1, 5},  // rounds to the previous phenotype
      {0.3, 1.2, 1, 3, 1, 3, 4, 2},        // new, violates a constraint
      {0.3, 1.2, 2, 2, 2, 2, 4, 2},        // cached again
      {0.0, 0.0, 1, 1, 1, 1, 6, 6},        // new
  };
  pagmo::vector_double xs;
  for (const auto& x : designs) xs.insert(xs.end(), x.begin(), x.end());
  pa::Evaluator batch(*problem, pa::Encoding(*problem, {}, {}, "ga"), pa::EvaluationSettings{2, true, 4}, false);
  (void)batch.fitness(designs[0]);
  const pagmo::vector_double got = batch.batch_fitness(xs);
  EXPECT_EQ(batch.design_evaluations(), 4);  // designs 0, 1 (with 2 and 3), 4 and 6
  EXPECT_EQ(batch.cache_hits(), 4);          // designs 0 and 5 cached, 2 and 3 repeats of 1
  pa::Evaluator single(*problem, pa::Encoding(*problem, {}, {}, "ga"), pa::EvaluationSettings{}, false);
  for (std::size_t i = 0; i < designs.size(); ++i) {
    EXPECT_EQ(got[i], single.fitness(designs[i])[0]) << "design " << i;
  }
  // The records stay reachable after the batch (the cache owns the keys now).
  EXPECT_EQ(batch.batch_fitness(xs), got);
  EXPECT_EQ(batch.design_evaluations(), 4);
}

TEST(PagmoAdapter, BatchOverIndividualsAndOverSamplesAgreeWithTheSingleEvaluation) {
  const auto problem = toy_problem();
  pagmo::vector_double xs;
  for (int i = 0; i < 10; ++i) {
    const double r0 = 1 + i % 6, r1 = 6 - i % 6;
    const pagmo::vector_double x = {0.1 * i, 0.2 * i, 3, 2, 2, 1, r0, r1};
    xs.insert(xs.end(), x.begin(), x.end());
  }
  pa::EvaluationSettings individuals{3, true, 4}, samples{3, false, 4};
  pa::Evaluator a(*problem, pa::Encoding(*problem, {}, {}, "ga"), individuals, false);
  pa::Evaluator b(*problem, pa::Encoding(*problem, {}, {}, "ga"), samples, false);
  EXPECT_EQ(a.batch_fitness(xs), b.batch_fitness(xs));
}

TEST(Ga, SgaFindsTheKnownMixedIntegerOptimumWithTheSortRepair) {
  const auto r = solve_toy({{"algorithm", "sga"}, {"population", 40}, {"generations", 300}, {"stall_generations", 60},
                            {"sort_descending", {"s"}}});
  expect_toy_optimum(r);
  EXPECT_EQ(r.statistics["repair"]["sorted_descending"][0], (Json{"s[0]", "s[1]", "s[2]", "s[3]"}));
}

TEST(Ga, GacoFindsTheKnownMixedIntegerOptimumWithTheSortRepair) {
  const auto r = solve_toy({{"algorithm", "gaco"}, {"population", 40}, {"generations", 300}, {"stall_generations", 60},
                            {"sort_descending", {"s"}}, {"gaco", {{"ker", 20}}}});
  expect_toy_optimum(r);
}

TEST(Ga, PenaltiesAloneAlsoReachTheConstrainedOptimum) {
  const auto r = solve_toy({{"algorithm", "sga"}, {"population", 60}, {"generations", 400}, {"stall_generations", 80}});
  expect_toy_optimum(r);
}

TEST(Ga, IdenticalSeedsGiveIdenticalResultsWhateverTheThreadCount) {
  const Json options = {{"algorithm", "sga"}, {"population", 20}, {"generations", 30}, {"runs", 2}};
  const auto a = solve_toy(options, 2, 99), b = solve_toy(options, 2, 99), c = solve_toy(options, 1, 99);
  ASSERT_TRUE(a.best && b.best && c.best);
  EXPECT_TRUE(a.best->design == b.best->design);
  EXPECT_EQ(a.statistics["runs"], b.statistics["runs"]);
  EXPECT_EQ(a.statistics["runs"], c.statistics["runs"]);
  const auto d = solve_toy(options, 2, 100);
  EXPECT_NE(a.statistics["runs"], d.statistics["runs"]);
  const Json gaco = {{"algorithm", "gaco"}, {"population", 20}, {"generations", 30}, {"gaco", {{"ker", 10}}}};
  EXPECT_EQ(solve_toy(gaco, 2, 5).statistics["runs"], solve_toy(gaco, 1, 5).statistics["runs"]);
}

TEST(Ga, RunsAreSummarisedAndClustered) {
  const auto r = solve_toy({{"population", 16}, {"generations", 40}, {"runs", 5}, {"sort_descending", {"s"}}});
  ASSERT_EQ(r.statistics["runs"].size(), 5u);
  ASSERT_TRUE(r.statistics.contains("clusters")) << r.statistics.dump();
  const Json& c = r.statistics["clusters"];
  EXPECT_EQ(c["variables"], (Json{"x[0]", "x[1]"}));  // the real components by default
  EXPECT_GE(c["k"].get<int>(), 1);
  int members = 0;
  for (const Json& cluster : c["clusters"]) members += cluster["size"].get<int>();
  EXPECT_EQ(members, 5);
  EXPECT_FALSE(r.statistics["report"].empty());
  // The best run is the result.
  double best = -1e300;
  for (const Json& run : r.statistics["runs"]) best = std::max(best, run["score"].get<double>());
  EXPECT_EQ(r.best->score, best);
}

TEST(Ga, OutcomesAreStatusesNotExceptions) {
  const auto budget = solve_toy({{"population", 10}, {"generations", 3}, {"stall_generations", 50}});
  EXPECT_EQ(budget.status, hapsyn::SolverStatus::kBudgetExhausted);
  EXPECT_NE(budget.message.find("generation limit (3)"), std::string::npos) << budget.message;
  const auto converged = solve_toy({{"population", 10}, {"generations", 500}, {"stall_generations", 5}});
  EXPECT_EQ(converged.status, hapsyn::SolverStatus::kConverged) << converged.message;

  const auto problem = toy_problem();
  hapsyn::plugins::GaSolver solver(ga_options({{"population", 10}}));
  std::atomic<bool> stop{true};
  hapsyn::SolverContext context;
  context.stop = &stop;
  EXPECT_EQ(solver.solve(*problem, context).status, hapsyn::SolverStatus::kStopped);
}

TEST(Ga, BadOptionsNameThePathTheValueAndTheRule) {
  using hapsyn::test::expect_error;
  expect_error([] { hapsyn::plugins::GaSolver s(ga_options({{"algorithm", "gaco"}, {"population", 10}, {"gaco", {{"ker", 30}}}})); },
               {"problem: solver.options.gaco.ker = 30", "must not exceed options.population (10)"});
  expect_error([] { hapsyn::plugins::GaSolver s(ga_options({{"population", 4}, {"sga", {{"param_s", 5}}}})); },
               {"problem: solver.options.sga.param_s = 5", "must not exceed options.population (4)"});
  expect_error([] { hapsyn::plugins::GaSolver s(ga_options({{"sga", {{"mutation", "gaussian"}, {"param_m", 5.0}}}})); },
               {"problem: solver.options.sga.param_m = 5", "[0, 1]"});
  expect_error([] { hapsyn::plugins::GaSolver s(ga_options({{"fidelity", {{"subset_fraction", 0.1}}}})); },
               {"problem: solver.options.fidelity.subset_fraction = 0.1", "needs options.fidelity.generations >= 1"});
  expect_error([] { hapsyn::plugins::GaSolver s(ga_options({{"fidelity", {{"generations", 4}}}})); },
               {"problem: solver.options.fidelity.generations = 4", "subset_fraction < 1"});
  expect_error([] { hapsyn::plugins::GaSolver s(ga_options({{"fidelity", {{"refine_fraction", 0.5}}}})); },
               {"problem: solver.options.fidelity.refine_fraction = 0.5", "needs options.fidelity.generations >= 1"});
  expect_error(
      [] {
        hapsyn::plugins::GaSolver s(
            ga_options({{"fidelity", {{"subset_fraction", 0.2}, {"generations", 3}, {"refine_fraction", 0.2}}}}));
      },
      {"problem: solver.options.fidelity.refine_fraction = 0.2", "must be greater than options.fidelity.subset_fraction (0.2)"});
  expect_error([] { hapsyn::plugins::GaSolver s(ga_options({{"fidelity", {{"final_candidates", 0}}}})); },
               {"solver.options.fidelity.final_candidates", "0"});
  const auto problem = toy_problem();
  expect_error([&] { hapsyn::plugins::GaSolver(ga_options({{"sort_descending", {"q"}}})).check(*problem); },
               {"ga: options.sort_descending[0] = \"q\": no such design variable", "x, s, r"});
  expect_error([&] { hapsyn::plugins::GaSolver(ga_options({{"cluster_variables", {"x", "y"}}})).check(*problem); },
               {"ga: options.cluster_variables[1] = \"y\": no such design variable"});
  // Through a problem file: the schema's rules, and a study without free variables.
  Json doc = hapsyn::test::fivebar_study("ga");
  doc["solver"]["options"] = {{"algorithm", "de"}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); }, {"solver.options.algorithm", "de"});
  doc = hapsyn::read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/problems/fivebar-table2-best-gii.json");
  doc["solver"] = {{"plugin", "ga"}};
  expect_error([&] { hapsyn::load_study(doc, hapsyn::test::registry()); }, {"ga: no free design variable"});
}

TEST(Ga, MultiFidelityRanksTheFinalPopulationOnTheFullScene) {
  const Json doc = fivebar_ga_study({{"population", 16}, {"generations", 12}, {"stall_generations", 50},
                                     {"fidelity", {{"subset_fraction", 0.1}, {"generations", 6}}}});
  hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  hapsyn::SolverContext context;
  context.threads = 2;
  context.seed = 3;
  const auto r = study.solver->solve(*study.problem, context);
  ASSERT_TRUE(r.best.has_value()) << r.message;
  EXPECT_EQ(r.statistics["fidelity"]["subset_samples"], 45);  // ceil(0.1 * 441)
  expect_full_scene_values(study, r);
}

TEST(Ga, RefineSubsetRunsEndWithTheirCandidatesRankedOnTheFullScene) {
  const Json doc = fivebar_ga_study(
      {{"population", 16}, {"generations", 14}, {"stall_generations", 50},
       {"fidelity", {{"subset_fraction", 0.1}, {"generations", 4}, {"refine_fraction", 0.3}, {"final_candidates", 5}}}});
  hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  std::ostringstream log;
  hapsyn::SolverContext context;
  context.threads = 2;
  context.seed = 3;
  context.log = &log;
  const auto r = study.solver->solve(*study.problem, context);
  ASSERT_TRUE(r.best.has_value()) << r.message;
  EXPECT_EQ(r.statistics["fidelity"]["refine_samples"], 133);  // ceil(0.3 * 441)
  EXPECT_EQ(r.statistics["fidelity"]["final_candidates"], 5);
  EXPECT_NE(log.str().find("re-evaluated on the refine subset (133 samples)"), std::string::npos) << log.str();
  EXPECT_NE(log.str().find("its 5 best ranked on the full scene"), std::string::npos) << log.str();
  EXPECT_NE(log.str().find("gen 6/14 (refine)"), std::string::npos) << log.str();
  // The reported values are the full scene's, not the refine subset's (an upper bound of them
  // for this worst-case metric, so a mix-up would show).
  expect_full_scene_values(study, r);
  // The run's best is the best of the candidates on the full scene (the log gives it), not the
  // refine stage's best carried over.
  const std::string ranked = "on the refine subset, ";
  const std::size_t at = log.str().find(ranked, log.str().find("its 5 best ranked"));
  ASSERT_NE(at, std::string::npos) << log.str();
  EXPECT_NEAR(std::stod(log.str().substr(at + ranked.size())), r.best->score, 1e-5) << log.str();
  // 16 initial designs at the subset, the population again at each switch, the final 5: every
  // later generation's new designs come on top.
  EXPECT_GE(r.design_evaluations, 16 + 16 + 5);
}

// Another valid value of a declared option (its schema property): another choice, another
// list, or a number moved within its bounds.
Json other_value(const Json& property) {
  const Json& def = property["default"];
  if (property.contains("enum")) {
    for (const Json& choice : property["enum"]) {
      if (choice != def) return choice;
    }
  }
  if (property["type"] == "array") return Json{"x"};
  if (property["type"] == "integer") return def.get<int>() + 1;
  double v = def.get<double>() + 0.5;
  if (property.contains("maximum") && v > property["maximum"].get<double>()) {
    const double maximum = property["maximum"];
    v = maximum != def.get<double>() ? maximum : maximum / 2;
  }
  return v;
}

// The checkpoint's study fingerprint covers every declared option: another value of any one
// of them gives another fingerprint, so a checkpoint is never resumed under other options.
TEST(Ga, CheckpointFingerprintChangesWithEveryOption) {
  const auto problem = toy_problem();
  const std::string reference = hapsyn::study_fingerprint(*problem, hapsyn::options_to_json(ga_options({})));
  const auto fingerprint = [&](const Json& o) { return hapsyn::study_fingerprint(*problem, hapsyn::options_to_json(ga_options(o))); };
  // A declared rule ties these options to others: each is changed between two option sets that
  // keep the rules and differ in it alone.
  const Json fidelity = {{"subset_fraction", 0.5}, {"generations", 1}, {"refine_fraction", 0.75}};
  const auto with = [](Json base, const std::string& key, const Json& value) {
    base[key] = value;
    return base;
  };
  const std::map<std::string, std::pair<Json, Json>> tied = {
      {"fidelity.subset_fraction", {{{"fidelity", fidelity}}, {{"fidelity", with(fidelity, "subset_fraction", 0.25)}}}},
      {"fidelity.generations", {{{"fidelity", fidelity}}, {{"fidelity", with(fidelity, "generations", 2)}}}},
      {"fidelity.refine_fraction", {{{"fidelity", fidelity}}, {{"fidelity", with(fidelity, "refine_fraction", 1.0)}}}},
      {"sga.mutation",
       {{{"sga", {{"mutation", "gaussian"}, {"param_m", 0.5}}}}, {{"sga", {{"mutation", "uniform"}, {"param_m", 0.5}}}}}}};
  int options_changed = 0;
  std::function<void(const Json&, const std::vector<std::string>&)> visit = [&](const Json& schema,
                                                                                 const std::vector<std::string>& path) {
    for (const auto& [name, property] : schema["properties"].items()) {
      std::vector<std::string> at = path;
      at.push_back(name);
      if (property["type"] == "object") {
        visit(property, at);
        continue;
      }
      std::string key;
      for (const std::string& part : at) key += (key.empty() ? "" : ".") + part;
      if (const auto it = tied.find(key); it != tied.end()) {
        EXPECT_NE(fingerprint(it->second.first), fingerprint(it->second.second)) << key;
        ++options_changed;
        continue;
      }
      Json overrides = Json::object();
      Json* target = &overrides;
      for (std::size_t i = 0; i + 1 < at.size(); ++i) target = &(*target)[at[i]];
      (*target)[at.back()] = other_value(property);
      EXPECT_NE(hapsyn::study_fingerprint(*problem, hapsyn::options_to_json(ga_options(overrides))), reference)
          << overrides.dump();
      ++options_changed;
    }
  };
  visit(hapsyn::options_schema<hapsyn::plugins::GaOptions>(), {});
  EXPECT_EQ(options_changed, 33);
}

TEST(GaCli, FinishedStudyIsNotOverwrittenWithoutForce) {
  const fs::path out = fresh_dir("force");
  const std::string run = "run " + std::string(HAPSYN_SOURCE_DIR) + "/problems/fivebar-table2-best-gii.json --quiet --out " + out.string();
  ASSERT_EQ(hapsyn_cli(run).code, 0);
  const Output again = hapsyn_cli(run);
  EXPECT_EQ(again.code, 1);
  EXPECT_NE(again.out.find("already holds a finished study"), std::string::npos) << again.out;
  EXPECT_NE(again.out.find("--force"), std::string::npos) << again.out;
  const Output resume = hapsyn_cli(run + " --resume");
  EXPECT_EQ(resume.code, 1);
  EXPECT_NE(resume.out.find("has finished; there is nothing to resume"), std::string::npos) << resume.out;
  EXPECT_EQ(hapsyn_cli(run + " --force").code, 0);
  fs::remove_all(out);
}

TEST(GaCli, BadCheckpointsAreRefusedWithTheirReason) {
  const fs::path dir = fresh_dir("badcheckpoint");
  fs::create_directories(dir / "out");
  const Json doc = fivebar_ga_study({{"population", 8}, {"generations", 3}, {"checkpoint_every", 1}});
  const fs::path file = dir / "study.json";
  std::ofstream(file.string()) << doc.dump(2);
  const std::string run = "run " + file.string() + " --quiet --threads 1 --out " + (dir / "out").string() + " --resume";
  const fs::path checkpoint = dir / "out" / "checkpoint.json";
  std::ofstream(checkpoint.string()) << "{ not json";
  Output o = hapsyn_cli(run);
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.out.find("checkpoint.json: cannot be read as a checkpoint"), std::string::npos) << o.out;
  std::ofstream(checkpoint.string()) << R"({"seed": 5, "solver": "ga", "fingerprint": "0"})";
  o = hapsyn_cli(run + " --seed 6");
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.out.find("--seed 6: the checkpoint"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("was written with seed 5"), std::string::npos) << o.out;
  o = hapsyn_cli(run);
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.out.find("checkpoint: " + checkpoint.string() + ": not a hapsyn checkpoint"), std::string::npos) << o.out;
  EXPECT_FALSE(fs::exists(dir / "out" / "result.json"));
  // No checkpoint at all: --resume starts from the beginning and says so in the log.
  fs::remove(checkpoint);
  o = hapsyn_cli(run);
  ASSERT_EQ(o.code, 0) << o.out;
  std::ifstream log((dir / "out" / "run.log").string());
  const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("no checkpoint to resume from"), std::string::npos) << text;
  fs::remove_all(dir);
}

// kill -9 during a checkpointed `hapsyn run`, then --resume: the study finishes with the result
// of an uninterrupted run with the same seed and threads.
TEST(GaCli, KilledRunResumesFromItsCheckpointAndMatchesAnUninterruptedRun) {
  const fs::path dir = fresh_dir("kill");
  fs::create_directories(dir);
  Json doc = fivebar_ga_study({{"population", 24}, {"generations", 60}, {"stall_generations", 200}, {"runs", 3},
                               {"checkpoint_every", 2}, {"parallel_over", "individuals"}});
  doc["scene"]["options"]["step"] = 0.0025;
  const fs::path file = dir / "study.json";
  std::ofstream(file.string()) << doc.dump(2);
  const std::string common = "run " + file.string() + " --threads 2 --seed 17 --quiet --out ";

  const Output reference = hapsyn_cli(common + (dir / "reference").string());
  ASSERT_EQ(reference.code, 0) << reference.out;

  const fs::path out = dir / "killed";
  const fs::path checkpoint = out / "checkpoint.json";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const std::string binary = std::string(HAPSYN_BINARY_DIR) + "/bin/hapsyn";
    const std::string file_arg = file.string(), out_arg = out.string();
    ::execl(binary.c_str(), binary.c_str(), "run", file_arg.c_str(), "--threads", "2", "--seed", "17", "--quiet", "--out",
            out_arg.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  // Wait for a checkpoint in the middle of the second run, then kill -9.
  bool mid_run = false;
  for (int i = 0; i < 3000 && !mid_run; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (!fs::exists(checkpoint)) continue;
    try {
      const Json c = read_json(checkpoint);
      mid_run = c["state"]["completed_runs"].size() >= 1 && c["state"].contains("current");
    } catch (const std::exception&) {
      ADD_FAILURE() << "a checkpoint was read half-written";
    }
  }
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(mid_run) << "no mid-run checkpoint appeared";
  ASSERT_TRUE(WIFSIGNALED(status)) << "the run finished before it was killed";
  EXPECT_FALSE(fs::exists(out / "result.json"));

  const Output resumed = hapsyn_cli(common + out.string() + " --resume");
  ASSERT_EQ(resumed.code, 0) << resumed.out;
  const Json a = read_json(dir / "reference" / "result.json"), b = read_json(out / "result.json");
  EXPECT_EQ(a["best"], b["best"]);
  // Every run's optimum and generation count repeat (evaluation counts differ: the resumed
  // process starts with an empty cache).
  Json runs_a = a["statistics"]["runs"], runs_b = b["statistics"]["runs"];
  for (Json* runs : {&runs_a, &runs_b}) {
    for (Json& run : *runs) run = without_counts(run);
  }
  EXPECT_EQ(runs_a, runs_b);
  EXPECT_FALSE(fs::exists(checkpoint)) << "the checkpoint of a finished study is removed";
  std::ifstream log((out / "run.log").string());
  const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("ga: resuming from"), std::string::npos);
  fs::remove_all(dir);
}

namespace {
// A log stream that requests a stop once it has received `limit` lines: the GA logs a line per
// generation, so the stop falls at the same generation whatever the threads.
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

// The toy GA with a checkpoint file, stopped after `stop_after_lines` log lines (0: never).
hapsyn::SolverResult solve_toy_with(const Json& overrides, const std::string& checkpoint, bool resume,
                                    int stop_after_lines) {
  const auto problem = toy_problem();
  hapsyn::plugins::GaSolver solver(ga_options(overrides));
  StopAfterLines lines(stop_after_lines);
  std::ostream log(&lines);
  hapsyn::SolverContext context;
  context.threads = 2;
  context.seed = 11;
  context.stop = &lines.stop;
  context.log = &log;
  context.checkpoint_file = checkpoint;
  context.resume = resume;
  return solver.solve(*problem, context);
}

// Run records without the evaluation counts (a resumed process starts with an empty cache).
Json runs_without_counts(Json runs) {
  for (Json& run : runs) run = without_counts(run);
  return runs;
}

void write_document(const std::string& file, Json document, bool rechecksum) {
  if (rechecksum) {
    document.erase("checksum");
    document["checksum"] = hapsyn::fnv1a_hex(document.dump());
  }
  std::ofstream(file) << document.dump();
}
}  // namespace

TEST(Ga, StopMidRunCheckpointsAndResumeGivesTheUninterruptedResult) {
  for (const char* algorithm : {"sga", "gaco"}) {
    const Json options = {{"algorithm", algorithm}, {"population", 16}, {"generations", 30}, {"runs", 2},
                          {"stall_generations", 100}, {"checkpoint_every", 7}, {"gaco", {{"ker", 8}}}};
    const fs::path dir = fresh_dir("stop");
    fs::create_directories(dir);
    const std::string file = (dir / "checkpoint.json").string();
    const auto uninterrupted = solve_toy_with(options, "", false, 0);
    ASSERT_TRUE(uninterrupted.best.has_value()) << uninterrupted.message;
    const auto stopped = solve_toy_with(options, file, false, 45);  // in the second run
    EXPECT_EQ(stopped.status, hapsyn::SolverStatus::kStopped);
    ASSERT_TRUE(stopped.best.has_value());
    EXPECT_NE(stopped.message.find(": stopped on request; best score "), std::string::npos) << stopped.message;
    EXPECT_NE(stopped.message.find("; best so far; checkpoint " + file + " written, resume with --resume"),
              std::string::npos)
        << stopped.message;
    const Json checkpoint = read_json(file);
    EXPECT_EQ(checkpoint["solver"], "ga");
    ASSERT_TRUE(checkpoint["state"].contains("current"));
    EXPECT_EQ(checkpoint["state"]["current"]["run"], 1);
    const auto resumed = solve_toy_with(options, file, true, 0);
    ASSERT_TRUE(resumed.best.has_value()) << resumed.message;
    EXPECT_EQ(resumed.status, uninterrupted.status);
    EXPECT_EQ(resumed.best->design, uninterrupted.best->design);
    EXPECT_EQ(resumed.best->score, uninterrupted.best->score);
    EXPECT_EQ(runs_without_counts(resumed.statistics["runs"]), runs_without_counts(uninterrupted.statistics["runs"]));
    fs::remove_all(dir);
  }
}

TEST(Ga, StopInTheRefineStageResumesAsTheUninterruptedRun) {
  const Json options = {{"population", 16}, {"generations", 30}, {"runs", 2}, {"stall_generations", 100},
                        {"checkpoint_every", 7},
                        {"fidelity", {{"subset_fraction", 0.25}, {"generations", 5}, {"refine_fraction", 0.5},
                                      {"final_candidates", 4}}}};
  const fs::path dir = fresh_dir("stop-refine");
  fs::create_directories(dir);
  const std::string file = (dir / "checkpoint.json").string();
  const auto uninterrupted = solve_toy_with(options, "", false, 0);
  ASSERT_TRUE(uninterrupted.best.has_value()) << uninterrupted.message;
  const auto stopped = solve_toy_with(options, file, false, 50);  // in the second run's refine stage
  EXPECT_EQ(stopped.status, hapsyn::SolverStatus::kStopped);
  const Json checkpoint = read_json(file);
  ASSERT_TRUE(checkpoint["state"].contains("current"));
  EXPECT_EQ(checkpoint["state"]["current"]["run"], 1);
  EXPECT_EQ(checkpoint["state"]["current"]["refining"], true);
  const auto resumed = solve_toy_with(options, file, true, 0);
  ASSERT_TRUE(resumed.best.has_value()) << resumed.message;
  EXPECT_EQ(resumed.best->design, uninterrupted.best->design);
  EXPECT_EQ(resumed.best->score, uninterrupted.best->score);
  EXPECT_EQ(runs_without_counts(resumed.statistics["runs"]), runs_without_counts(uninterrupted.statistics["runs"]));
  fs::remove_all(dir);
}

TEST(Ga, DamagedEditedAndForeignCheckpointsAreRefused) {
  const Json options = {{"population", 16}, {"generations", 30}, {"runs", 2}, {"stall_generations", 100},
                        {"checkpoint_every", 7}};
  const fs::path dir = fresh_dir("bad-state");
  fs::create_directories(dir);
  const std::string file = (dir / "checkpoint.json").string();
  auto stop_midway = [&] {
    EXPECT_EQ(solve_toy_with(options, file, false, 45).status, hapsyn::SolverStatus::kStopped);
    return read_json(file);
  };
  auto resume = [&] { solve_toy_with(options, file, true, 0); };
  using hapsyn::test::expect_error;

  Json c = stop_midway();
  std::ofstream(file) << c.dump().substr(0, c.dump().size() / 2);
  expect_error(resume, {"checkpoint: " + file + ": not valid JSON (truncated or damaged); delete it, or run without --resume"});

  c = stop_midway();
  c["state"]["current"]["best_score"] = 99.0;
  write_document(file, c, false);
  expect_error(resume, {"checkpoint: " + file + ": damaged or edited (its checksum does not match its content)"});
  write_document(file, c, true);
  expect_error(resume, {"checkpoint: " + file + ": state.current: its best design scores ",
                        "on re-evaluation, the checkpoint claims 99; delete it, or run without --resume"});

  c = stop_midway();
  c["state"]["completed_runs"][0]["score"] = 99.0;
  write_document(file, c, true);
  expect_error(resume, {"checkpoint: " + file + ": state.completed_runs[0]: its best design scores ",
                        "the checkpoint claims 99"});

  c = stop_midway();
  c["state"]["completed_runs"][0].erase("free");
  write_document(file, c, true);
  expect_error(resume, {"checkpoint: " + file + ": state.completed_runs[0]: ", "free"});

  c = stop_midway();
  c["state"].erase("elapsed_seconds");
  write_document(file, c, true);
  expect_error(resume, {"checkpoint: " + file + ": state: ", "elapsed_seconds", "; delete it, or run without --resume"});

  c = stop_midway();
  c["state"]["current"]["stall"] = "three";
  write_document(file, c, true);
  expect_error(resume, {"checkpoint: " + file + ": state.current: ", "type must be number"});

  c = stop_midway();
  c["state"]["current"]["algorithm"] = "22 serialization::archive 17 damaged";
  write_document(file, c, true);
  expect_error(resume, {"checkpoint: " + file + ": state.current: "});

  c = stop_midway();
  c["solver"] = "nsga2";
  write_document(file, c, true);
  expect_error(resume, {"checkpoint: " + file + ": written by solver \"nsga2\", this study's solver is \"ga\""});

  (void)stop_midway();
  Json other = options;
  other["population"] = 20;
  expect_error([&] { solve_toy_with(other, file, true, 0); }, {"checkpoint: " + file + ": written for another study"});
  fs::remove_all(dir);
}

namespace {

// Rank 0 of a pretend two-rank job, in one process: farms run every task here (or, with
// `skip_odd`, leave the odd tasks out as a stopped MPI farm does), broadcasts keep rank 0's
// bytes. The solvers take their multi-rank paths: results serialized and collected, rank 0's
// records broadcast, run tasks.
class PretendTwoRanks : public hapsyn::LocalCluster {
 public:
  explicit PretendTwoRanks(bool skip_odd = false) : skip_odd_(skip_odd) {}
  int size() const override { return 2; }
  hapsyn::FarmOutcome run_tasks(const hapsyn::TaskFarm& farm, int threads) override {
    ++farms;
    if (!skip_odd_ || farm.shardable) return LocalCluster::run_tasks(farm, threads);
    hapsyn::TaskFarm even = farm;
    even.done = [&farm](long long i) { return i % 2 == 1 || (farm.done && farm.done(i)); };
    hapsyn::FarmOutcome outcome = LocalCluster::run_tasks(even, threads);
    outcome.stopped = farm.count > 1;
    return outcome;
  }
  int farms = 0;

 private:
  bool skip_odd_;
};

hapsyn::SolverResult solve_toy_on(const Json& overrides, hapsyn::Cluster* cluster, int threads,
                                  const std::string& checkpoint = "", bool resume = false) {
  const auto problem = toy_problem();
  hapsyn::plugins::GaSolver solver(ga_options(overrides));
  solver.check(*problem);
  hapsyn::SolverContext context;
  context.threads = threads;
  context.seed = 11;
  context.ranks = cluster;
  context.checkpoint_file = checkpoint;
  context.resume = resume;
  return solver.solve(*problem, context);
}

void expect_same_result(const hapsyn::SolverResult& a, const hapsyn::SolverResult& b) {
  ASSERT_TRUE(a.best.has_value()) << a.message;
  ASSERT_TRUE(b.best.has_value()) << b.message;
  EXPECT_EQ(a.status, b.status);
  EXPECT_TRUE(a.best->design == b.best->design);
  EXPECT_EQ(a.best->score, b.best->score);
  EXPECT_EQ(a.statistics["runs"], b.statistics["runs"]);
  EXPECT_EQ(a.statistics.contains("clusters"), b.statistics.contains("clusters"));
  if (a.statistics.contains("clusters")) {
    EXPECT_EQ(a.statistics.at("clusters"), b.statistics.at("clusters"));
  }
  EXPECT_EQ(a.design_evaluations, b.design_evaluations);
}

const Json kShardOptions = {{"algorithm", "sga"}, {"population", 12}, {"generations", 12}, {"runs", 5},
                            {"stall_generations", 100}, {"sort_descending", {"s"}}};

// The checkpoint states of the shards of a `count`-way split, each run as `hapsyn run --shard`.
std::vector<Json> shard_states(const Json& options, int count, const fs::path& dir) {
  std::vector<Json> states;
  for (int i = 0; i < count; ++i) {
    hapsyn::ShardCluster shard(i, count);
    const std::string file = (dir / ("shard" + std::to_string(i) + ".json")).string();
    const auto r = solve_toy_on(options, &shard, 2, file);
    if (count > 1) {
      EXPECT_EQ(r.status, hapsyn::SolverStatus::kStopped);
      EXPECT_EQ(r.message, shard.shard_message());
    }
    states.push_back(read_json(file)["state"]);
  }
  return states;
}

}  // namespace

TEST(PagmoAdapter, PrefetchedOffspringCountAsEvaluationsNotCacheHits) {
  const auto problem = toy_problem();
  const pa::Encoding encoding(*problem, {}, {}, "ga");
  auto plain = std::make_shared<pa::Evaluator>(*problem, encoding, pa::EvaluationSettings{}, false);
  auto fetched = std::make_shared<pa::Evaluator>(*problem, encoding, pa::EvaluationSettings{2, true, 4}, false);
  const pagmo::problem p = pa::make_problem(plain), q = pa::make_problem(fetched);
  pagmo::algorithm a{pagmo::sga(1u, 0.9, 10., 0.1, 10., 2u, "sbx", "polynomial", "tournament", 7u)};
  pagmo::algorithm b = a;
  pagmo::population pa_ = pa::random_population(p, *plain, 10, 3), pb = pa::random_population(q, *fetched, 10, 3);
  for (int g = 0; g < 5; ++g) {
    pa_ = a.evolve(pa_);
    const long long before = fetched->design_evaluations();
    fetched->prefetch(b, pb);
    const long long prefetched = fetched->design_evaluations() - before;
    pb = b.evolve(pb);
    EXPECT_EQ(fetched->design_evaluations(), before + prefetched) << "evolve found every offspring in the cache";
  }
  EXPECT_EQ(pa_.get_x(), pb.get_x());
  EXPECT_EQ(pa_.get_f(), pb.get_f());
  EXPECT_EQ(plain->design_evaluations(), fetched->design_evaluations());
  EXPECT_EQ(plain->cache_hits(), fetched->cache_hits());
}

TEST(PagmoAdapter, BatchesOverRanksAndStoppedFarmsGiveTheLocalValues) {
  const auto problem = toy_problem();
  pagmo::vector_double xs;
  for (int i = 0; i < 9; ++i) {
    const pagmo::vector_double x = {0.1 * i, 0.2 * i, 3, 2, 1.0 + i % 3, 1, 1.0 + i % 6, 6.0 - i % 6};
    xs.insert(xs.end(), x.begin(), x.end());
  }
  pa::EvaluationSettings local{2, true, 4}, ranks = local, stopped = local;
  PretendTwoRanks two, half(true);
  ranks.cluster = &two;
  stopped.cluster = &half;
  pa::Evaluator a(*problem, pa::Encoding(*problem, {}, {}, "ga"), local, false);
  pa::Evaluator b(*problem, pa::Encoding(*problem, {}, {}, "ga"), ranks, false);
  pa::Evaluator c(*problem, pa::Encoding(*problem, {}, {}, "ga"), stopped, false);
  const auto f = a.batch_fitness(xs);
  EXPECT_EQ(b.batch_fitness(xs), f);
  EXPECT_EQ(c.batch_fitness(xs), f);
  EXPECT_EQ(two.farms, 1);
  EXPECT_EQ(b.design_evaluations(), a.design_evaluations());
  EXPECT_EQ(c.sample_evaluations(), a.sample_evaluations());
}

TEST(Ga, RunsAsRankTasksAndBatchesOverRanksGiveThePlainResult) {
  // The switch and the final ranking of a refine subset re-evaluate over the ranks, as the
  // generations do.
  const Json refine = {{"subset_fraction", 0.25}, {"generations", 3}, {"refine_fraction", 0.5}, {"final_candidates", 4}};
  for (const auto& [algorithm, fidelity] : {std::pair<const char*, Json>{"sga", Json::object()},
                                            {"gaco", Json::object()}, {"sga", refine}}) {
    Json options = kShardOptions;
    options["algorithm"] = algorithm;
    options["gaco"] = {{"ker", 8}};
    if (!fidelity.empty()) options["fidelity"] = fidelity;
    SCOPED_TRACE(options.dump());
    const auto plain = solve_toy_on(options, nullptr, 2);
    PretendTwoRanks farm;  // 5 runs >= 2 ranks: the runs farm
    expect_same_result(solve_toy_on(options, &farm, 2), plain);
    EXPECT_EQ(farm.farms, 1) << "one farm of runs; their batches stay on their rank";
    options["runs"] = 1;  // fewer runs than ranks: one after another, batches over the ranks
    const auto single = solve_toy_on(options, nullptr, 1);
    PretendTwoRanks batches;
    expect_same_result(solve_toy_on(options, &batches, 2), single);
    EXPECT_GT(batches.farms, 12);
  }
}

TEST(Ga, ShardsMergedAndResumedGiveThePlainResult) {
  const auto plain = solve_toy_on(kShardOptions, nullptr, 2);
  EXPECT_EQ(plain.statistics["runs"].size(), 5u);
  const auto problem = toy_problem();
  hapsyn::plugins::GaSolver solver(ga_options(kShardOptions));
  const std::string fingerprint =
      hapsyn::study_fingerprint(*problem, hapsyn::options_to_json(ga_options(kShardOptions)));
  for (int count = 1; count <= 3; ++count) {
    const fs::path dir = fresh_dir("shards" + std::to_string(count));
    fs::create_directories(dir);
    const std::vector<Json> states = shard_states(kShardOptions, count, dir);
    // Each shard holds its contiguous share of the runs.
    for (int i = 0; i < count; ++i) {
      const Json& runs = states[static_cast<std::size_t>(i)]["completed_runs"];
      ASSERT_EQ(runs.size(), static_cast<std::size_t>(5 * (i + 1) / count - 5 * i / count));
      EXPECT_EQ(runs[0]["run"], 5 * i / count);
    }
    const Json merged = solver.merge_shards(*problem, states);
    hapsyn::SolverContext context;
    context.seed = 11;
    context.checkpoint_file = (dir / "checkpoint.json").string();
    hapsyn::write_checkpoint(context, "ga", fingerprint, merged);
    const auto resumed = solve_toy_on(kShardOptions, nullptr, 1, context.checkpoint_file, true);
    expect_same_result(resumed, plain);
    EXPECT_EQ(resumed.message, plain.message);
    fs::remove_all(dir);
  }
}

TEST(Ga, MergeRefusesOverlappingMissingUnfinishedAndDamagedShards) {
  const auto problem = toy_problem();
  hapsyn::plugins::GaSolver solver(ga_options(kShardOptions));
  const fs::path dir = fresh_dir("merge");
  fs::create_directories(dir);
  const std::vector<Json> states = shard_states(kShardOptions, 2, dir);
  using hapsyn::test::expect_error;
  const auto merge = [&](const std::vector<Json>& s) { return [&solver, &problem, s] { solver.merge_shards(*problem, s); }; };
  expect_error(merge({states[0], states[1], states[1]}),
               {"merge: shards 2 and 3 both hold run 3: the shares overlap (give each shard of one job array once)"});
  expect_error(merge({states[0]}),
               {"merge: run 3 of 5 is in no shard: every shard must finish (hapsyn run --shard i/N --resume) "
                "before merging"});
  Json unfinished = states[1];
  unfinished["current"] = {{"run", 4}};
  expect_error(merge({states[0], unfinished}),
               {"merge: shard 2 of 2 has run 5 in progress: finish the shard (hapsyn run --shard i/N --resume) "
                "before merging"});
  Json outside = states[1];
  outside["completed_runs"][0]["run"] = 7;
  expect_error(merge({states[0], outside}), {"merge: shard 2 of 2: run 8 outside 1..5 (options.runs)"});
  Json damaged = states[0];
  damaged.erase("run_seconds");
  expect_error(merge({damaged, states[1]}), {"merge: shard 1 of 2: damaged ga state: ", "run_seconds"});

  // A merged state whose runs another seed made is refused on resume.
  Json foreign = solver.merge_shards(*problem, states);
  foreign["completed_runs"][1]["seed"] = 1;
  hapsyn::SolverContext context;
  context.seed = 11;
  context.checkpoint_file = (dir / "checkpoint.json").string();
  hapsyn::write_checkpoint(context, "ga", hapsyn::study_fingerprint(*problem, hapsyn::options_to_json(ga_options(kShardOptions))),
                           foreign);
  expect_error([&] { solve_toy_on(kShardOptions, nullptr, 1, context.checkpoint_file, true); },
               {"state.completed_runs[1]: seed is not the one of run 1 of the study seed"});
  fs::remove_all(dir);
}

TEST(Ga, GacoResumedAnywhereContinuesExactly) {
  // gaco's stall count compares the population's champion (the best it ever held, which gaco's
  // populations of fresh ants seldom contain): a resumed run must reach every later generation
  // in the state (the algorithm's archive and counters included) of an uninterrupted one.
  const Json options = {{"algorithm", "gaco"}, {"population", 12}, {"generations", 200}, {"stall_generations", 1000},
                        {"checkpoint_every", 1000}, {"gaco", {{"ker", 6}}}};
  const fs::path dir = fresh_dir("gaco-resume");
  fs::create_directories(dir);
  const std::string file = (dir / "checkpoint.json").string();
  const auto state_after = [&](int lines, bool resume) {
    EXPECT_EQ(solve_toy_with(options, file, resume, lines).status, hapsyn::SolverStatus::kStopped);
    return read_json(file)["state"]["current"];
  };
  int compared = 0;
  for (int first : {10, 40, 90}) {
    (void)state_after(first, false);
    const Json resumed = state_after(60, true);
    // The uninterrupted run stopped at the same generation (one log line per generation).
    const int generation = resumed["generation"].get<int>();
    for (int lines = generation - 5; lines <= generation + 5; ++lines) {
      const Json plain = state_after(lines, false);
      if (plain["generation"] != generation) continue;
      EXPECT_EQ(plain["algorithm"], resumed["algorithm"]) << "resumed after " << first << " lines";
      EXPECT_EQ(plain["x"], resumed["x"]);
      EXPECT_EQ(plain["champion_f"], resumed["champion_f"]);
      ++compared;
      break;
    }
  }
  EXPECT_EQ(compared, 3);
  fs::remove_all(dir);
}

TEST(Ga, RunStoppedInOneProcessResumesAsRankTasks) {
  // A single process stops in the middle of run 2 (a checkpoint with a run in progress); the
  // resume on two ranks runs the remaining runs as tasks and gives the uninterrupted result.
  Json options = kShardOptions;
  options["checkpoint_every"] = 3;
  const auto plain = solve_toy_on(options, nullptr, 2);
  const fs::path dir = fresh_dir("stop-then-ranks");
  fs::create_directories(dir);
  const std::string file = (dir / "checkpoint.json").string();
  EXPECT_EQ(solve_toy_with(options, file, false, 22).status, hapsyn::SolverStatus::kStopped);
  const Json state = read_json(file)["state"];
  ASSERT_TRUE(state.contains("current"));
  EXPECT_EQ(state["current"]["run"], 1);
  PretendTwoRanks ranks;
  const auto resumed = solve_toy_on(options, &ranks, 2, file, true);
  EXPECT_EQ(ranks.farms, 1);
  ASSERT_TRUE(resumed.best.has_value()) << resumed.message;
  EXPECT_EQ(resumed.status, plain.status);
  EXPECT_TRUE(resumed.best->design == plain.best->design);
  EXPECT_EQ(runs_without_counts(resumed.statistics["runs"]), runs_without_counts(plain.statistics["runs"]));
  fs::remove_all(dir);
}

namespace {

// A run's history as checked by every history test: it starts at generation 0 (the initial
// population), its generations never fall, its evaluations rise strictly and end at the run's
// count, and its last best is the run's reported score.
void expect_history_of_run(const Json& run) {
  ASSERT_TRUE(run.contains("history")) << run.dump();
  const Json& h = run["history"];
  ASSERT_GE(h["generation"].size(), 2u);
  EXPECT_EQ(h["generation"].front(), 0);
  EXPECT_EQ(h["generation"].back(), run["generations"]);
  for (std::size_t i = 1; i < h["generation"].size(); ++i) {
    EXPECT_LE(h["generation"][i - 1].get<int>(), h["generation"][i].get<int>()) << i;
    EXPECT_LT(h["evaluations"][i - 1].get<long long>(), h["evaluations"][i].get<long long>()) << i;
  }
  EXPECT_EQ(h["evaluations"].back(), run["designs"]);
  EXPECT_EQ(h["best"].back(), run["score"]);
}

}  // namespace

// sga reinserts the best of parents and offspring (pagmo's "pure elitism"), so on one fidelity
// its population's best never falls.
TEST(Ga, HistoryFollowsEveryRunAndSgasBestNeverFalls) {
  const auto r = solve_toy({{"algorithm", "sga"}, {"population", 16}, {"generations", 40}, {"runs", 3},
                            {"stall_generations", 100}});
  ASSERT_EQ(r.statistics["runs"].size(), 3u);
  for (const Json& run : r.statistics["runs"]) {
    expect_history_of_run(run);
    const Json& h = run["history"];
    EXPECT_EQ(h["generation"].size(), run["generations"].get<std::size_t>() + 1) << "one entry per generation";
    EXPECT_FALSE(h.contains("fidelity")) << "no subset, no fidelity column";
    for (std::size_t i = 1; i < h["best"].size(); ++i) {
      EXPECT_GE(h["best"][i].get<double>(), h["best"][i - 1].get<double>()) << "generation " << h["generation"][i];
      EXPECT_LE(h["mean"][i].get<double>(), h["best"][i].get<double>());
    }
  }
}

TEST(Ga, HistoryOfAMultiFidelityRunNamesItsFidelityAndEndsOnTheFullScene) {
  const Json doc = fivebar_ga_study(
      {{"population", 16}, {"generations", 14}, {"stall_generations", 50},
       {"fidelity", {{"subset_fraction", 0.1}, {"generations", 4}, {"refine_fraction", 0.3}, {"final_candidates", 5}}}});
  hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  hapsyn::SolverContext context;
  context.threads = 2;
  context.seed = 3;
  const auto r = study.solver->solve(*study.problem, context);
  const Json& run = r.statistics["runs"][0];
  expect_history_of_run(run);
  const Json& h = run["history"];
  EXPECT_EQ(h["fidelity"].front(), "subset");
  EXPECT_EQ(h["fidelity"][h["fidelity"].size() - 2], "refine");
  EXPECT_EQ(h["fidelity"].back(), "full");
  // The final ranking is an entry of the last generation, after that generation's own.
  EXPECT_EQ(h["generation"][h["generation"].size() - 2], h["generation"].back());
  EXPECT_TRUE(h["mean"].back().is_null());
}

TEST(Ga, HistoryContinuesAcrossAResume) {
  const Json options = {{"population", 16}, {"generations", 30}, {"runs", 2}, {"stall_generations", 100},
                        {"checkpoint_every", 7}};
  const fs::path dir = fresh_dir("history-resume");
  fs::create_directories(dir);
  const std::string file = (dir / "checkpoint.json").string();
  const auto uninterrupted = solve_toy_with(options, "", false, 0);
  EXPECT_EQ(solve_toy_with(options, file, false, 45).status, hapsyn::SolverStatus::kStopped);
  const Json current = read_json(file)["state"]["current"];
  ASSERT_EQ(current["run"], 1);
  const int stopped_at = current["generation"];
  EXPECT_EQ(current["history"]["generation"].back(), stopped_at);
  const auto resumed = solve_toy_with(options, file, true, 0);
  const Json& run = resumed.statistics["runs"][1];
  expect_history_of_run(run);
  // The generations before the stop are the checkpoint's, the later ones the resumed process's:
  // together those of the uninterrupted run (evaluation counts aside: a resumed process starts
  // with an empty cache).
  EXPECT_EQ(run["history"]["generation"], uninterrupted.statistics["runs"][1]["history"]["generation"]);
  EXPECT_EQ(run["history"]["best"], uninterrupted.statistics["runs"][1]["history"]["best"]);
  EXPECT_EQ(run["history"]["mean"], uninterrupted.statistics["runs"][1]["history"]["mean"]);
  for (int g = 0; g <= stopped_at; ++g) {
    EXPECT_EQ(run["history"]["evaluations"][static_cast<std::size_t>(g)],
              current["history"]["evaluations"][static_cast<std::size_t>(g)]);
  }
  fs::remove_all(dir);
}

TEST(Ga, RunWithPlotsWritesItsConvergenceFigure) {
  // Through its text, as a problem file is read (the seed an unsigned number).
  const Json doc = Json::parse(fivebar_ga_study({{"population", 12}, {"generations", 8}, {"runs", 3}}).dump());
  hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  study.resolved["output"]["plots"] = true;
  const fs::path dir = fresh_dir("convergence-plot");
  hapsyn::RunOptions options;
  options.output_directory = dir.string();
  options.quiet = true;
  const Json result = hapsyn::run_study(study, options);
  std::ifstream dat((dir / "convergence.dat").string());
  const std::string data((std::istreambuf_iterator<char>(dat)), std::istreambuf_iterator<char>());
  for (int run = 1; run <= 3; ++run) {
    EXPECT_NE(data.find("# run " + std::to_string(run) + "\n"), std::string::npos) << data;
  }
  if (!hapsyn::gnuplot_available()) GTEST_SKIP() << "gnuplot is not installed";
  EXPECT_EQ(result["files"]["convergence_plot"], "convergence.png, convergence.svg") << result.dump();
  std::ifstream png((dir / "convergence.png").string(), std::ios::binary);
  std::string magic(8, '\0');
  png.read(&magic[0], 8);
  EXPECT_EQ(magic, std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_GT(fs::file_size(dir / "convergence.svg"), 1000u);
  fs::remove_all(dir);
}
