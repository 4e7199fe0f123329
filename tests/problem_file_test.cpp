// Problem files: reading, malformed-JSON positions, and --set overrides.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <functional>
#include <hapsyn/error.hpp>
#include <hapsyn/json.hpp>
#include <hapsyn/internal/problem_file.hpp>

#include "test_support.hpp"
#include <string>
#include <vector>

namespace {

using hapsyn::Json;
using hapsyn::test::error_of;


std::string parse_error(const std::string& text) {
  return error_of([&] { hapsyn::parse_problem_text(text, "p.json"); });
}

std::string override_error(Json problem, const std::string& assignment) {
  return error_of([&] { hapsyn::apply_override(problem, assignment); });
}

Json overridden(Json problem, const std::string& assignment) {
  hapsyn::apply_override(problem, assignment);
  return problem;
}

Json sample_problem() {
  return Json::parse(R"({
    "name": "fivebar-gii",
    "scene": {"plugin": "planar_square", "options": {"side": 0.1, "step": 0.001}},
    "design": {"l0": {"lower": 0.0, "upper": 0.3}},
    "objectives": [{"metric": "gii", "sense": "maximize"}],
    "solver": {"plugin": "culling", "options": {"polish": true}}
  })");
}

// A file in a fresh temporary directory, removed with the fixture.
class ProblemFile : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/hapsyn-problem-file-test-XXXXXX";
    ASSERT_NE(mkdtemp(pattern), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    for (const auto& f : files_) std::remove(f.c_str());
    std::remove(dir_.c_str());
  }
  std::string write(const std::string& name, const std::string& content) {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path) << content;
    files_.push_back(path);
    return path;
  }
  std::string dir_;
  std::vector<std::string> files_;
};

// ---- reading and parsing ----

TEST_F(ProblemFile, ReadsAFile) {
  const std::string path =
      write("ok.json", R"({"name": "x", "scene": {"options": {"step": 0.001}}})");
  const Json problem = hapsyn::read_problem_file(path);
  EXPECT_EQ(problem["name"], "x");
  EXPECT_EQ(problem["scene"]["options"]["step"], 0.001);
}

TEST_F(ProblemFile, RefusesAMissingFile) {
  const std::string path = dir_ + "/absent.json";
  EXPECT_EQ(error_of([&] { hapsyn::read_problem_file(path); }),
            "problem: cannot read problem file " + path + ": No such file or directory");
}

TEST_F(ProblemFile, RefusesADirectory) {
  EXPECT_EQ(error_of([&] { hapsyn::read_problem_file(dir_); }),
            "problem: problem file " + dir_ + " is not a regular file (a directory)");
}

TEST_F(ProblemFile, RefusesAFifoWithoutWaitingForAWriter) {
  const std::string path = dir_ + "/fifo.json";
  ASSERT_EQ(mkfifo(path.c_str(), 0600), 0);
  files_.push_back(path);
  EXPECT_EQ(error_of([&] { hapsyn::read_problem_file(path); }),
            "problem: problem file " + path + " is not a regular file (a FIFO)");
}

TEST_F(ProblemFile, RefusesADeviceInsteadOfReadingItForever) {
  EXPECT_EQ(error_of([] { hapsyn::read_problem_file("/dev/zero"); }),
            "problem: problem file /dev/zero is not a regular file (a device or socket)");
}

TEST_F(ProblemFile, RefusesDeepNestingBeforeBuildingTheDocument) {
  // 60 KB of '[' overflowed the stack in nlohmann's recursive destructor.
  const std::string path = write("deep.json", "{\"a\":\n" + std::string(60000, '[') + std::string(60000, ']') + "}");
  EXPECT_EQ(error_of([&] { hapsyn::read_problem_file(path); }),
            "problem: " + path + ":2:256: nesting deeper than 256 levels (arrays and objects inside each other): "
            "refused before it is built");
}

TEST_F(ProblemFile, RefusesADuplicateKeyWithItsPathAndPosition) {
  const std::string path = write("dup.json", "{\"design\": {\n  \"l1\": {\"lower\": 0.1},\n    \"l1\": {\"lower\": 0.2}}}");
  EXPECT_EQ(error_of([&] { hapsyn::read_problem_file(path); }),
            "problem: " + path + ":3:5: duplicate key \"l1\" in design (each key may appear once)");
}

TEST_F(ProblemFile, ReportsTheFileNameInSyntaxErrors) {
  const std::string path = write("bad.json", "{\n  \"name\": \"x\",\n}\n");
  EXPECT_EQ(error_of([&] { hapsyn::read_problem_file(path); }),
            "problem: " + path + ":3:1: malformed JSON: unexpected '}'; expected string literal");
}

