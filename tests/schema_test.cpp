// Plugin option schemas: the supported keywords, default filling and the error messages users
// see (path, offending value, rule).
#include <gtest/gtest.h>

#include <functional>
#include <hapsyn/error.hpp>
#include <hapsyn/json.hpp>
#include <hapsyn/schema.hpp>

#include "test_support.hpp"
#include <limits>
#include <string>

namespace {

using hapsyn::Json;
using hapsyn::test::error_of;


std::string validation_error(const Json& schema, const Json& value, const std::string& path) {
  return error_of([&] { hapsyn::validate_and_fill(schema, value, path); });
}

std::string schema_error(const Json& schema) {
  return error_of([&] { hapsyn::check_schema(schema, "plugin 'demo' schema.json"); });
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// A schema in the style of a plugin's schema.json.
Json scene_schema() {
  return Json::parse(R"({
    "type": "object",
    "description": "a planar square workspace",
    "properties": {
      "side": {"type": "number", "exclusiveMinimum": 0, "unit": "m", "default": 0.1},
      "step": {"type": "number", "exclusiveMinimum": 0, "maximum": 1, "unit": "m"},
      "count": {"type": "integer", "minimum": 1, "default": 4},
      "shape": {"type": "string", "enum": ["square", "disc"], "default": "square"},
      "closed": {"type": "boolean", "default": true},
      "centre": {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2}
    },
    "required": ["step"]
  })");
}

const double kInf = std::numeric_limits<double>::infinity();

// ---- render_value and nearest_name ----

TEST(Json, RenderValueIsCompactJson) {
  EXPECT_EQ(hapsyn::render_value(Json(-0.001)), "-0.001");
  EXPECT_EQ(hapsyn::render_value(Json("abc")), "\"abc\"");
  EXPECT_EQ(hapsyn::render_value(Json::parse(R"({"a": [1, 2], "b": null})")),
            R"({"a":[1,2],"b":null})");
  EXPECT_EQ(hapsyn::render_value(Json(true)), "true");
}

TEST(Json, RenderValueTruncatesTo60Characters) {
  const std::string rendered = hapsyn::render_value(Json(std::string(100, 'x')));
  EXPECT_EQ(rendered.size(), 60u);
  EXPECT_EQ(rendered, "\"" + std::string(56, 'x') + "...");
  Json big = Json::array();
  for (int i = 0; i < 1000; ++i) big.push_back(i);
  EXPECT_EQ(hapsyn::render_value(big).size(), 60u);
  EXPECT_EQ(hapsyn::render_value(big).substr(0, 8), "[0,1,2,3");
}

TEST(Json, RenderValueNeverSplitsAUtf8Character) {
  // "\xc3\xa9" is the two-byte 'é'. Cutting "a + 40 é" at 57 bytes would split one.
  std::string e_acute = "\xc3\xa9", text = "a", expected = "\"a";
  for (int i = 0; i < 40; ++i) text += e_acute;
  for (int i = 0; i < 27; ++i) expected += e_acute;
  EXPECT_EQ(hapsyn::render_value(Json(text)), expected + "...");
}

TEST(Json, RenderValueShowsNonFiniteNumbers) {
  EXPECT_EQ(hapsyn::render_value(Json(kInf)), "inf");
  EXPECT_EQ(hapsyn::render_value(Json(-kInf)), "-inf");
  EXPECT_EQ(hapsyn::render_value(Json(std::nan(""))), "nan");
  EXPECT_EQ(hapsyn::render_value(Json::array({1, kInf})), "[1,inf]");
}

TEST(Json, NearestNameFindsTyposAndTranspositions) {
  const std::vector<std::string> keys = {"side", "step", "threads", "polish"};
  EXPECT_EQ(hapsyn::nearest_name("threds", keys), "threads");
  EXPECT_EQ(hapsyn::nearest_name("stpe", keys), "step");
  EXPECT_EQ(hapsyn::nearest_name("steps", keys), "step");
  EXPECT_EQ(hapsyn::nearest_name("polsh", keys), "polish");
}

TEST(Json, NearestNameRefusesDistantWords) {
  const std::vector<std::string> keys = {"side", "step", "threads"};
  EXPECT_EQ(hapsyn::nearest_name("budget", keys), "");
  EXPECT_EQ(hapsyn::nearest_name("xy", keys), "");
  EXPECT_EQ(hapsyn::nearest_name("step", {}), "");
  // "thrads" is one edit away (limit 2 for 6 letters), "thxxds" three.
  EXPECT_EQ(hapsyn::nearest_name("thrads", keys), "threads");
  EXPECT_EQ(hapsyn::nearest_name("thxxds", keys), "");
}

TEST(Json, NearestNameAllowsOneEditForShortWords) {
  EXPECT_EQ(hapsyn::nearest_name("r0", {"r", "l0"}), "r");  // first of equally close wins
  EXPECT_EQ(hapsyn::nearest_name("q", {"r"}), "r");
}

// ---- validate_and_fill: accepted values and defaults ----

TEST(Schema, FillsDefaultsForAbsentProperties) {
  const Json filled =
      hapsyn::validate_and_fill(scene_schema(), Json{{"step", 0.001}}, "scene.options");
  EXPECT_EQ(filled, Json::parse(R"({"step": 0.001, "side": 0.1, "count": 4, "shape": "square",
                                     "closed": true})"));
}

TEST(Schema, KeepsGivenValuesOverDefaults) {
  const Json value = Json::parse(R"({"step": 0.5, "side": 0.2, "count": 7, "shape": "disc",
                                      "closed": false, "centre": [0.0, 0.1]})");
  EXPECT_EQ(hapsyn::validate_and_fill(scene_schema(), value, "scene.options"), value);
}

