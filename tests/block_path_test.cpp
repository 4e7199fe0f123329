// The evaluator's block path (Problem::evaluate_blocks, hapsyn/accel/sample_block.hpp) against its
// per-sample path. Worst case, on the five-bar: the same status, failing sample, sample count,
// critical samples and pruning decisions for every design, threshold, subset and front, and the
// same objectives. Averaging, on the haptic 6R with coverage (scene attributes): the same status
// and sample count, reductions and objectives to 1e-12 relative.
#include <hapsyn/accel/sample_block.hpp>
#include "test_support.hpp"

#include <hapsyn/problem.hpp>
#include <hapsyn/internal/study.hpp>

#include <gtest/gtest.h>

#include "vector_targets.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

namespace {

using hapsyn::EvalOptions;
using hapsyn::EvalStatus;
using hapsyn::Evaluation;
using hapsyn::Json;
using hapsyn::Problem;

std::shared_ptr<Problem> fivebar_problem(const Json& objectives, double step = 0.005) {
  Json doc = hapsyn::test::fivebar_study();
  doc["scene"]["options"]["step"] = step;
  doc["objectives"] = objectives;
  if (objectives.size() > 1) doc["solver"] = Json{{"plugin", "nsga2"}};
  return hapsyn::load_study(doc, hapsyn::test::registry()).problem;
}

// Expects the two evaluations of one design to be the same; `what` names the case.
void expect_same(const Evaluation& block, const Evaluation& single, const std::string& what) {
  ASSERT_EQ(block.status, single.status) << what;
  EXPECT_EQ(block.samples_evaluated, single.samples_evaluated) << what;
  EXPECT_EQ(block.failed_constraint, single.failed_constraint) << what;
  EXPECT_EQ(block.failed_sample, single.failed_sample) << what;
  EXPECT_EQ(block.failed_status, single.failed_status) << what;
  if (block.status != EvalStatus::kFeasible && block.status != EvalStatus::kPruned) return;
  EXPECT_EQ(block.critical_samples, single.critical_samples) << what;
  if (block.status != EvalStatus::kFeasible) return;
  ASSERT_EQ(block.objectives.size(), single.objectives.size()) << what;
  for (std::size_t o = 0; o < single.objectives.size(); ++o) {
    EXPECT_EQ(block.objectives[o], single.objectives[o]) << what;  // bit for bit
  }
}

// Random free designs inside the study's bounds, weighted towards feasible ones (long links).
std::vector<std::vector<double>> designs(const Problem& problem, int count, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<std::vector<double>> out;
  for (int i = 0; i < count; ++i) {
    out.push_back({0.3 * u(rng), 0.05 + 0.25 * u(rng), 0.05 + 0.25 * u(rng), 0.6 * u(rng)});
  }
  (void)problem;
  return out;
}

TEST(BlockPath, FiveBarStudiesTakeIt) {
  EXPECT_TRUE(fivebar_problem(Json::array({Json{{"metric", "gii"}}}))->block_path());
  EXPECT_TRUE(fivebar_problem(Json::array({Json{{"metric", "gii"}}, Json{{"metric", "gdi"}}}))->block_path());
}

void evaluations_equal_the_per_sample_path() {
  const auto problem = fivebar_problem(Json::array({Json{{"metric", "gii"}}}));
  ASSERT_TRUE(problem->block_path());
  auto block_scratch = problem->make_eval_scratch();
  auto single_scratch = problem->make_eval_scratch();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> threshold(0.0, 0.9);
  int feasible = 0, pruned = 0, failed = 0;
  for (const std::vector<double>& x : designs(*problem, 3000, 11)) {
    for (const double below : {-std::numeric_limits<double>::infinity(), threshold(rng)}) {
      EvalOptions block, single;
      block.prune_below = single.prune_below = below;
      single.per_sample = true;
      const Evaluation b = problem->evaluate(x.data(), *block_scratch, block);
      const Evaluation& s = problem->evaluate(x.data(), *single_scratch, single);
      expect_same(b, s, "threshold " + std::to_string(below));
      if (::testing::Test::HasFatalFailure()) return;
      feasible += s.status == EvalStatus::kFeasible;
      pruned += s.status == EvalStatus::kPruned;
      failed += s.status == EvalStatus::kSampleFailed;
    }
  }
  // Each outcome happened often enough for the comparison to mean something.
  EXPECT_GT(feasible, 100);
  EXPECT_GT(pruned, 100);
  EXPECT_GT(failed, 100);
}

TEST(BlockPath, EvaluationsEqualThePerSamplePathWithAndWithoutPruning) { evaluations_equal_the_per_sample_path(); }

TEST(BlockPath, SubsetsInAnyOrderEqualThePerSamplePath) {
  const auto problem = fivebar_problem(Json::array({Json{{"metric", "gii"}}, Json{{"metric", "gdi"}}}));
  auto block_scratch = problem->make_eval_scratch();
  auto single_scratch = problem->make_eval_scratch();
  std::mt19937_64 rng(5);
  std::vector<int> all(static_cast<std::size_t>(problem->samples().size()));
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  int nonempty = 0;
  for (const std::vector<double>& x : designs(*problem, 1500, 13)) {
    std::shuffle(all.begin(), all.end(), rng);
    std::vector<int> subset(all.begin(), all.begin() + static_cast<long>(rng() % 40));
    EvalOptions block, single;
    block.subset = single.subset = &subset;
    single.per_sample = true;
    const Evaluation b = problem->evaluate(x.data(), *block_scratch, block);
    const Evaluation& s = problem->evaluate(x.data(), *single_scratch, single);
    expect_same(b, s, "subset of " + std::to_string(subset.size()));
    if (HasFatalFailure()) return;
    nonempty += !subset.empty() && s.status == EvalStatus::kFeasible;
  }
  EXPECT_GT(nonempty, 50);
}

TEST(BlockPath, ParetoPruningEqualsThePerSamplePath) {
  const auto problem = fivebar_problem(Json::array({Json{{"metric", "gii"}}, Json{{"metric", "gdi"}}}));
  auto block_scratch = problem->make_eval_scratch();
  auto single_scratch = problem->make_eval_scratch();
  // A front of two mutually non-dominated points, sorted by the first objective, descending.
  const std::vector<double> front = {0.6, 0.3, 0.4, 0.5};
  int pruned = 0;
  for (const std::vector<double>& x : designs(*problem, 2000, 17)) {
    EvalOptions block, single;
    block.prune_dominated_by = single.prune_dominated_by = &front;
    single.per_sample = true;
    const Evaluation b = problem->evaluate(x.data(), *block_scratch, block);
    const Evaluation& s = problem->evaluate(x.data(), *single_scratch, single);
    expect_same(b, s, "front");
    if (HasFatalFailure()) return;
    pruned += s.status == EvalStatus::kPruned;
  }
  EXPECT_GT(pruned, 50);
}

}  // namespace

