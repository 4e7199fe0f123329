#pragma once
/// \file
/// Solvers: single-objective (maximize a metric or a weighted sum) or Pareto (a front).
/// An optimizer outcome (converged, budget spent, infeasible) is a status and a message in
/// the SolverResult, never an exception; exceptions are for bad input only.
#include <hapsyn/json.hpp>
#include <hapsyn/problem.hpp>

#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace hapsyn {

class Cluster;  // hapsyn/cluster.hpp: the processes of a run

enum class SolverStatus {
  kConverged,        ///< the solver's optimality/termination criterion was met
  kBudgetExhausted,  ///< evaluation, iteration or time budget spent
  kInfeasible,       ///< no feasible design found
  kStopped,          ///< interrupted on request
  kFailed,           ///< the method failed (message says why)
};
const char* to_string(SolverStatus status);

/// A design with its objective values.
struct SolutionPoint {
  Eigen::VectorXd design;          ///< full design (all components)
  std::vector<double> objectives;  ///< natural values, one per objective
  double score = 0.0;              ///< weighted, sense-signed sum (maximized)
};

struct SolverResult {
  SolverStatus status = SolverStatus::kFailed;
  std::string message;
  std::optional<SolutionPoint> best;   ///< single-objective solvers
  std::vector<SolutionPoint> front;    ///< Pareto solvers: non-dominated points
  long long design_evaluations = 0;    ///< designs evaluated (any status)
  long long sample_evaluations = 0;    ///< mechanism solves (IK + quantities) performed
  Json statistics = Json::object();    ///< solver-specific figures for result.json
};

/// What the framework hands a solver besides the problem.
struct SolverContext {
  int threads = 1;                  ///< worker threads the solver may use
  std::uint64_t seed = 0;           ///< for stochastic solvers
  std::ostream* progress = nullptr; ///< progress lines (stderr), nullptr = quiet
  std::string output_directory;     ///< where the solver may write extra files
  /// Set when the user asks to stop (SIGINT, SIGTERM or SIGUSR1 in `hapsyn run`; may be null).
  /// A solver polls stop_requested() between units of work (a design, a block, a generation),
  /// writes its checkpoint and returns kStopped with its best so far.
  const std::atomic<bool>* stop = nullptr;
  /// The run's log (run.log in the output directory; null when there is none). Solvers write
  /// their progress lines here too, also with --quiet.
  std::ostream* log = nullptr;
  /// Where a solver that checkpoints writes its checkpoint (a JSON document, written with
  /// write_file_atomically; it must hold the run's "seed" at the top level); empty = none.
  std::string checkpoint_file;
  /// Continue from checkpoint_file when it exists (`hapsyn run --resume`); a solver without
  /// checkpoints starts over.
  bool resume = false;

  /// The processes of this run (MPI ranks or a shard; hapsyn/cluster.hpp); null: this process
  /// alone. Read it through cluster().
  Cluster* ranks = nullptr;
  /// The study's hypervolume reference point (indicators.reference_point: natural units, one
  /// value per objective); empty: none. A Pareto solver may report the hypervolume of its front
  /// as it goes against this point (never one it makes up).
  std::vector<double> reference_point;

  /// True once a stop was requested (see `stop`).
  bool stop_requested() const { return stop != nullptr && stop->load(std::memory_order_relaxed); }
  /// The processes of this run: *ranks, else Cluster::local() (include hapsyn/cluster.hpp to
  /// use it).
  Cluster& cluster() const;
  /// This context for a sub-solver that runs inside one task of a farm: the same, on this
  /// process alone (Cluster::local()), without progress lines or a checkpoint of its own.
  SolverContext in_task() const {
    SolverContext c = *this;
    c.ranks = nullptr;
    c.progress = nullptr;
    c.log = nullptr;
    c.checkpoint_file.clear();
    c.resume = false;
    return c;
  }
};

/// What a solver can do: read once, at load (Solver::specs()).
struct SolverSpecs {
  /// A Pareto solver: several objectives give a front instead of a weighted sum.
  bool pareto = false;
  /// solve() spreads its work over the ranks of an MPI job through context.cluster().run_tasks
  /// (and follows the rules of hapsyn/cluster.hpp: deterministic between farms, stop checks that
  /// see the agreed flag). False: under mpirun the framework runs solve() on rank 0 alone and
  /// the other ranks wait.
  bool distributed = false;
  /// `hapsyn run --shard i/N` can split this solver's job (it has a shardable task farm), and
  /// Solver::merge_shards() combines the shares' checkpoints.
  bool shardable = false;
};

/// Solver plugin: the one pure virtual is solve(); everything else has a default.
///
/// Life cycle: created once per study (options filled from its declarations, sub-solvers
/// created by the framework: see hapsyn/options.hpp, SubSolver); specs() is read at load;
/// check() runs once at load, after the problem is built and before anything runs; solve() runs
/// once per run, from one thread (it may start `context.threads` workers of its own and call
/// Problem::evaluate / evaluate_parallel from them: the problem is thread-safe, one
/// Problem::EvalScratch per thread).
///
/// What the framework checks centrally, so a solver need not: the problem's designs are
/// validated on every evaluation (finite, within bounds), plugin outputs are checked for NaN/inf,
/// options are validated. The solver reports its outcome as a status and a message in the
/// SolverResult; it throws hapsyn::Error only for bad input (a problem it cannot handle, found in
/// check()), and never for an optimizer outcome.
class Solver {
 public:
  Solver() = default;
  Solver(const Solver&) = delete;
  Solver& operator=(const Solver&) = delete;
  virtual ~Solver() = default;
  /// Solves the problem. Returns kConverged, kBudgetExhausted, kInfeasible, kStopped (when
  /// *context.stop became true: return the best found so far promptly) or kFailed with a message
  /// saying why. best (single-objective) or front (specs().pareto) holds full design vectors with
  /// their natural objective values. Never throws for an optimizer outcome.
  virtual SolverResult solve(const Problem& problem, const SolverContext& context) const = 0;
  /// What the solver can do (read once, at load).
  virtual SolverSpecs specs() const { return {}; }
  /// Throws hapsyn::Error if the problem is not one this solver handles (e.g. a non-worst-case
  /// metric for culling, a free variable without a grid step), and checks its sub-solvers
  /// against the problems they will see (check_sub_solver in plugins/solvers/shared). Called
  /// once at load, before solve(); the message is reported as "problem: solver: <message>".
  virtual void check(const Problem& problem) const {}
  /// Combines the checkpoint states ("state" of each shard's checkpoint.json, by shard index)
  /// of a sharded run into the state of one checkpoint from which `--resume` finishes the study
  /// with the result of a single run (every claimed value is re-checked there).
  /// \throws Error("merge", ...) when the shares overlap, leave tasks out or disagree; the
  ///         default throws "solver does not support --shard".
  virtual Json merge_shards(const Problem& problem, const std::vector<Json>& states) const;
};

}  // namespace hapsyn
