// Declared cross-field rules of an options struct: schema, messages, order.
#include "test_support.hpp"

#include <hapsyn/options.hpp>
#include <hapsyn/schema.hpp>

#include <cstdint>
#include <cstdlib>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using hapsyn::Json;
using hapsyn::test::expect_error;

struct Range {
  double lower{};
  double upper{};
  static void declare(hapsyn::OptionDeclarations<Range>& d) {
    d.add(&Range::lower, "lower", 0.0, "lower end");
    d.add(&Range::upper, "upper", 1.0, "upper end");
    d.rule({"lower", "upper"}, "lower < upper", [](const Range& r) { return r.lower < r.upper; });
  }
};

struct Grid {
  double side{};
  double step{};
  std::vector<double> steps;
  Range range;
  static void declare(hapsyn::OptionDeclarations<Grid>& d) {
    d.add(&Grid::side, "side", 1.0, "side");
    d.add(&Grid::step, "step", 0.5, "step");
    d.add(&Grid::steps, "steps", {0.5, 0.5}, "steps per axis");
    d.add(&Grid::range, "range", "a range");
    d.rule({"step", "side"}, "step <= side", [](const Grid& g) -> std::string {
      return g.step <= g.side ? "" : "must be <= side (" + Json(g.side).dump() + ")";
    });
    d.rule({"steps", "side"}, "every step <= side", [](const Grid& g) -> std::string {
      for (std::size_t i = 0; i < g.steps.size(); ++i) {
        if (g.steps[i] > g.side) return "[" + std::to_string(i) + "] = " + Json(g.steps[i]).dump() + ": must be <= side";
      }
      return "";
    });
    d.rule({"range.upper", "side"}, "range.upper <= side", [](const Grid& g) { return g.range.upper <= g.side; });
  }
};

TEST(Options, RulesAppearInTheSchemaNextToTheirFields) {
  const Json schema = hapsyn::options_schema<Grid>();
  ASSERT_TRUE(schema.contains("x-rules"));
  EXPECT_EQ(schema["x-rules"][0], (Json{{"fields", {"step", "side"}}, {"rule", "step <= side"}}));
  EXPECT_EQ(schema["x-rules"].size(), 3u);
  EXPECT_EQ(schema["properties"]["range"]["x-rules"][0]["rule"], "lower < upper");
  EXPECT_NO_THROW(hapsyn::check_schema(schema, "test"));
  EXPECT_FALSE(hapsyn::options_schema<hapsyn::NoOptions>().contains("x-rules"));
}

TEST(Options, KeptRulesLetTheOptionsThrough) {
  const Grid g = hapsyn::make_options<Grid>(Json{{"side", 2.0}, {"step", 2.0}, {"range", {{"upper", 2.0}}}});
  EXPECT_EQ(g.step, 2.0);
  EXPECT_EQ(g.range.upper, 2.0);
}

TEST(Options, BrokenRuleReturningTextNamesPathValueAndRule) {
  expect_error([] { hapsyn::make_options<Grid>(Json{{"step", 1.5}}); },
               {"problem: options.step = 1.5: must be <= side (1.0)"});
  expect_error([] { hapsyn::make_options<Grid>(Json{{"step", 1.5}}, "scene.options"); },
               {"problem: scene.options.step = 1.5: must be <= side (1.0)"});
}

TEST(Options, BrokenRuleNamingAnElementPutsItInThePath) {
  expect_error([] { hapsyn::make_options<Grid>(Json{{"steps", {0.5, 3.0}}}); },
               {"problem: options.steps[1] = 3.0: must be <= side"});
}

TEST(Options, BrokenPredicateRuleNamesEveryFieldItsValueAndTheRule) {
  expect_error([] { hapsyn::make_options<Grid>(Json{{"range", {{"upper", 2.0}}}}); },
               {"problem: options.range.upper = 2.0: must satisfy range.upper <= side (side = 1.0)"});
}

TEST(Options, RulesOfAGroupNameTheGroupsPath) {
  expect_error([] { hapsyn::make_options<Grid>(Json{{"range", {{"lower", 1.0}, {"upper", 0.5}}}}); },
               {"problem: options.range.lower = 1.0: must satisfy lower < upper (upper = 0.5)"});
}

TEST(Options, InAStudyTheMessageIsThePluginsAsItsConstructorWouldSay) {
  hapsyn::PluginArguments arguments;
  arguments.plugin = "grid_scene";
  arguments.json_path = "scene.options";
  Json resolved = hapsyn::validate_and_fill(hapsyn::options_schema<Grid>(), Json{{"step", 1.5}}, "scene.options");
  expect_error([&] { hapsyn::OptionDeclarations<Grid>::fill(resolved, arguments); },
               {"grid_scene: options.step = 1.5: must be <= side (1.0)"});
}