TEST(ProblemFileParse, ReportsLineAndColumnOfAMissingColon) {
  EXPECT_EQ(parse_error("{\n  \"a\": 1,\n  \"b\" 2\n}"),
            "problem: p.json:3:7: malformed JSON: unexpected number literal; expected ':'");
}

TEST(ProblemFileParse, ReportsLineAndColumnOfATrailingComma) {
  EXPECT_EQ(parse_error("{\n  \"scene\": {\n    \"step\": 0.001,\n  }\n}"),
            "problem: p.json:4:3: malformed JSON: unexpected '}'; expected string literal");
}

TEST(ProblemFileParse, ReportsLineAndColumnOfABadLiteral) {
  const std::string message = parse_error("{\n\n  \"polish\": tru\n}");
  EXPECT_EQ(message.rfind("problem: p.json:3:", 0), 0u) << message;
  EXPECT_NE(message.find("malformed JSON: invalid literal"), std::string::npos) << message;
}

TEST(ProblemFileParse, CountsColumnsInCharactersNotBytes) {
  // 'é' is two bytes but one column.
  EXPECT_EQ(parse_error("{\"\xc3\xa9\" 1}"),
            "problem: p.json:1:6: malformed JSON: unexpected number literal; expected ':'");
}

TEST(ProblemFileParse, ReportsUnexpectedEndOfInput) {
  EXPECT_EQ(parse_error("{\n  \"a\": [1, 2"),
            "problem: p.json:2:13: malformed JSON: unexpected end of input; expected ']'");
  EXPECT_EQ(parse_error(""),
            "problem: p.json:1:1: malformed JSON: unexpected end of input; expected '[', '{', or a "
            "literal");
}

TEST(ProblemFileParse, ReportsTrailingContent) {
  const std::string message = parse_error("{\"a\": 1}\n{\"b\": 2}");
  EXPECT_EQ(message.rfind("problem: p.json:2:1: malformed JSON: ", 0), 0u) << message;
  EXPECT_NE(message.find("expected end of input"), std::string::npos) << message;
}

TEST(ProblemFileParse, ReportsNumbersOutOfRangeAtTheirStart) {
  EXPECT_EQ(parse_error("{\n  \"step\": 1e999\n}"),
            "problem: p.json:2:11: malformed JSON: number 1e999 is out of range");
}

TEST(ProblemFileParse, RefusesATopLevelThatIsNotAnObject) {
  EXPECT_EQ(parse_error("[1, 2]"),
            "problem: p.json: top level = [1,2]: must be an object, not an array");
  EXPECT_EQ(parse_error("\"fivebar\""),
            "problem: p.json: top level = \"fivebar\": must be an object, not a string");
  EXPECT_EQ(parse_error("null"), "problem: p.json: top level = null: must be an object, not null");
}

TEST(ProblemFileParse, AcceptsNestingUpToTheLimit) {
  const std::size_t n = hapsyn::kMaxJsonDepth - 1;  // inside the top-level object
  const Json doc = hapsyn::parse_problem_text("{\"a\":" + std::string(n, '[') + std::string(n, ']') + "}", "p.json");
  EXPECT_TRUE(doc["a"].is_array());
}

TEST(ProblemFileParse, NamesTheArrayElementHoldingADuplicateKey) {
  EXPECT_EQ(parse_error(R"({"objectives": [{"metric": "gii"}, {"metric": "gdi", "metric": "gii"}]})"),
            "problem: p.json:1:54: duplicate key \"metric\" in objectives[1] (each key may appear once)");
  EXPECT_EQ(parse_error(R"({"a": 1, "a": 2})"),
            "problem: p.json:1:10: duplicate key \"a\" in the top level (each key may appear once)");
}

TEST(ProblemFileParse, AcceptsTheSameKeyInDifferentObjects) {
  const Json doc = hapsyn::parse_problem_text(R"({"a": {"x": 1}, "b": {"x": 2}, "c": [{"x": 3}, {"x": 4}]})", "p.json");
  EXPECT_EQ(doc["c"][1]["x"], 4);
}

TEST(ProblemFileParse, RefusesInvalidUtf8InAString) {
  EXPECT_THAT(parse_error("{\"name\": \"\xff\"}"), ::testing::HasSubstr("p.json:1:11: malformed JSON: invalid string: ill-formed UTF-8"));
}

