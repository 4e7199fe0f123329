// One test row per plugin found in the build tree (TEST_P over the registry, so one bad plugin is
// one failing row): it loads; its options schema (derived from its declarations) is complete
// and is what `hapsyn describe --json` prints; it can be created with its defaults; and a study
// using it gives identical results twice under the same seed, on one and on two threads.
//
// The study for a plugin is plugins/<kind>/<name>/conformance.json when the plugin ships one
// (one convention for every kind), else the kind's default study below with the plugin
// substituted. A plugin that fits neither fails here: ship a conformance.json with it.
#include "test_support.hpp"

#include <hapsyn/accel/mechanism_acceleration.hpp>
#include <hapsyn/accel/metric_acceleration.hpp>

#include <boost/filesystem.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>

using hapsyn::Json;
namespace fs = boost::filesystem;

namespace {
Json default_study(const hapsyn::PluginRecord& plugin) {
  Json doc = Json::parse(R"({
    "name": "conformance",
    "mechanism": {"plugin": "fivebar"},
    "scene": {"plugin": "planar_square", "options": {"side": 0.1, "step": 0.01}},
    "design": {"l0": {"value": 0.0004}, "l1": {"value": 0.2997}, "l2": {"value": 0.3}, "r": {"value": 0.4196}},
    "objectives": [{"metric": "gii"}],
    "solver": {"plugin": "evaluate"},
    "seed": 7
  })");
  if (plugin.kind == "mechanism") doc["mechanism"]["plugin"] = plugin.name;
  if (plugin.kind == "scene") doc["scene"] = {{"plugin", plugin.name}};
  if (plugin.kind == "metric") doc["objectives"][0]["metric"] = plugin.name;
  if (plugin.kind == "solver") {
    doc = hapsyn::test::fivebar_study(plugin.name);
    doc["seed"] = 7;
  }
  return doc;
}

Json study_for(const hapsyn::PluginRecord& plugin) {
  for (const char* kind : {"mechanisms", "scenes", "metrics", "solvers"}) {
    const fs::path file = fs::path(HAPSYN_SOURCE_DIR) / "plugins" / kind / plugin.name / "conformance.json";
    if (fs::exists(file)) return hapsyn::read_problem_file(file.string());
  }
  return default_study(plugin);
}

// Statistics minus wall-clock durations (keys containing "seconds"): everything else must repeat.
Json without_durations(const Json& j) {
  if (j.is_array()) {
    Json out = Json::array();
    for (const Json& e : j) out.push_back(without_durations(e));
    return out;
  }
  if (!j.is_object()) return j;
  Json out = Json::object();
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (it.key().find("seconds") == std::string::npos) out[it.key()] = without_durations(it.value());
  }
  return out;
}

// One solve; with `with_statistics` the solver's message and statistics (minus durations) are
// part of the result. Pruning and culling statistics on several threads depend on timing (which
// design raised the incumbent first), so they are compared on one thread only.
Json solve_once(const Json& doc, int threads, bool with_statistics) {
  hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  hapsyn::SolverContext context;
  context.threads = threads;
  context.seed = 7;
  const hapsyn::SolverResult r = study.solver->solve(*study.problem, context);
  Json j = {{"status", hapsyn::to_string(r.status)}};
  if (with_statistics) {
    j["message"] = r.message;
    j["statistics"] = without_durations(r.statistics);
  }
  if (r.best) {
    j["best_design"] = study.problem->design_to_json(r.best->design);
    j["best_objectives"] = r.best->objectives;
  }
  for (const auto& p : r.front) j["front"].push_back(p.objectives);
  return j;
}

void check_schema_is_documented(const Json& schema, const std::string& path) {
  if (!schema.contains("properties")) return;
  std::set<std::string> required;
  if (schema.contains("required")) {
    for (const auto& r : schema["required"]) required.insert(r.get<std::string>());
  }
  for (auto it = schema["properties"].begin(); it != schema["properties"].end(); ++it) {
    const std::string p = path + "." + it.key();
    EXPECT_TRUE(it.value().contains("description")) << p << " has no description";
    EXPECT_TRUE(it.value().contains("default") || required.count(it.key())) << p << " has neither a default nor is required";
    check_schema_is_documented(it.value(), p);
  }
}
}  // namespace

std::vector<std::string> plugin_names() { return hapsyn::test::registry().known_names(); }

class Conformance : public ::testing::TestWithParam<std::string> {};

TEST_P(Conformance, LoadsWithACompleteSchema) {
  const hapsyn::PluginRecord& plugin = hapsyn::test::registry().find(GetParam());
  EXPECT_EQ(plugin.name, GetParam());
  EXPECT_TRUE(plugin.schema.contains("description")) << "the declarations have no describe(...) text";
  check_schema_is_documented(plugin.schema, plugin.name);
}

