// The single-process and shard clusters, --shard parsing and what every cluster shares. The MPI
// cluster is in cluster_mpi.cpp (built with HAPSYN_WITH_MPI) or cluster_no_mpi.cpp.
#include <hapsyn/cluster.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/parallel.hpp>
#include <hapsyn/solver.hpp>

#include <cstdlib>
#include <mutex>
#include <unistd.h>

namespace hapsyn {

std::string Cluster::host(int r) const {
  (void)r;
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "localhost";
  return name;
}

std::string Cluster::shard_message() const {
  const auto [index, count] = shard();
  return "shard " + std::to_string(index + 1) + "/" + std::to_string(count) +
         " done: combine the shards' output directories with hapsyn merge";
}

Cluster& Cluster::local() {
  static LocalCluster instance;
  return instance;
}

FarmOutcome LocalCluster::run_tasks(const TaskFarm& farm, int threads) {
  std::mutex collect_mutex;
  std::atomic<bool> stopped{false};
  parallel_for_dynamic(farm.count, std::max(1, threads), 1, [&](long long index, int thread) {
    if (stopped.load(std::memory_order_relaxed) || (farm.done && farm.done(index))) return;
    std::optional<std::string> result = farm.run(index, thread);
    if (!result) {
      stopped = true;
      return;
    }
    if (farm.collect) {
      std::lock_guard<std::mutex> lock(collect_mutex);
      farm.collect(index, std::move(*result));
    }
  });
  FarmOutcome outcome;
  outcome.stopped = stopped.load();
  return outcome;
}

ShardCluster::ShardCluster(int index, int count) : index_(index), count_(count) {
  if (count < 1 || index < 0 || index >= count) {
    throw Error("shard", "share " + std::to_string(index + 1) + "/" + std::to_string(count) +
                             ": the share i of i/N must lie in 1..N and N must be >= 1");
  }
}

FarmOutcome ShardCluster::run_tasks(const TaskFarm& farm, int threads) {
  if (!farm.shardable || count_ == 1) return LocalCluster::run_tasks(farm, threads);
  // Contiguous shares: a grid slice stays a slice; (count*i)/N in long double cannot overflow.
  const auto bound = [&](int i) {
    return static_cast<long long>(static_cast<long double>(farm.count) * i / count_);
  };
  const long long first = bound(index_), last = bound(index_ + 1);
  TaskFarm mine = farm;
  mine.done = [&farm, first, last](long long index) {
    return index < first || index >= last || (farm.done && farm.done(index));
  };
  FarmOutcome outcome = LocalCluster::run_tasks(mine, threads);
  outcome.partial = true;
  return outcome;
}

namespace {

// A whole number in [lo, hi], or nullopt.
std::optional<long long> whole_number(const std::string& text, long long lo, long long hi) {
  if (text.empty() || text.size() > 9) return std::nullopt;
  for (char c : text) {
    if (c < '0' || c > '9') return std::nullopt;
  }
  const long long v = std::stoll(text);
  if (v < lo || v > hi) return std::nullopt;
  return v;
}

}  // namespace

std::pair<int, int> parse_shard(const std::string& text) {
  const std::string::size_type slash = text.find('/');
  const std::string what = "--shard " + text + ": ";
  if (slash == std::string::npos) throw Error("shard", what + "expected i/N (share i of N, e.g. 2/8)");
  const std::optional<long long> i = whole_number(text.substr(0, slash), 0, 100000000);
  const std::optional<long long> n = whole_number(text.substr(slash + 1), 0, 100000000);
  if (!i || !n) throw Error("shard", what + "i and N must be whole numbers (share i of N, e.g. 2/8)");
  if (*n < 1) throw Error("shard", what + "the share count N must be >= 1");
  if (*i < 1 || *i > *n) {
    throw Error("shard", what + "the share i must lie in 1..N (N = " + std::to_string(*n) + ")");
  }
  return {static_cast<int>(*i - 1), static_cast<int>(*n)};
}

int launcher_ranks() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_SIZE", "PMI_SIZE"}) {
    if (const char* v = std::getenv(name)) {
      const int n = std::atoi(v);
      if (n > 0) return n;
    }
  }
  return 1;
}

Cluster& SolverContext::cluster() const { return ranks != nullptr ? *ranks : Cluster::local(); }

Json Solver::merge_shards(const Problem& problem, const std::vector<Json>& states) const {
  (void)problem;
  (void)states;
  throw Error("merge", "this solver does not support --shard (grid, culling, ga and the sweep and compare cases do)");
}

}  // namespace hapsyn