TEST(Schema, FillsNestedDefaultsInGivenAndAbsentSubObjects) {
  const Json schema = Json::parse(R"({
    "type": "object",
    "properties": {
      "mesh": {"type": "object", "properties": {
        "n": {"type": "integer", "default": 10},
        "refine": {"type": "object", "properties": {"levels": {"type": "integer", "default": 2}}}}},
      "start": {"type": "object", "default": {},
                "properties": {"x": {"type": "number", "default": 0.5}}},
      "needs": {"type": "object", "properties": {"k": {"type": "number"}}, "required": ["k"]}
    }
  })");
  EXPECT_EQ(hapsyn::validate_and_fill(schema, Json::object(), "solver.options"),
            Json::parse(R"({"mesh": {"n": 10, "refine": {"levels": 2}}, "start": {"x": 0.5}})"));
  EXPECT_EQ(hapsyn::validate_and_fill(
                schema, Json::parse(R"({"mesh": {"n": 3}, "needs": {"k": 1}})"), "solver.options"),
            Json::parse(R"({"mesh": {"n": 3, "refine": {"levels": 2}}, "start": {"x": 0.5},
                            "needs": {"k": 1}})"));
}

TEST(Schema, AcceptsIntegralNumbersAsIntegers) {
  const Json filled = hapsyn::validate_and_fill(scene_schema(), Json{{"step", 0.1}, {"count", 3.0}},
                                                "scene.options");
  EXPECT_TRUE(filled["count"].is_number_integer());
  EXPECT_EQ(filled["count"], 3);
}

TEST(Schema, AcceptsIntegersAsNumbers) {
  const Json filled = hapsyn::validate_and_fill(scene_schema(), Json{{"step", 1}}, "scene.options");
  EXPECT_EQ(filled["step"], 1);
}

TEST(Schema, AcceptsAListOfTypes) {
  const Json schema = Json::parse(R"({"type": "object", "properties": {
      "seed": {"type": ["integer", "string"]}}})");
  EXPECT_NO_THROW(hapsyn::validate_and_fill(schema, Json{{"seed", 12}}, "solver.options"));
  EXPECT_NO_THROW(hapsyn::validate_and_fill(schema, Json{{"seed", "auto"}}, "solver.options"));
  EXPECT_EQ(validation_error(schema, Json{{"seed", 1.5}}, "solver.options"),
            "problem: solver.options.seed = 1.5: must be an integer or a string");
}

TEST(Schema, AcceptsAnyKeyWhenAdditionalPropertiesIsTrue) {
  const Json schema = Json::parse(R"({"type": "object", "additionalProperties": true})");
  const Json value = Json::parse(R"({"anything": {"deep": [1, "x"]}})");
  EXPECT_EQ(hapsyn::validate_and_fill(schema, value, "output"), value);
}