struct Misspelt {
  double a{};
  static void declare(hapsyn::OptionDeclarations<Misspelt>& d) {
    d.add(&Misspelt::a, "a", 0.0, "a");
    d.rule({"a", "b"}, "a < b", [](const Misspelt&) { return true; });
  }
};

TEST(Options, RuleNamingAnUndeclaredFieldIsRefusedWhenTheSchemaIsMade) {
  try {
    hapsyn::options_schema<Misspelt>();
    ADD_FAILURE() << "expected std::logic_error";
  } catch (const std::logic_error& e) {
    EXPECT_STREQ(e.what(), "options rule 'a < b': names 'b', which is not a declared option");
  }
}

TEST(Options, MalformedRulesInASchemaAreRefused) {
  const Json schema = {{"type", "object"}, {"x-rules", {{{"fields", Json::array()}, {"rule", "x"}}}}};
  expect_error([&] { hapsyn::check_schema(schema, "test"); },
               {"schema: test: x-rules = [{\"fields\":[],\"rule\":\"x\"}]: must be an array of {\"fields\": [...], \"rule\": TEXT}"});
}

// The kinds of option a problem file's own schema needs, declared as a plugin would.
struct Stage {
  std::string kind;
  double share{};
  static void declare(hapsyn::OptionDeclarations<Stage>& d) {
    d.add(&Stage::kind, "kind", {}, "what the stage does").required().one_of({"coarse", "fine"});
    d.add(&Stage::share, "share", 0.5, "share of the budget").range(0, 1);
    d.rule({"share"}, "share > 0 for a fine stage", [](const Stage& s) { return s.kind != "fine" || s.share > 0; });
  }
};

// An optional group: none of its options has a default.
struct Limits {
  std::optional<double> low;
  double high{};
  static void declare(hapsyn::OptionDeclarations<Limits>& d) {
    d.add(&Limits::low, "low", "low end (default: none)");
    d.add(&Limits::high, "high", {}, "high end").required();
  }
};

struct Plan {
  std::string solver;
  Range range;
  std::vector<Stage> stages;
  Json extra;
  std::optional<std::string> label;
  std::optional<int> budget;
  std::optional<Limits> limits;
  std::optional<std::vector<double>> point;
  std::uint64_t seed{};
  std::optional<std::uint64_t> salt;
  static void declare(hapsyn::OptionDeclarations<Plan>& d) {
    d.add(&Plan::solver, "solver", {}, "the solver's name").required();
    d.add(&Plan::range, "range", "a range").required();
    d.add(&Plan::stages, "stages", "the stages, in order").min_size(1).required();
    d.add(&Plan::extra, "extra", "anything");
    d.add(&Plan::label, "label", "a label (default: none)");
    d.add(&Plan::budget, "budget", "evaluations (default: unlimited)").range(1, 1000);
    d.add(&Plan::limits, "limits", "limits (default: none)");
    d.add(&Plan::point, "point", "a point (default: none)");
    d.add(&Plan::seed, "seed", 7, "a seed");
    d.add(&Plan::salt, "salt", "a salt (default: none)");
    d.rule({"label", "solver"}, "label differs from solver",
           [](const Plan& p) { return !p.label || *p.label != p.solver; });
  }
};

// The smallest Plan a file may give.
Json minimal_plan() {
  return Json{{"solver", "ga"}, {"range", Json::object()}, {"stages", Json::array({Json{{"kind", "coarse"}}})}};
}

TEST(Options, RequiredKeysAreListedWithoutADefault) {
  const Json schema = hapsyn::options_schema<Plan>();
  EXPECT_EQ(schema["required"], (Json{"solver", "range", "stages"}));
  EXPECT_FALSE(schema["properties"]["solver"].contains("default"));
  EXPECT_FALSE(schema["properties"]["range"].contains("default"));
  EXPECT_FALSE(schema["properties"]["stages"].contains("default"));
  EXPECT_EQ(schema["properties"]["stages"]["items"]["required"], (Json{"kind"}));
  EXPECT_NO_THROW(hapsyn::check_schema(schema, "test"));
}

TEST(Options, MissingRequiredKeyNamesItsPath) {
  for (const char* key : {"solver", "range", "stages"}) {
    Json options = minimal_plan();
    options.erase(key);
    expect_error([&] { hapsyn::make_options<Plan>(options, "solver.options"); },
                 {"problem: solver.options." + std::string(key) + ": required key is missing"});
  }
  Json options = minimal_plan();
  options["stages"].push_back(Json{{"share", 0.1}});
  expect_error([&] { hapsyn::make_options<Plan>(options); }, {"problem: options.stages[1].kind: required key is missing"});
}

