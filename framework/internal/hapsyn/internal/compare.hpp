#pragma once
/// \file
/// Studies side by side (`hapsyn compare`): runs several problem files on the same machine, one
/// after the other, and tabulates their fronts' quality, evaluations and time; writes
/// compare.json, compare.csv and gnuplot plots (fronts overlaid, Unal's Figures 3 and 7; local
/// values over the workspace for studies with one design, Figure 2).
#include <hapsyn/cluster.hpp>
#include <hapsyn/json.hpp>
#include <hapsyn/internal/registry.hpp>

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
  /// The processes that share the studies (an MPI job, or one share under --shard); null: this
  /// one. Every rank calls run_compare with the same options (see run_compare).
  Cluster* cluster = nullptr;
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
///
/// Several processes (options.cluster): the studies are the tasks of one shardable task farm, in
/// file order; each runs entirely on the rank that takes it (the study folders must be on a file
/// system every rank sees), rank 0 tabulates them in file order and alone writes compare.json,
/// compare.csv and the plots; every rank returns its summary. The studies then run at the same
/// time, so a study that names another one's result as its reference front
/// (indicators.reference_front) needs that study finished by an earlier comparison.
/// Under --shard i/N (a ShardCluster) only the i-th contiguous share of the studies runs; the
/// summary covers those alone, has "shard": {"index" (1-based), "count", "cases": the share's
/// study folders} and "message" Cluster::shard_message(), status "finished" once the share is
/// done; merge_compare_shards combines the shares. compare.json records what the comparison
/// needs to run again: "options": {"files", "overrides", "seed" (or null), "plots"} and
/// "working_directory" (relative files are relative to it).
Json run_compare(const CompareOptions& options, const Registry& registry);

/// True when `dir` holds a comparison's summary (a regular file compare.json).
bool is_compare_output(const std::string& dir);

/// Combines the output directories of the shares of one comparison (`hapsyn compare ...
/// --shard i/N`) into out_dir, as merge_sweep_shards does for a sweep: the shares must have the
/// same options (files, overrides, seed), hapsyn version and share count, each share 1..N once;
/// their study folders are linked or copied into out_dir and the comparison runs there with
/// every study reused (none runs again; a relative file that is not found from the current
/// directory is taken relative to the recorded working directory). Returns the summary.
/// \throws Error("merge", ...) as merge_sweep_shards (with "comparison" for "sweep").
Json merge_compare_shards(const std::vector<std::string>& dirs, const std::string& out_dir, const Registry& registry,
                          int threads);

/// Prints the summary's table.
void print_compare(const Json& summary, std::ostream& out);

}  // namespace hapsyn
