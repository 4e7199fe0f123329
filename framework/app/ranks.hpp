#pragma once
// The processes a command runs on: an MPI job (started by mpirun/srun with several ranks), one
// share of a SLURM job array (--shard i/N), or this process alone; and loading a study on them.
#include <hapsyn/cluster.hpp>
#include <hapsyn/internal/study.hpp>

#include <atomic>
#include <functional>
#include <memory>
#include <string>

namespace hapsyn_cli {

/// Thrown on ranks other than 0 (and on rank 0 after it printed) to end with `code` and nothing
/// more on stderr: one message per job, not one per rank.
struct QuietExit {
  int code;
};

/// An MPI cluster when the launcher started several ranks (refused with the reason in a build
/// without MPI, and together with --shard), a ShardCluster for `shard` ("i/N", checked), else
/// null (this process). `requested` is set by the signal handlers, `agreed` is what solvers see.
/// \throws hapsyn::Error("shard" | "mpi", ...)
std::unique_ptr<hapsyn::Cluster> make_run_cluster(const std::string& shard, double rank_timeout,
                                                  const std::atomic<bool>* requested, std::atomic<bool>* agreed);

/// Loads the study on every rank: the first rank of each node first (it builds the scene cache),
/// then the node's others (they read it). A load error on any rank is every rank's: rank 0
/// rethrows the first one (naming the rank when it is not 0), the others throw QuietExit{1}.
hapsyn::Study load_on_ranks(hapsyn::Cluster* cluster, const std::function<hapsyn::Study()>& load);

/// This process's rank as the launcher's environment gives it (OMPI_COMM_WORLD_RANK, PMIX_RANK,
/// PMI_RANK), 0 outside a launcher: who reports an error found before the cluster exists.
int launcher_rank();

/// The rank of this process in `cluster` (0 when null).
inline int rank_of(const hapsyn::Cluster* cluster) { return cluster != nullptr ? cluster->rank() : 0; }

}  // namespace hapsyn_cli