TEST(Options, OptionalKeyLeftOutStaysAbsent) {
  const Json resolved = hapsyn::validate_and_fill(hapsyn::options_schema<Plan>(), minimal_plan(), "options");
  for (const char* key : {"label", "budget", "limits", "point", "salt"}) EXPECT_FALSE(resolved.contains(key)) << key;
  EXPECT_EQ(resolved["seed"], 7);
  EXPECT_EQ(resolved["extra"], Json::object());
  const Plan plan = hapsyn::make_options<Plan>(minimal_plan());
  EXPECT_FALSE(plan.label || plan.budget || plan.limits || plan.point || plan.salt);
  const Json values = hapsyn::options_to_json(plan);
  for (const char* key : {"label", "budget", "limits", "point", "salt"}) EXPECT_FALSE(values.contains(key)) << key;
  EXPECT_EQ(values["stages"], (Json::array({Json{{"kind", "coarse"}, {"share", 0.5}}})));
}

TEST(Options, OptionalKeyGivenIsValidatedAndFilled) {
  Json options = minimal_plan();
  options["label"] = "first";
  options["budget"] = 10.0;
  options["limits"] = {{"high", 2.0}};
  options["point"] = {1.0, 2.0};
  const Plan plan = hapsyn::make_options<Plan>(options);
  EXPECT_EQ(plan.label, std::optional<std::string>("first"));
  EXPECT_EQ(plan.budget, std::optional<int>(10));
  ASSERT_TRUE(plan.limits.has_value());
  EXPECT_FALSE(plan.limits->low.has_value());
  EXPECT_EQ(plan.limits->high, 2.0);
  EXPECT_EQ(plan.point, std::optional<std::vector<double>>({1.0, 2.0}));
  EXPECT_EQ(hapsyn::options_to_json(plan)["limits"], (Json{{"high", 2.0}}));
  options["limits"] = Json::object();
  expect_error([&] { hapsyn::make_options<Plan>(options); }, {"problem: options.limits.high: required key is missing"});
  options["limits"] = {{"high", 2.0}};
  options["budget"] = 0;
  expect_error([&] { hapsyn::make_options<Plan>(options); }, {"problem: options.budget = 0: must be >= 1"});
  options["budget"] = 1;
  options["label"] = 3;
  expect_error([&] { hapsyn::make_options<Plan>(options); }, {"problem: options.label = 3: must be a string"});
}

struct Defaults {
  double x{};
  static void declare(hapsyn::OptionDeclarations<Defaults>& d) { d.add(&Defaults::x, "x", 1.0, "x"); }
};

struct OptionalDefaults {
  std::optional<Defaults> d;
  static void declare(hapsyn::OptionDeclarations<OptionalDefaults>& d) { d.add(&OptionalDefaults::d, "d", "d"); }
};

TEST(Options, OptionalGroupWithDefaultsIsRefusedWhenTheSchemaIsMade) {
  try {
    hapsyn::options_schema<OptionalDefaults>();
    ADD_FAILURE() << "expected std::logic_error";
  } catch (const std::logic_error& e) {
    EXPECT_STREQ(e.what(),
                 "optional group 'd': its options 'x' have defaults, which would fill it when left out; declare it as "
                 "a group (default {}) or give its options no defaults (required() or std::optional)");
  }
}

TEST(Options, RulesMayNameOptionalKeysAndAnUnsetOneReadsNull) {
  Json options = minimal_plan();
  options["label"] = "ga";
  expect_error([&] { hapsyn::make_options<Plan>(options); },
               {"problem: options.label = \"ga\": must satisfy label differs from solver (solver = \"ga\")"});
  EXPECT_EQ(hapsyn::detail::value_at(Json{{"a", 1}}, "b"), Json());
  EXPECT_EQ(hapsyn::detail::value_at(Json{{"a", 1}}, "a.b"), Json());
}

TEST(Options, FreeFormJsonKeepsAnyObject) {
  Json options = minimal_plan();
  options["extra"] = {{"anything", {1, "two", Json::object()}}};
  EXPECT_EQ(hapsyn::make_options<Plan>(options).extra, options["extra"]);
  options["extra"] = Json::array();
  expect_error([&] { hapsyn::make_options<Plan>(options); }, {"problem: options.extra = []: must be an object"});
}

TEST(Options, ListOfGroupsFillsEachElementAndNamesItsIndex) {
  Json options = minimal_plan();
  options["stages"].push_back(Json{{"kind", "fine"}, {"share", 0.25}});
  const Plan plan = hapsyn::make_options<Plan>(options);
  ASSERT_EQ(plan.stages.size(), 2u);
  EXPECT_EQ(plan.stages[0].share, 0.5);
  EXPECT_EQ(plan.stages[1].kind, "fine");
  EXPECT_EQ(plan.stages[1].share, 0.25);
  options["stages"][1]["kind"] = "medium";
  expect_error([&] { hapsyn::make_options<Plan>(options); },
               {"problem: options.stages[1].kind = \"medium\": must be one of \"coarse\", \"fine\""});
  options["stages"][1] = Json{{"kind", "fine"}, {"shares", 1}};
  expect_error([&] { hapsyn::make_options<Plan>(options); },
               {"problem: options.stages[1].shares: unknown key (did you mean 'share'?); known keys: kind, share"});
  options["stages"] = Json::array();
  expect_error([&] { hapsyn::make_options<Plan>(options); }, {"problem: options.stages = []: must have at least 1 item"});
}