TEST(ProblemFileTextRules, RefusesInvalidUtf8InAValueOrKeyNamingThePath) {
  Json doc = {{"objectives", Json::array({Json::object({{"name", "a\xff"}})})}};
  EXPECT_EQ(error_of([&] { hapsyn::check_json_text_rules(doc); }),
            "problem: objectives[0].name = \"a\\xff\": invalid UTF-8 at byte 1 (text must be UTF-8)");
  Json keys = {{"design", {{"l\xc3", 1}}}};
  EXPECT_EQ(error_of([&] { hapsyn::check_json_text_rules(keys); }),
            "problem: design has key \"l\\xc3\": invalid UTF-8 at byte 1 (text must be UTF-8)");
}

TEST(ProblemFileTextRules, AcceptsMultiByteCharactersAndRefusesOverlongAndSurrogateForms) {
  EXPECT_EQ(error_of([] { hapsyn::check_json_text_rules(Json{{"n", "\xc3\xa9\xe2\x82\xac\xf0\x9f\x98\x80"}}); }), "(no error)");
  EXPECT_THAT(error_of([] { hapsyn::check_json_text_rules(Json{{"n", "\xc0\xaf"}}); }), ::testing::HasSubstr("invalid UTF-8 at byte 0"));
  EXPECT_THAT(error_of([] { hapsyn::check_json_text_rules(Json{{"n", "\xed\xa0\x80"}}); }), ::testing::HasSubstr("invalid UTF-8 at byte 0"));
  EXPECT_THAT(error_of([] { hapsyn::check_json_text_rules(Json{{"n", "ab\xe2\x82"}}); }), ::testing::HasSubstr("invalid UTF-8 at byte 2"));
}

TEST(ProblemFileParse, AcceptsAnObject) {
  EXPECT_EQ(hapsyn::parse_problem_text("{\"name\": \"x\"}", "p.json"), Json({{"name", "x"}}));
}

// ---- apply_override: values ----

TEST(ProblemFileOverride, SetsANumber) {
  const Json p = overridden(sample_problem(), "scene.options.step=0.005");
  EXPECT_TRUE(p["scene"]["options"]["step"].is_number_float());
  EXPECT_EQ(p["scene"]["options"]["step"], 0.005);
  EXPECT_EQ(p["scene"]["options"]["side"], 0.1);  // siblings are kept
}

TEST(ProblemFileOverride, ReadsTheValueAsJsonWhenItParses) {
  EXPECT_EQ(overridden(sample_problem(), "solver.options={}")["solver"]["options"], Json::object());
  EXPECT_EQ(
      overridden(sample_problem(), "solver.options.polish=false")["solver"]["options"]["polish"],
      false);
  EXPECT_EQ(overridden(sample_problem(), "name=\"quoted\"")["name"], "quoted");
  EXPECT_EQ(
      overridden(sample_problem(), "scene.options.centre=[1,2]")["scene"]["options"]["centre"],
      Json::array({1, 2}));
  EXPECT_EQ(
      overridden(sample_problem(), "solver.options.budget=100")["solver"]["options"]["budget"],
      100);
  EXPECT_EQ(overridden(sample_problem(), "solver.options.x=null")["solver"]["options"]["x"],
            nullptr);
}

TEST(ProblemFileOverride, KeepsTheRawStringWhenTheValueIsNotJson) {
  EXPECT_EQ(overridden(sample_problem(), "solver.plugin=grid")["solver"]["plugin"], "grid");
  EXPECT_EQ(overridden(sample_problem(), "name=a=b")["name"], "a=b");  // first '=' splits
  EXPECT_EQ(overridden(sample_problem(), "name=")["name"], "");
  EXPECT_EQ(overridden(sample_problem(), "name=[1,")["name"], "[1,");
}

TEST(ProblemFileOverride, KeepsNonJsonNumbersAsStrings) {
  EXPECT_EQ(overridden(sample_problem(), "scene.options.step=NaN")["scene"]["options"]["step"],
            "NaN");
  EXPECT_EQ(overridden(sample_problem(), "scene.options.step=Infinity")["scene"]["options"]["step"],
            "Infinity");
  EXPECT_EQ(overridden(sample_problem(), "scene.options.step=1e999")["scene"]["options"]["step"],
            "1e999");
}

// ---- apply_override: paths ----

TEST(ProblemFileOverride, CreatesMissingObjects) {
  const Json p = overridden(sample_problem(), "design.l1.value=0.1");
  EXPECT_EQ(p["design"]["l1"], Json({{"value", 0.1}}));
  EXPECT_EQ(p["design"]["l0"]["upper"], 0.3);
  EXPECT_EQ(overridden(Json::object(), "output.directory=out")["output"]["directory"], "out");
  EXPECT_EQ(overridden(Json(), "name=x"), Json({{"name", "x"}}));
}

