#include "test_support.hpp"

#include <hapsyn/data_file.hpp>

#include <boost/filesystem.hpp>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>

using hapsyn::Json;
using hapsyn::test::expect_error;
using hapsyn::test::fivebar_study;
using hapsyn::test::registry;

namespace {
void load(const Json& doc) { hapsyn::load_study(doc, registry()); }
}  // namespace

TEST(Study, ValidStudyLoadsWithResolvedDefaults) {
  const hapsyn::Study study = hapsyn::load_study(fivebar_study(), registry());
  EXPECT_EQ(study.problem->dimension(), 4u);
  EXPECT_EQ(study.problem->samples().size(), 25);
  EXPECT_EQ(study.resolved["solver"]["options"]["prune"], true);
  EXPECT_EQ(study.resolved["objectives"][0]["sense"], "maximize");
  EXPECT_EQ(study.resolved["design"]["l1"]["unit"], "m");
  EXPECT_EQ(study.plugins.size(), 4u);
}

TEST(Study, UnknownTopLevelKeySuggestsTheNearName) {
  Json doc = fivebar_study();
  doc["solvr"] = doc["solver"];
  expect_error([&] { load(doc); }, {"solvr", "did you mean 'solver'"});
}

TEST(Study, UnknownDesignVariableListsTheMechanismsVariables) {
  Json doc = fivebar_study();
  doc["design"]["l3"] = {{"value", 0.1}};
  expect_error([&] { load(doc); }, {"design.l3", "unknown design variable", "l0, l1, l2, r"});
}

TEST(Study, UnknownKeyInADesignVariableIsRefused) {
  Json doc = fivebar_study();
  doc["design"]["l1"]["stpe"] = 0.01;
  expect_error([&] { load(doc); }, {"design.l1.stpe", "did you mean 'step'"});
}

TEST(Study, LowerAboveUpperIsRefused) {
  Json doc = fivebar_study();
  doc["design"]["l1"] = {{"lower", 0.3}, {"upper", 0.2}};
  expect_error([&] { load(doc); }, {"design.l1.upper = 0.2: must be >= lower (0.3)"});
}

TEST(Study, StepLargerThanTheRangeIsRefused) {
  Json doc = fivebar_study();
  doc["design"]["l0"]["step"] = 0.5;
  expect_error([&] { load(doc); }, {"design.l0.step = 0.5", "must not exceed the range"});
}

TEST(Study, NonPositiveStepIsRefused) {
  Json doc = fivebar_study();
  doc["design"]["l0"]["step"] = 0.0;
  expect_error([&] { load(doc); }, {"design.l0.step = 0: must be > 0"});
}

TEST(Study, FixedValueOutsideTheBoundsIsRefused) {
  Json doc = fivebar_study();
  doc["design"]["l1"] = {{"value", 0.5}};
  expect_error([&] { load(doc); }, {"design.l1.value = 0.5", "must lie within the bounds [0.01, 0.3]"});
}

TEST(Study, FixedValueWithWidenedBoundsIsAccepted) {
  Json doc = fivebar_study();
  doc["design"]["l1"] = {{"value", 0.5}, {"lower", 0.01}, {"upper", 1.0}};
  EXPECT_NO_THROW(load(doc));
}

TEST(Study, BoundOutsideTheMechanismsLimitIsRefused) {
  Json doc = fivebar_study();
  doc["design"]["l1"]["lower"] = 0.0;
  expect_error([&] { load(doc); }, {"design.l1.lower = 0", "must be >= 0.0001", "mechanism's limit"});
}

TEST(Study, NonFiniteNumbersAreRefused) {
  Json doc = fivebar_study();
  doc["design"]["l0"]["upper"] = std::numeric_limits<double>::infinity();
  expect_error([&] { load(doc); }, {"design.l0.upper", "must be finite"});
  Json doc2 = fivebar_study();
  doc2["scene"]["options"]["side"] = std::numeric_limits<double>::infinity();
  expect_error([&] { load(doc2); }, {"scene.options.side", "finite"});
}

TEST(Study, WrongTypesAreRefused) {
  Json doc = fivebar_study();
  doc["scene"]["options"]["side"] = "big";
  expect_error([&] { load(doc); }, {"scene.options.side = \"big\"", "must be a number"});
  Json doc2 = fivebar_study();
  doc2["design"]["l0"]["lower"] = "zero";
  expect_error([&] { load(doc2); }, {"design.l0.lower = \"zero\"", "must be a number"});
  Json doc3 = fivebar_study();
  doc3["objectives"] = Json::object();
  expect_error([&] { load(doc3); }, {"objectives", "array"});
}

TEST(Study, UnknownPluginSuggestsTheNearName) {
  Json doc = fivebar_study();
  doc["mechanism"]["plugin"] = "fivebars";
  expect_error([&] { load(doc); }, {"unknown plugin 'fivebars'", "did you mean 'fivebar'"});
}

