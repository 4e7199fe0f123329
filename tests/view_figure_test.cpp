// hapsyn view's figure document (framework/app/view/view_figure.hpp): the human of a scene that
// models one, at the drawn sample, and every way a scene's info.figure can break the contract.
#include "view_figure.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace {

using hapsyn::Json;
using hapsyn::SampleSet;
using hapsyn::test::error_of;

SampleSet scene_with_figure() {
  SampleSet set;
  set.coordinates = {"x", "y", "z"};
  set.poses = SampleSet::RowMatrix::Zero(2, 3);
  SampleSet::RowMatrix arm(2, 6);
  arm << 0, 0, 1, 0, 0, 0.5,  //
      0, 0, 1, 0.5, 0, 1;
  set.attributes["arm"] = arm;
  set.info["figure"] = {{"arm_attribute", "arm"},
                        {"arm_joints", {"shoulder", "hand"}},
                        {"body_lines", {{{0, 0, 1}, {0, 0.3, 1}}}},
                        {"head_centre", {0, 0.15, 1.2}},
                        {"head_radius", 0.1}};
  return set;
}

TEST(ViewFigure, GivesTheArmAtTheDrawnSampleAndTheBody) {
  const SampleSet set = scene_with_figure();
  const Json figure = hapsyn_cli::figure_json(set, 1);
  EXPECT_EQ(figure["arm"], Json({{0.0, 0.0, 1.0}, {0.5, 0.0, 1.0}}));
  EXPECT_EQ(figure["arm_joints"], Json({"shoulder", "hand"}));
  EXPECT_EQ(figure["body_lines"], set.info["figure"]["body_lines"]);
  EXPECT_EQ(figure["head_radius"], 0.1);
}

TEST(ViewFigure, IsNullWithoutAFigureOrADrawnSample) {
  SampleSet set = scene_with_figure();
  EXPECT_TRUE(hapsyn_cli::figure_json(set, -1).is_null());
  set.info.erase("figure");
  EXPECT_TRUE(hapsyn_cli::figure_json(set, 0).is_null());
}

TEST(ViewFigure, AFigureOutsideTheContractIsRefusedNamingTheKeyTheValueAndTheRule) {
  const auto refusal = [](const char* key, const Json& value) {
    SampleSet set = scene_with_figure();
    set.info["figure"][key] = value;
    return error_of([&] { hapsyn_cli::figure_json(set, 0); });
  };
  EXPECT_EQ(refusal("arm_attribute", 3), "view: the scene's info.figure.arm_attribute = 3: must name a per-sample attribute");
  EXPECT_EQ(refusal("arm_attribute", "legs"),
            "view: the scene's info.figure.arm_attribute = \"legs\": the scene has no attribute of that name");
  EXPECT_EQ(refusal("arm_joints", Json({"shoulder"})),
            "view: the scene's info.figure.arm_joints = [\"shoulder\"]: must name the attribute's 2 joints");
  EXPECT_EQ(refusal("head_centre", Json({0, 1})), "view: the scene's info.figure.head_centre = [0,1]: must be 3 finite numbers");
  EXPECT_EQ(refusal("head_radius", -1), "view: the scene's info.figure.head_radius = -1: must be a finite number >= 0");
  EXPECT_EQ(refusal("body_lines", Json({{{0, 0}}})),
            "view: the scene's info.figure.body_lines = [[[0,0]]]: every point must be 3 finite numbers");
  EXPECT_EQ(refusal("body_lines", Json({1})),
            "view: the scene's info.figure.body_lines = [1]: every polyline must be a list of [x, y, z] points");
  EXPECT_EQ(refusal("body_lines", "torso"), "view: the scene's info.figure.body_lines = \"torso\": must be a list of polylines");

  SampleSet set = scene_with_figure();
  set.info["figure"] = "a human";
  EXPECT_EQ(error_of([&] { hapsyn_cli::figure_json(set, 0); }), "view: the scene's info.figure = \"a human\": must be an object");
  set = scene_with_figure();
  set.attributes["arm"] = SampleSet::RowMatrix::Zero(2, 4);
  EXPECT_EQ(error_of([&] { hapsyn_cli::figure_json(set, 0); }),
            "view: the scene's info.figure.arm_attribute = \"arm\": its attribute must have 3 columns per joint (x, y, "
            "z), at least 2 joints");
  set = scene_with_figure();
  set.attributes["arm"](0, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(error_of([&] { hapsyn_cli::figure_json(set, 0); }),
            "view: the scene's info.figure.arm_attribute = \"arm\": its values at the drawn sample must be finite");
}

}  // namespace