namespace {

// Groups of up to 8 designs: one grid line (l0, l1, l2 shared, r varying: the five-bar's design
// lanes) or, every fourth group, designs that differ in l1 (evaluated one by one).
std::vector<std::vector<std::vector<double>>> design_groups(int groups, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<std::vector<std::vector<double>>> out;
  for (int g = 0; g < groups; ++g) {
    const double l0 = 0.3 * u(rng), l1 = 0.05 + 0.25 * u(rng), l2 = 0.05 + 0.25 * u(rng);
    const int count = 1 + static_cast<int>(rng() % 8);
    std::vector<std::vector<double>> group;
    for (int i = 0; i < count; ++i) {
      group.push_back({l0, g % 4 == 3 ? 0.05 + 0.25 * u(rng) : l1, l2, 0.6 * u(rng)});
    }
    out.push_back(group);
  }
  return out;
}

// `unsized_outs`: before each group, outs is the caller's vector of default evaluations (empty
// objectives and critical samples), which evaluate_designs must fill as it fills its own.
void expect_groups_equal_single_evaluations(const Problem& problem, const EvalOptions& options, int groups,
                                            unsigned seed, int& decided_in_lanes, bool unsized_outs = false) {
  auto lanes_scratch = problem.make_eval_scratch();
  auto single_scratch = problem.make_eval_scratch();
  std::vector<Evaluation> outs;
  for (const auto& group : design_groups(groups, seed)) {
    if (unsized_outs) outs.assign(hapsyn::kBlockLanes, Evaluation{});
    const double* designs[hapsyn::kBlockLanes];
    for (std::size_t i = 0; i < group.size(); ++i) designs[i] = group[i].data();
    problem.evaluate_designs(designs, static_cast<int>(group.size()), *lanes_scratch, options, outs);
    for (std::size_t i = 0; i < group.size(); ++i) {
      EvalOptions single = options;
      single.per_sample = true;
      expect_same(outs[i], problem.evaluate(group[i].data(), *single_scratch, single), "design lane " + std::to_string(i));
      if (::testing::Test::HasFatalFailure()) return;
      decided_in_lanes += outs[i].status != EvalStatus::kFeasible && outs[i].samples_evaluated > 0 &&
                          outs[i].samples_evaluated <= hapsyn::kBlockLanes;
    }
  }
}

}  // namespace

