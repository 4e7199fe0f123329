// Objectives per group of samples: each group's value is the study's own evaluation restricted to
// that group's samples; the spread is the plain mean and sample deviation over the groups; the
// groupings a scene declares are checked centrally.
#include "test_support.hpp"

#include <hapsyn/internal/groups.hpp>
#include <hapsyn/internal/maps.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

using hapsyn::Json;
using hapsyn::test::fivebar_study;
using hapsyn::test::registry;
using ::testing::HasSubstr;

namespace {
const std::vector<double> kDesign = {0.0004, 0.2997, 0.3, 0.4196};

// The five-bar study of the test support with its samples split into three groups (sample i in
// group i mod 3) and a second grouping that puts every sample in one group.
std::shared_ptr<const hapsyn::Problem> grouped_problem(const hapsyn::Problem& base) {
  auto samples = std::make_shared<hapsyn::SampleSet>(base.samples());
  hapsyn::SampleGrouping thirds{"third", {"a", "b", "c"}, {}}, all{"all", {"everything"}, {}};
  for (int i = 0; i < samples->size(); ++i) {
    thirds.of_sample.push_back(i % 3);
    all.of_sample.push_back(0);
  }
  samples->groups = {thirds, all};
  hapsyn::check_groups(*samples, "test");
  auto mechanism = registry().create_mechanism("fivebar", Json{{"rho", 1.08}}, "mechanism");
  return std::make_shared<const hapsyn::Problem>("fivebar", mechanism, samples, base.metrics(), base.objectives(),
                                                 base.design_space());
}
}  // namespace

TEST(Groups, EachGroupIsTheEvaluationOfItsSamples) {
  Json doc = fivebar_study();
  doc["objectives"] = Json::array({{{"metric", "gii"}}, {{"metric", "gdi"}}});
  const hapsyn::Study study = hapsyn::load_study(doc, registry());
  const auto problem = grouped_problem(*study.problem);
  const hapsyn::SampleRecords records = hapsyn::record_samples(*problem, problem->full_design(kDesign.data()));
  const std::vector<hapsyn::GroupTable> tables = hapsyn::group_tables(*problem, records);
  ASSERT_EQ(tables.size(), 2u);
  EXPECT_EQ(tables[0].grouping, "third");
  auto ws = problem->make_eval_scratch();
  for (int g = 0; g < 3; ++g) {
    std::vector<int> subset;
    for (int i = g; i < problem->samples().size(); i += 3) subset.push_back(i);
    hapsyn::EvalOptions options;
    options.subset = &subset;
    const hapsyn::Evaluation& e = problem->evaluate(kDesign.data(), *ws, options);
    ASSERT_EQ(e.status, hapsyn::EvalStatus::kFeasible);
    EXPECT_EQ(tables[0].samples[static_cast<std::size_t>(g)], static_cast<int>(subset.size()));
    EXPECT_DOUBLE_EQ(tables[0].values(g, 0), e.objectives[0]);
    EXPECT_DOUBLE_EQ(tables[0].values(g, 1), e.objectives[1]);
  }
  // The one-group grouping is the whole design's value, with no spread.
  const hapsyn::Evaluation& whole = problem->evaluate(kDesign.data(), *ws);
  EXPECT_DOUBLE_EQ(tables[1].values(0, 0), whole.objectives[0]);
  EXPECT_EQ(tables[1].standard_deviation(0), 0.0);
  // Mean and sample standard deviation over the three groups, computed here by hand.
  const Eigen::VectorXd v = tables[0].values.col(0);
  const double mean = v.mean();
  const double sd = std::sqrt((v.array() - mean).square().sum() / 2.0);
  EXPECT_DOUBLE_EQ(tables[0].mean(0), mean);
  EXPECT_NEAR(tables[0].standard_deviation(0), sd, 1e-15);
}

TEST(Groups, CsvJsonAndTextCarryEveryGroup) {
  Json doc = fivebar_study();
  const hapsyn::Study study = hapsyn::load_study(doc, registry());
  const auto problem = grouped_problem(*study.problem);
  const hapsyn::SampleRecords records = hapsyn::record_samples(*problem, problem->full_design(kDesign.data()));
  const std::vector<hapsyn::GroupTable> tables = hapsyn::group_tables(*problem, records);
  const std::string csv = hapsyn::groups_csv(tables);
  EXPECT_THAT(csv, HasSubstr("grouping,group,samples,gii\n"));
  EXPECT_THAT(csv, HasSubstr("third,b,"));
  EXPECT_THAT(csv, HasSubstr("third,std,"));
  const Json json = hapsyn::groups_json(tables);
  ASSERT_TRUE(json.contains("third"));
  EXPECT_EQ(json["third"]["groups"].size(), 3u);
  EXPECT_DOUBLE_EQ(json["third"]["groups"][2]["values"]["gii"].get<double>(), tables[0].values(2, 0));
  const std::string text = hapsyn::groups_text(json);
  EXPECT_THAT(text, HasSubstr("everything"));
  EXPECT_THAT(text, HasSubstr("std"));
  EXPECT_THAT(hapsyn::groups_text(json, 2), HasSubstr("third: 3 groups (groups.csv)"));
}

TEST(Groups, BadGroupingsAreRefusedWithTheRule) {
  hapsyn::SampleSet s;
  s.poses = hapsyn::SampleSet::RowMatrix::Zero(3, 2);
  const auto error = [&](hapsyn::SampleGrouping g) {
    s.groups = {std::move(g)};
    return hapsyn::test::error_of([&] { hapsyn::check_groups(s, "scene_x"); });
  };
  EXPECT_THAT(error({"", {"a"}, {0, 0, 0}}), HasSubstr("scene_x: groups[0].name is empty"));
  EXPECT_THAT(error({"g", {}, {0, 0, 0}}), HasSubstr("has no labels"));
  EXPECT_THAT(error({"g", {"a", "a"}, {0, 0, 0}}), HasSubstr("labels[1] = \"a\": listed twice"));
  EXPECT_THAT(error({"g", {"a", ""}, {0, 0, 0}}), HasSubstr("labels[1] is empty"));
  EXPECT_THAT(error({"g", {"a"}, {0, 0}}), HasSubstr("of_sample has 2 entries for 3 samples"));
  EXPECT_THAT(error({"g", {"a"}, {0, 1, 0}}), HasSubstr("of_sample[1] = 1: must be in [0, 1)"));
  s.groups = {{"g", {"a"}, {0, 0, 0}}, {"g", {"b"}, {0, 0, 0}}};
  EXPECT_THAT(hapsyn::test::error_of([&] { hapsyn::check_groups(s, "scene_x"); }),
              HasSubstr("groups[1].name = \"g\": two groupings have this name"));
}

TEST(Groups, MissingQuantitiesAreNamedNotNumbered) {
  Json doc = fivebar_study();
  doc["objectives"] = Json::array({{{"metric", "motion_feasibility"}, {"options", {{"share", "velocity"}}}}});
  EXPECT_THAT(hapsyn::test::error_of([&] { hapsyn::load_study(doc, registry()); }),
              HasSubstr("does not provide: actuator_limits, joint_velocity"));
}

TEST(Groups, TimelineOfASceneWithoutTrajectoriesIsRefusedAtLoad) {
  Json doc = fivebar_study();
  doc["output"] = {{"timeline", "S01/reaching"}};
  EXPECT_THAT(hapsyn::test::error_of([&] { hapsyn::load_study(doc, registry()); }),
              HasSubstr("output.timeline = \"S01/reaching\": the scene has no trajectories"));
}