TEST_P(Conformance, DescribePrintsTheDeclaredSchema) {
  const hapsyn::PluginRecord& plugin = hapsyn::test::registry().find(GetParam());
  const auto json = hapsyn::test::hapsyn_cli("describe " + GetParam() + " --json");
  ASSERT_EQ(json.code, 0) << json.out;
  EXPECT_EQ(Json::parse(json.out), plugin.schema);
  const auto text = hapsyn::test::hapsyn_cli("describe " + GetParam());
  ASSERT_EQ(text.code, 0) << text.out;
  for (auto it = plugin.schema["properties"].begin(); it != plugin.schema["properties"].end(); ++it) {
    EXPECT_NE(text.out.find(it.key()), std::string::npos) << it.key() << " missing from:\n" << text.out;
    EXPECT_NE(text.out.find(it.value()["default"].dump()), std::string::npos)
        << it.key() << "'s default missing from:\n" << text.out;
  }
}

TEST_P(Conformance, CreatedWithDefaultsAndDeterministic) {
  const hapsyn::PluginRecord& plugin = hapsyn::test::registry().find(GetParam());
  const Json doc = study_for(plugin);
  Json first, second;
  ASSERT_NO_THROW(first = solve_once(doc, 1, true)) << "no conformance study fits; ship plugins/<kind>/"
                                                     << plugin.name << "/conformance.json";
  second = solve_once(doc, 1, true);
  EXPECT_EQ(first, second);
  // Two threads: the same result (statistics aside), and the same as on one thread.
  const Json parallel = solve_once(doc, 2, false);
  EXPECT_EQ(parallel, solve_once(doc, 2, false));
  // Across thread counts only the summation order of averaging metrics may differ (last bits).
  EXPECT_EQ(parallel["status"], first["status"]);
  EXPECT_EQ(parallel.value("best_design", Json()), first.value("best_design", Json()));
  if (first.contains("best_objectives")) {
    for (std::size_t i = 0; i < first["best_objectives"].size(); ++i) {
      const double a = first["best_objectives"][i], b = parallel["best_objectives"][i];
      EXPECT_NEAR(a, b, 1e-12 * std::max(1.0, std::abs(a)));
    }
  }
  EXPECT_TRUE(first.contains("best_design") || first.contains("front")) << first.dump();
}

// A study on the block path (docs/design.md sections 13 and 14) must give what the per-sample
// loop gives (the same statuses, sample counts and critical samples; objectives to 1e-12
// relative): the plugin's block kernels (solve_block, local_block, solve_designs) against its
// plain ones, at points spread over the free design box.
TEST_P(Conformance, BlockPathsEqualThePerSampleLoop) {
  const hapsyn::PluginRecord& plugin = hapsyn::test::registry().find(GetParam());
  const hapsyn::Study study = hapsyn::load_study(study_for(plugin), hapsyn::test::registry());
  const hapsyn::Problem& problem = *study.problem;
  if (!problem.block_path()) return;  // nothing but the per-sample loop to run
  const hapsyn::DesignSpace& space = problem.design_space();
  const std::size_t n = space.free_size();
  std::vector<std::vector<double>> designs;
  for (int k = 0; k < 24; ++k) {
    std::vector<double> x(n);
    for (std::size_t i = 0; i < n; ++i) {
      const hapsyn::DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[i])];
      const double t = std::fmod(0.137 * (k + 1) * (i + 3), 1.0);
      x[i] = c.lower + t * (c.upper - c.lower);
    }
    designs.push_back(x);
  }
  auto fast = problem.make_eval_scratch(), plain = problem.make_eval_scratch();
  std::vector<hapsyn::Evaluation> group;
  const double* pointers[hapsyn::kBlockLanes];
  for (std::size_t first = 0; first < designs.size(); first += hapsyn::kBlockLanes) {
    const int count = static_cast<int>(std::min<std::size_t>(hapsyn::kBlockLanes, designs.size() - first));
    for (int i = 0; i < count; ++i) pointers[i] = designs[first + static_cast<std::size_t>(i)].data();
    problem.evaluate_designs(pointers, count, *fast, hapsyn::EvalOptions{}, group);
    for (int i = 0; i < count; ++i) {
      hapsyn::EvalOptions single;
      single.per_sample = true;
      const hapsyn::Evaluation expected = problem.evaluate(pointers[i], *plain, single);
      const hapsyn::Evaluation block = problem.evaluate(pointers[i], *fast);
      const hapsyn::Evaluation* both[] = {&block, &group[static_cast<std::size_t>(i)]};
      for (const hapsyn::Evaluation* e : both) {
        EXPECT_EQ(e->status, expected.status);
        EXPECT_EQ(e->samples_evaluated, expected.samples_evaluated);
        EXPECT_EQ(e->failed_sample, expected.failed_sample);
        if (expected.status == hapsyn::EvalStatus::kFeasible) {
          // The block kernels' contract: local values to 1e-12 relative (the five-bar's are bit
          // for bit, block_path_test checks that).
          for (std::size_t o = 0; o < expected.objectives.size(); ++o) {
            EXPECT_NEAR(e->objectives[o], expected.objectives[o], 1e-12 * std::max(1.0, std::abs(expected.objectives[o])));
          }
          EXPECT_EQ(e->critical_samples, expected.critical_samples);
        }
      }
    }
  }
}

