#include "pagmo_adapter.hpp"

#include <hapsyn/cluster.hpp>
#include <hapsyn/bytes.hpp>

#include <hapsyn/error.hpp>
#include <hapsyn/parallel.hpp>

#include <pagmo/algorithms/gaco.hpp>
#include <pagmo/algorithms/nsga2.hpp>
#include <pagmo/algorithms/sga.hpp>
#include <pagmo/population.hpp>
#include <pagmo/s11n.hpp>
#include <pagmo/utils/generic.hpp>

#include <boost/archive/text_iarchive.hpp>
#include <boost/archive/text_oarchive.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>

namespace hapsyn::plugins::pagmo_adapter {

namespace {
std::vector<std::vector<int>> sort_groups(const Problem& problem, const std::vector<std::string>& names,
                                          const std::string& key, const std::string& component) {
  const DesignSpace& space = problem.design_space();
  std::vector<std::vector<int>> groups;
  for (std::size_t i = 0; i < names.size(); ++i) {
    bool declared = false;
    std::vector<int> group;
    std::string variables;
    for (std::size_t k = 0; k < space.components().size(); ++k) {
      const DesignComponent& c = space.components()[k];
      if (c.index == 0) variables += (variables.empty() ? "" : ", ") + c.variable;
      if (c.variable != names[i]) continue;
      declared = true;
      const auto& free = space.free_indices();
      const auto it = std::find(free.begin(), free.end(), static_cast<int>(k));
      if (it != free.end()) group.push_back(static_cast<int>(it - free.begin()));
    }
    if (!declared) {
      throw Error(component, "options." + key + "[" + std::to_string(i) + "] = \"" + names[i] +
                                 "\": no such design variable; the variables are: " + variables);
    }
    if (group.size() > 1) groups.push_back(group);
  }
  return groups;
}
}  // namespace

Encoding::Encoding(const Problem& problem, const std::vector<std::string>& sort_descending,
                   const std::vector<std::string>& sort_ascending, const std::string& component) {
  const DesignSpace& space = problem.design_space();
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t k = 0; k < space.free_size(); ++k) {
      const DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
      if (c.integer != (pass == 1)) continue;
      to_free_.push_back(static_cast<int>(k));
      lower_.push_back(c.lower);
      upper_.push_back(c.upper);
      if (c.integer) ++integer_count_;
    }
  }
  descending_ = sort_groups(problem, sort_descending, "sort_descending", component);
  ascending_ = sort_groups(problem, sort_ascending, "sort_ascending", component);
}

std::vector<double> Encoding::decode(const double* x) const {
  std::vector<double> free(to_free_.size());
  const std::size_t first_integer = to_free_.size() - integer_count_;
  for (std::size_t i = 0; i < to_free_.size(); ++i) {
    double v = i >= first_integer ? std::round(x[i]) : x[i];
    v = std::min(upper_[i], std::max(lower_[i], v));
    free[static_cast<std::size_t>(to_free_[i])] = v;
  }
  auto apply = [&](const std::vector<int>& group, bool descending) {
    std::vector<double> values;
    for (int k : group) values.push_back(free[static_cast<std::size_t>(k)]);
    if (descending) {
      std::sort(values.begin(), values.end(), std::greater<double>());
    } else {
      std::sort(values.begin(), values.end());
    }
    for (std::size_t j = 0; j < group.size(); ++j) free[static_cast<std::size_t>(group[j])] = values[j];
  };
  for (const auto& g : descending_) apply(g, true);
  for (const auto& g : ascending_) apply(g, false);
  return free;
}

pagmo::vector_double Encoding::encode(const std::vector<double>& free) const {
  pagmo::vector_double x(to_free_.size());
  for (std::size_t i = 0; i < to_free_.size(); ++i) x[i] = free[static_cast<std::size_t>(to_free_[i])];
  return x;
}

Json Encoding::describe_repair(const Problem& problem) const {
  auto names = [&](const std::vector<std::vector<int>>& groups) {
    Json out = Json::array();
    for (const auto& g : groups) {
      Json names_of_group = Json::array();
      for (int k : g) {
        names_of_group.push_back(
            problem.design_space().components()[static_cast<std::size_t>(problem.design_space().free_indices()[static_cast<std::size_t>(k)])].name);
      }
      out.push_back(names_of_group);
    }
    return out;
  };
  return {{"sorted_descending", names(descending_)}, {"sorted_ascending", names(ascending_)}};
}

