// Design spaces: the checks build_design_space makes on grid steps, and grid counts.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <hapsyn/design_space.hpp>
#include <hapsyn/error.hpp>

#include "test_support.hpp"

namespace {

using hapsyn::Json;
using hapsyn::test::error_of;
using ::testing::HasSubstr;

std::vector<hapsyn::VariableDecl> lengths(const std::vector<std::string>& names) {
  std::vector<hapsyn::VariableDecl> decls;
  for (const std::string& n : names) {
    hapsyn::VariableDecl d;
    d.name = n;
    d.unit = "m";
    d.default_lower = {0.0};
    d.default_upper = {1.0};
    d.hard_lower = {0.0};
    decls.push_back(d);
  }
  return decls;
}

hapsyn::DesignSpace space_of(const Json& design, const std::vector<std::string>& names = {"l0", "l1"}) {
  Json resolved;
  return hapsyn::build_design_space(design, lengths(names), resolved);
}

std::string error_for(const Json& design, const std::vector<std::string>& names = {"l0", "l1"}) {
  return error_of([&] { space_of(design, names); });
}

TEST(DesignSpaceStep, StepNotDividingTheRangeIsRefusedWithTheNearestDividingSteps) {
  // 0.07 over [0.01, 0.3] never visited 0.3 and reported GII 0.776594 instead of 0.782733.
  EXPECT_EQ(error_for({{"l1", {{"lower", 0.01}, {"upper", 0.3}, {"step", 0.07}}}}),
            "problem: design.l1.step = 0.07: does not divide [0.01, 0.3] (4.14 steps), so the grid would never "
            "visit the upper bound: use 0.0725 (4 steps) or 0.058 (5 steps), or set upper to 0.29");
}

TEST(DesignSpaceStep, StepDividingTheRangeUpToRoundingIsAccepted) {
  // (0.3 - 0.01) / 0.01 evaluates to 28.999999999999996.
  const hapsyn::DesignSpace space = space_of({{"l0", {{"value", 0.1}}}, {"l1", {{"lower", 0.01}, {"upper", 0.3}, {"step", 0.01}}}});
  EXPECT_EQ(space.grid_count(0), 30);
  EXPECT_DOUBLE_EQ(space.grid_value(0, 29), 0.3);
}

TEST(DesignSpaceStep, IntegerStepNotDividingTheRangeProposesOnlyAnUpperBound) {
  std::vector<hapsyn::VariableDecl> decls = lengths({"n"});
  decls[0].integer = true;
  decls[0].default_upper = {10.0};
  Json resolved;
  EXPECT_EQ(error_of([&] { hapsyn::build_design_space({{"n", {{"step", 3}}}}, decls, resolved); }),
            "problem: design.n.step = 3: does not divide [0, 10] (3.33 steps), so the grid would never visit the "
            "upper bound: set upper to 9");
}

TEST(DesignSpaceStep, TinyStepIsRefusedInsteadOfOverflowingTheCount) {
  // 1e-20 overflowed the count into a 1-point axis: a wrong answer reported as success.
  EXPECT_EQ(error_for({{"l0", {{"lower", 0.0}, {"upper", 0.3}, {"step", 1e-20}}}}),
            "problem: design.l0.step = 1e-20: makes 3e+19 grid points on [0, 0.3], more than the 1e+09 a design "
            "variable may have; use a larger step");
}

TEST(DesignSpaceStep, GridOfMoreThanTheCapIsRefusedNamingEachAxis) {
  Json design = Json::object();
  const std::vector<std::string> names = {"a", "b", "c"};
  for (const std::string& n : names) design[n] = {{"lower", 0.0}, {"upper", 1.0}, {"step", 1e-8}};
  EXPECT_THAT(error_for(design, names),
              HasSubstr("problem: design: the grid has 1e+24 points (a: 100000001 x b: 100000001 x c: 100000001), more than the "
                        "9e+18 a design grid may have"));
}

TEST(DesignSpaceStep, GridCountOfAHandBuiltSpaceIsCheckedToo) {
  hapsyn::DesignComponent c;
  c.name = c.variable = "l0";
  c.upper = 0.3;
  c.step = 1e-20;
  const hapsyn::DesignSpace space({c});
  EXPECT_THAT(error_of([&] { space.grid_count(0); }), HasSubstr("design.l0: a step of 1e-20 makes more than 1000000000"));
}

}  // namespace
