#pragma once
/// \file
/// Studies side by side (`hapsyn compare`): runs several problem files on the same machine, one
/// after the other, and tabulates their fronts' quality, evaluations and time; writes
/// compare.json, compare.csv and gnuplot plots (fronts overlaid, Unal's Figures 3 and 7; local
/// values over the workspace for studies with one design, Figure 2).
#include <hapsyn/json.hpp>
#include <hapsyn/registry.hpp>

#include <atomic>
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace hapsyn {

struct CompareOptions {
  std::vector<std::string> files;      ///< problem files, run in this order
  std::vector<std::string> overrides;  ///< "path=value", applied to every study
  std::string output_directory = "results/compare";
  int threads = 0;
  std::optional<std::uint64_t> seed;
  bool plots = true;                   ///< write the gnuplot plots (needs gnuplot)
  /// Setting it asks the runs to stop (each run's solver returns "stopped"; no further run
  /// starts). Null: no stop request possible.
  const std::atomic<bool>* stop = nullptr;
  /// Run every study again, overwriting finished ones (by default a study folder that holds a
  /// finished result.json of the same problem and seed is reused: see run_compare).
  bool force = false;
};

/// Runs each study into <out>/<study name>/ (a study is validated just before it runs, so a
/// reference study listed first can produce the reference front later ones name in their
/// "indicators" section), then writes <out>/compare.json, compare.csv and the plots.
/// Returns the summary: "rows" (study, file, solver, status, reused, points, hypervolume,
/// spacing, spacing_relative, generational_distance, inverted_generational_distance,
/// max_domination_gap, best_dominated, designs, samples, wall_time_s, time_ratio to the first
/// study), "plots", "machine", "hapsyn", "status" ("finished" or "stopped") and, when stopped,
/// "message".
///
/// Continuing: a study folder that already holds a finished result.json (any status but
/// "stopped") of the same resolved problem (and seed, when options.seed is set) is reused, not
/// run again; a stopped study is resumed from its checkpoint; so the same `hapsyn compare`
/// command run again after a stop continues. options.force runs every study again.
/// Stopping (options.stop set): the study in progress stops, no further study starts, and
/// compare.json and compare.csv hold the finished studies.
/// \throws Error("compare", ...) with no file, two studies of the same name, or a study folder
///         that holds a result of another problem or seed ("<folder> holds a result of another
///         problem (first difference at ...); delete it, or choose another --out"); a study's
///         own errors as `hapsyn run` reports them, prefixed with its file.
Json run_compare(const CompareOptions& options, const Registry& registry);

/// Prints the summary's table.
void print_compare(const Json& summary, std::ostream& out);

}  // namespace hapsyn