Evaluator::Evaluator(const Problem& problem, Encoding encoding, EvaluationSettings settings, bool multi_objective)
    : problem_(problem), encoding_(std::move(encoding)), settings_(settings), multi_objective_(multi_objective) {
  settings_.threads = std::max(1, settings_.threads);
  settings_.sample_chunks = std::max(1, settings_.sample_chunks);
  // Each thread makes its scratch at its first design, in evaluate() (docs/design.md section 1.5).
  workspaces_.resize(static_cast<std::size_t>(settings_.threads));
}

void Evaluator::set_subset(const std::vector<int>* subset, int fidelity_level) {
  subset_ = subset;
  fidelity_level_ = fidelity_level;
}

DesignRecord Evaluator::make_record(const Evaluation& e) const {
  DesignRecord r;
  const std::size_t n = objective_count();
  if (e.status == EvalStatus::kFeasible) {
    r.feasible = true;
    r.objectives = e.objectives;
    r.score = e.score;
    if (multi_objective_) {
      for (std::size_t o = 0; o < n; ++o) {
        const bool maximize = problem_.objectives()[o].sense == Sense::kMaximize;
        r.fitness.push_back(maximize ? -e.objectives[o] : e.objectives[o]);
      }
    } else {
      r.fitness.push_back(-e.score);
    }
    return r;
  }
  r.score = -std::numeric_limits<double>::infinity();
  double penalty = kSampleFailedFitness;
  if (e.status == EvalStatus::kConstraintViolated) {
    r.failure = "design constraint '" + problem_.constraint_names()[static_cast<std::size_t>(e.failed_constraint)] + "' violated";
    penalty = kConstraintFitness;
  } else {
    r.failure = std::string("sample ") + std::to_string(e.failed_sample) + " " + to_string(e.failed_status);
  }
  r.fitness.assign(n, penalty);
  return r;
}

Evaluator::Outcome Evaluator::evaluate(const std::vector<double>& free, int thread) {
  if (settings_.over_individuals) {
    EvalOptions options;
    options.subset = subset_;
    std::unique_ptr<Problem::EvalScratch>& ws = workspaces_[static_cast<std::size_t>(thread)];
    if (!ws) ws = problem_.make_eval_scratch();
    // The scratch's own evaluation, read in place: copying it cost a few allocations per design.
    return outcome_of(free, problem_.evaluate(free.data(), *ws, options));
  }
  Problem::ParallelOptions options;
  options.chunks = settings_.sample_chunks;
  options.subset = subset_;
  return outcome_of(free, problem_.evaluate_parallel(free.data(), settings_.threads, options));
}

Evaluator::Outcome Evaluator::outcome_of(const std::vector<double>& free, const Evaluation& e) const {
  Outcome out;
  out.samples = e.samples_evaluated;
  out.record = make_record(e);
  if (e.status == EvalStatus::kConstraintViolated) add_violation(free, out.record);
  return out;
}

void Evaluator::add_violation(const std::vector<double>& free, DesignRecord& record) const {
  std::vector<double> g(problem_.constraint_count());
  problem_.constraints(free.data(), g.data());
  double violation = 0.0;
  for (double v : g) violation += std::max(0.0, v);
  for (double& f : record.fitness) f += violation;
}

const DesignRecord& Evaluator::record(const pagmo::vector_double& x) {
  std::vector<double> free = encoding_.decode(x);
  Key key(fidelity_level_, std::move(free));
  const auto found = cache_.find(key);
  if (found != cache_.end()) {
    // A prefetched design's first look-up stands for the evaluation fitness() would have made.
    if (prefetched_.erase(key) == 0) ++cache_hits_;
    return found->second;
  }
  Outcome o = evaluate(key.second, 0);
  ++designs_;
  samples_ += o.samples;
  return cache_.emplace(std::move(key), std::move(o.record)).first->second;
}