TEST(Schema, ValidatesExtraKeysAgainstAnAdditionalPropertiesSchema) {
  const Json schema =
      Json::parse(R"({"type": "object", "additionalProperties": {"type": "number"}})");
  EXPECT_NO_THROW(hapsyn::validate_and_fill(schema, Json{{"w1", 0.5}}, "weights"));
  EXPECT_EQ(validation_error(schema, Json{{"w1", "a"}}, "weights"),
            "problem: weights.w1 = \"a\": must be a number");
}

TEST(Schema, UntypedSchemaAcceptsAnyValue) {
  const Json schema = Json::parse(R"({"description": "free-form"})");
  EXPECT_NO_THROW(hapsyn::validate_and_fill(schema, Json::parse(R"({"a": [1, {"b": 2}]})"), "x"));
  EXPECT_NO_THROW(hapsyn::validate_and_fill(schema, Json("text"), "x"));
}

TEST(Schema, ValidatesArrayItemsAndFillsTheirDefaults) {
  const Json schema = Json::parse(R"({"type": "array", "minItems": 1, "items": {
      "type": "object", "properties": {"metric": {"type": "string"},
                                       "sense": {"enum": ["minimize", "maximize"], "default": "minimize"}},
      "required": ["metric"]}})");
  EXPECT_EQ(hapsyn::validate_and_fill(schema, Json::parse(R"([{"metric": "gii"}])"), "objectives"),
            Json::parse(R"([{"metric": "gii", "sense": "minimize"}])"));
  EXPECT_EQ(
      validation_error(schema, Json::parse(R"([{"metric": "gii"}, {"metric": 3}])"), "objectives"),
      "problem: objectives[1].metric = 3: must be a string");
  EXPECT_EQ(validation_error(schema, Json::parse(R"([{"metric": "gii"}, {}])"), "objectives"),
            "problem: objectives[1].metric: required key is missing");
}

// ---- validate_and_fill: error messages ----

TEST(Schema, RefusesValueAtOrBelowExclusiveMinimum) {
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", -0.001}}, "scene.options"),
            "problem: scene.options.step = -0.001: must be > 0");
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", 0}}, "scene.options"),
            "problem: scene.options.step = 0: must be > 0");
}

TEST(Schema, RefusesValueAboveMaximum) {
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", 1.5}}, "scene.options"),
            "problem: scene.options.step = 1.5: must be <= 1");
  EXPECT_NO_THROW(hapsyn::validate_and_fill(scene_schema(), Json{{"step", 1}}, "scene.options"));
}

TEST(Schema, RefusesValueBelowMinimum) {
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", 0.1}, {"count", 0}}, "scene.options"),
            "problem: scene.options.count = 0: must be >= 1");
}

TEST(Schema, RefusesValueAtExclusiveMaximum) {
  const Json schema = Json::parse(R"({"type": "number", "exclusiveMaximum": 0.5})");
  EXPECT_EQ(validation_error(schema, Json(0.5), "mechanism.options.ratio"),
            "problem: mechanism.options.ratio = 0.5: must be < 0.5");
  EXPECT_NO_THROW(hapsyn::validate_and_fill(schema, Json(0.49), "mechanism.options.ratio"));
}

TEST(Schema, RefusesStringForNumber) {
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", "abc"}}, "scene.options"),
            "problem: scene.options.step = \"abc\": must be a number");
}

TEST(Schema, RefusesBooleanForNumber) {
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", true}}, "scene.options"),
            "problem: scene.options.step = true: must be a number");
}

TEST(Schema, RefusesFractionalNumberForInteger) {
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", 0.1}, {"count", 2.5}}, "scene.options"),
            "problem: scene.options.count = 2.5: must be an integer");
}

TEST(Schema, RefusesEachWrongType) {
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", 0.1}, {"shape", 1}}, "scene.options"),
            "problem: scene.options.shape = 1: must be a string");
  EXPECT_EQ(
      validation_error(scene_schema(), Json{{"step", 0.1}, {"closed", "yes"}}, "scene.options"),
      "problem: scene.options.closed = \"yes\": must be a boolean");
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", 0.1}, {"centre", 0}}, "scene.options"),
            "problem: scene.options.centre = 0: must be an array");
  EXPECT_EQ(validation_error(scene_schema(), Json::array({1}), "scene.options"),
            "problem: scene.options = [1]: must be an object");
}

