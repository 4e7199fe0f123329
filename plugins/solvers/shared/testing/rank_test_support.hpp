#pragma once
// Test helpers for the distributed grid-based solvers (grid_test and culling_test include it):
// the ranks of one job emulated inside one process, and the --shard / hapsyn merge round trip.
//
// EmulatedRanks: rank r is a thread that calls solve() with its own Cluster; the ranks' task
// farms meet in a hub where every thread of every rank takes the next task from one queue, the
// results go to rank 0's collect(), and after each task the rank learns what every other rank
// shares, as under MPI (where it happens per request). broadcast and all_gather are
// collectives; a call order that differs between ranks hangs here as it would under MPI.
#include "shared/testing/stop_test_support.hpp"

#include <hapsyn/cluster.hpp>
#include <hapsyn/solver.hpp>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

namespace hapsyn::test {

class EmulatedRanks {
 public:
  explicit EmulatedRanks(int size) : size_(size), farms_(static_cast<std::size_t>(size)), gathered_(static_cast<std::size_t>(size)) {
    for (int r = 0; r < size; ++r) ranks_.push_back(std::make_unique<Rank>(*this, r));
  }

  /// Runs solve(r) on one thread per rank; returns each rank's result (rank 0's is the run's).
  std::vector<SolverResult> run(const std::function<SolverResult(Cluster&)>& solve) {
    std::vector<SolverResult> results(static_cast<std::size_t>(size_));
    std::vector<std::exception_ptr> errors(static_cast<std::size_t>(size_));
    std::vector<std::thread> threads;
    for (int r = 0; r < size_; ++r) {
      threads.emplace_back([&, r] {
        try {
          results[static_cast<std::size_t>(r)] = solve(*ranks_[static_cast<std::size_t>(r)]);
        } catch (...) {
          errors[static_cast<std::size_t>(r)] = std::current_exception();
        }
      });
    }
    for (std::thread& t : threads) t.join();
    for (const std::exception_ptr& e : errors) {
      if (e) std::rethrow_exception(e);
    }
    return results;
  }

 private:
  class Rank : public Cluster {
   public:
    Rank(EmulatedRanks& hub, int rank) : hub_(hub), rank_(rank) {}
    int rank() const override { return rank_; }
    int size() const override { return hub_.size_; }
    FarmOutcome run_tasks(const TaskFarm& farm, int threads) override { return hub_.run_tasks(rank_, farm, threads); }
    void broadcast(std::string& bytes) override {
      if (rank_ == 0) hub_.broadcast_ = bytes;
      hub_.barrier();
      if (rank_ != 0) bytes = hub_.broadcast_;
      hub_.barrier();
    }
    std::vector<std::string> all_gather(const std::string& bytes) override {
      hub_.gathered_[static_cast<std::size_t>(rank_)] = bytes;
      hub_.barrier();
      std::vector<std::string> all = hub_.gathered_;
      hub_.barrier();
      return all;
    }

   private:
    EmulatedRanks& hub_;
    int rank_;
  };

  void barrier() {
    std::unique_lock<std::mutex> lock(mutex_);
    const long long generation = generation_;
    if (++waiting_ == size_) {
      waiting_ = 0;
      ++generation_;
      changed_.notify_all();
      return;
    }
    changed_.wait(lock, [&] { return generation_ != generation; });
  }

  FarmOutcome run_tasks(int rank, const TaskFarm& farm, int threads) {
    if (rank == 0) {
      next_ = 0;
      stopped_ = false;
    }
    farms_[static_cast<std::size_t>(rank)] = &farm;
    barrier();
    std::vector<std::thread> pool;
    for (int t = 0; t < std::max(1, threads); ++t) {
      pool.emplace_back([&, t] {
        for (;;) {
          long long index;
          {
            std::lock_guard<std::mutex> lock(mutex_);
            while (next_ < farm.count && farm.done && farm.done(next_)) ++next_;
            if (stopped_ || next_ >= farm.count) return;
            index = next_++;
          }
          std::optional<std::string> result = farm.run(index, t);
          std::lock_guard<std::mutex> lock(collect_mutex_);
          if (!result) {
            stopped_ = true;
            return;
          }
          const TaskFarm& root = *farms_[0];
          if (root.collect) root.collect(index, std::move(*result));
          if (farm.learn) {
            for (int r = 0; r < size_; ++r) {
              const TaskFarm& other = *farms_[static_cast<std::size_t>(r)];
              if (r != rank && other.share) farm.learn(other.share());
            }
          }
        }
      });
    }
    for (std::thread& t : pool) t.join();
    barrier();  // every rank's tasks are done: no farm is used after this
    FarmOutcome outcome;
    outcome.stopped = stopped_;
    barrier();  // every rank read the outcome before rank 0 resets it for the next farm
    return outcome;
  }

  int size_;
  std::vector<std::unique_ptr<Rank>> ranks_;
  std::vector<const TaskFarm*> farms_;
  std::mutex mutex_, collect_mutex_;
  std::condition_variable changed_;
  int waiting_ = 0;
  long long generation_ = 0;
  long long next_ = 0;
  std::atomic<bool> stopped_{false};
  std::string broadcast_;
  std::vector<std::string> gathered_;
};

/// One --shard i/N split and `hapsyn merge` in process: shard k of `count` runs with a
/// ShardCluster and its own checkpoint file under `dir`; the states of the shards in `merged`
/// (all by default) are merged with solver.merge_shards and written as `dir`/merged.json (the
/// first listed shard's envelope, checksum recomputed, as the CLI writes it); the study is then
/// resumed there. `solve(context)` runs the solver; `check_shard(k, result)` sees each share's.
inline SolverResult shard_merge_resume(const Solver& solver, const Problem& problem, int count, const std::string& dir,
                                       const std::function<SolverResult(const SolverContext&)>& solve,
                                       const std::function<void(int, const SolverResult&)>& check_shard,
                                       std::vector<int> merged = {}) {
  if (merged.empty()) {
    for (int k = 0; k < count; ++k) merged.push_back(k);
  }
  std::vector<Json> states;
  Json envelope;
  for (int k = 0; k < count; ++k) {
    ShardCluster shard(k, count);
    SolverContext context;
    context.threads = 2;
    context.seed = 11;
    context.ranks = &shard;
    context.checkpoint_file = dir + "/shard-" + std::to_string(k) + ".json";
    check_shard(k, solve(context));
    if (std::find(merged.begin(), merged.end(), k) == merged.end()) continue;
    Json c = read_json_file(context.checkpoint_file);
    if (envelope.is_null()) envelope = c;
    states.push_back(c["state"]);
  }
  envelope["state"] = solver.merge_shards(problem, states);
  const std::string file = dir + "/merged.json";
  write_json_file(file, envelope, true);
  SolverContext context;
  context.threads = 2;
  context.seed = 11;
  context.checkpoint_file = file;
  context.resume = true;
  return solve(context);
}

}  // namespace hapsyn::test
