#pragma once
/// \file
/// The processes a run uses: one (the default) or the ranks of an MPI job
/// (`mpirun -n N hapsyn run FILE --threads T`), or one share of a SLURM job array
/// (`hapsyn run FILE --shard i/N`). docs/design.md section 12 describes the model; in short:
///
/// - **SPMD with task farms.** Every rank loads the same study and runs the same solve() with
///   the same options and seed. A solver hands its expensive, independent work to run_tasks():
///   tasks are given out one at a time to every thread of every rank (a work queue: ranks that
///   finish early take more), and each result reaches rank 0 only, which owns the solver's
///   state, its checkpoint and every file. Code between task farms runs on every rank alike and
///   must be deterministic (the same inputs give the same outcome), so all ranks follow the same
///   control flow; what rank 0 alone knows (the collected results), the solver broadcasts when
///   the other ranks need it (a GA's fitness values, a chosen point).
/// - **Stop requests are agreed.** With more than one rank a signal only marks the rank's own
///   request; the flag solvers see (SolverContext::stop) changes inside run_tasks() only, on
///   every rank in the same farm, so replicated code never diverges. A single process sees its
///   signal at once, as before.
/// - **Results do not depend on the rank count** when tasks are independent and rank 0 combines
///   their results by a rule that does not depend on the order they arrive in (the best score,
///   ties to the lowest index; a front; a list by task index).
/// - **Faults end the job.** A rank that dies ends the job (mpirun reports the rank and host);
///   a rank that stops answering for `rank_timeout` seconds makes rank 0 write its checkpoint
///   (TaskFarm::on_abort) and abort the job with a message naming the rank and host.
///
/// Plugins never see MPI: this interface is all they use (MPI is inside libhapsyn, built with
/// HAPSYN_WITH_MPI).
#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn {

/// One task farm (see Cluster::run_tasks). Only `count` and `run` are required.
struct TaskFarm {
  /// Number of tasks; task indices are 0 .. count-1 (count >= 0).
  long long count = 0;
  /// Runs task `index` on worker thread `thread` (0 .. threads-1 of the calling rank; use it to
  /// pick per-thread scratch) and returns its result (any bytes, empty included), or nullopt when
  /// it stopped before finishing because a stop was requested (the task counts as not done).
  /// Called concurrently from the rank's threads, never for a task `done` says is done. May not
  /// call run_tasks (a task that runs a whole sub-solver gives it Cluster::local()).
  std::function<std::optional<std::string>(long long index, int thread)> run;
  /// On rank 0 only, one call at a time (never concurrently with itself), as tasks finish, in
  /// any order: task `index`'s result. Rank 0 records it, reports progress, writes checkpoints.
  std::function<void(long long index, std::string&& result)> collect;
  /// Optional: tasks done before this run (a resumed checkpoint): not run, not collected. Must
  /// give the same answer on every rank.
  std::function<bool(long long index)> done;
  /// Optional, knowledge that prunes shared as ranks find it (an incumbent score, a front,
  /// critical samples): `share` serializes what this rank knows now, `learn` merges what another
  /// rank knew (idempotent and monotone: old news must be harmless). Called from the cluster's
  /// communication thread concurrently with `run`: both must lock what they touch. Not called
  /// in a single process.
  std::function<std::string()> share;
  std::function<void(const std::string&)> learn;
  /// Optional, rank 0: called just before the job is aborted because a rank stopped answering
  /// (write the checkpoint of the tasks collected so far here). Called concurrently with `run`.
  std::function<void()> on_abort;
  /// True for the farm that splits a solver's whole job (the grid's chunks, GA runs, sweep
  /// cases): under `--shard i/N` only the i-th share of its tasks runs. False for farms inside
  /// a unit of work (one GA generation's fitness batch), which always run in full.
  bool shardable = false;
};

/// How a farm ended; the same on every rank.
struct FarmOutcome {
  /// A stop was requested (on any rank): some tasks may not have run. The solver writes its
  /// checkpoint and returns SolverStatus::kStopped.
  bool stopped = false;
  /// Under --shard, a shardable farm ran only this shard's tasks: the solver writes its
  /// checkpoint (what `hapsyn merge` combines) and returns kStopped with shard_message().
  bool partial = false;
};

