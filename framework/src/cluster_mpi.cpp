// The MPI cluster (HAPSYN_WITH_MPI): a task farm served by rank 0 over point-to-point messages.
//
// Why this shape: rank 0 owns the solver's state (the best so far, the checkpoint), so it is the
// natural place for the queue; every other rank's threads ask it for one task at a time and hand
// in the previous task's result with the request, which makes the queue dynamic (a rank with
// cheaper designs simply asks more often) at one round trip per task. Waiting is done by polling
// with short sleeps, never by a blocking MPI call: Open MPI busy-waits in blocking calls, and an
// idle rank 0 server spinning on a core would halve the work of a rank sharing it.
#include <hapsyn/bytes.hpp>
#include <hapsyn/cluster.hpp>
#include <hapsyn/error.hpp>

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <exception>
#include <iomanip>
#include <iostream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

namespace hapsyn {

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kTagRequest = 1;
constexpr int kTagHeartbeat = 2;
constexpr int kTagReplyBase = 1000;  // + thread index
constexpr long long kNoTask = -1;    // reply: no task left
constexpr long long kStopTask = -2;  // reply: the job is stopping
constexpr double kHeartbeatSeconds = 1.0;

// Sleeps a little longer each time nothing happened (up to 0.2 ms: about 1% of a core at most,
// and a request waits at most that long for an idle rank 0), so that waiting costs no core.
class Backoff {
 public:
  void idle() {
    if (spins_ < 64) {
      ++spins_;
      std::this_thread::yield();
      return;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(sleep_us_));
    sleep_us_ = std::min(200, sleep_us_ * 2);
  }
  void busy() {
    spins_ = 0;
    sleep_us_ = 20;
  }

 private:
  int spins_ = 0, sleep_us_ = 20;
};

// Completes a request by polling (see the file comment).
void wait_polling(MPI_Request& request) {
  Backoff backoff;
  for (;;) {
    int done = 0;
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (done) return;
    backoff.idle();
  }
}

void send_bytes(const std::string& bytes, int to, int tag, MPI_Comm comm) {
  MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, to, tag, comm);
}

std::string receive_probed(const MPI_Status& status, MPI_Comm comm) {
  int n = 0;
  MPI_Get_count(&status, MPI_BYTE, &n);
  std::string bytes(static_cast<std::size_t>(n), '\0');
  MPI_Recv(bytes.data(), n, MPI_BYTE, status.MPI_SOURCE, status.MPI_TAG, comm, MPI_STATUS_IGNORE);
  return bytes;
}

// Receives one message from `from` with `tag`, polling; false when `timeout_s` passed first.
bool receive_polling(std::string& bytes, int from, int tag, MPI_Comm comm, double timeout_s) {
  Backoff backoff;
  const auto start = Clock::now();
  for (;;) {
    int flag = 0;
    MPI_Status status;
    MPI_Iprobe(from, tag, comm, &flag, &status);
    if (flag) {
      bytes = receive_probed(status, comm);
      return true;
    }
    if (std::chrono::duration<double>(Clock::now() - start).count() > timeout_s) return false;
    backoff.idle();
  }
}

class MpiCluster;

[[noreturn]] void fail_rank(const MpiCluster& cluster, const std::string& what);

class MpiCluster : public Cluster {
 public:
  MpiCluster(const std::atomic<bool>* requested, std::atomic<bool>* visible, double rank_timeout)
      : requested_(requested), visible_(visible), timeout_(rank_timeout) {
    MPI_Comm_dup(MPI_COMM_WORLD, &comm_);
    MPI_Comm_rank(comm_, &rank_);
    MPI_Comm_size(comm_, &size_);
    MPI_Comm_split_type(comm_, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &node_);
    char name[MPI_MAX_PROCESSOR_NAME] = {};
    int length = 0;
    MPI_Get_processor_name(name, &length);
    hosts_ = all_gather(std::string(name, static_cast<std::size_t>(length)));
  }
  ~MpiCluster() override {
    MPI_Comm_free(&node_);
    MPI_Comm_free(&comm_);
  }