TEST(Schema, RefusesNonFiniteNumbers) {
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", kInf}}, "scene.options"),
            "problem: scene.options.step = inf: must be finite");
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", std::nan("")}}, "scene.options"),
            "problem: scene.options.step = nan: must be finite");
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", 0.1}, {"centre", {0.0, -kInf}}},
                             "scene.options"),
            "problem: scene.options.centre[1] = -inf: must be finite");
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", 0.1}, {"count", kInf}}, "scene.options"),
            "problem: scene.options.count = inf: must be finite");
}

TEST(Schema, RefusesNonFiniteNumbersInFreeFormValues) {
  const Json schema = Json::parse(R"({"type": "object", "additionalProperties": true})");
  EXPECT_EQ(validation_error(schema, Json{{"a", {{"b", kInf}}}}, "output"),
            "problem: output.a.b = inf: must be finite");
}

TEST(Schema, RefusesStringsThatOnlyLookLikeNumbers) {
  // What --set leaves of "NaN" and "Infinity", which are not JSON.
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", "NaN"}}, "scene.options"),
            "problem: scene.options.step = \"NaN\": must be a number");
}

TEST(Schema, RefusesValueOutsideEnum) {
  const Json schema = Json::parse(R"({"type": "object", "properties": {
      "elbow": {"type": "string", "enum": ["out", "in"], "default": "out"}}})");
  EXPECT_EQ(validation_error(schema, Json{{"elbow", "up"}}, "mechanism.options"),
            "problem: mechanism.options.elbow = \"up\": must be one of \"out\", \"in\"");
}

TEST(Schema, RefusesUnknownKeyWithSuggestion) {
  const Json schema = Json::parse(R"({"type": "object", "properties": {
      "a": {"type": "number"}, "b": {"type": "number"}, "threads": {"type": "integer"}}})");
  EXPECT_EQ(
      validation_error(schema, Json{{"threds", 4}}, "solver.options"),
      "problem: solver.options.threds: unknown key (did you mean 'threads'?); known keys: a, b, "
      "threads");
}

TEST(Schema, RefusesUnknownKeyWithoutSuggestionWhenNothingIsClose) {
  EXPECT_EQ(
      validation_error(scene_schema(), Json{{"step", 0.1}, {"budget", 5}}, "scene.options"),
      "problem: scene.options.budget: unknown key; known keys: centre, closed, count, shape, side, "
      "step");
}

TEST(Schema, RefusesAnyKeyForAnObjectWithEmptyProperties) {
  const Json schema = Json::parse(R"({"type": "object", "properties": {}})");
  EXPECT_EQ(validation_error(schema, Json{{"x", 1}}, "solver.options"),
            "problem: solver.options.x: unknown key; this object takes no keys");
  EXPECT_NO_THROW(hapsyn::validate_and_fill(schema, Json::object(), "solver.options"));
}

TEST(Schema, TreatsAnObjectWithoutPropertiesAsFreeForm) {
  // How the framework's own problem schema leaves "options" to each plugin's schema.
  const Json schema = Json::parse(R"({"type": "object", "properties": {
      "plugin": {"type": "string"}, "options": {"type": "object", "default": {}}}})");
  const Json value = Json::parse(R"({"plugin": "fivebar", "options": {"elbow": "out"}})");
  EXPECT_EQ(hapsyn::validate_and_fill(schema, value, "mechanism"), value);
  EXPECT_EQ(hapsyn::validate_and_fill(schema, Json{{"plugin", "fivebar"}}, "mechanism"),
            Json::parse(R"({"plugin": "fivebar", "options": {}})"));
  EXPECT_EQ(validation_error(schema, Json{{"options", {{"step", -kInf}}}}, "mechanism"),
            "problem: mechanism.options.step = -inf: must be finite");
}

TEST(Schema, ChecksRequiredKeysOfAFreeFormObject) {
  const Json schema = Json::parse(R"({"type": "object", "required": ["plugin"]})");
  EXPECT_NO_THROW(hapsyn::validate_and_fill(schema, Json{{"plugin", "x"}, {"other", 1}}, "solver"));
  EXPECT_EQ(validation_error(schema, Json{{"other", 1}}, "solver"),
            "problem: solver.plugin: required key is missing");
}