TEST(DesignLanes, GroupsOfDesignsEqualTheirSingleEvaluations) {
  const auto problem = fivebar_problem(Json::array({Json{{"metric", "gii"}}}));
  int decided = 0;
  EvalOptions plain;
  expect_groups_equal_single_evaluations(*problem, plain, 400, 21, decided);
  EvalOptions pruned;
  pruned.prune_below = 0.5;
  expect_groups_equal_single_evaluations(*problem, pruned, 400, 22, decided);
  EXPECT_GT(decided, 500);  // most designs were decided in the lanes, not by the fallback
}

TEST(DesignLanes, SubsetsAndFrontsEqualTheirSingleEvaluations) {
  const auto problem = fivebar_problem(Json::array({Json{{"metric", "gii"}}, Json{{"metric", "gdi"}}}));
  std::vector<int> subset = {0, 20, 440, 420, 220, 17, 3};  // corners first, as culling's critical samples
  EvalOptions bound;
  bound.subset = &subset;
  bound.prune_below = 1.1;  // weighted sum of GII and GDI
  int decided = 0;
  expect_groups_equal_single_evaluations(*problem, bound, 400, 23, decided);
  const std::vector<double> front = {0.6, 0.3, 0.4, 0.5};
  EvalOptions pareto;
  pareto.prune_dominated_by = &front;
  expect_groups_equal_single_evaluations(*problem, pareto, 400, 24, decided);
  EvalOptions complete;  // the designs that survive the subset are complete: their objectives are written
  complete.subset = &subset;
  int unused = 0;
  expect_groups_equal_single_evaluations(*problem, complete, 200, 26, unused, true);
  expect_groups_equal_single_evaluations(*problem, bound, 200, 27, unused, true);
  std::vector<int> none;
  EvalOptions empty;
  empty.subset = &none;
  expect_groups_equal_single_evaluations(*problem, empty, 50, 25, decided);
  EXPECT_GT(decided, 300);
}

// ---- Averaging studies: the haptic 6R with the coverage metric (scene attributes M_v, M_a).
namespace {

std::shared_ptr<Problem> coverage_problem(const Json& terms, const Json& extra_objective = Json()) {
  Json doc = Json::parse(R"({
    "name": "block-coverage",
    "mechanism": {"plugin": "haptic6r"},
    "scene": {"plugin": "human_arm", "options": {"lattice_step": 0.3, "orientations": 20, "joint3_steps": 5, "cache": false, "threads": 1}},
    "design": {"l": {"lower": [0.3, 0.3, 0.3, 0.3, 0.12], "upper": [1.0, 1.0, 1.5, 1.0, 0.3]},
               "s": {"value": [3, 3, 2, 2, 1, 1]}, "r": {"lower": 1, "upper": 6}},
    "objectives": [{"metric": "coverage"}],
    "solver": {"plugin": "ga"},
    "seed": 1
  })");
  doc["objectives"][0]["options"] = {{"terms", terms}};
  if (!extra_objective.is_null()) doc["objectives"].push_back(extra_objective);
  return hapsyn::load_study(doc, hapsyn::test::registry()).problem;
}

std::vector<double> haptic6r_design(std::mt19937_64& rng, const Problem& problem) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> x;
  for (const int index : problem.design_space().free_indices()) {
    const hapsyn::DesignComponent& c = problem.design_space().components()[static_cast<std::size_t>(index)];
    x.push_back(c.integer ? std::round(c.lower + u(rng) * (c.upper - c.lower)) : c.lower + u(rng) * (c.upper - c.lower));
  }
  return x;
}

}  // namespace

TEST(BlockPath, AveragingStudiesWithSceneAttributesTakeIt) {
  EXPECT_TRUE(coverage_problem(Json::array({"pose", "velocity", "acceleration", "force"}))->block_path());
  EXPECT_TRUE(coverage_problem(Json::array({"pose"}))->block_path());
  // One worst-case metric among averaging ones: the per-sample loop.
  EXPECT_FALSE(coverage_problem(Json::array({"pose"}), Json{{"metric", "gii"}, {"options", {{"rows", "translational"}}}})->block_path());
}

