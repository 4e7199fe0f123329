#include "sub_solver.hpp"

#include <hapsyn/cluster.hpp>
#include <hapsyn/checkpoint.hpp>
#include <hapsyn/error.hpp>

#include <algorithm>
#include <chrono>
#include <mutex>
#include <ostream>
#include <sstream>

namespace hapsyn::plugins {

namespace {
constexpr int kFullDesignChunks = 16;
}  // namespace

const Solver* sub_solver_for_solve(const SubSolver& sub_solver, const std::string& component, const std::string& role,
                                   SolverResult& result) {
  if (!sub_solver.solver) {
    result.status = SolverStatus::kFailed;
    result.message = component + " has no " + role +
                     " (sub-solvers are created when the study is loaded through the registry)";
    return nullptr;
  }
  return sub_solver.solver.get();
}

void check_sub_solver(const SubSolver& sub_solver, const Problem& problem, const std::string& component,
                      const std::string& where) {
  if (!sub_solver.solver) return;
  try {
    sub_solver.solver->check(problem);
  } catch (const Error& e) {
    throw Error(component, where + ": " + e.what());
  }
}

Json sub_solver_json(const SubSolver& sub_solver) {
  return {{"plugin", sub_solver.plugin}, {"options", sub_solver.options}};
}

std::shared_ptr<const Problem> single_objective_problem(const Problem& problem, std::size_t index) {
  Objective o = problem.objectives().at(index);
  o.weight = 1.0;
  return problem.with_objectives({o});
}

std::shared_ptr<const Problem> reweighted_problem(const Problem& problem, const std::vector<double>& weights) {
  std::vector<Objective> objectives = problem.objectives();
  for (std::size_t i = 0; i < objectives.size() && i < weights.size(); ++i) objectives[i].weight = weights[i];
  return problem.with_objectives(std::move(objectives));
}

std::shared_ptr<const Problem> fixed_component_problem(const Problem& problem, std::size_t free_index, double value) {
  std::vector<DesignComponent> components = problem.design_space().components();
  DesignComponent& c = components.at(static_cast<std::size_t>(problem.design_space().free_indices().at(free_index)));
  c.lower = c.upper = value;
  c.step = 0.0;
  c.fixed = true;
  return problem.with_design_space(DesignSpace(std::move(components)));
}

SolverResult run_sub_solver(const Solver& solver, const Problem& problem, const SolverContext& parent,
                            const std::string& what) {
  SolverContext context = parent;
  // The parent checkpoints its finished subproblems; the sub-solver writes none of its own.
  context.checkpoint_file.clear();
  context.resume = false;
  if (!what.empty()) solver_line(parent, what + " ...");
  const auto t0 = std::chrono::steady_clock::now();
  SolverResult result = solver.solve(problem, context);
  if (!what.empty()) {
    std::ostringstream line;
    line.precision(3);
    line << what << ": " << to_string(result.status) << " in "
         << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s";
    solver_line(parent, line.str());
  }
  return result;
}

bool evaluate_full_design(const Problem& problem, const Eigen::VectorXd& full, int threads,
                          std::vector<double>& objectives, long long& samples) {
  const DesignSpace& space = problem.design_space();
  std::vector<double> x(space.free_size());
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = full[space.free_indices()[k]];
  // A fixed chunk count: the values (averaging metrics too) do not depend on the thread count,
  // so a resumed run re-evaluates a checkpoint's points to the same bits.
  Problem::ParallelOptions parallel;
  parallel.chunks = kFullDesignChunks;
  const Evaluation e = problem.evaluate_parallel(x.data(), threads, parallel);
  samples += e.samples_evaluated;
  objectives.clear();
  if (e.status != EvalStatus::kFeasible) return false;
  objectives = e.objectives;
  return true;
}

// ---------------------------------------------------------------------------------------------
// Subproblem checkpoints.

namespace {

Json point_design_json(const std::optional<SolutionPoint>& point) {
  if (!point) return nullptr;
  Json design = Json::array();
  for (Eigen::Index i = 0; i < point->design.size(); ++i) design.push_back(point->design[i]);
  return design;
}

bool is_count(const Json& v) { return v.is_number_integer() && v.get<long long>() >= 0; }

bool is_number_array(const Json& v, std::size_t size) {
  return v.is_array() && v.size() == size && std::all_of(v.begin(), v.end(), [](const Json& x) { return x.is_number(); });
}

// One entry of a list, its shape checked and its point re-evaluated.
FinishedSubproblem read_entry(const Problem& problem, const SolverContext& context, const Json& entry,
                              const std::string& where, long long& recheck_samples) {
  if (!entry.is_object()) throw bad_checkpoint(context, where + ": not an object");
  FinishedSubproblem f;
  if (!entry.contains("record") || !entry["record"].is_object()) {
    throw bad_checkpoint(context, where + ".record: missing or not an object");
  }
  f.record = entry["record"];
  for (const char* key : {"design_evaluations", "sample_evaluations"}) {
    if (!entry.contains(key) || !is_count(entry[key])) {
      throw bad_checkpoint(context, where + "." + key + ": missing or not a count (an integer >= 0)");
    }
  }
  f.design_evaluations = entry["design_evaluations"].get<long long>();
  f.sample_evaluations = entry["sample_evaluations"].get<long long>();
  const Json design = entry.value("design", Json());
  const Json claimed = entry.value("objectives", Json());
  if (design.is_null() && claimed.is_null()) return f;  // an infeasible subproblem: nothing to check
  const std::size_t n = problem.design_space().components().size(), m = problem.objectives().size();
  if (!is_number_array(design, n)) {
    throw bad_checkpoint(context, where + ".design = " + design.dump() + ": must be " + std::to_string(n) +
                                      " numbers (the full design)");
  }
  if (!is_number_array(claimed, m)) {
    throw bad_checkpoint(context, where + ".objectives = " + claimed.dump() + ": must be " + std::to_string(m) +
                                      " numbers (one per objective)");
  }
  // The design as the problem would build it from its free components: an edited fixed
  // component shows here.
  const DesignSpace& space = problem.design_space();
  std::vector<double> x(space.free_size());
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = design[static_cast<std::size_t>(space.free_indices()[k])].get<double>();
  const Eigen::VectorXd full = problem.full_design(x.data());
  for (std::size_t i = 0; i < n; ++i) {
    if (full[static_cast<Eigen::Index>(i)] != design[i].get<double>()) {
      throw bad_checkpoint(context, where + ".design[" + std::to_string(i) + "] = " + design[i].dump() + ": " +
                                        space.components()[i].name + " is fixed at " +
                                        Json(full[static_cast<Eigen::Index>(i)]).dump() + " in this study");
    }
  }
  std::vector<double> values;
  bool feasible = false;
  try {
    feasible = evaluate_full_design(problem, full, context.threads, values, recheck_samples);
  } catch (const Error& e) {  // out of bounds, not finite: the framework's checks
    throw bad_checkpoint(context, where + ".design = " + design.dump() + ": cannot be evaluated (" + e.what() + ")");
  }
  if (!feasible) {
    throw bad_checkpoint(context, where + ": the design is not feasible, the checkpoint claims objectives " + claimed.dump());
  }
  // Evaluation is deterministic (bit-identical at any thread count): any difference is an edit.
  for (std::size_t i = 0; i < m; ++i) {
    if (values[i] != claimed[i].get<double>()) {
      throw bad_checkpoint(context, where + ": the design re-evaluates to objectives " + Json(values).dump() +
                                        ", the checkpoint claims " + claimed.dump());
    }
  }
  f.point = SolutionPoint{full, values, problem.score(values)};
  return f;
}

}  // namespace

namespace {

Json entry_json(const FinishedSubproblem& f) {
  return {{"record", f.record},
          {"design", point_design_json(f.point)},
          {"objectives", f.point ? Json(f.point->objectives) : Json(nullptr)},
          {"design_evaluations", f.design_evaluations},
          {"sample_evaluations", f.sample_evaluations}};
}

}  // namespace

std::optional<FinishedSubproblem> finished_unless_stopped(const SolverResult& result,
                                                          std::atomic<long long>& interrupted_designs,
                                                          std::atomic<long long>& interrupted_samples) {
  if (result.status == SolverStatus::kStopped) {
    interrupted_designs += result.design_evaluations;
    interrupted_samples += result.sample_evaluations;
    return std::nullopt;
  }
  FinishedSubproblem f;
  f.design_evaluations = result.design_evaluations;
  f.sample_evaluations = result.sample_evaluations;
  return f;
}

std::size_t finished_count(const SubproblemSlots& slots) {
  return static_cast<std::size_t>(
      std::count_if(slots.begin(), slots.end(), [](const std::optional<FinishedSubproblem>& f) { return f.has_value(); }));
}

std::string SubproblemCheckpoint::where(const std::string& list, std::size_t task) const {
  const auto l = positions.find(list);
  std::size_t position = task;
  if (l != positions.end()) {
    const auto p = l->second.find(task);
    if (p != l->second.end()) position = p->second;
  }
  return list + "[" + std::to_string(position) + "]";
}

void write_subproblem_checkpoint(const SolverContext& context, const std::string& solver, const std::string& fingerprint,
                                 const std::map<std::string, const SubproblemSlots*>& lists, double seconds) {
  if (context.checkpoint_file.empty() || !context.cluster().root()) return;
  Json state = Json::object();
  for (const auto& [name, slots] : lists) {
    Json entries = Json::array();
    for (std::size_t task = 0; task < slots->size(); ++task) {
      if (!(*slots)[task]) continue;
      Json entry = entry_json(*(*slots)[task]);
      entry["task"] = task;
      entries.push_back(std::move(entry));
    }
    state[name] = entries;
  }
  state["seconds"] = seconds;
  write_checkpoint(context, solver, fingerprint, state);
}

std::optional<SubproblemCheckpoint> read_subproblem_checkpoint(const Problem& problem, const SolverContext& context,
                                                               const std::string& solver, const std::string& fingerprint,
                                                               const std::map<std::string, std::size_t>& limits) {
  const std::optional<Json> state = read_checkpoint(context, solver, fingerprint);
  if (!state) {
    if (context.resume) solver_line(context, solver + ": no checkpoint to resume from; starting from the beginning");
    return std::nullopt;
  }
  SubproblemCheckpoint checkpoint;
  if (!state->contains("seconds") || !(*state)["seconds"].is_number() || !((*state)["seconds"].get<double>() >= 0.0)) {
    throw bad_checkpoint(context, "seconds: missing or not a number >= 0");
  }
  checkpoint.seconds = (*state)["seconds"].get<double>();
  for (const auto& [name, limit] : limits) {
    if (!state->contains(name) || !(*state)[name].is_array()) throw bad_checkpoint(context, "no \"" + name + "\" array");
    const Json& entries = (*state)[name];
    if (entries.size() > limit) {
      throw bad_checkpoint(context, name + ": " + std::to_string(entries.size()) + " finished subproblems, this study has " +
                                        std::to_string(limit));
    }
    SubproblemSlots& slots = checkpoint.lists[name];
    slots.assign(limit, std::nullopt);
    long long previous = -1;
    for (std::size_t i = 0; i < entries.size(); ++i) {
      const std::string where = name + "[" + std::to_string(i) + "]";
      // Entries without a task index come from checkpoints that kept the finished prefix.
      long long task = static_cast<long long>(i);
      if (entries[i].is_object() && entries[i].contains("task")) {
        const Json& t = entries[i]["task"];
        if (!is_count(t) || t.get<long long>() >= static_cast<long long>(limit)) {
          throw bad_checkpoint(context, where + ".task = " + t.dump() + ": must be an integer in 0.." +
                                            std::to_string(limit - 1) + " (a subproblem of this study)");
        }
        task = t.get<long long>();
      }
      if (task <= previous) {
        throw bad_checkpoint(context, where + ".task = " + std::to_string(task) +
                                          ": the entries must be in increasing task order, each task once (the entry "
                                          "before is task " + std::to_string(previous) + ")");
      }
      previous = task;
      slots[static_cast<std::size_t>(task)] = read_entry(problem, context, entries[i], where, checkpoint.recheck_samples);
      checkpoint.positions[name][static_cast<std::size_t>(task)] = i;
    }
  }
  return checkpoint;
}

// ---------------------------------------------------------------------------------------------
// Subproblem farms.

SolverContext task_context(const SolverContext& context) {
  SolverContext c = context.in_task();
  // One process runs one task at a time per sub-solver farm (SubproblemFarm::threads = 1 for
  // whole sub-solvers), so its sub-solver may talk to the progress stream and the log as before.
  if (context.cluster().size() == 1) {
    c.progress = context.progress;
    c.log = context.log;
  }
  return c;
}

std::string subproblem_bytes(const FinishedSubproblem& finished) { return entry_json(finished).dump(); }

namespace {

// An entry of entry_json, trusted (it comes from a rank of this run, not from a file).
FinishedSubproblem entry_from_json(const Problem& problem, const Json& entry) {
  FinishedSubproblem f;
  f.record = entry.at("record");
  f.design_evaluations = entry.at("design_evaluations").get<long long>();
  f.sample_evaluations = entry.at("sample_evaluations").get<long long>();
  const Json& design = entry.at("design");
  if (!design.is_null()) {
    Eigen::VectorXd full(static_cast<Eigen::Index>(design.size()));
    for (std::size_t i = 0; i < design.size(); ++i) full[static_cast<Eigen::Index>(i)] = design[i].get<double>();
    std::vector<double> values = entry.at("objectives").get<std::vector<double>>();
    const double score = problem.score(values);
    f.point = SolutionPoint{full, std::move(values), score};
  }
  return f;
}

}  // namespace

FinishedSubproblem subproblem_from_bytes(const Problem& problem, const std::string& bytes) {
  return entry_from_json(problem, Json::parse(bytes));
}

FarmOutcome run_subproblem_farm(const Problem& problem, const SolverContext& context, SubproblemSlots& slots,
                                const SubproblemFarm& farm) {
  Cluster& cluster = context.cluster();
  std::vector<std::size_t> tasks = farm.tasks;
  if (tasks.empty()) {
    for (std::size_t i = 0; i < slots.size(); ++i) tasks.push_back(i);
  }
  // Fixed before the farm: collect fills slots while other threads ask what is done.
  std::vector<char> done(tasks.size());
  for (std::size_t t = 0; t < tasks.size(); ++t) done[t] = slots.at(tasks[t]).has_value() ? 1 : 0;
  // collect and on_abort both reach the slots on rank 0.
  std::mutex mutex;
  TaskFarm f;
  f.count = static_cast<long long>(tasks.size());
  f.done = [&](long long t) { return done[static_cast<std::size_t>(t)] != 0; };
  f.run = [&](long long t, int) -> std::optional<std::string> {
    std::optional<FinishedSubproblem> finished = farm.run(tasks[static_cast<std::size_t>(t)]);
    if (!finished) return std::nullopt;
    return subproblem_bytes(*finished);
  };
  f.collect = [&](long long t, std::string&& bytes) {
    const std::size_t index = tasks[static_cast<std::size_t>(t)];
    std::lock_guard<std::mutex> lock(mutex);
    slots[index] = subproblem_from_bytes(problem, bytes);
    if (farm.what && cluster.size() > 1) {
      std::ostringstream line;
      line.precision(3);
      line << farm.what(index) << ": " << slots[index]->record.value("status", std::string("finished")) << " in "
           << slots[index]->record.value("seconds", 0.0) << " s";
      solver_line(context, line.str());
    }
    if (farm.collected) farm.collected(index);
  };
  if (farm.on_abort) {
    f.on_abort = [&] {
      std::lock_guard<std::mutex> lock(mutex);
      farm.on_abort();
    };
  }
  const FarmOutcome outcome = cluster.run_tasks(f, std::max(1, farm.threads));
  if (cluster.size() > 1) {
    // Rank 0 alone collected: every rank continues from its slots.
    std::string bytes;
    if (cluster.root()) {
      Json all = Json::array();
      for (const std::optional<FinishedSubproblem>& s : slots) all.push_back(s ? entry_json(*s) : Json(nullptr));
      bytes = all.dump();
    }
    cluster.broadcast(bytes);
    if (!cluster.root()) {
      const Json all = Json::parse(bytes);
      for (std::size_t i = 0; i < slots.size() && i < all.size(); ++i) {
        if (all[i].is_null()) {
          slots[i].reset();
        } else {
          slots[i] = entry_from_json(problem, all[i]);
        }
      }
    }
  }
  return outcome;
}

void solver_line(const SolverContext& context, const std::string& line) {
  if (context.progress) *context.progress << line << "\n";
  if (context.log) *context.log << line << "\n";
}

std::string checkpoint_note(const SolverContext& context) {
  if (context.checkpoint_file.empty()) return "; no checkpoint (no checkpoint file in this context)";
  return "; checkpoint " + context.checkpoint_file + " written: `hapsyn run --resume` continues from there";
}

}  // namespace hapsyn::plugins