TEST(Schema, RefusesMissingRequiredKey) {
  EXPECT_EQ(validation_error(scene_schema(), Json{{"side", 0.2}}, "scene.options"),
            "problem: scene.options.step: required key is missing");
}

TEST(Schema, ReportsATypoedRequiredKeyAsUnknown) {
  const std::string message =
      validation_error(scene_schema(), Json{{"stpe", 0.1}}, "scene.options");
  EXPECT_TRUE(contains(message, "scene.options.stpe: unknown key (did you mean 'step'?)"))
      << message;
}

TEST(Schema, RefusesArraysOfTheWrongLength) {
  EXPECT_EQ(
      validation_error(scene_schema(), Json{{"step", 0.1}, {"centre", {0.0}}}, "scene.options"),
      "problem: scene.options.centre = [0.0]: must have at least 2 items");
  EXPECT_EQ(
      validation_error(scene_schema(), Json{{"step", 0.1}, {"centre", {0, 1, 2}}}, "scene.options"),
      "problem: scene.options.centre = [0,1,2]: must have at most 2 items");
  const Json one = Json::parse(R"({"type": "array", "minItems": 1})");
  EXPECT_EQ(validation_error(one, Json::array(), "objectives"),
            "problem: objectives = []: must have at least 1 item");
}

TEST(Schema, RefusesBadArrayItemWithItsIndex) {
  EXPECT_EQ(validation_error(scene_schema(), Json{{"step", 0.1}, {"centre", {0.0, "a"}}},
                             "scene.options"),
            "problem: scene.options.centre[1] = \"a\": must be a number");
}

TEST(Schema, TruncatesLongOffendingValues) {
  const std::string message =
      validation_error(scene_schema(), Json{{"step", std::string(200, 'z')}}, "scene.options");
  EXPECT_EQ(message,
            "problem: scene.options.step = \"" + std::string(56, 'z') + "...: must be a number");
}

TEST(Schema, ReportsTheTopLevelWhenThePathIsEmpty) {
  EXPECT_EQ(validation_error(Json::parse(R"({"type": "string"})"), Json(1), ""),
            "problem: (top level) = 1: must be a string");
}

// ---- check_schema ----

TEST(Schema, CheckSchemaAcceptsEverySupportedKeyword) {
  const Json schema = Json::parse(R"({
    "type": "object", "description": "all words", "additionalProperties": false,
    "properties": {
      "n": {"type": "integer", "minimum": 0, "maximum": 10, "default": 3, "unit": "1"},
      "x": {"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 1},
      "mode": {"enum": ["a", "b"]},
      "list": {"type": "array", "items": {"type": "string"}, "minItems": 0, "maxItems": 4},
      "extra": {"type": "object", "additionalProperties": {"type": "boolean"}}
    },
    "required": ["x"]
  })");
  EXPECT_NO_THROW(hapsyn::check_schema(schema, "plugin 'demo' schema.json"));
  EXPECT_NO_THROW(hapsyn::check_schema(scene_schema(), "plugin 'demo' schema.json"));
}

TEST(Schema, CheckSchemaRefusesUnknownKeyword) {
  const std::string message = schema_error(Json::parse(R"({"type": "object", "properties": {
      "name": {"type": "string", "pattern": "^[a-z]+$"}}})"));
  EXPECT_TRUE(contains(message,
                       "schema: plugin 'demo' schema.json: properties.name: unsupported keyword "
                       "'pattern'; supported: type, properties"))
      << message;
}

TEST(Schema, CheckSchemaRefusesUnknownKeywordAtTheTopLevel) {
  const std::string message = schema_error(Json::parse(R"({"type": "object", "oneOf": []})"));
  EXPECT_TRUE(contains(
      message, "schema: plugin 'demo' schema.json: (top level): unsupported keyword 'oneOf'"))
      << message;
}