  int rank() const override { return rank_; }
  int size() const override { return size_; }
  std::string host(int r) const override { return hosts_.at(static_cast<std::size_t>(r)); }
  double rank_timeout() const override { return timeout_; }
  MPI_Comm node() const { return node_; }
  MPI_Comm comm() const { return comm_; }

  void broadcast(std::string& bytes) override {
    std::uint64_t n = bytes.size();
    MPI_Request request;
    MPI_Ibcast(&n, 1, MPI_UINT64_T, 0, comm_, &request);
    wait_polling(request);
    bytes.resize(n);
    if (n == 0) return;
    MPI_Ibcast(bytes.data(), static_cast<int>(n), MPI_BYTE, 0, comm_, &request);
    wait_polling(request);
  }

  std::vector<std::string> all_gather(const std::string& bytes) override {
    const int mine = static_cast<int>(bytes.size());
    std::vector<int> counts(static_cast<std::size_t>(size_)), offsets(static_cast<std::size_t>(size_));
    MPI_Request request;
    MPI_Iallgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, comm_, &request);
    wait_polling(request);
    int total = 0;
    for (int r = 0; r < size_; ++r) {
      offsets[static_cast<std::size_t>(r)] = total;
      total += counts[static_cast<std::size_t>(r)];
    }
    std::string all(static_cast<std::size_t>(total), '\0');
    MPI_Iallgatherv(bytes.data(), mine, MPI_BYTE, all.data(), counts.data(), offsets.data(), MPI_BYTE, comm_, &request);
    wait_polling(request);
    std::vector<std::string> out;
    for (int r = 0; r < size_; ++r) {
      out.push_back(all.substr(static_cast<std::size_t>(offsets[static_cast<std::size_t>(r)]),
                               static_cast<std::size_t>(counts[static_cast<std::size_t>(r)])));
    }
    return out;
  }

  FarmOutcome run_tasks(const TaskFarm& farm, int threads) override {
    threads = std::max(1, threads);
    ++farm_id_;
    bool stop_seen = rank_ == 0 ? serve(farm, threads) : work(farm, threads);
    stop_seen = stop_seen || requested();
    // The outcome is agreed: a stop seen by any rank (even one whose signal came after its last
    // task) is everyone's, so the solvers' replicated code takes the same branch on every rank.
    int mine = stop_seen ? 1 : 0, any = 0;
    MPI_Request request;
    MPI_Iallreduce(&mine, &any, 1, MPI_INT, MPI_LOR, comm_, &request);
    wait_polling(request);
    if (visible_ != nullptr) visible_->store(any != 0);
    FarmOutcome outcome;
    outcome.stopped = any != 0;
    return outcome;
  }

 private:
  bool requested() const { return requested_ != nullptr && requested_->load(std::memory_order_relaxed); }
  void make_visible() {
    if (visible_ != nullptr) visible_->store(true);
  }

  // ---- rank 0: its own threads take tasks directly; this thread serves the other ranks. ----

  struct Queue {
    explicit Queue(const TaskFarm& f) : farm(f) {}
    const TaskFarm& farm;
    std::mutex mutex;
    long long next = 0;
    bool stopping = false;

    // The next task to run, or kNoTask / kStopTask (caller holds mutex).
    long long take() {
      if (stopping) return kStopTask;
      while (next < farm.count && farm.done && farm.done(next)) ++next;
      return next < farm.count ? next++ : kNoTask;
    }
  };

  bool serve(const TaskFarm& farm, int threads) {
    Queue queue(farm);
    std::vector<std::thread> local;
    std::atomic<int> local_running{threads};
    for (int t = 0; t < threads; ++t) {
      local.emplace_back([&, t] {
        run_local_thread(queue, t);
        --local_running;
      });
    }
    serve_remote(queue, local_running);
    for (std::thread& t : local) t.join();
    return queue.stopping;
  }

  void run_local_thread(Queue& queue, int thread) {
    try {
      for (;;) {
        long long index;
        {
          std::lock_guard<std::mutex> lock(queue.mutex);
          index = queue.take();
        }
        if (index < 0) return;
        std::optional<std::string> result = queue.farm.run(index, thread);
        std::lock_guard<std::mutex> lock(queue.mutex);
        if (!result) {
          queue.stopping = true;
          make_visible();
          return;
        }
        if (queue.farm.collect) queue.farm.collect(index, std::move(*result));
      }
    } catch (const std::exception& e) {
      fail_rank(*this, e.what());
    }
  }

  // One remote thread's message: the task it finished (or kNoTask) with its result, whether it
  // saw a stop, whether it asks for a task (a reply follows) and whether it is its last message
  // in this farm, and its shared knowledge.
  struct Request {
    long long farm = 0, finished = kNoTask;
    int thread = 0, threads = 0;
    bool stop = false, ask = false, last = false;
    std::string result, share;
  };

  static std::string encode(const Request& r) {
    ByteWriter out;
    out.put(r.farm).put(r.thread).put(r.threads).put(r.finished);
    out.put(static_cast<char>(r.stop)).put(static_cast<char>(r.ask)).put(static_cast<char>(r.last));
    out.put_string(r.result).put_string(r.share);
    return out.bytes();
  }

  static Request parse_request(const std::string& bytes) {
    ByteReader in(bytes);
    Request r;
    r.farm = in.get<long long>();
    r.thread = in.get<int>();
    r.threads = in.get<int>();
    r.finished = in.get<long long>();
    r.stop = in.get<char>() != 0;
    r.ask = in.get<char>() != 0;
    r.last = in.get<char>() != 0;
    r.result = in.get_string();
    r.share = in.get_string();
    return r;
  }

  void serve_remote(Queue& queue, const std::atomic<int>& local_running) {
    const TaskFarm& farm = queue.farm;
    std::vector<Clock::time_point> last_seen(static_cast<std::size_t>(size_), Clock::now());
    // Per rank, its threads that have not sent their last message; -1 until its first message
    // says how many it runs (ranks on different nodes may run different thread counts).
    std::vector<int> open_per_rank(static_cast<std::size_t>(size_), -1);
    open_per_rank[0] = 0;
    const auto remote_open = [&] {
      return std::any_of(open_per_rank.begin(), open_per_rank.end(), [](int n) { return n != 0; });
    };
    Backoff backoff;
    try {
      while (remote_open() || local_running.load() > 0) {
        if (requested()) {
          std::lock_guard<std::mutex> lock(queue.mutex);
          queue.stopping = true;
          make_visible();
        }
        int flag = 0;
        MPI_Status status;
        MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, comm_, &flag, &status);
        if (!flag) {
          check_ranks_alive(farm, last_seen, open_per_rank);
          backoff.idle();
          continue;
        }
        backoff.busy();
        const std::string bytes = receive_probed(status, comm_);
        const int from = status.MPI_SOURCE;
        last_seen[static_cast<std::size_t>(from)] = Clock::now();
        if (status.MPI_TAG != kTagRequest) continue;  // a heartbeat: being alive is all it says
        const Request request = parse_request(bytes);
        int& open = open_per_rank[static_cast<std::size_t>(from)];
        if (open < 0) open = request.threads;
        if (farm.learn && !request.share.empty()) farm.learn(request.share);
        long long next = kNoTask;
        {
          std::lock_guard<std::mutex> lock(queue.mutex);
          if (request.stop) {
            queue.stopping = true;
            make_visible();
          }
          if (request.finished >= 0 && farm.collect) farm.collect(request.finished, std::string(request.result));
          if (request.ask) next = queue.take();
        }
        if (request.ask) {
          ByteWriter reply;
          reply.put(farm_id_).put(next).put_string(next >= 0 && farm.share ? farm.share() : std::string());
          send_bytes(reply.bytes(), from, kTagReplyBase + request.thread, comm_);
        }
        if (request.last) --open;
      }
    } catch (const std::exception& e) {
      fail_rank(*this, e.what());
    }
  }

  // A rank that still has threads in the farm and has sent nothing (no request, no heartbeat)
  // for timeout_ seconds is hung or lost: the job ends with its name, after the checkpoint.
  void check_ranks_alive(const TaskFarm& farm, const std::vector<Clock::time_point>& last_seen,
                         const std::vector<int>& open_per_rank) {
    const auto now = Clock::now();
    for (int r = 1; r < size_; ++r) {
      const double silent = std::chrono::duration<double>(now - last_seen[static_cast<std::size_t>(r)]).count();
      if (open_per_rank[static_cast<std::size_t>(r)] == 0 || silent <= timeout_) continue;
      if (farm.on_abort) farm.on_abort();
      std::ostringstream s;
      s << "hapsyn: error: rank " << r << " on " << host(r) << " has not answered for " << std::fixed
        << std::setprecision(1) << silent << " s (--rank-timeout " << timeout_
        << " s): it hung or its node was lost; ending the job. The last checkpoint is kept: continue with "
           "`hapsyn run FILE --resume`, on any number of ranks\n";
      std::cerr << s.str() << std::flush;
      MPI_Abort(comm_, 5);
      std::abort();  // MPI_Abort does not return
    }
  }

  // ---- ranks 1..N-1: each thread asks rank 0 for tasks; this thread sends heartbeats. ----

  bool work(const TaskFarm& farm, int threads) {
    std::atomic<int> running{threads};
    std::atomic<bool> stop_seen{false};
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t) {
      pool.emplace_back([&, t] {
        run_remote_thread(farm, t, threads, stop_seen);
        --running;
      });
    }
    auto last_beat = Clock::now();
    while (running.load() > 0) {
      if (requested()) make_visible();  // this rank's running tasks stop now; rank 0 hears it next
      if (std::chrono::duration<double>(Clock::now() - last_beat).count() >= kHeartbeatSeconds) {
        ByteWriter beat;
        beat.put(farm_id_);
        send_bytes(beat.bytes(), 0, kTagHeartbeat, comm_);
        last_beat = Clock::now();
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    for (std::thread& t : pool) t.join();
    return stop_seen.load();
  }

  // Each thread keeps one request in flight besides the task it runs (it asks for the next task
  // when it starts one), so the round trip to rank 0 overlaps the work instead of adding to it.
  // It ends once rank 0 said "no more" (or "stop") and no request is in flight, with a last
  // message (rank 0 counts those to know the farm is over).
  void run_remote_thread(const TaskFarm& farm, int thread, int threads, std::atomic<bool>& stop_seen) {
    try {
      Request message;
      message.farm = farm_id_;
      message.thread = thread;
      message.threads = threads;
      int in_flight = 0;
      bool no_more = false;
      std::vector<long long> ready;  // tasks received, not yet run
      const auto send = [&](bool ask) {
        message.stop = message.stop || requested() || (visible_ != nullptr && visible_->load());
        message.ask = ask;
        message.share = farm.share ? farm.share() : std::string();
        send_bytes(encode(message), 0, kTagRequest, comm_);
        message.finished = kNoTask;
        message.result.clear();
        if (ask) ++in_flight;
      };
      // One reply: a task to run, or "no more" / "stop".
      const auto take_reply = [&](const std::string& bytes) {
        --in_flight;
        ByteReader in(bytes);
        in.get<long long>();  // farm id
        const long long index = in.get<long long>();
        const std::string share = in.get_string();
        if (index == kStopTask) {
          stop_seen = true;
          make_visible();
        }
        if (index < 0) {
          no_more = true;
          return;
        }
        if (farm.learn && !share.empty()) farm.learn(share);
        ready.push_back(index);
      };
      const auto wait_reply = [&] {
        std::string bytes;
        if (!receive_polling(bytes, 0, kTagReplyBase + thread, comm_, timeout_)) {
          fail_rank(*this, "rank 0 on " + host(0) + " has not answered a task request for " +
                               std::to_string(static_cast<int>(timeout_)) + " s (--rank-timeout): it hung or its node was lost");
        }
        take_reply(bytes);
      };
      const auto poll_reply = [&] {
        int flag = 0;
        MPI_Status status;
        MPI_Iprobe(0, kTagReplyBase + thread, comm_, &flag, &status);
        if (flag) take_reply(receive_probed(status, comm_));
      };
      const auto may_ask = [&] { return !no_more && !message.stop && in_flight == 0; };
      send(true);
      for (;;) {
        if (ready.empty()) {
          if (in_flight == 0) break;
          wait_reply();
          continue;
        }
        const long long index = ready.front();
        ready.erase(ready.begin());
        if (may_ask()) send(true);  // the next task travels while this one runs
        std::optional<std::string> out = message.stop ? std::nullopt : farm.run(index, thread);
        if (out) {
          message.finished = index;
          message.result = std::move(*out);
          if (in_flight > 0) poll_reply();  // usually here already: then the result asks for the next
          send(may_ask());
        } else {
          message.stop = true;  // not run, nor those received after it: a resumed run does them
          stop_seen = true;
          ready.clear();
          send(false);
        }
      }
      message.last = true;
      send(false);
    } catch (const std::exception& e) {
      fail_rank(*this, e.what());
    }
  }

  const std::atomic<bool>* requested_;
  std::atomic<bool>* visible_;
  double timeout_;
  MPI_Comm comm_ = MPI_COMM_NULL, node_ = MPI_COMM_NULL;
  int rank_ = 0, size_ = 1;
  std::vector<std::string> hosts_;
  long long farm_id_ = 0;
};