pagmo::vector_double Evaluator::fitness(const pagmo::vector_double& x) {
  if (recording_) {
    // prefetch()'s probe: the design is noted; the value only steers the probe's reinsertion,
    // which is thrown away.
    recorded_.insert(recorded_.end(), x.begin(), x.end());
    const auto found = cache_.find(Key(fidelity_level_, encoding_.decode(x)));
    return found != cache_.end() ? found->second.fitness : pagmo::vector_double(objective_count(), kSampleFailedFitness);
  }
  return record(x).fitness;
}

namespace {

// Exact binary records for the farm's results and rank 0's broadcast (hapsyn/bytes.hpp).
void put_record(ByteWriter& w, const DesignRecord& r, long long samples) {
  w.put_vector(r.fitness);
  w.put_vector(r.objectives);
  w.put(r.score);
  w.put(static_cast<char>(r.feasible ? 1 : 0));
  w.put_string(r.failure);
  w.put(samples);
}

void get_record(ByteReader& in, DesignRecord& r, long long& samples) {
  r.fitness = in.get_vector();
  r.objectives = in.get_vector();
  r.score = in.get<double>();
  r.feasible = in.get<char>() != 0;
  r.failure = in.get_string();
  samples = in.get<long long>();
}

}  // namespace

std::size_t Evaluator::fill_cache(std::vector<std::vector<double>>& decoded, std::vector<const DesignRecord*>& found,
                                  std::vector<std::vector<double>>* evaluated) {
  // Distinct phenotypes not in the cache, in order of first appearance: todo[k] is the index in
  // `decoded` of the k-th; slot[i] the todo entry design i waits for (-1: cached). Looked up in
  // place (a key borrows the vector and gives it back), so that a design costs no copy here.
  const std::size_t count = decoded.size();
  found.assign(count, nullptr);
  std::vector<std::size_t> todo;
  std::vector<std::ptrdiff_t> slot(count, -1);
  struct DerefHash {
    std::size_t operator()(const std::vector<double>* v) const { return VectorHash()(*v); }
  };
  struct DerefEqual {
    bool operator()(const std::vector<double>* a, const std::vector<double>* b) const { return *a == *b; }
  };
  std::unordered_map<const std::vector<double>*, std::size_t, DerefHash, DerefEqual> queued;
  for (std::size_t i = 0; i < count; ++i) {
    Key key(fidelity_level_, std::move(decoded[i]));
    const auto cached = cache_.find(key);
    decoded[i] = std::move(key.second);
    if (cached != cache_.end()) {
      found[i] = &cached->second;
      continue;
    }
    const auto [queued_at, added] = queued.emplace(&decoded[i], todo.size());
    if (added) todo.push_back(i);
    slot[i] = static_cast<std::ptrdiff_t>(queued_at->second);
  }
  const std::size_t n = todo.size();
  const auto design = [&](std::size_t k) -> const std::vector<double>& { return decoded[todo[k]]; };
  std::vector<DesignRecord> records(n);
  std::vector<long long> samples(n, 0);
  std::vector<char> have(n, 0);
  Cluster& cluster = settings_.cluster != nullptr ? *settings_.cluster : Cluster::local();
  const bool several = cluster.size() > 1;
  // One task per design: the same split whatever the rank count, and each design evaluated by
  // the one path of the settings, so the values do not depend on where it ran.
  TaskFarm farm;
  farm.count = static_cast<long long>(n);
  farm.run = [&](long long i, int thread) -> std::optional<std::string> {
    Outcome o = evaluate(design(static_cast<std::size_t>(i)), thread);
    if (!several) {
      records[static_cast<std::size_t>(i)] = std::move(o.record);
      samples[static_cast<std::size_t>(i)] = o.samples;
      have[static_cast<std::size_t>(i)] = 1;
      return std::string();
    }
    ByteWriter w;
    put_record(w, o.record, o.samples);
    return w.take();
  };
  farm.collect = [&](long long i, std::string&& bytes) {
    if (!several) return;
    ByteReader in(bytes);
    get_record(in, records[static_cast<std::size_t>(i)], samples[static_cast<std::size_t>(i)]);
    have[static_cast<std::size_t>(i)] = 1;
  };
  // Over the samples each design takes every thread of its rank: one task per rank at a time.
  (void)cluster.run_tasks(farm, settings_.over_individuals ? settings_.threads : 1);
  if (several) {
    std::string all;
    if (cluster.root()) {
      ByteWriter w;
      for (std::size_t i = 0; i < n; ++i) {
        w.put(have[i]);
        if (have[i]) put_record(w, records[i], samples[i]);
      }
      all = w.take();
    }
    cluster.broadcast(all);
    if (!cluster.root()) {
      ByteReader in(all);
      for (std::size_t i = 0; i < n; ++i) {
        have[i] = in.get<char>();
        if (have[i]) get_record(in, records[i], samples[i]);
      }
    }
  }
  // A stop ends an MPI farm early; the designs it left out are evaluated here, on every rank
  // alike (no collective), so that the batch, and the generation, complete identically.
  std::vector<long long> missing;
  for (std::size_t i = 0; i < n; ++i) {
    if (!have[i]) missing.push_back(static_cast<long long>(i));
  }
  if (!missing.empty()) {
    const auto one = [&](long long k, int thread) {
      const std::size_t i = static_cast<std::size_t>(missing[static_cast<std::size_t>(k)]);
      Outcome o = evaluate(design(i), thread);
      records[i] = std::move(o.record);
      samples[i] = o.samples;
    };
    if (settings_.over_individuals) {
      parallel_for_dynamic(static_cast<long long>(missing.size()), settings_.threads, 1, one);
    } else {
      for (long long k = 0; k < static_cast<long long>(missing.size()); ++k) one(k, 0);
    }
  }
  if (evaluated) {
    evaluated->clear();
    for (std::size_t k = 0; k < n; ++k) evaluated->push_back(design(k));
  }
  // The queue's keys point into `decoded`, whose vectors move into the cache now.
  queued.clear();
  std::vector<const DesignRecord*> records_of(n);
  for (std::size_t k = 0; k < n; ++k) {
    ++designs_;
    samples_ += samples[k];
    records_of[k] = &cache_.emplace(Key(fidelity_level_, std::move(decoded[todo[k]])), std::move(records[k])).first->second;
  }
  for (std::size_t i = 0; i < count; ++i) {
    if (slot[i] >= 0) found[i] = records_of[static_cast<std::size_t>(slot[i])];
  }
  return n;
}

