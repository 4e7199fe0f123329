#pragma once
/// \file
/// Objectives per group of samples (SampleGrouping: the subject, activity or recording a sample
/// comes from) and along time within one recording: the tables and plots of a validation on
/// recorded motion (Fennel 2022, section VII-B: shares per subject with their spread).
#include <hapsyn/json.hpp>
#include <hapsyn/internal/maps.hpp>

#include <Eigen/Core>
#include <string>
#include <vector>

namespace hapsyn {

/// Every objective per group of one SampleGrouping of the scene, and its spread across groups.
struct GroupTable {
  std::string grouping;                 ///< SampleGrouping::name, e.g. "subject"
  std::vector<std::string> objectives;  ///< the objectives' names (columns)
  std::vector<std::string> labels;      ///< the groups (rows), in the scene's order
  std::vector<int> samples;             ///< per group: its sample count
  Eigen::MatrixXd values;               ///< groups x objectives (grouped_objective_values); NaN = undefined
  /// Per objective, over the groups with a value: the mean and the sample standard deviation
  /// (n - 1 in the denominator; 0 for a single group) of the group values, each group counting
  /// once whatever its size (the paper's spread across subjects). NaN when no group has a value.
  Eigen::VectorXd mean, standard_deviation;
};

/// One GroupTable per grouping of the scene (none when it declares no groupings).
std::vector<GroupTable> group_tables(const Problem& problem, const SampleRecords& records);

/// groups.csv: grouping, group, samples, one column per objective; after each grouping's groups
/// a row "mean" and a row "std" (empty cells = undefined).
std::string groups_csv(const std::vector<GroupTable>& tables);

/// result.json's "groups": {grouping: {"objectives": [...], "groups": [{"label", "samples",
/// "values": {objective: value or null}}], "mean": {...}, "std": {...}}}.
Json groups_json(const std::vector<GroupTable>& tables);

/// result.json's "groups" (groups_json) as aligned text for the terminal: one table per
/// grouping with at most `max_rows` groups (a larger one is named with its count), values as
/// percentages when every value of an objective lies in [0, 1].
std::string groups_text(const Json& groups, std::size_t max_rows = 20);

/// Writes timeline.{dat,gp,png} into `directory`: every objective evaluated on each single
/// sample of the group `label` of grouping `grouping`, against the scene attribute "time" (one
/// panel per objective, stepped). Does nothing and returns "" when the scene lacks the time
/// attribute or the grouping; sets `message` when gnuplot is missing or fails.
/// \returns the PNG's file name, or "" when not rendered. \throws Error("output") when the
/// label is not a group of the grouping (the message lists the groups) or a file cannot be written.
std::string plot_timeline(const Problem& problem, const SampleRecords& records, const std::string& grouping,
                          const std::string& label, const std::string& directory, std::string& message);

}  // namespace hapsyn
