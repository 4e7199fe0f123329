// The task farm's own cost (hapsyn/cluster.hpp), per task, under mpirun:
//
//   mpirun --oversubscribe -n 2 build/bin/cluster_benchmark [--tasks N] [--bytes B] [--work-us W]
//
// Runs farms of N tasks whose run() does W microseconds of arithmetic and returns B bytes, on
// this process's LocalCluster (the baseline, rank 0 alone) and on the MPI cluster (every rank,
// one thread each), and prints per task: the wall time, the farm's overhead against the
// baseline, and the round trip of one request (farms with W = 0). Rank 0 prints; the hapsyn
// version and machine head the output. Not a Google Benchmark: the measurement is collective.
#include <hapsyn/cluster.hpp>
#include <hapsyn/output_files.hpp>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iomanip>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

// About `us` microseconds of dependent floating-point work (not optimized away).
double spin(double us, long long seed) {
  double x = static_cast<double>(seed % 97) * 1e-3 + 1.0;
  const long long iterations = static_cast<long long>(us * 150.0);
  for (long long i = 0; i < iterations; ++i) x = std::sqrt(x * 1.0000001 + 0.5);
  return x;
}

double farm_seconds(hapsyn::Cluster& cluster, long long tasks, std::size_t bytes, double work_us) {
  hapsyn::TaskFarm farm;
  farm.count = tasks;
  double sink = 0.0;
  farm.run = [&](long long index, int) -> std::optional<std::string> {
    std::string result(bytes, 'x');
    if (!result.empty()) result[0] = static_cast<char>('a' + static_cast<int>(spin(work_us, index)) % 26);
    else spin(work_us, index);
    return result;
  };
  farm.collect = [&](long long, std::string&& result) { sink += static_cast<double>(result.size()); };
  std::string go;
  cluster.broadcast(go);  // start together
  const auto t0 = Clock::now();
  cluster.run_tasks(farm, 1);
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  if (sink < 0) std::cerr << sink;
  return s;
}

// The round trip of one request: empty tasks, while rank 0's own thread sleeps through its
// tasks so that the other ranks take nearly all of them; the time per task a rank other than 0
// ran is what one request-reply costs (with B bytes of result).
std::pair<double, long long> round_trip(hapsyn::Cluster& cluster, long long tasks, std::size_t bytes) {
  if (cluster.size() == 1) return {0.0, 0};
  std::atomic<long long> mine{0};
  hapsyn::TaskFarm farm;
  farm.count = tasks;
  farm.run = [&](long long, int) -> std::optional<std::string> {
    if (cluster.root()) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    ++mine;
    return std::string(bytes, 'x');
  };
  farm.collect = [](long long, std::string&&) {};
  std::string go;
  cluster.broadcast(go);
  const auto t0 = Clock::now();
  cluster.run_tasks(farm, 1);
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  const std::vector<std::string> counts = cluster.all_gather(std::to_string(mine.load()));
  long long remote_max = 1;
  for (std::size_t r = 1; r < counts.size(); ++r) remote_max = std::max(remote_max, std::stoll(counts[r]));
  return {1e6 * s / static_cast<double>(remote_max), remote_max};
}

long long option(int argc, char** argv, const char* name, long long fallback) {
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], name) == 0) return std::atoll(argv[i + 1]);
  }
  return fallback;
}

}  // namespace

int main(int argc, char** argv) {
  const long long tasks = option(argc, argv, "--tasks", 20000);
  const auto bytes = static_cast<std::size_t>(option(argc, argv, "--bytes", 64));
  const double work_us = static_cast<double>(option(argc, argv, "--work-us", 200));
  std::atomic<bool> requested{false}, visible{false};
  std::unique_ptr<hapsyn::Cluster> mpi;
  if (hapsyn::launcher_ranks() > 1) mpi = hapsyn::make_mpi_cluster(&requested, &visible, 60.0);
  hapsyn::Cluster& cluster = mpi ? *mpi : hapsyn::Cluster::local();
  const bool root = cluster.root();
  if (root) {
    std::cout << "hapsyn " << hapsyn::version() << " cluster_benchmark: " << cluster.size() << " rank(s) x 1 thread, "
              << tasks << " tasks of " << work_us << " us returning " << bytes << " bytes\n"
              << "machine: " << hapsyn::machine_info().dump() << "\n";
  }
  double local_s = 0.0;
  if (root) local_s = farm_seconds(hapsyn::Cluster::local(), tasks, bytes, work_us);
  const double farm_s = farm_seconds(cluster, tasks, bytes, work_us);
  const auto [round_trip_us, remote_tasks] = round_trip(cluster, tasks, bytes);
  if (root) {
    const double n = static_cast<double>(tasks);
    std::cout << std::fixed << std::setprecision(2) << "rank 0 alone (LocalCluster, baseline): " << 1e6 * local_s / n
              << " us per task\n"
              << cluster.size() << " ranks: " << 1e6 * farm_s / n << " us per task wall, speed-up "
              << local_s / farm_s << "x\n"
              << "round trip of one task request (empty tasks, rank 0 serving " << cluster.size() - 1
              << " other rank(s), " << remote_tasks << " requests): " << round_trip_us << " us\n";
  }
  return 0;
}
