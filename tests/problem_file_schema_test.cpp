// The problem file's schema, derived from its declarations (framework/src/problem_file_schema.cpp),
// against the hand-written JSON schema it replaced, kept here as the independent reference: the
// same document, the same resolution of every problem file in the repository, the same messages.
#include "test_support.hpp"

#include <hapsyn/internal/reference.hpp>
#include <hapsyn/schema.hpp>

#include <boost/filesystem.hpp>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace {

using hapsyn::Json;
namespace fs = boost::filesystem;

// The framework's schema of a problem file as it was written by hand before it was declared.
const char* const kFormerProblemSchema = R"json({
  "type": "object",
  "properties": {
    "name": {"type": "string", "description": "Study name (used for the default output directory)", "default": "study"},
    "description": {"type": "string", "description": "Free text", "default": ""},
    "mechanism": {"type": "object", "required": ["plugin"], "description": "What is designed: a mechanism plugin and its options", "properties": {
        "plugin": {"type": "string", "description": "Mechanism plugin name"},
        "options": {"type": "object", "description": "Options of the mechanism plugin", "default": {}}}},
    "scene": {"type": "object", "required": ["plugin"], "description": "The task-space samples the mechanism must serve: a scene plugin and its options", "properties": {
        "plugin": {"type": "string", "description": "Scene plugin name"},
        "options": {"type": "object", "description": "Options of the scene plugin", "default": {}}}},
    "objectives": {"type": "array", "minItems": 1, "description": "What is optimized: one entry per metric (several for a Pareto study or a weighted sum)", "items": {"type": "object", "required": ["metric"], "properties": {
        "metric": {"type": "string", "description": "Metric plugin name"},
        "name": {"type": "string", "description": "Label (default: the metric name)"},
        "sense": {"type": "string", "enum": ["maximize", "minimize"], "default": "maximize", "description": "Whether larger or smaller values of the metric are better"},
        "weight": {"type": "number", "minimum": 0, "description": "Weight in a weighted-sum study (>= 0; use sense to minimize)", "default": 1.0},
        "options": {"type": "object", "description": "Options of the metric plugin", "default": {}}}}},
    "solver": {"type": "object", "required": ["plugin"], "description": "How the design space is searched: a solver plugin and its options", "properties": {
        "plugin": {"type": "string", "description": "Solver plugin name"},
        "options": {"type": "object", "description": "Options of the solver plugin", "default": {}}}},
    "output": {"type": "object", "default": {}, "description": "What the run writes besides result.json", "properties": {
        "directory": {"type": "string", "description": "Output directory (default results/<name>)"},
        "samples_csv": {"type": "boolean", "description": "Write samples.csv for the best design", "default": true},
        "maps": {"type": "boolean", "description": "Write maps.csv: every objective per workspace position for the best design", "default": true},
        "plots": {"type": "boolean", "description": "Draw figures with gnuplot, each as PNG and SVG: the position maps (map_<objective>: slices by height for 3-D scenes), a Pareto front (front), the GA's and NSGA-II's convergence (convergence) and, for scenes of recorded motion, one trajectory (timeline)", "default": false},
        "groups": {"type": "boolean", "description": "For scenes that group their samples (subject, activity, trajectory): every objective per group with the mean and standard deviation across groups, in result.json and groups.csv", "default": true},
        "timeline": {"type": "string", "description": "With plots: the trajectory drawn in timeline.png (every objective on each sample along time); default the scene's first trajectory"}}},
    "indicators": {"type": "object", "description": "Front-quality indicators written into result.json", "properties": {
        "reference_front": {"type": "string", "description": "result.json of a study whose front is the reference (IGD, GD, domination gaps)"},
        "reference_point": {"type": "array", "items": {"type": "number"}, "description": "Hypervolume reference point, one value per objective (natural units), worse than every front point"}}},
    "design": {"type": "object", "description": "The mechanism's design variables by name (hapsyn describe MECHANISM lists them), each an object with \"lower\" and \"upper\" (bounds of the search, within the variable's hard limits), \"step\" (grid spacing for grid solvers) or \"value\" (fixes it); a vector variable takes lists. A variable not named keeps its declared default bounds. Checked against the mechanism's declarations, not by this schema"},
    "seed": {"type": "integer", "minimum": 0, "maximum": 18446744073709551615, "description": "Random seed, an unsigned 64-bit integer (default: drawn and recorded)"},
    "threads": {"type": "integer", "minimum": 0, "maximum": 1024, "description": "Worker threads (0 = all cores)"}
  },
  "required": ["mechanism", "scene", "objectives", "solver"]
})json";

