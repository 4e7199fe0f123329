#pragma once
/// \file
/// The one bridge between hapsyn and pagmo 2.18, shared by the `ga` and `nsga2` solvers
/// (static library hapsyn_pagmo_adapter; solvers include it as "shared/pagmo_adapter.hpp").
/// pagmo's type erasure stays behind this header's implementation and the two solvers; of the
/// framework, only the hypervolume of pareto.cpp uses pagmo.
///
/// - Encoding: pagmo wants the integer components last (get_nix()); hapsyn's free vector keeps
///   declaration order. The encoding permutes (reals first, then integers, each in free order),
///   rounds integer components and applies the constraint repair.
/// - Repair: the free components of each variable named in `sort_descending` (`sort_ascending`)
///   are sorted in descending (ascending) order before evaluation: the haptic 6R's
///   s_i >= s_{i+1} holds for every decoded design (a decoder: the genotype stays unsorted in
///   the population, the phenotype evaluated and reported is sorted). Fixed components keep
///   their values; any constraint still violated is penalised.
/// - Fitness (pagmo minimises): single-objective -score; multi-objective per objective -f for
///   maximise, f for minimise. Infeasible designs: kSampleFailedFitness when a sample fails
///   (worst-case metrics), kConstraintFitness + the sum of the violations when a design
///   constraint fails, in every component: worse than any feasible design with |score| < 1e9.
/// - Evaluation: batch_fitness (used by pagmo algorithms with a batch evaluator: gaco, nsga2;
///   by the solvers for initial populations and re-rankings; and for sga's offspring through
///   Evaluator::prefetch) is a task farm over the ranks of EvaluationSettings::cluster (one task
///   per design, on the threads of every rank; hapsyn/cluster.hpp), whose fitness values rank 0
///   broadcasts so that every rank's replicated pagmo algorithm goes on with the same values.
///   Each design is evaluated by one path, fixed by the settings: "individuals" one design per
///   thread (Problem::evaluate, samples in sample order), "samples" one design after another
///   split over the samples in a fixed number of chunks (Problem::evaluate_parallel). The same
///   path serves single designs (fitness(), record()). Phenotypes already evaluated at the same
///   fidelity come from a cache, which therefore returns exactly what a fresh evaluation would
///   (bit for bit): a run's trajectory depends neither on the cache's content (other runs, a
///   resume) nor on the thread or rank count.
#include <hapsyn/cluster.hpp>
#include <hapsyn/json.hpp>
#include <hapsyn/problem.hpp>

#include <pagmo/algorithm.hpp>
#include <pagmo/problem.hpp>
#include <pagmo/types.hpp>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

namespace hapsyn::plugins::pagmo_adapter {

/// Fitness component of a design whose evaluation met a failing sample.
constexpr double kSampleFailedFitness = 1e9;
/// Fitness component of a design that violates a design constraint (plus the violation).
constexpr double kConstraintFitness = 2e9;

/// Maps pagmo decision vectors (reals first, integers last) to hapsyn free vectors and back.
class Encoding {
 public:
  /// \param sort_descending, sort_ascending variable names whose free components are sorted
  /// \param component the solver name, for errors
  /// \throws Error("<component>: options.sort_descending[i] = \"x\": no such design variable; ...")
  Encoding(const Problem& problem, const std::vector<std::string>& sort_descending,
           const std::vector<std::string>& sort_ascending, const std::string& component);

  std::size_t size() const { return to_free_.size(); }
  /// Number of integer components (the last ones of a pagmo vector).
  std::size_t integer_count() const { return integer_count_; }
  /// Bounds in pagmo order.
  const pagmo::vector_double& lower() const { return lower_; }
  const pagmo::vector_double& upper() const { return upper_; }
  /// Free vector (hapsyn order) of a pagmo vector: integers rounded, clamped, repaired.
  std::vector<double> decode(const pagmo::vector_double& x) const { return decode(x.data()); }
  /// The same for the size() values at `x` (one design of a concatenated batch).
  std::vector<double> decode(const double* x) const;
  /// Pagmo vector of a free vector (no repair).
  pagmo::vector_double encode(const std::vector<double>& free) const;
  /// Free indices of each sort group (descending groups first), for the README/statistics.
  Json describe_repair(const Problem& problem) const;