pagmo::vector_double Evaluator::batch_fitness(const pagmo::vector_double& xs) {
  const std::size_t dim = encoding_.size();
  const std::size_t n = dim == 0 ? 0 : xs.size() / dim;
  const std::size_t nf = objective_count();
  std::vector<std::vector<double>> decoded(n);
  for (std::size_t i = 0; i < n; ++i) decoded[i] = encoding_.decode(xs.data() + i * dim);
  std::vector<const DesignRecord*> found;
  const std::size_t evaluated = fill_cache(decoded, found);
  pagmo::vector_double out(n * nf);
  for (std::size_t i = 0; i < n; ++i) {
    std::copy(found[i]->fitness.begin(), found[i]->fitness.end(), out.begin() + static_cast<std::ptrdiff_t>(i * nf));
  }
  cache_hits_ += static_cast<long long>(n - evaluated);
  return out;
}

void Evaluator::prefetch(const pagmo::algorithm& algorithm, const pagmo::population& population) {
  recorded_.clear();
  prefetched_.clear();
  recording_ = true;
  try {
    pagmo::algorithm probe(algorithm);
    (void)probe.evolve(population);
  } catch (...) {
    recording_ = false;
    throw;
  }
  recording_ = false;
  const std::size_t dim = encoding_.size();
  const std::size_t n = dim == 0 ? 0 : recorded_.size() / dim;
  std::vector<std::vector<double>> decoded(n), evaluated;
  for (std::size_t i = 0; i < n; ++i) decoded[i] = encoding_.decode(recorded_.data() + i * dim);
  std::vector<const DesignRecord*> found;
  fill_cache(decoded, found, &evaluated);
  for (auto& free : evaluated) prefetched_.emplace(fidelity_level_, std::move(free));
}

pagmo::problem make_problem(const std::shared_ptr<Evaluator>& evaluator) { return pagmo::problem{Udp(evaluator)}; }