// An error inside a farm cannot be thrown to the solver: the other ranks would wait for this one
// forever. It is printed with the rank's name and the job ends.
void fail_rank(const MpiCluster& cluster, const std::string& what) {
  std::cerr << "hapsyn: error: rank " << cluster.rank() << " on " << cluster.host(cluster.rank()) << ": " << what
            << "\n"
            << std::flush;
  MPI_Abort(cluster.comm(), 3);
  std::abort();
}

// Finalizes MPI at exit, once, when this process initialized it.
struct MpiSession {
  MpiSession() {
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_MULTIPLE, &provided);
    if (provided < MPI_THREAD_MULTIPLE) {
      MPI_Finalize();
      throw Error("mpi", "this MPI library gives no MPI_THREAD_MULTIPLE (the farm's threads talk to rank 0 "
                         "concurrently): use an Open MPI built with thread support");
    }
  }
  ~MpiSession() {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized) MPI_Finalize();
  }
};

}  // namespace

bool mpi_built() { return true; }

std::unique_ptr<Cluster> make_mpi_cluster(const std::atomic<bool>* requested, std::atomic<bool>* visible,
                                          double rank_timeout) {
  if (!(rank_timeout > 0)) throw Error("mpi", "--rank-timeout must be > 0 s");
  static MpiSession session;  // MPI_Finalize after main returns, after every cluster is gone
  return std::make_unique<MpiCluster>(requested, visible, rank_timeout);
}

bool first_on_node(const Cluster& cluster) {
  const auto* mpi = dynamic_cast<const MpiCluster*>(&cluster);
  if (mpi == nullptr) return true;
  int node_rank = 0;
  MPI_Comm_rank(mpi->node(), &node_rank);
  return node_rank == 0;
}

void node_barrier(const Cluster& cluster) {
  const auto* mpi = dynamic_cast<const MpiCluster*>(&cluster);
  if (mpi == nullptr) return;
  MPI_Request request;
  MPI_Ibarrier(mpi->node(), &request);
  wait_polling(request);
}

void abort_job(const Cluster& cluster, int code) {
  if (const auto* mpi = dynamic_cast<const MpiCluster*>(&cluster)) {
    MPI_Abort(mpi->comm(), code);
  }
  std::exit(code);
}

}  // namespace hapsyn