TEST(ProblemFileOverride, TreatsDigitSegmentsAsKeysInObjects) {
  const Json p = overridden(sample_problem(), "design.0.value=1");
  EXPECT_TRUE(p["design"].is_object());
  EXPECT_EQ(p["design"]["0"]["value"], 1);
  EXPECT_EQ(overridden(Json::object(), "a.1=2"), Json::parse(R"({"a": {"1": 2}})"));
}

TEST(ProblemFileOverride, IndexesArraysWithDotsOrBrackets) {
  EXPECT_EQ(overridden(sample_problem(), "objectives.0.metric=gci")["objectives"][0]["metric"],
            "gci");
  EXPECT_EQ(overridden(sample_problem(), "objectives[0].metric=gci")["objectives"][0]["metric"],
            "gci");
  EXPECT_EQ(overridden(sample_problem(), "objectives[0]={\"metric\":\"x\"}")["objectives"][0],
            Json({{"metric", "x"}}));
  const Json nested = overridden(Json::parse(R"({"m": [[1, 2], [3]]})"), "m[1][0]=9");
  EXPECT_EQ(nested["m"], Json::parse("[[1, 2], [9]]"));
}

TEST(ProblemFileOverride, AppendsAtIndexEqualToSize) {
  const Json p = overridden(sample_problem(), "objectives[1].metric=manipulability");
  ASSERT_EQ(p["objectives"].size(), 2u);
  EXPECT_EQ(p["objectives"][1], Json({{"metric", "manipulability"}}));
  EXPECT_EQ(overridden(sample_problem(), "objectives.1=3")["objectives"][1], 3);
}

TEST(ProblemFileOverride, TrimsSpacesAroundThePath) {
  EXPECT_EQ(overridden(sample_problem(), " solver.plugin =grid")["solver"]["plugin"], "grid");
}

// ---- apply_override: errors ----

TEST(ProblemFileOverride, RefusesAnAssignmentWithoutEquals) {
  EXPECT_EQ(override_error(sample_problem(), "scene.options.step"),
            "set: 'scene.options.step': expected path=value (no '=')");
}

TEST(ProblemFileOverride, RefusesAnEmptyPath) {
  EXPECT_EQ(override_error(sample_problem(), "=5"), "set: '=5': empty path before '='");
  EXPECT_EQ(override_error(sample_problem(), "  =5"), "set: '  =5': empty path before '='");
}

TEST(ProblemFileOverride, RefusesAnEmptyPathSegment) {
  EXPECT_EQ(override_error(sample_problem(), "scene..step=1"),
            "set: 'scene..step=1': empty path segment in 'scene..step'");
  EXPECT_EQ(override_error(sample_problem(), ".name=1"),
            "set: '.name=1': empty path segment in '.name'");
  EXPECT_EQ(override_error(sample_problem(), "name.=1"),
            "set: 'name.=1': empty path segment in 'name.'");
  EXPECT_EQ(override_error(sample_problem(), "objectives.[0]=1"),
            "set: 'objectives.[0]=1': empty path segment in 'objectives.[0]'");
}

TEST(ProblemFileOverride, RefusesMalformedBrackets) {
  EXPECT_EQ(
      override_error(sample_problem(), "objectives[x]=1"),
      "set: 'objectives[x]=1': malformed index '[x]': expected [N] with N a non-negative integer");
  EXPECT_EQ(override_error(sample_problem(), "objectives[-1]=1"),
            "set: 'objectives[-1]=1': malformed index '[-1]': expected [N] with N a non-negative "
            "integer");
  EXPECT_EQ(override_error(sample_problem(), "objectives[0=1"),
            "set: 'objectives[0=1': unclosed '[' in 'objectives[0'");
  EXPECT_EQ(override_error(sample_problem(), "objectives[0]metric=1"),
            "set: 'objectives[0]metric=1': expected '.' or '[' after ']' in 'objectives[0]metric'");
}

TEST(ProblemFileOverride, RefusesAnIndexIntoANonArray) {
  EXPECT_EQ(override_error(sample_problem(), "solver[0]=1"),
            "set: 'solver[0]=1': cannot index into solver: "
            "{\"options\":{\"polish\":true},\"plugin\":\"culling\"} "
            "is not an array");
  EXPECT_EQ(override_error(sample_problem(), "weights[0]=1"),
            "set: 'weights[0]=1': cannot index into weights: it is missing");
  EXPECT_EQ(override_error(Json::object(), "[0]=1"),
            "set: '[0]=1': cannot index into the problem: {} is not an array");
}

