#pragma once
/// \file
/// A batch of study cases (`hapsyn sweep`'s runs, `hapsyn compare`'s studies): run each into its
/// own directory, reuse a finished one, resume a stopped one, split the batch into shards, and
/// gather the shards' directories for a merge. The caller says what a case is (how it is checked
/// for reuse, how it runs, what of its result rank 0 keeps: its "record") and tabulates.
#include <hapsyn/cluster.hpp>
#include <hapsyn/json.hpp>
#include <hapsyn/internal/study_runner.hpp>  // RunOptions

#include <atomic>
#include <cstdint>
#include <exception>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace hapsyn {

/// The cases of a batch and what to do with each. Every rank gives the same batch.
struct CaseBatch {
  long long count = 0;           ///< the cases 0..count-1, in order
  std::string output_directory;  ///< created by rank 0; each case runs in a folder of it
  /// Names the errors of rank 0's reuse decisions that are not hapsyn::Errors ("sweep").
  std::string component;
  /// Reuse nothing: every case of the share runs (the caller's run then overwrites).
  bool force = false;
  /// Setting it asks the cases to stop: the one in progress stops (its run returns nullopt), no
  /// further one starts. Null: no stop request possible.
  const std::atomic<bool>* stop = nullptr;
  /// Rank 0, before any case runs, for each case of this share in order (not with `force`): the
  /// record of its finished result to reuse, or nullopt to run it. What it throws, every rank
  /// throws (as an Error of the same component and message).
  std::function<std::optional<Json>(long long case_index)> reuse;
  /// On the rank that takes the case: runs it on this process alone; its record (sent to rank
  /// 0), or nullopt when it stopped.
  std::function<std::optional<Json>(long long case_index)> run;
};

/// What a batch left behind.
struct CaseBatchOutcome {
  long long first = 0;  ///< this share's cases are [first, last) (all of them without --shard)
  long long last = 0;
  std::vector<std::optional<Json>> records;  ///< rank 0: per case, its record; nullopt: not finished
  std::vector<char> reused;                  ///< per case, reused (every rank)
  std::vector<char> started;                 ///< per case, started by this process
};

/// Runs the batch on `cluster`: rank 0 creates the output directory and decides which cases of
/// this share are reused (CaseBatch::reuse) and tells every rank, or throws its error on every
/// rank; then the other cases are the tasks of one shardable task farm, one case at a time per
/// rank (CaseBatch::run), their records gathered on rank 0.
CaseBatchOutcome run_case_batch(const CaseBatch& batch, Cluster& cluster);

/// Sets a case's run to continue what its folder (run.output_directory) holds: with `force` it
/// overwrites a finished run (the batch owns its folders); else a stopped run's result.json
/// gives way to the continued run's, which resumes from checkpoint.json when there is one.
void continue_in_folder(RunOptions& run, bool force);

/// Rank 0: the first case of this share that did not finish, by its name in `names` (with
/// " (not started)" when this single process never started it); "" when all finished.
std::string first_unfinished(const CaseBatchOutcome& outcome, const std::vector<std::string>& names,
                             const Cluster& cluster);

/// Under --shard i/N (cluster.shard() of more than one share): adds summary["shard"] =
/// {"index" (1-based), "count", "cases": the share's names} and, when the share finished
/// (`stopped_at` empty), summary["message"] = Cluster::shard_message(). Nothing otherwise.
void add_shard_entry(Json& summary, const CaseBatchOutcome& outcome, const std::vector<std::string>& names,
                     const Cluster& cluster, const std::string& stopped_at);

/// Rank 0 makes the summary (`make`), and every rank returns it; what `make` throws every rank
/// throws (an exception that is not an Error as Error(component, what())).
Json summary_on_every_rank(Cluster& cluster, const std::function<Json()>& make, const std::string& component);

/// An error decided on one rank, to be thrown alike on every rank: {"component", "message"}
/// (an exception that is not an Error gets `fallback_component`).
Json error_record(const std::exception& e, const std::string& fallback_component);

/// Throws the Error of an error_record.
[[noreturn]] void throw_record(const Json& record);

/// The tasks [first, last) of a shardable task farm of `count` tasks that run on `cluster`: all
/// of them, or under --shard i/N the i-th contiguous share as ShardCluster runs it (sweep and
/// compare: the runs a share's summary covers).
std::pair<long long, long long> shard_tasks(const Cluster& cluster, long long count);

/// The finished result to reuse from a run folder (sweep and compare): the parsed
/// <directory>/result.json when it exists, is not "stopped", and was run with `resolved` as its
/// problem (and `seed` when given); nullopt when there is none or it was stopped (the caller
/// resumes that run). `component` and `what` (e.g. "sweep", "this sweep") name the caller in
/// errors.
/// \throws Error(component, "<directory> holds a result of another problem (first difference
///         at <JSON pointer>: ...)" / "... with seed <s>, ..." / "<file>: not a readable result
///         (...)", each ending "; delete it, or choose another --out").
std::optional<Json> reusable_result(const std::string& directory, const Json& resolved,
                                    const std::optional<std::uint64_t>& seed, const std::string& component,
                                    const std::string& what);

/// (sweep and compare) The summaries `<dir>/<summary_file>` of the shares of one job, read and
/// checked for merging (see merge_sweep_shards for the rules; `same` lists the JSON pointers
/// that must agree, each with its name for the message, `what` names the job: "sweep"), returned
/// in share order; each share's case folders ("shard"/"cases") are then hard-linked or copied
/// into out_dir.
/// \throws Error("merge", ...) as merge_sweep_shards.
std::vector<Json> gather_shards(const std::vector<std::string>& dirs, const std::string& out_dir,
                                const std::string& summary_file, const std::string& what,
                                const std::vector<std::pair<std::string, std::string>>& same);

}  // namespace hapsyn