const Json& former_schema() {
  static const Json schema = Json::parse(kFormerProblemSchema);
  return schema;
}

// `schema` with "additionalProperties": false on every object that lists "properties": what the
// validator assumes where the word is absent (hapsyn/schema.hpp), and what a declaration writes.
Json with_closed_objects(Json schema) {
  if (!schema.is_object()) return schema;
  if (schema.contains("properties")) {
    if (!schema.contains("additionalProperties")) schema["additionalProperties"] = false;
    for (auto& p : schema["properties"].items()) p.value() = with_closed_objects(p.value());
  }
  if (schema.contains("items")) schema["items"] = with_closed_objects(schema["items"]);
  return schema;
}

// What load_study's validation makes of `document` (without "design", which it checks by hand):
// the resolved document, or the message it is refused with.
std::string outcome(const Json& schema, Json document) {
  if (document.is_object()) document.erase("design");
  try {
    return hapsyn::validate_and_fill(schema, document, "").dump();
  } catch (const hapsyn::Error& e) {
    return std::string("error: ") + e.what();
  }
}

// Every JSON file of the repository that looks like a problem file (it names "objectives"):
// shipped problems, examples, plugins' conformance studies, test and fuzz problems.
std::vector<fs::path> problem_files() {
  std::vector<fs::path> out;
  for (const char* folder : {"problems", "examples", "plugins", "tests"}) {
    for (fs::recursive_directory_iterator it(fs::path(HAPSYN_SOURCE_DIR) / folder), end; it != end; ++it) {
      if (it->path().extension() != ".json" || !fs::is_regular_file(it->path())) continue;
      std::ifstream in(it->path().string());
      std::stringstream text;
      text << in.rdbuf();
      if (text.str().find("\"objectives\"") != std::string::npos) out.push_back(it->path());
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(ProblemFileSchema, IsTheFormerHandWrittenSchema) {
  EXPECT_EQ(hapsyn::problem_file_schema(), with_closed_objects(former_schema()));
  // The required keys in the order they are reported.
  EXPECT_EQ(hapsyn::problem_file_schema()["required"], (Json{"mechanism", "scene", "objectives", "solver"}));
  EXPECT_NO_THROW(hapsyn::check_schema(hapsyn::problem_file_schema(), "problem file"));
}

TEST(ProblemFileSchema, ResolvesEveryProblemFileInTheRepositoryAsTheFormerSchema) {
  const std::vector<fs::path> files = problem_files();
  // problems/ alone holds over 20 studies; examples, conformance studies and test problems add more.
  EXPECT_GE(files.size(), 50u);
  int resolved = 0;
  for (const fs::path& file : files) {
    Json document;
    try {
      document = hapsyn::read_problem_file(file.string());
    } catch (const hapsyn::Error&) {
      continue;  // a fuzz input refused before validation
    }
    const std::string expected = outcome(former_schema(), document);
    EXPECT_EQ(outcome(hapsyn::problem_file_schema(), document), expected) << file;
    if (expected.rfind("error: ", 0) != 0) ++resolved;
  }
  EXPECT_GE(resolved, 40);
}

TEST(ProblemFileSchema, ResolvesEveryShippedProblem) {
  // Resolution fills the defaults and leaves the optional keys without one out.
  int count = 0;
  for (const fs::path& file : problem_files()) {
    if (file.parent_path().filename() != "problems" || file.parent_path().parent_path() != fs::path(HAPSYN_SOURCE_DIR)) continue;
    const Json document = hapsyn::read_problem_file(file.string());
    Json input = document;
    input.erase("design");
    const Json resolved = hapsyn::validate_and_fill(hapsyn::problem_file_schema(), input, "");
    EXPECT_EQ(resolved["output"].contains("directory"), document.value("output", Json::object()).contains("directory")) << file;
    EXPECT_EQ(resolved.contains("indicators"), document.contains("indicators")) << file;
    EXPECT_EQ(resolved.contains("seed"), document.contains("seed")) << file;
    EXPECT_EQ(resolved["objectives"].size(), document["objectives"].size()) << file;
    for (const Json& o : resolved["objectives"]) {
      EXPECT_TRUE(o.contains("sense") && o.contains("weight") && o.contains("options")) << file;
    }
    ++count;
  }
  // Every file of problems/, counted here by a plain listing (problem_files() walks the tree).
  int listed = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(HAPSYN_SOURCE_DIR) / "problems")) {
    listed += entry.path().extension() == ".json" ? 1 : 0;
  }
  EXPECT_GE(listed, 20);
  EXPECT_EQ(count, listed);
}

// Mutations of a shipped problem, each refused (or accepted) the same way by both schemas.
TEST(ProblemFileSchema, EveryMessageIsTheFormerSchemas) {
  const Json base = hapsyn::read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/problems/fivebar-pareto-nsga2.json");
  const std::vector<std::pair<std::string, Json>> changes = {
      {"/mechanism", nullptr},
      {"/scene", nullptr},
      {"/objectives", nullptr},
      {"/solver", nullptr},
      {"/mechanism/plugin", nullptr},
      {"/solver/plugin", nullptr},
      {"/objectives/1/metric", nullptr},
      {"/objectives", Json::array()},
      {"/objectives", Json::object()},
      {"/objectives/1/sense", "max"},
      {"/objectives/1/weight", -1},
      {"/objectives/1/weight", "1"},
      {"/objectives/1/wieght", 1},
      {"/objectives/1/name", 3},
      {"/objectives/1/options", 3},
      {"/objectives/0", "gii"},
      {"/mechanism", "fivebar"},
      {"/mechanism/options", Json::array()},
      {"/mechanism/plugins", "fivebar"},
      {"/scene/options", 1.5},
      {"/solver/option", Json::object()},
      {"/namee", "x"},
      {"/name", 3},
      {"/description", false},
      {"/seed", -1},
      {"/seed", 1.5},
      {"/seed", Json::parse("18446744073709551615")},
      {"/seed", Json::parse("18446744073709551616")},
      {"/seed", "1"},
      {"/threads", 1025},
      {"/threads", -1},
      {"/threads", 2.0},
      {"/output", Json::array()},
      {"/output/plot", true},
      {"/output/directory", 3},
      {"/output/timeline", Json::array()},
      {"/indicators", Json::object()},
      {"/indicators", 1},
      {"/indicators/reference_point", Json::array({"a"})},
      {"/indicators/reference_point", Json::array({1.0, 2.0})},
      {"/indicators/reference_front", 2},
      {"/indicators/reference_pont", Json::array()},
  };
  for (const auto& [pointer, value] : changes) {
    Json document = base;
    if (value.is_null()) {
      const Json::json_pointer p(pointer);
      document.at(p.parent_pointer()).erase(p.back());
    } else {
      document[Json::json_pointer(pointer)] = value;
    }
    EXPECT_EQ(outcome(hapsyn::problem_file_schema(), document), outcome(former_schema(), document)) << pointer;
  }
}

TEST(ProblemFileSchema, MessagesNameThePathAndTheRule) {
  // The former schema's messages, written out (the tests of load_study check more of them).
  Json document = hapsyn::read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/problems/fivebar-pareto-nsga2.json");
  document.erase("design");
  Json no_scene = document;
  no_scene.erase("scene");
  EXPECT_EQ(outcome(hapsyn::problem_file_schema(), no_scene), "error: problem: scene: required key is missing");
  Json no_metric = document;
  no_metric["objectives"][1].erase("metric");
  EXPECT_EQ(outcome(hapsyn::problem_file_schema(), no_metric),
            "error: problem: objectives[1].metric: required key is missing");
  Json bad_sense = document;
  bad_sense["objectives"][1]["sense"] = "max";
  EXPECT_EQ(outcome(hapsyn::problem_file_schema(), bad_sense),
            "error: problem: objectives[1].sense = \"max\": must be one of \"maximize\", \"minimize\"");
  Json empty = document;
  empty["objectives"] = Json::array();
  EXPECT_EQ(outcome(hapsyn::problem_file_schema(), empty),
            "error: problem: objectives = []: must have at least 1 item");
  Json threads = document;
  threads["threads"] = 1025;
  EXPECT_EQ(outcome(hapsyn::problem_file_schema(), threads), "error: problem: threads = 1025: must be <= 1024");
}

}  // namespace