pagmo::population random_population(const pagmo::problem& problem, Evaluator& evaluator, std::size_t size,
                                    std::uint64_t seed) {
  std::mt19937 rng(static_cast<std::mt19937::result_type>(seed ^ (seed >> 32)));
  std::vector<pagmo::vector_double> x;
  pagmo::vector_double all;
  for (std::size_t i = 0; i < size; ++i) {
    x.push_back(pagmo::random_decision_vector(problem, rng));
    all.insert(all.end(), x.back().begin(), x.back().end());
  }
  const pagmo::vector_double f = evaluator.batch_fitness(all);
  const std::size_t nf = evaluator.objective_count();
  pagmo::population population(problem, 0u, static_cast<unsigned>(seed));
  for (std::size_t i = 0; i < size; ++i) {
    population.push_back(x[i], pagmo::vector_double(f.begin() + static_cast<std::ptrdiff_t>(i * nf),
                                                    f.begin() + static_cast<std::ptrdiff_t>((i + 1) * nf)));
  }
  return population;
}

pagmo::population restore_population(const pagmo::problem& problem, const std::vector<pagmo::vector_double>& x,
                                     const std::vector<pagmo::vector_double>& f) {
  pagmo::population population(problem, 0u, 0u);
  for (std::size_t i = 0; i < x.size(); ++i) population.push_back(x[i], f[i]);
  return population;
}

void reevaluate(pagmo::population& population, Evaluator& evaluator) {
  pagmo::vector_double all;
  for (const auto& x : population.get_x()) all.insert(all.end(), x.begin(), x.end());
  const pagmo::vector_double f = evaluator.batch_fitness(all);
  const std::size_t nf = evaluator.objective_count();
  const auto xs = population.get_x();
  for (std::size_t i = 0; i < xs.size(); ++i) {
    population.set_xf(i, xs[i], pagmo::vector_double(f.begin() + static_cast<std::ptrdiff_t>(i * nf),
                                                     f.begin() + static_cast<std::ptrdiff_t>((i + 1) * nf)));
  }
}

std::string save_algorithm(const pagmo::algorithm& algorithm) {
  std::ostringstream out;
  {
    boost::archive::text_oarchive archive(out);
    archive << algorithm;
  }
  return out.str();
}

pagmo::algorithm load_algorithm(const std::string& text) {
  std::istringstream in(text);
  pagmo::algorithm algorithm;
  boost::archive::text_iarchive archive(in);
  archive >> algorithm;
  return algorithm;
}

std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t index) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (index + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

Json matrix_to_json(const std::vector<pagmo::vector_double>& rows) {
  Json out = Json::array();
  for (const auto& r : rows) out.push_back(r);
  return out;
}

std::vector<pagmo::vector_double> matrix_from_json(const Json& j) {
  std::vector<pagmo::vector_double> rows;
  for (const Json& r : j) rows.push_back(r.get<pagmo::vector_double>());
  return rows;
}

std::string format_duration(double seconds) {
  char buffer[64];
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  if (seconds < 60) {
    std::snprintf(buffer, sizeof buffer, "%.1fs", seconds);
  } else if (seconds < 3600) {
    std::snprintf(buffer, sizeof buffer, "%dm%02ds", static_cast<int>(seconds) / 60, static_cast<int>(seconds) % 60);
  } else {
    std::snprintf(buffer, sizeof buffer, "%dh%02dm", static_cast<int>(seconds) / 3600, (static_cast<int>(seconds) % 3600) / 60);
  }
  return buffer;
}

ProgressReporter::ProgressReporter(std::ostream* progress, std::ostream* log, double interval)
    : progress_(progress), log_(log), interval_(interval), last_(std::chrono::steady_clock::now()) {}

void ProgressReporter::line(const std::string& text, bool force) {
  if (log_) {
    *log_ << text << "\n";
    log_->flush();
  }
  if (!progress_) return;
  const auto now = std::chrono::steady_clock::now();
  if (force || first_ || std::chrono::duration<double>(now - last_).count() >= interval_) {
    *progress_ << text << "\n";
    progress_->flush();
    last_ = now;
    first_ = false;
  }
}

}  // namespace hapsyn::plugins::pagmo_adapter