TEST(Schema, CheckSchemaRefusesInvalidDefault) {
  EXPECT_EQ(schema_error(Json::parse(R"({"type": "object", "properties": {
                "step": {"type": "number", "exclusiveMinimum": 0, "default": -1}}})")),
            "schema: plugin 'demo' schema.json: properties.step.default = -1: must be > 0");
  EXPECT_EQ(schema_error(Json::parse(R"({"type": "object", "properties": {
                "elbow": {"enum": ["out", "in"], "default": "up"}}})")),
            "schema: plugin 'demo' schema.json: properties.elbow.default = \"up\": must be one of "
            "\"out\", "
            "\"in\"");
}

TEST(Schema, CheckSchemaRefusesInvalidDefaultNestedInADefault) {
  EXPECT_EQ(
      schema_error(Json::parse(R"({"type": "object", "properties": {
                "start": {"type": "object", "default": {"x": "a"},
                          "properties": {"x": {"type": "number"}}}}})")),
      "schema: plugin 'demo' schema.json: properties.start.default.x = \"a\": must be a number");
}

TEST(Schema, CheckSchemaRefusesMalformedKeywordValues) {
  EXPECT_EQ(schema_error(Json::parse(R"({"type": "float"})")),
            "schema: plugin 'demo' schema.json: type = \"float\": must be one of object, number, "
            "integer, "
            "string, boolean, array, or a list of them");
  EXPECT_EQ(schema_error(Json::parse(R"({"type": "number", "minimum": "0"})")),
            "schema: plugin 'demo' schema.json: minimum = \"0\": must be a number");
  EXPECT_EQ(schema_error(Json::parse(R"({"type": "number", "exclusiveMinimum": true})")),
            "schema: plugin 'demo' schema.json: exclusiveMinimum = true: must be a number");
  EXPECT_EQ(schema_error(Json::parse(R"({"type": "number", "minimum": 2, "maximum": 1})")),
            "schema: plugin 'demo' schema.json: minimum = 2: must be <= maximum (1)");
  EXPECT_EQ(schema_error(Json::parse(R"({"type": "array", "minItems": -1})")),
            "schema: plugin 'demo' schema.json: minItems = -1: must be a non-negative integer");
  EXPECT_EQ(schema_error(Json::parse(R"({"type": "array", "items": [{"type": "number"}]})")),
            "schema: plugin 'demo' schema.json: items = [{\"type\":\"number\"}]: must be a schema "
            "(lists of "
            "item schemas are not supported)");
  EXPECT_EQ(schema_error(Json::parse(R"({"enum": []})")),
            "schema: plugin 'demo' schema.json: enum = []: must be a non-empty array");
  EXPECT_EQ(schema_error(Json::parse(R"({"type": "object", "additionalProperties": "no"})")),
            "schema: plugin 'demo' schema.json: additionalProperties = \"no\": must be a boolean "
            "or a schema");
  EXPECT_EQ(schema_error(Json::parse(R"({"type": "object", "properties": {"a": 1}})")),
            "schema: plugin 'demo' schema.json: properties.a: a schema must be an object, not 1");
  EXPECT_EQ(schema_error(Json::parse(R"({"description": 3})")),
            "schema: plugin 'demo' schema.json: description = 3: must be a string");
}

TEST(Schema, CheckSchemaRefusesEnumChoiceOfTheWrongType) {
  EXPECT_EQ(schema_error(Json::parse(R"({"type": "string", "enum": ["a", 2]})")),
            "schema: plugin 'demo' schema.json: enum[1] = 2: must be a string");
}

TEST(Schema, CheckSchemaAcceptsRequiredKeysOfAFreeFormObject) {
  EXPECT_NO_THROW(hapsyn::check_schema(Json::parse(R"({"type": "object", "required": ["plugin"]})"),
                                       "problem schema"));
}

TEST(Schema, CheckSchemaRefusesRequiredKeysThatCannotBeGiven) {
  EXPECT_EQ(schema_error(
                Json::parse(R"({"type": "object", "properties": {"a": {}}, "required": ["b"]})")),
            "schema: plugin 'demo' schema.json: required = [\"b\"]: 'b' is not in properties and "
            "additionalProperties is false");
  EXPECT_EQ(schema_error(Json::parse(R"({"type": "object", "properties": {"a": {"default": 1}},
                                        "required": ["a"]})")),
            "schema: plugin 'demo' schema.json: required = [\"a\"]: 'a' is required and also has a "
            "default");
}
}  // namespace
