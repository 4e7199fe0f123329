#include "ranks.hpp"

#include <hapsyn/error.hpp>

#include <cstdlib>
#include <exception>
#include <optional>

namespace hapsyn_cli {

std::unique_ptr<hapsyn::Cluster> make_run_cluster(const std::string& shard, double rank_timeout,
                                                  const std::atomic<bool>* requested, std::atomic<bool>* agreed) {
  const int launched = hapsyn::launcher_ranks();
  if (launched > 1) {
    if (!shard.empty()) {
      throw hapsyn::Error("shard", "--shard " + shard + " under mpirun (" + std::to_string(launched) +
                                       " ranks): a share runs as one process; use either mpirun or --shard");
    }
    return hapsyn::make_mpi_cluster(requested, agreed, rank_timeout);
  }
  if (!shard.empty()) {
    const auto [index, count] = hapsyn::parse_shard(shard);
    return std::make_unique<hapsyn::ShardCluster>(index, count);
  }
  return nullptr;
}

int launcher_rank() {
  for (const char* name : {"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"}) {
    if (const char* v = std::getenv(name)) return std::atoi(v);
  }
  return 0;
}

hapsyn::Study load_on_ranks(hapsyn::Cluster* cluster, const std::function<hapsyn::Study()>& load) {
  if (cluster == nullptr || cluster->size() == 1) return load();
  std::optional<hapsyn::Study> study;
  std::string error;
  std::exception_ptr own;
  const auto attempt = [&] {
    try {
      study.emplace(load());
    } catch (const std::exception& e) {
      error = e.what();
      own = std::current_exception();
    }
  };
  // The node's first rank builds (and caches) the scene while the others wait, then they load
  // it from the cache instead of building it again.
  const bool first = hapsyn::first_on_node(*cluster);
  if (first) attempt();
  hapsyn::node_barrier(*cluster);
  if (!first) attempt();
  const std::vector<std::string> errors = cluster->all_gather(error);
  for (std::size_t r = 0; r < errors.size(); ++r) {
    if (errors[r].empty()) continue;
    if (!cluster->root()) throw QuietExit{1};
    if (r == 0) std::rethrow_exception(own);  // as a single process reports it
    throw hapsyn::Error("rank " + std::to_string(r) + " on " + cluster->host(static_cast<int>(r)), errors[r]);
  }
  return std::move(*study);
}

}  // namespace hapsyn_cli