TEST(Options, RuleOfAListElementNamesItsIndex) {
  Json options = minimal_plan();
  options["stages"].push_back(Json{{"kind", "fine"}, {"share", 0}});
  expect_error([&] { hapsyn::make_options<Plan>(options); },
               {"problem: options.stages[1].share = 0.0: must satisfy share > 0 for a fine stage"});
}

TEST(Options, UnsignedIntegerTakesTheWholeRange) {
  const Json schema = hapsyn::options_schema<Plan>();
  EXPECT_EQ(schema["properties"]["seed"]["maximum"], Json(std::numeric_limits<std::uint64_t>::max()));
  EXPECT_EQ(schema["properties"]["salt"]["minimum"], 0);
  Json options = minimal_plan();
  options["seed"] = Json::parse("18446744073709551615");
  options["salt"] = Json::parse("18446744073709551615");
  const Plan plan = hapsyn::make_options<Plan>(options);
  EXPECT_EQ(plan.seed, 18446744073709551615ull);
  EXPECT_EQ(plan.salt, std::optional<std::uint64_t>(18446744073709551615ull));
  EXPECT_EQ(hapsyn::options_to_json(plan)["seed"].dump(), "18446744073709551615");
  options["seed"] = Json::parse("18446744073709551616");  // 2^64: beyond the range
  expect_error([&] { hapsyn::make_options<Plan>(options); },
               {"problem: options.seed = 1.8446744073709552e+19: must be an integer"});
  options["seed"] = -1;
  expect_error([&] { hapsyn::make_options<Plan>(options); }, {"problem: options.seed = -1: must be >= 0"});
  options["seed"] = 2.5;
  expect_error([&] { hapsyn::make_options<Plan>(options); }, {"problem: options.seed = 2.5: must be an integer"});
}

// A metric declaring a required key, an optional one, a list of groups, free-form JSON and an
// unsigned integer (tests/plugins/test_metric.cpp, TEST_PLUGIN_OPTION_KINDS), through the registry.
const hapsyn::Registry& test_plugins() {
  static const hapsyn::Registry registry({HAPSYN_TEST_PLUGIN_DIR});
  return registry;
}

TEST(Options, PluginWithEveryKindOfOptionIsCreatedThroughTheRegistry) {
  Json resolved;
  test_plugins().create_metric("optionkinds", Json{{"label", "a"}}, "objectives[0]", &resolved);
  EXPECT_EQ(resolved, (Json{{"label", "a"}, {"stages", Json::array()}, {"extra", Json::object()}, {"seed", 1}}));
  const Json given = {{"label", "a"}, {"limit", 2.0}, {"stages", {{{"kind", "x"}}}}, {"seed", 18446744073709551615ull}};
  test_plugins().create_metric("optionkinds", given, "objectives[0]", &resolved);
  EXPECT_EQ(resolved["limit"], 2.0);
  EXPECT_EQ(resolved["stages"], given["stages"]);
  EXPECT_EQ(resolved["seed"].dump(), "18446744073709551615");
  expect_error([] { test_plugins().create_metric("optionkinds", Json::object(), "objectives[0]"); },
               {"objectives[0].options.label: required key is missing"});
  expect_error(
      [] {
        test_plugins().create_metric("optionkinds", Json{{"label", "a"}, {"stages", {Json::object()}}}, "objectives[0]");
      },
      {"objectives[0].options.stages[0].kind: required key is missing"});
}

TEST(Options, DescribeShowsRequiredAndOptionalKeysAndTheKeysOfListElements) {
  ::setenv("HAPSYN_PLUGIN_PATH", HAPSYN_TEST_PLUGIN_DIR, 1);
  const hapsyn::test::Output o = hapsyn::test::hapsyn_cli("describe optionkinds");
  ::unsetenv("HAPSYN_PLUGIN_PATH");
  EXPECT_EQ(o.code, 0) << o.out;
  for (const char* line : {"  label                  string   default (required)        a label\n",
                           "  limit                  number   default (none)            a limit (default: none)\n",
                           "  stages[].kind          string   default (required)        what the stage does\n",
                           "  seed                   integer  default 1                 a seed [>= 0 <= 18446744073709551615]\n"}) {
    EXPECT_NE(o.out.find(line), std::string::npos) << "missing: " << line << "in:\n" << o.out;
  }
}

}  // namespace