 private:
  std::vector<int> to_free_;  // pagmo position -> free index
  std::size_t integer_count_ = 0;
  pagmo::vector_double lower_, upper_;
  std::vector<std::vector<int>> descending_, ascending_;  // free indices, in component order
};

/// How designs are evaluated.
struct EvaluationSettings {
  /// Threads of this process.
  int threads = 1;
  /// The path of every evaluation: "individuals" (one design per thread at a time, each on one
  /// thread) or "samples" (one design at a time, split over the threads by sample chunks).
  bool over_individuals = true;
  /// Chunks of the sample order when one design is split over the samples (fixed: the result
  /// does not depend on the thread count).
  int sample_chunks = 16;
  /// The ranks batches are farmed over (SolverContext::cluster(): an MPI job); null: this
  /// process alone. Every rank must then make the same evaluator calls in the same order.
  Cluster* cluster = nullptr;
};

/// A decoded design's outcome, as the cache keeps it.
struct DesignRecord {
  pagmo::vector_double fitness;
  std::vector<double> objectives;  ///< natural values (empty when infeasible)
  double score = 0.0;              ///< -inf when infeasible
  bool feasible = false;
  std::string failure;             ///< why not feasible
};

/// The shared, mutable evaluation state behind the UDP (pagmo copies UDPs; copies share it).
/// Not thread-safe itself: pagmo calls it from one thread; it parallelises inside.
class Evaluator {
 public:
  Evaluator(const Problem& problem, Encoding encoding, EvaluationSettings settings, bool multi_objective);

  const Problem& problem() const { return problem_; }
  const Encoding& encoding() const { return encoding_; }
  std::size_t objective_count() const { return multi_objective_ ? problem_.objectives().size() : 1; }

  /// Evaluate on this subset of samples from now on (null = the full scene). The cache keeps
  /// one table per fidelity.
  void set_subset(const std::vector<int>* subset, int fidelity_level);
  bool full_fidelity() const { return subset_ == nullptr; }

  /// One design (from the cache, or evaluated on this process alone: no collective).
  pagmo::vector_double fitness(const pagmo::vector_double& x);
  /// Concatenated decision vectors in, concatenated fitness vectors out. Collective when
  /// EvaluationSettings::cluster has several ranks: the designs not cached are a task farm over
  /// the ranks, their records broadcast from rank 0; designs a stopped farm left out are
  /// evaluated on every rank alike, so the batch is always complete (the caller sees the agreed
  /// stop flag afterwards).
  pagmo::vector_double batch_fitness(const pagmo::vector_double& xs);
  /// The record of a design at the current fidelity (evaluated when not cached, as fitness()).
  const DesignRecord& record(const pagmo::vector_double& x);
  /// For algorithms that ask fitness() one design at a time (sga): evolves a copy of
  /// `algorithm` (random engine included) on a copy of `population` while recording the designs
  /// asked for, and evaluates them as one batch (batch_fitness), so that the real evolve() that
  /// follows finds every offspring in the cache. Exact for algorithms whose offspring of a
  /// generation do not depend on the fitness of other offspring of the same generation (sga
  /// with one generation per evolve(): selection, crossover and mutation come before the
  /// evaluation). Counters and cache hits end up as if the offspring had been evaluated by
  /// fitness(). Collective as batch_fitness.
  void prefetch(const pagmo::algorithm& algorithm, const pagmo::population& population);

  long long design_evaluations() const { return designs_; }
  long long sample_evaluations() const { return samples_; }
  long long cache_hits() const { return cache_hits_; }
  /// Adds evaluations done before a resume.
  void add_counts(long long designs, long long samples) {
    designs_ += designs;
    samples_ += samples;
  }

 private:
  using Key = std::pair<int, std::vector<double>>;  // fidelity level, decoded free vector
  // Hash of a key consistent with its ==: the bits of each value, with -0 taken as +0. A hash
  // map, not an ordered one: a long run caches ~1e6 designs, and the ordered map's vector
  // comparisons were a tenth of an NSGA-II run (nothing iterates the cache in order).
  struct KeyHash {
    std::size_t operator()(const Key& key) const {
      std::uint64_t h = 0x9e3779b97f4a7c15ULL ^ static_cast<std::uint64_t>(key.first);
      for (double v : key.second) {
        std::uint64_t bits = 0;
        const double value = v == 0.0 ? 0.0 : v;
        std::memcpy(&bits, &value, sizeof bits);
        h ^= bits + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
      }
      return static_cast<std::size_t>(h);
    }
  };
  struct VectorHash {
    std::size_t operator()(const std::vector<double>& v) const { return KeyHash()(Key(0, v)); }
  };
  // A fresh evaluation's outcome.
  struct Outcome {
    DesignRecord record;
    long long samples = 0;
  };
  DesignRecord make_record(const Evaluation& e) const;
  // Evaluates one design by the settings' path; `thread` picks the scratch of the
  // over-individuals path (the samples path splits over all threads itself).
  Outcome evaluate(const std::vector<double>& free, int thread);
  // The outcome of design `free`'s evaluation `e`.
  Outcome outcome_of(const std::vector<double>& free, const Evaluation& e) const;
  // Adds the design's constraint violation (the sum of its positive constraint values) to
  // every fitness component of a constraint-violating design's record.
  void add_violation(const std::vector<double>& free, DesignRecord& record) const;
  // Evaluates the distinct designs of `decoded` not in the cache (over the cluster) and caches
  // them (the keys moved out of `decoded`); found[i] is then design i's record. Returns how many
  // designs it evaluated, and their keys in `evaluated` when not null.
  std::size_t fill_cache(std::vector<std::vector<double>>& decoded, std::vector<const DesignRecord*>& found,
                         std::vector<std::vector<double>>* evaluated = nullptr);