TEST(ProblemFileOverride, RefusesAnIndexOutOfRange) {
  EXPECT_EQ(override_error(sample_problem(), "objectives[2].metric=x"),
            "set: 'objectives[2].metric=x': index 2 is out of range: objectives has 1 element (use "
            "1 to append)");
  EXPECT_EQ(
      override_error(sample_problem(), "objectives.5=x"),
      "set: 'objectives.5=x': index 5 is out of range: objectives has 1 element (use 1 to append)");
  EXPECT_EQ(
      override_error(sample_problem(), "objectives[99999999999999999999999]=x"),
      "set: 'objectives[99999999999999999999999]=x': malformed index '[99999999999999999999999]': "
      "expected [N] with N a non-negative integer");
}

TEST(ProblemFileOverride, RefusesAKeyIntoAnArray) {
  EXPECT_EQ(override_error(sample_problem(), "objectives.metric=x"),
            "set: 'objectives.metric=x': objectives is an array: 'metric' must be an index (e.g. "
            "objectives.0 "
            "or objectives[0])");
}

TEST(ProblemFileOverride, RefusesAPathThroughAScalar) {
  EXPECT_EQ(
      override_error(sample_problem(), "name.first=x"),
      "set: 'name.first=x': cannot set 'first' inside name: \"fivebar-gii\" is not an object");
  EXPECT_EQ(override_error(sample_problem(), "solver.options.polish.level=2"),
            "set: 'solver.options.polish.level=2': cannot set 'level' inside "
            "solver.options.polish: true is not "
            "an object");
  EXPECT_EQ(override_error(sample_problem(), "objectives[0].metric.x=1"),
            "set: 'objectives[0].metric.x=1': cannot set 'x' inside objectives[0].metric: \"gii\" "
            "is not an "
            "object");
}

TEST(ProblemFileOverride, RefusesAValueThatIsNotUtf8) {
  // Taken as a string, it passed validation and made dump() throw after the whole solve.
  EXPECT_EQ(override_error(sample_problem(), "name=\xff"),
            "set: \"name=\\xff\": invalid UTF-8 at byte 5 (paths and values must be UTF-8)");
}

TEST(ProblemFileOverride, RefusesAValueNestedTooDeep) {
  EXPECT_THAT(override_error(sample_problem(), "scene.options.x=" + std::string(5000, '[') + std::string(5000, ']')),
              ::testing::HasSubstr("value at 1:257: nesting deeper than 256 levels"));
}

// Issue 53, cause 8: a path of 60,000 segments took 10 s to refuse (the name of every prefix was
// built); it is refused by its length before it is split, and the message shows its start only.
TEST(ProblemFileOverride, RefusesAPathDeeperThanAProblemNestsAtOnce) {
  std::string path = "a";
  for (int i = 0; i < 60000; ++i) path += ".b";
  const std::string message = override_error(sample_problem(), path + "=1");
  EXPECT_EQ(message, "set: '" + path.substr(0, 200) + "...': path of more than 256 segments: a problem file nests at most that deep");
  std::string fits = "a";
  for (int i = 0; i < 200; ++i) fits += ".b";
  Json problem = sample_problem();
  hapsyn::apply_override(problem, fits + "=1");
  const Json* node = &problem["a"];
  for (int i = 0; i < 200; ++i) node = &(*node)["b"];
  EXPECT_EQ(*node, 1);
}

TEST(ProblemFileOverride, RefusesAValueWithADuplicateKey) {
  EXPECT_THAT(override_error(sample_problem(), R"(scene.options={"side": 0.1, "side": 0.2})"),
              ::testing::HasSubstr("value at 1:15: duplicate key \"side\" in the top level"));
}

TEST(ProblemFileOverride, LeavesTheProblemUnchangedWhenRefused) {
  Json copy = sample_problem();
  EXPECT_THROW(hapsyn::apply_override(copy, "extra.a.b[0]=1"), hapsyn::Error);
  EXPECT_EQ(copy, sample_problem());
  EXPECT_THROW(hapsyn::apply_override(copy, "objectives[1][0]=1"), hapsyn::Error);
  EXPECT_EQ(copy, sample_problem());
}

}  // namespace

TEST(ProblemFileParse, RefusesANulByteInsteadOfIgnoringWhatFollowsIt) {
  // nlohmann's lexer ends the input at a NUL: "garbage" would be ignored without a word.
  EXPECT_EQ(parse_error(std::string("{\"name\": \"x\"}\n\0garbage", 23)),
            "problem: p.json:2:1: a NUL byte: JSON text may not contain one (is this a binary file?)");
}
