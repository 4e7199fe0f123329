// A build without MPI (HAPSYN_WITH_MPI=OFF): the MPI cluster is refused with the reason.
#include <hapsyn/cluster.hpp>
#include <hapsyn/error.hpp>

#include <cstdlib>

namespace hapsyn {

bool mpi_built() { return false; }

std::unique_ptr<Cluster> make_mpi_cluster(const std::atomic<bool>*, std::atomic<bool>*, double) {
  throw Error("mpi", "this hapsyn was built without MPI (HAPSYN_WITH_MPI=OFF); under mpirun every rank would run the whole "
                     "study alone: rebuild with -DHAPSYN_WITH_MPI=ON (Open MPI, libopenmpi-dev), or run one process, or "
                     "split the study with --shard i/N");
}

bool first_on_node(const Cluster&) { return true; }
void node_barrier(const Cluster&) {}
void abort_job(const Cluster&, int code) { std::exit(code); }

}  // namespace hapsyn
