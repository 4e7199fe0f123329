#include "ga_checkpoint.hpp"

#include "shared/pagmo_adapter.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/options.hpp>
#include <hapsyn/output_files.hpp>

#include <fstream>
#include <sstream>

namespace hapsyn::plugins::ga {

namespace pa = pagmo_adapter;

namespace {

// FNV-1a: a stable hash of the study text.
std::string fnv1a(const std::string& text) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  std::ostringstream s;
  s << std::hex << h;
  return s.str();
}

}  // namespace

std::string study_fingerprint(const Problem& problem, const GaOptions& options) {
  std::ostringstream s;
  s.precision(17);
  s << options_to_json(options).dump() << "|" << problem.samples().size() << "|";
  for (int k : problem.design_space().free_indices()) {
    const DesignComponent& c = problem.design_space().components()[static_cast<std::size_t>(k)];
    s << c.name << ":" << c.lower << ":" << c.upper << ":" << c.integer << ";";
  }
  for (const Objective& o : problem.objectives()) s << o.name << ":" << o.weight << ":" << (o.sense == Sense::kMaximize) << ";";
  return fnv1a(s.str());
}

Checkpoint read_checkpoint(const std::string& file, const std::string& fingerprint) {
  std::ifstream in(file);
  Json document;
  try {
    document = Json::parse(in);
  } catch (const std::exception& e) {
    throw Error("ga", file + ": cannot be read as a checkpoint (" + e.what() + ")");
  }
  if (document.value("solver", "") != "ga" || document.value("fingerprint", "") != fingerprint) {
    throw Error("ga", file + ": written for another study (solver '" + document.value("solver", "?") + "', fingerprint " +
                          document.value("fingerprint", "?") + ", this study " + fingerprint +
                          "); delete it or run without --resume");
  }
  Checkpoint c;
  c.completed_runs = document.at("completed_runs");
  c.run_seconds = document.at("run_seconds").get<std::vector<double>>();
  c.designs = document.at("evaluations").at("designs");
  c.samples = document.at("evaluations").at("samples");
  c.elapsed_seconds = document.at("elapsed_seconds");
  if (document.contains("current")) c.current = document.at("current");
  return c;
}

void write_checkpoint(const std::string& file, std::uint64_t seed, const std::string& fingerprint,
                      const Checkpoint& checkpoint) {
  Json c;
  c["seed"] = seed;
  c["solver"] = "ga";
  c["fingerprint"] = fingerprint;
  c["completed_runs"] = checkpoint.completed_runs;
  c["run_seconds"] = checkpoint.run_seconds;
  c["evaluations"] = {{"designs", checkpoint.designs}, {"samples", checkpoint.samples}};
  c["elapsed_seconds"] = checkpoint.elapsed_seconds;
  if (checkpoint.current) c["current"] = *checkpoint.current;
  write_file_atomically(file, c.dump() + "\n");
}

Json run_to_json(const RunState& state, const pagmo::algorithm& algorithm, const pagmo::population& population) {
  Json current;
  current["run"] = state.run;
  current["generation"] = state.generation;
  current["stall"] = state.stall;
  current["switched"] = state.switched;
  current["best_score"] = state.best_x.empty() ? Json(nullptr) : Json(state.best_score);
  current["best_x"] = state.best_x;
  current["designs_before"] = state.designs_before;
  current["run_seconds"] = state.seconds_before;
  current["algorithm"] = pa::save_algorithm(algorithm);
  current["population_seed"] = population.get_seed();
  current["x"] = pa::matrix_to_json(population.get_x());
  current["f"] = pa::matrix_to_json(population.get_f());
  return current;
}

void restore_run(const Json& current, const pagmo::problem& problem, RunState& state, pagmo::algorithm& algorithm,
                 pagmo::population& population) {
  state.generation = current.at("generation");
  state.stall = current.at("stall");
  state.switched = current.at("switched");
  state.best_x = current.at("best_x").get<pagmo::vector_double>();
  if (!state.best_x.empty()) state.best_score = current.at("best_score");
  state.designs_before = current.at("designs_before");
  state.seconds_before = current.at("run_seconds");
  algorithm = pa::load_algorithm(current.at("algorithm").get<std::string>());
  pagmo::population restored(problem, 0u, current.at("population_seed").get<unsigned>());
  const auto xs = pa::matrix_from_json(current.at("x"));
  const auto fs = pa::matrix_from_json(current.at("f"));
  for (std::size_t i = 0; i < xs.size(); ++i) restored.push_back(xs[i], fs[i]);
  population = restored;
}

}  // namespace hapsyn::plugins::ga