void averaging_evaluations_equal_the_per_sample_path() {
  std::mt19937_64 rng(31);
  for (const Json& terms : {Json::array({"pose", "velocity", "acceleration", "force"}), Json::array({"velocity"}),
                            Json::array({"acceleration", "force"})}) {
    const auto problem = coverage_problem(terms);
    ASSERT_TRUE(problem->block_path());
    auto block_ws = problem->make_eval_scratch(), single_ws = problem->make_eval_scratch();
    std::vector<int> subset;  // a scattered subset of odd size (a partial last block)
    for (int i = problem->samples().size() - 1; i >= 0; i -= 7) subset.push_back(i);
    int reached = 0;
    for (int k = 0; k < 12; ++k) {
      const std::vector<double> x = haptic6r_design(rng, *problem);
      const std::vector<int>* const subsets[] = {nullptr, &subset};
      for (const std::vector<int>* s : subsets) {
        EvalOptions fast, slow;
        fast.subset = slow.subset = s;
        slow.per_sample = true;
        const Evaluation block = problem->evaluate(x.data(), *block_ws, fast);
        const Evaluation single = problem->evaluate(x.data(), *single_ws, slow);
        ASSERT_EQ(block.status, single.status);
        EXPECT_EQ(block.samples_evaluated, single.samples_evaluated);
        if (single.status != EvalStatus::kFeasible) continue;
        for (std::size_t m = 0; m < single.reduced.size(); ++m) {
          for (std::size_t i = 0; i < single.reduced[m].size(); ++i) {
            EXPECT_NEAR(block.reduced[m][i], single.reduced[m][i], 1e-12 * std::max(1.0, std::abs(single.reduced[m][i])))
                << terms.dump() << ", design " << k << ", local " << i;
          }
        }
        for (std::size_t o = 0; o < single.objectives.size(); ++o) {
          EXPECT_NEAR(block.objectives[o], single.objectives[o], 1e-12 * std::max(1.0, std::abs(single.objectives[o])));
        }
        reached += single.reduced[0][1] > 0.0;
      }
    }
    EXPECT_GT(reached, 6) << "too few designs reach the workspace to test anything";
  }
}

// On every vector target this machine runs: the haptic 6R's and coverage's block kernels are
// compiled per target (hapsyn/accel/vector_dispatch.hpp), each with its own lanes type.
TEST(BlockPath, AveragingEvaluationsEqualThePerSamplePath) {
  hapsyn::testing::for_each_vector_target(averaging_evaluations_equal_the_per_sample_path);
}

// The evaluator's block copy of the scene attributes (QuantityBlock::attribute_lanes; the
// coverage test checks the kernel with and without it bit for bit) against the rows gathered
// per lane: the full order reads the copy, the same samples rotated by one (not a run of whole
// blocks) gather, and evaluate_parallel's chunks (runs of whole blocks) read the copy again.
// Two metrics list M_v in the first study (one copy serves both).
TEST(BlockPath, AttributeBlockCopiesAgreeWithTheGatheredRows) {
  const auto shared = coverage_problem(
      Json::array({"velocity"}),
      Json{{"metric", "coverage"}, {"name", "J"}, {"options", {{"terms", {"pose", "velocity", "acceleration", "force"}}}}});
  const auto separate =
      coverage_problem(Json::array({"acceleration"}), Json{{"metric", "coverage"}, {"name", "J_v"}, {"options", {{"terms", {"velocity"}}}}});
  std::mt19937_64 rng(33);
  int reached = 0;
  for (const auto& p : {shared, separate}) {
    ASSERT_TRUE(p->block_path());
    auto copy_ws = p->make_eval_scratch(), gather_ws = p->make_eval_scratch();
    std::vector<int> rotated = p->sample_order();
    std::rotate(rotated.begin(), rotated.begin() + 1, rotated.end());
    EvalOptions gathered;
    gathered.subset = &rotated;
    Problem::ParallelOptions chunked;
    chunked.chunks = 5;
    for (int k = 0; k < 8; ++k) {
      const std::vector<double> x = haptic6r_design(rng, *p);
      const Evaluation copied = p->evaluate(x.data(), *copy_ws);
      const Evaluation gather = p->evaluate(x.data(), *gather_ws, gathered);
      const Evaluation parallel = p->evaluate_parallel(x.data(), 2, chunked);
      ASSERT_EQ(copied.status, gather.status);
      ASSERT_EQ(copied.status, parallel.status);
      EXPECT_EQ(copied.samples_evaluated, gather.samples_evaluated);
      EXPECT_EQ(copied.samples_evaluated, parallel.samples_evaluated);
      if (copied.status != EvalStatus::kFeasible) continue;
      for (std::size_t m = 0; m < copied.reduced.size(); ++m) {
        for (std::size_t i = 0; i < copied.reduced[m].size(); ++i) {
          const double want = gather.reduced[m][i], tolerance = 1e-12 * std::max(1.0, std::abs(want));
          EXPECT_NEAR(copied.reduced[m][i], want, tolerance) << "design " << k << ", metric " << m << ", local " << i;
          EXPECT_NEAR(parallel.reduced[m][i], want, tolerance) << "design " << k << ", metric " << m << ", local " << i;
        }
      }
      reached += copied.reduced[0][1] > 0.0;
    }
  }
  EXPECT_GT(reached, 4) << "too few designs reach the workspace to test anything";
}