/// The processes of a run. Obtain one with Cluster::local(), or (the CLI) make_mpi_cluster() /
/// make_shard_cluster(). A solver reaches it as SolverContext::cluster().
class Cluster {
 public:
  virtual ~Cluster() = default;
  /// This process's rank, 0 .. size()-1. Rank 0 writes every file and prints.
  virtual int rank() const { return 0; }
  /// Number of ranks (1 for a single process and for a shard).
  virtual int size() const { return 1; }
  bool root() const { return rank() == 0; }
  /// Host name of rank r (for messages).
  virtual std::string host(int r) const;
  /// Collective (every rank calls it, in the same order): runs the farm's tasks on every thread
  /// of every rank (`threads` per rank, >= 1) and collects their results on rank 0.
  /// Exceptions thrown by `run` or `collect` end the job: in a single process they propagate
  /// (the first); under MPI the rank prints it and aborts the job (never a hang).
  virtual FarmOutcome run_tasks(const TaskFarm& farm, int threads) = 0;
  /// Collective: rank 0's `bytes` replace every other rank's.
  virtual void broadcast(std::string& bytes) { (void)bytes; }
  /// Collective: every rank's `bytes`, by rank, on every rank.
  virtual std::vector<std::string> all_gather(const std::string& bytes) { return {bytes}; }
  /// This run's share under --shard (index 0-based, count >= 1); {0, 1} otherwise.
  virtual std::pair<int, int> shard() const { return {0, 1}; }
  /// "shard 2/3 (tasks 10..19 of 30) done: combine the shards with hapsyn merge": the message of
  /// a solver's result after a partial farm.
  std::string shard_message() const;
  /// Seconds without a message from a rank, within a task farm, before the job is aborted.
  virtual double rank_timeout() const { return 0.0; }

  /// The single-process cluster (one per process; thread-safe).
  static Cluster& local();
};

/// A single process (the default): run_tasks is a dynamic parallel-for over `threads`
/// threads; `collect` is serialized with a mutex. A stop is a task that returns nullopt.
class LocalCluster : public Cluster {
 public:
  FarmOutcome run_tasks(const TaskFarm& farm, int threads) override;
};

/// One share of a SLURM job array (`--shard i/N`, 1-based in the CLI, `index` 0-based here):
/// shardable farms run the tasks [count*index/N, count*(index+1)/N); other farms run in full.
class ShardCluster : public LocalCluster {
 public:
  /// \throws Error("shard", ...) unless 0 <= index < count.
  ShardCluster(int index, int count);
  FarmOutcome run_tasks(const TaskFarm& farm, int threads) override;
  std::pair<int, int> shard() const override { return {index_, count_}; }

 private:
  int index_, count_;
};

/// Parses `--shard i/N` (1 <= i <= N, N >= 1, whole numbers) into {i-1, N}.
/// \throws Error("shard", "--shard 3/2: the share i must lie in 1..N (N = 2)") and likewise for
///         "0/0", "a/b", "1/" (the rule named).
std::pair<int, int> parse_shard(const std::string& text);

/// True when this build has MPI (HAPSYN_WITH_MPI).
bool mpi_built();
/// True when the process was started by mpirun/srun as one of several ranks (from the
/// launcher's environment: OMPI_COMM_WORLD_SIZE, PMI_SIZE, PMIX_SIZE), whatever the build.
int launcher_ranks();

/// The MPI cluster of this process (initializes MPI with MPI_THREAD_MULTIPLE on first use;
/// MPI is finalized at exit). `requested` is the flag the process's signal handlers set;
/// `visible` the one solvers see (SolverContext::stop), set only inside task farms.
/// `rank_timeout` seconds: see Cluster::rank_timeout (> 0).
/// \throws Error("mpi", ...) when this build has no MPI, or MPI gives less than
///         MPI_THREAD_MULTIPLE.
std::unique_ptr<Cluster> make_mpi_cluster(const std::atomic<bool>* requested, std::atomic<bool>* visible,
                                          double rank_timeout);

/// Under MPI: true for the first rank of each node (MPI_COMM_TYPE_SHARED); always true
/// otherwise. The CLI lets it load the study first (building the scene cache), then the node's
/// other ranks load it from the cache.
bool first_on_node(const Cluster& cluster);
/// Collective over the ranks of this node (a no-op outside MPI).
void node_barrier(const Cluster& cluster);

/// Sends the process's error to the launcher and ends every rank (MPI_Abort with `code`);
/// outside MPI, std::exit(code).
[[noreturn]] void abort_job(const Cluster& cluster, int code);

}  // namespace hapsyn
