#include "test_support.hpp"

#include <cmath>
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
