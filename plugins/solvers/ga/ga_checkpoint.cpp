#include "ga_checkpoint.hpp"

#include "shared/pagmo_adapter.hpp"

#include <hapsyn/checkpoint.hpp>
#include <hapsyn/error.hpp>

#include <stdexcept>

namespace hapsyn::plugins::ga {

namespace pa = pagmo_adapter;

namespace {

// Runs `read`, turning what nlohmann or boost throw for a damaged state (a missing field, a
// wrong type, a broken archive) into a bad checkpoint naming `path` and the file.
template <class Read>
auto checked(const SolverContext& context, const std::string& path, Read&& read) -> decltype(read()) {
  try {
    return read();
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw bad_checkpoint(context, path + ": " + e.what());
  }
}

}  // namespace

Json checkpoint_to_state(const Checkpoint& checkpoint) {
  Json c;
  c["completed_runs"] = checkpoint.completed_runs;
  c["run_seconds"] = checkpoint.run_seconds;
  c["evaluations"] = {{"designs", checkpoint.designs}, {"samples", checkpoint.samples}};
  c["elapsed_seconds"] = checkpoint.elapsed_seconds;
  if (checkpoint.current) c["current"] = *checkpoint.current;
  return c;
}

Checkpoint checkpoint_from_state(const SolverContext& context, const Json& state) {
  Checkpoint c;
  checked(context, "state", [&] {
    c.completed_runs = state.at("completed_runs");
    if (!c.completed_runs.is_array()) throw std::invalid_argument("completed_runs is not an array");
    c.run_seconds = state.at("run_seconds").get<std::vector<double>>();
    if (c.run_seconds.size() != c.completed_runs.size()) {
      throw std::invalid_argument("run_seconds has " + std::to_string(c.run_seconds.size()) + " entries for " +
                                  std::to_string(c.completed_runs.size()) + " completed runs");
    }
    c.designs = state.at("evaluations").at("designs").get<long long>();
    c.samples = state.at("evaluations").at("samples").get<long long>();
    c.elapsed_seconds = state.at("elapsed_seconds").get<double>();
    if (state.contains("current")) {
      c.current = state.at("current");
      (void)c.current->at("run").get<int>();
      (void)c.current->at("generation").get<int>();
    }
    return 0;
  });
  return c;
}

Json run_to_json(const RunState& state, const pagmo::algorithm& algorithm, const pagmo::population& population) {
  Json current;
  current["run"] = state.run;
  current["generation"] = state.generation;
  current["stall"] = state.stall;
  current["switched"] = state.switched;
  current["refining"] = state.refining;
  current["best_score"] = state.best_x.empty() ? Json(nullptr) : Json(state.best_score);
  current["best_x"] = state.best_x;
  current["run_designs"] = state.designs;
  current["run_seconds"] = state.seconds_before;
  current["history"] = state.history.json();
  current["algorithm"] = pa::save_algorithm(algorithm);
  current["population_seed"] = population.get_seed();
  current["x"] = pa::matrix_to_json(population.get_x());
  current["f"] = pa::matrix_to_json(population.get_f());
  // The population's champion is the best individual it ever held, not the best of the current
  // ones; gaco steers by it (its stall counter compares champions), so it is part of the state.
  if (population.size() > 0) {
    current["champion_x"] = population.champion_x();
    current["champion_f"] = population.champion_f();
  }
  return current;
}

void restore_run(const SolverContext& context, const Json& current, const pagmo::problem& problem, RunState& state,
                 pagmo::algorithm& algorithm, pagmo::population& population) {
  checked(context, "state.current", [&] {
    state.generation = current.at("generation");
    state.stall = current.at("stall");
    state.switched = current.at("switched");
    state.refining = current.at("refining");
    state.best_x = current.at("best_x").get<pagmo::vector_double>();
    if (!state.best_x.empty()) state.best_score = current.at("best_score");
    // Absent in checkpoints of earlier versions (they counted the study's designs instead).
    state.designs = current.contains("run_designs") ? current.at("run_designs").get<long long>() : 0;
    state.seconds_before = current.at("run_seconds");
    state.history = current.contains("history") ? ConvergenceHistory::from_json(current.at("history")) : ConvergenceHistory();
    algorithm = pa::load_algorithm(current.at("algorithm").get<std::string>());
    pagmo::population restored(problem, 0u, current.at("population_seed").get<unsigned>());
    const auto xs = pa::matrix_from_json(current.at("x"));
    const auto fs = pa::matrix_from_json(current.at("f"));
    if (xs.size() != fs.size()) throw std::invalid_argument("x and f have different sizes");
    // push_back checks the vectors' sizes against the problem (std::invalid_argument). The
    // champion goes in first, in the place of the first individual, which then takes its place
    // back by set_xf: a champion is only ever replaced by a strictly better individual, so the
    // restored one is the saved one.
    const bool champion = current.contains("champion_x") && !xs.empty();
    if (champion) {
      restored.push_back(current.at("champion_x").get<pagmo::vector_double>(),
                         current.at("champion_f").get<pagmo::vector_double>());
    }
    for (std::size_t i = champion ? 1 : 0; i < xs.size(); ++i) restored.push_back(xs[i], fs[i]);
    if (champion) restored.set_xf(0, xs[0], fs[0]);
    population = restored;
    return 0;
  });
}

}  // namespace hapsyn::plugins::ga