// MechanismAcceleration::reachable_interval, where a mechanism has one, never leaves out a value at which
// the sample solves: the grid solvers rule whole runs of designs out on it. Each component of
// the study's design is scanned over the interval and as far again on either side, at the
// study's first samples.
TEST_P(Conformance, ReachableIntervalsHoldEverySolvedValue) {
  const hapsyn::PluginRecord& plugin = hapsyn::test::registry().find(GetParam());
  const hapsyn::Study study = hapsyn::load_study(study_for(plugin), hapsyn::test::registry());
  const hapsyn::Problem& problem = *study.problem;
  const hapsyn::Mechanism& mechanism = problem.mechanism();
  const hapsyn::MechanismAcceleration& accel = problem.mechanism_acceleration();
  const hapsyn::DesignSpace& space = problem.design_space();
  std::vector<double> design(space.size());
  for (std::size_t c = 0; c < space.size(); ++c) {
    const hapsyn::DesignComponent& component = space.components()[c];
    design[c] = 0.5 * (component.lower + component.upper);
  }
  auto scratch = mechanism.make_scratch();
  hapsyn::SampleQuantities q;
  const std::size_t samples = std::min<std::size_t>(12, problem.sample_order().size());
  for (std::size_t c = 0; c < space.size(); ++c) {
    for (std::size_t k = 0; k < samples; ++k) {
      const double* pose = problem.samples().pose(problem.sample_order()[k]);
      double lower = 0.0, upper = 0.0;
      if (!accel.reachable_interval(design.data(), static_cast<int>(c), pose, lower, upper)) continue;
      const double centre = lower <= upper ? 0.5 * (lower + upper) : design[c];
      const double half = lower <= upper ? std::max(0.5 * (upper - lower), 1e-3) : 1.0;
      std::vector<double> x = design;
      for (int i = 0; i <= 300; ++i) {
        x[c] = centre + 3.0 * half * (i / 150.0 - 1.0);
        std::unique_ptr<const hapsyn::MechanismModel> model;
        try {
          model = mechanism.build(x.data());
        } catch (const hapsyn::Error&) {
          continue;  // a value the mechanism refuses (outside its hard limits)
        }
        q.sample = problem.sample_order()[k];
        model->solve(pose, problem.needs(), *scratch, q);
        if (q.status != hapsyn::SampleStatus::kReachable) continue;
        EXPECT_TRUE(x[c] >= lower && x[c] <= upper)
            << space.components()[c].name << " = " << x[c] << " solves sample " << problem.sample_order()[k]
            << " outside the reachable interval [" << lower << ", " << upper << "]";
      }
    }
  }
}

// MetricAcceleration::combine_block, where a metric has it, is combine() per lane bit for bit (the design
// lanes' pruning decisions rest on it), also for reductions at their identities, zero and
// negative values.
TEST_P(Conformance, CombineBlockEqualsCombinePerLane) {
  const hapsyn::PluginRecord& plugin = hapsyn::test::registry().find(GetParam());
  const hapsyn::Study study = hapsyn::load_study(study_for(plugin), hapsyn::test::registry());
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> uniform(-2.0, 3.0);
  const double specials[] = {0.0, -0.0, 1.0, std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity(), 1e-300, 1e300};
  for (const hapsyn::MetricEntry& entry : study.problem->metrics()) {
    const std::size_t k = entry.metric->locals().size();
    std::vector<double> reduced(k * hapsyn::kBlockLanes), lane(k);
    double combined[hapsyn::kBlockLanes];
    for (int round = 0; round < 200; ++round) {
      for (std::size_t j = 0; j < reduced.size(); ++j) {
        reduced[j] = (round + j) % 3 == 0 ? specials[(static_cast<std::size_t>(round) + j) % 7] : uniform(random);
      }
      const hapsyn::MetricAcceleration* accel = entry.metric->acceleration();
      if (accel == nullptr || !accel->combine_block(reduced.data(), 5, combined)) break;  // not implemented: nothing to check
      for (int i = 0; i < hapsyn::kBlockLanes; ++i) {
        for (std::size_t j = 0; j < k; ++j) lane[j] = reduced[j * hapsyn::kBlockLanes + static_cast<std::size_t>(i)];
        const double expected = entry.metric->combine(lane.data(), 5);
        EXPECT_EQ(std::memcmp(&combined[i], &expected, sizeof expected), 0)
            << entry.plugin << " lane " << i << ": combine_block " << combined[i] << ", combine " << expected;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Registry, Conformance, ::testing::ValuesIn(plugin_names()),
                         [](const ::testing::TestParamInfo<std::string>& row) { return row.param; });

TEST(Conformance, RegistryFindsEveryInTreePlugin) {
  std::vector<std::string> errors;
  const auto plugins = hapsyn::test::registry().list(&errors);
  EXPECT_TRUE(errors.empty()) << errors.front();
  EXPECT_GE(plugins.size(), 15u);
}
