// Declared cross-field rules of an options struct: schema, messages, order.
#include "test_support.hpp"

#include <hapsyn/options.hpp>
#include <hapsyn/schema.hpp>

#include <stdexcept>

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

}  // namespace
