#pragma once
/// \file
/// Test support (not linked into any plugin): two ranks of an MPI job played one after the
/// other in one process, to check that a distributed solver's replicated code gives every rank
/// the same result through the same collectives, without MPI.
///
/// Rank 0 (ReplayCluster(0, tape, &stop)) runs every task of every farm on a LocalCluster and
/// records each farm's outcome and each broadcast on the tape; as the MPI cluster agrees, a farm
/// is stopped also when `stop` (the flag of rank 0's context) was set by its end. Rank 1
/// (ReplayCluster(1, tape, &visible), run afterwards) runs only the odd tasks and throws their
/// results away (a non-root rank's results reach rank 0 only), takes the recorded outcomes (the
/// agreed stop: it sets `visible`, the flag its context.stop points to, as the MPI cluster
/// does) and receives rank 0's bytes for each broadcast. A collective that rank 1 calls in another order than rank 0 (under MPI,
/// a hang) throws std::logic_error naming both.
#include <hapsyn/cluster.hpp>

#include <atomic>
#include <deque>
#include <memory>
#include <stdexcept>
#include <string>

namespace hapsyn::plugins::test {

/// What rank 0 did, in order: "farm <count> <stopped>" or "broadcast" followed by its bytes.
struct ReplayTape {
  std::deque<std::string> events;
  std::deque<std::string> bytes;
};

class ReplayCluster : public LocalCluster {
 public:
  ReplayCluster(int rank, std::shared_ptr<ReplayTape> tape, std::atomic<bool>* stop = nullptr)
      : rank_(rank), tape_(std::move(tape)), stop_(stop) {}
  int rank() const override { return rank_; }
  int size() const override { return 2; }
  int farms() const { return farms_; }

  FarmOutcome run_tasks(const TaskFarm& farm, int threads) override {
    ++farms_;
    if (rank_ == 0) {
      FarmOutcome outcome = LocalCluster::run_tasks(farm, threads);
      outcome.stopped = outcome.stopped || (stop_ != nullptr && stop_->load());
      tape_->events.push_back(farm_event(farm, outcome.stopped));
      return outcome;
    }
    const std::string expected = next("farm");
    TaskFarm mine = farm;
    mine.collect = nullptr;  // only rank 0 collects
    mine.done = [&farm](long long index) { return index % 2 == 0 || (farm.done && farm.done(index)); };
    (void)LocalCluster::run_tasks(mine, threads);
    FarmOutcome outcome;
    outcome.stopped = expected == farm_event(farm, true);
    if (!outcome.stopped && expected != farm_event(farm, false)) {
      throw std::logic_error("rank 1 ran " + farm_event(farm, false) + " where rank 0 ran " + expected);
    }
    if (stop_ != nullptr) stop_->store(outcome.stopped);
    return outcome;
  }

  void broadcast(std::string& bytes) override {
    if (rank_ == 0) {
      tape_->events.push_back("broadcast");
      tape_->bytes.push_back(bytes);
      return;
    }
    next("broadcast");
    bytes = tape_->bytes.front();
    tape_->bytes.pop_front();
  }

 private:
  static std::string farm_event(const TaskFarm& farm, bool stopped) {
    return "farm " + std::to_string(farm.count) + (stopped ? " stopped" : " finished");
  }
  std::string next(const std::string& what) {
    if (tape_->events.empty()) throw std::logic_error("rank 1 called " + what + " after rank 0's last collective");
    std::string event = tape_->events.front();
    tape_->events.pop_front();
    if (event.rfind(what, 0) != 0) throw std::logic_error("rank 1 called " + what + " where rank 0 called " + event);
    return event;
  }

  int rank_;
  std::shared_ptr<ReplayTape> tape_;
  std::atomic<bool>* stop_;
  int farms_ = 0;
};

}  // namespace hapsyn::plugins::test
