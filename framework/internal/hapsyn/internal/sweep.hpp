#pragma once
/// \file
/// Speed against accuracy: run one study across values of some keys and measure each run's
/// error against a reference run, with its time and evaluation count (`hapsyn sweep`).
#include <hapsyn/cluster.hpp>
#include <hapsyn/json.hpp>
#include <hapsyn/pareto.hpp>  // inverted_generational_distance
#include <hapsyn/internal/registry.hpp>

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn {

/// One varied axis: one or more keys set together to each value in turn.
struct SweepAxis {
  std::vector<std::string> paths;  ///< e.g. {"design.l0.step", "design.l1.step"}
  std::vector<Json> values;        ///< e.g. {0.01, 0.005}
};

/// Parses "path[,path...]=v1,v2,..." (values are JSON when they parse, else strings; commas
/// inside brackets, braces or quotes do not split). \throws Error("sweep", ...) when malformed.
SweepAxis parse_sweep_axis(const std::string& spec);

struct SweepOptions {
  std::vector<SweepAxis> axes;
  /// Overrides ("path=value") that make the reference run; empty = the last combination.
  std::vector<std::string> reference;
  std::string output_directory = "results/sweep";
  int threads = 0;
  std::optional<std::uint64_t> seed;
  bool quiet = true;  ///< no solver progress lines
  /// Setting it asks the runs to stop (each run's solver returns "stopped"; no further run
  /// starts). Null: no stop request possible.
  const std::atomic<bool>* stop = nullptr;
  /// Run every combination again, overwriting finished runs (by default a run folder that holds
  /// a finished result.json of the same problem and seed is reused: see run_sweep).
  bool force = false;
  /// The processes that share the runs (an MPI job, or one share under --shard); null: this
  /// one. Every rank calls run_sweep with the same arguments (see run_sweep).
  Cluster* cluster = nullptr;
};

/// Runs the grid of combinations (and the reference when it is not one of them), writes
/// <out>/sweep.csv, <out>/sweep.json and one sub-directory per run, and returns the summary:
/// per run its values, wall time, evaluations, status, objectives and the errors against the
/// reference (max objective difference, design distance [SI], front IGD for Pareto studies),
/// and "status": "finished" or "stopped".
///
/// Continuing: a run folder that already holds a finished result.json (any status but
/// "stopped") of the same resolved problem (and, when options.seed is set, the same seed) is
/// reused, not run again (its row says "reused": true and keeps the stored times); a run whose
/// result is "stopped", or that left only a checkpoint, is resumed from its checkpoint. So the
/// same `hapsyn sweep` command run again after a stop continues the sweep. options.force runs
/// everything again.
///
/// Stopping (options.stop set): the run in progress stops (its solver returns "stopped" and
/// writes its checkpoint), no further run starts, and sweep.csv and sweep.json are written with
/// the finished runs, "status": "stopped" and a "message" saying how to continue; the errors
/// against the reference are null when the reference did not run.
/// \throws Error for a malformed axis or an invalid study (before any run starts);
///         Error("sweep", "<run folder>: ...; delete it, or choose another --out") when a run
///         folder holds a result of another problem or seed, or an unreadable result.json; a
///         run's own errors as Error("sweep", "<run folder> (<values>): <error>").
///
/// Several processes (options.cluster): the runs are the tasks of one shardable task farm, in
/// the order above (the reference last when it is not a combination). Each run happens entirely
/// on the rank that takes it (the run folders must be on a file system every rank sees); its
/// result reaches rank 0, which alone writes sweep.json, sweep.csv and the plot, with the rows in
/// run order whichever rank ran them; every rank returns rank 0's summary. Finished runs are
/// found (and foreign results refused) by rank 0 before the farm, so every rank throws the same
/// errors before any run starts.
/// Under --shard i/N (a ShardCluster) only the i-th contiguous share of the runs (see
/// shard_tasks) runs; the summary covers those runs alone, has "shard": {"index" (1-based),
/// "count", "cases": the share's run folders} and "message" Cluster::shard_message(); its
/// status is "finished" once the share is done. merge_sweep_shards combines the shares.
///
/// sweep.json records what the sweep needs to run again: "problem" (the document after --set),
/// "problem_directory" (the folder its relative paths resolve against, or ""), and "options":
/// {"axes": [{"paths", "values"}], "reference": the overrides, "seed": options.seed or null}.
/// Its "runs" hold per run, besides the above, "case": its folder name.
Json run_sweep(const Json& problem, const SweepOptions& options, const Registry& registry);

/// True when `dir` holds a sweep's summary (a regular file sweep.json): what `hapsyn merge`
/// tells sweeps from other output directories by.
bool is_sweep_output(const std::string& dir);

/// Combines the output directories of the shares of one sweep (`hapsyn sweep ... --shard i/N`,
/// i = 1..N, given in any order) into `out_dir`: checks the shares belong together, hard-links
/// (or copies, across file systems) every share's run folders into out_dir (replacing folders of
/// those names there), then runs the sweep in out_dir on this process with `threads` threads per
/// run, reusing every run (none runs again). Returns the summary, the same as a single
/// `hapsyn sweep` gives (values, objectives, errors; "reused" is true and the times are the
/// shares'), also written as out_dir/sweep.json and sweep.csv.
/// \throws Error("merge", ...) naming the rule and the directory: no directory given;
///         "<dir>/sweep.json: not a readable sweep summary (...)"; "<dir> is not a shard of a
///         sweep (its sweep.json has no "shard" entry: it ran without --shard)"; "<dir> (shard
///         2/3) is not of the same sweep as <dir0> (shard 1/3): its <problem / axes / reference
///         / seed / hapsyn version / shard count> differs"; "shard 2/3 is given twice (<dirA>,
///         <dirB>)"; "shard 2/3 is missing (given: 1/3, 3/3)"; "<dir> (shard 2/3) stopped
///         before its runs finished ..."; "<out_dir> is shard 1/3's directory ..."; "<dir>/<run
///         folder>: missing ..." or one that holds no finished result of the sweep's run.
Json merge_sweep_shards(const std::vector<std::string>& dirs, const std::string& out_dir, const Registry& registry,
                        int threads);

}  // namespace hapsyn