TEST(Study, PluginOfTheWrongKindIsRefused) {
  Json doc = fivebar_study();
  doc["objectives"][0]["metric"] = "grid";
  expect_error([&] { load(doc); }, {"objectives[0].metric = \"grid\"", "is a solver plugin, not a metric plugin"});
}

TEST(Study, MissingRequiredSectionIsRefused) {
  Json doc = fivebar_study();
  doc.erase("solver");
  expect_error([&] { load(doc); }, {"solver", "required"});
}

TEST(Study, GridSolverNeedsAStepForEveryFreeVariable) {
  Json doc = fivebar_study();
  doc["design"]["l0"].erase("step");
  expect_error([&] { load(doc); }, {"design.l0 has no step"});
}

TEST(Study, EvaluateSolverNeedsAFixedDesign) {
  expect_error([&] { load(fivebar_study("evaluate")); }, {"evaluate", "design.l0 is not fixed"});
}

TEST(Study, DuplicateObjectiveNamesAreRefused) {
  Json doc = fivebar_study();
  doc["objectives"].push_back({{"metric", "gii"}});
  expect_error([&] { load(doc); }, {"objectives[1].name = \"gii\"", "duplicate objective name"});
}

TEST(Study, SceneOptionRelationsAreCheckedByThePlugin) {
  Json doc = fivebar_study();
  doc["scene"]["options"]["step"] = 0.03;
  expect_error([&] { load(doc); }, {"scene.options", "step"});
}

TEST(Study, OverridesApplyBeforeValidation) {
  Json doc = fivebar_study();
  hapsyn::apply_override(doc, "scene.options.step=0.05");
  hapsyn::apply_override(doc, "solver.options={}");
  const hapsyn::Study study = hapsyn::load_study(doc, registry());
  EXPECT_EQ(study.problem->samples().size(), 9);
}

// ---- hostile or mistaken input (issue 20) ----

TEST(StudyNames, StudyNameThatIsAPathIsRefused) {
  // "../../x" wrote outside results/.
  Json doc = fivebar_study();
  doc["name"] = "../../x";
  expect_error([&] { load(doc); }, {"problem: name = \"../../x\": must not start with '.'"});
  doc["name"] = "a/b";
  expect_error([&] { load(doc); }, {"name = \"a/b\": must use only letters, digits, '.', '_' and '-'", "'/' is not allowed"});
  doc["name"] = std::string(101, 'a');
  expect_error([&] { load(doc); }, {"name = \"aaaa", "must have at most 100 characters (it has 101)"});
  doc["name"] = "fivebar-gii_v2.1";
  EXPECT_NO_THROW(load(doc));
}

TEST(StudyNames, PluginNameThatIsAPathIsRefusedNamingTheKey) {
  Json doc = fivebar_study();
  doc["mechanism"]["plugin"] = "y.so/../payload";
  expect_error([&] { load(doc); }, {"problem: mechanism.plugin = \"y.so/../payload\": must use only letters"});
  doc = fivebar_study();
  doc["objectives"][0]["metric"] = "../gii";
  expect_error([&] { load(doc); }, {"problem: objectives[0].metric = \"../gii\": must not start with '.'"});
}

TEST(StudyNames, UnknownPluginNamesTheKeyThatNamedIt) {
  Json doc = fivebar_study();
  doc["scene"]["plugin"] = "planar_squares";
  expect_error([&] { load(doc); }, {"problem: scene.plugin = \"planar_squares\": registry: unknown plugin 'planar_squares'",
                                    "did you mean 'planar_square'"});
  doc = fivebar_study();
  doc["solver"]["plugin"] = "gird";
  expect_error([&] { load(doc); }, {"problem: solver.plugin = \"gird\": registry: unknown plugin"});
  doc = fivebar_study();
  doc["objectives"][0]["metric"] = "gi";
  expect_error([&] { load(doc); }, {"problem: objectives[0].metric = \"gi\": registry: unknown plugin 'gi'"});
}

TEST(StudyWeights, AllZeroWeightsAreRefusedForASingleObjectiveSolver) {
  // Every design scored 0 and the solver reported an arbitrary one as converged.
  Json doc = fivebar_study();
  doc["objectives"] = Json::array({{{"metric", "gii"}, {"weight", 0}}, {{"metric", "gdi"}, {"weight", 0.0}}});
  expect_error([&] { load(doc); }, {"problem: objectives: every weight is 0 (gii, gdi)", "nonzero \"weight\""});
  doc["objectives"][1]["weight"] = 0.5;
  EXPECT_NO_THROW(load(doc));
}

TEST(StudyWeights, NegativeWeightIsRefused) {
  Json doc = fivebar_study();
  doc["objectives"][0]["weight"] = -1;
  expect_error([&] { load(doc); }, {"problem: objectives[0].weight = -1: must be >= 0"});
}

TEST(StudySchema, ThreadsOutOfRangeAreRefused) {
  Json doc = fivebar_study();
  doc["threads"] = 4294967297LL;
  expect_error([&] { load(doc); }, {"problem: threads = 4294967297: must be <= 1024"});
  doc["threads"] = -1;
  expect_error([&] { load(doc); }, {"problem: threads = -1: must be >= 0"});
  doc["threads"] = 1024;
  EXPECT_NO_THROW(load(doc));
}