  const Problem& problem_;
  Encoding encoding_;
  EvaluationSettings settings_;
  bool multi_objective_;
  const std::vector<int>* subset_ = nullptr;
  int fidelity_level_ = 0;
  std::unordered_map<Key, DesignRecord, KeyHash> cache_;
  std::vector<std::unique_ptr<Problem::EvalScratch>> workspaces_;
  long long designs_ = 0, samples_ = 0, cache_hits_ = 0;
  // prefetch(): recording the designs fitness() is asked for, and the prefetched designs whose
  // first look-up is the evaluation fitness() would have made (not a cache hit).
  bool recording_ = false;
  pagmo::vector_double recorded_;
  std::unordered_set<Key, KeyHash> prefetched_;
};

/// The pagmo user-defined problem: a thin, copyable handle on an Evaluator.
class Udp {
 public:
  Udp() = default;
  explicit Udp(std::shared_ptr<Evaluator> evaluator) : evaluator_(std::move(evaluator)) {}
  pagmo::vector_double fitness(const pagmo::vector_double& x) const { return evaluator_->fitness(x); }
  pagmo::vector_double batch_fitness(const pagmo::vector_double& xs) const { return evaluator_->batch_fitness(xs); }
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const {
    return {evaluator_->encoding().lower(), evaluator_->encoding().upper()};
  }
  pagmo::vector_double::size_type get_nix() const { return evaluator_->encoding().integer_count(); }
  pagmo::vector_double::size_type get_nobj() const { return evaluator_->objective_count(); }
  /// The shared cache and counters are not safe for pagmo's own thread-based evaluators.
  pagmo::thread_safety get_thread_safety() const { return pagmo::thread_safety::none; }
  std::string get_name() const { return "hapsyn problem"; }

 private:
  std::shared_ptr<Evaluator> evaluator_;
};

/// A pagmo problem around an evaluator.
pagmo::problem make_problem(const std::shared_ptr<Evaluator>& evaluator);

/// A pagmo population of `size` random individuals (uniform in the bounds, integers uniform),
/// drawn from `seed` and evaluated in one batch.
pagmo::population random_population(const pagmo::problem& problem, Evaluator& evaluator, std::size_t size,
                                    std::uint64_t seed);
/// A population with the given decision and fitness vectors (nothing evaluated).
pagmo::population restore_population(const pagmo::problem& problem, const std::vector<pagmo::vector_double>& x,
                                     const std::vector<pagmo::vector_double>& f);
/// Re-evaluates every individual of `population` in one batch (after a fidelity switch).
void reevaluate(pagmo::population& population, Evaluator& evaluator);

/// An algorithm with its state (random engine included) as text (boost text archive), and back.
std::string save_algorithm(const pagmo::algorithm& algorithm);
pagmo::algorithm load_algorithm(const std::string& text);

/// splitmix64: independent 64-bit seeds from one (run r of a study: derive_seed(seed, r)).
std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t index);

/// JSON of a vector of vectors of doubles (exact round trip) and back.
Json matrix_to_json(const std::vector<pagmo::vector_double>& rows);
std::vector<pagmo::vector_double> matrix_from_json(const Json& j);

/// "1h02m", "3m05s", "12.3s".
std::string format_duration(double seconds);

/// Writes a line to the run log always and to the progress stream at most every `interval`
/// seconds (or when `force`).
class ProgressReporter {
 public:
  ProgressReporter(std::ostream* progress, std::ostream* log, double interval);
  void line(const std::string& text, bool force = false);

 private:
  std::ostream* progress_;
  std::ostream* log_;
  double interval_;
  std::chrono::steady_clock::time_point last_;
  bool first_ = true;
};

}  // namespace hapsyn::plugins::pagmo_adapter