TEST(StudySchema, SeedIsAnUnsigned64BitInteger) {
  Json doc = fivebar_study();
  doc["seed"] = -1;
  expect_error([&] { load(doc); }, {"problem: seed = -1: must be >= 0"});
  doc["seed"] = 1.5;
  expect_error([&] { load(doc); }, {"problem: seed = 1.5: must be an integer"});
  doc["seed"] = std::numeric_limits<std::uint64_t>::max();
  EXPECT_EQ(hapsyn::load_study(doc, registry()).resolved["seed"].get<std::uint64_t>(),
            std::numeric_limits<std::uint64_t>::max());
}

TEST(StudyText, InvalidUtf8FromAnOverrideIsRefusedAtLoad) {
  // A string taken as is by --set passed validation and made dump() throw after the solve.
  Json doc = fivebar_study();
  doc["description"] = "caf\xe9";
  expect_error([&] { load(doc); }, {"problem: description = \"caf\\xe9\": invalid UTF-8 at byte 3"});
}

TEST(StudyDesign, StepNotDividingTheRangeIsRefusedAtLoad) {
  Json doc = fivebar_study();
  doc["design"]["l1"] = {{"lower", 0.01}, {"upper", 0.3}, {"step", 0.07}};
  expect_error([&] { load(doc); }, {"design.l1.step = 0.07: does not divide [0.01, 0.3] (4.14 steps)",
                                    "use 0.0725 (4 steps) or 0.058 (5 steps), or set upper to 0.29"});
}

TEST(StudyDesign, TinyStepIsRefusedAtLoad) {
  Json doc = fivebar_study();
  doc["design"]["l0"]["step"] = 1e-20;
  expect_error([&] { load(doc); }, {"design.l0.step = 1e-20: makes 3e+19 grid points"});
}

namespace {
// A fresh temporary folder, not the current directory.
boost::filesystem::path temp_folder(const std::string& name) {
  const auto dir = boost::filesystem::temp_directory_path() / boost::filesystem::unique_path(name + "-%%%%%%");
  boost::filesystem::create_directories(dir);
  return dir;
}
}  // namespace

TEST(StudyPaths, ReferenceFrontResolvesAgainstTheProblemFilesFolder) {
  const auto dir = temp_folder("hapsyn-study-paths");
  std::ofstream(dir / "ref.json") << Json{{"front", {{{"objectives", {{"gii", 0.5}, {"gdi", 0.1}}}}}}}.dump();
  Json doc = fivebar_study("nbi");
  doc["objectives"] = Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  doc["indicators"] = {{"reference_front", "ref.json"}};
  ASSERT_NE(boost::filesystem::current_path(), dir);
  {
    const hapsyn::ProblemDirectoryScope scope((dir / "problem.json").string());
    const hapsyn::Study study = hapsyn::load_study(doc, registry());
    EXPECT_EQ(study.reference_front.size(), 1u);
    EXPECT_EQ(study.resolved["indicators"]["reference_front"], (dir / "ref.json").string());
  }
  // Outside the scope the current directory is used, as before: not written yet, not an error.
  const hapsyn::Study outside = hapsyn::load_study(doc, registry());
  EXPECT_TRUE(outside.reference_front.empty());
  EXPECT_EQ(outside.reference_front_missing, (boost::filesystem::current_path() / "ref.json").string());
  boost::filesystem::remove_all(dir);
}

TEST(StudyPaths, PluginDataFileResolvesAgainstTheProblemFilesFolderFirst) {
  const auto dir = temp_folder("hapsyn-study-data");
  std::ofstream(dir / "points.csv") << "x,y\n0.0,0.2\n0.01,0.2\n";
  Json doc = fivebar_study();
  doc["scene"] = {{"plugin", "point_list"}, {"options", {{"file", "points.csv"}}}};
  expect_error([&] { load(doc); }, {"point_list: options.file = \"points.csv\": no such file"});
  const hapsyn::ProblemDirectoryScope scope((dir / "problem.json").string());
  EXPECT_EQ(hapsyn::problem_directory(), dir.string());
  EXPECT_EQ(hapsyn::load_study(doc, registry()).problem->samples().size(), 2);
  EXPECT_EQ(hapsyn::find_data_file("x", "file", "points.csv"), (dir / "points.csv").string());
  boost::filesystem::remove_all(dir);
}

TEST(StudyPaths, ScopesNestAndRestoreThePreviousFolder) {
  EXPECT_EQ(hapsyn::problem_directory(), "");
  {
    const hapsyn::ProblemDirectoryScope outer("/a/b/p.json");
    {
      const hapsyn::ProblemDirectoryScope inner("/c/q.json");
      EXPECT_EQ(hapsyn::problem_directory(), "/c");
    }
    EXPECT_EQ(hapsyn::problem_directory(), "/a/b");
  }
  EXPECT_EQ(hapsyn::problem_directory(), "");
}
