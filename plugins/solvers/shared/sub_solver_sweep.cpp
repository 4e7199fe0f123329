#include "sub_solver_sweep.hpp"

#include <hapsyn/checkpoint.hpp>

#include <atomic>
#include <optional>
#include <utility>

namespace hapsyn::plugins {

namespace {

using Clock = SubSolverSweepOutcome::Clock;

// Reads the checkpoint to resume from into `outcome` (nothing without one), after checking that
// each finished entry is this study's subproblem of that index.
void resume(const Problem& problem, const SolverContext& context, const SubSolverSweep& sweep,
            SubSolverSweepOutcome& outcome) {
  std::optional<SubproblemCheckpoint> checkpoint =
      read_subproblem_checkpoint(problem, context, sweep.solver, sweep.fingerprint, {{"finished", sweep.count}});
  if (!checkpoint) return;
  outcome.finished = std::move(checkpoint->lists["finished"]);
  for (std::size_t i = 0; i < outcome.finished.size(); ++i) {
    if (!outcome.finished[i]) continue;
    const Json claimed = outcome.finished[i]->record.value(sweep.key, Json());
    const Json identity = sweep.identity(i);
    if (claimed != identity) {
      throw bad_checkpoint(context, checkpoint->where("finished", i) + ".record." + sweep.key + " = " + claimed.dump() +
                                        ": this study's " + sweep.named(i) + " is " + identity.dump());
    }
  }
  outcome.seconds_before = checkpoint->seconds;
  const std::size_t finished = finished_count(outcome.finished);
  outcome.resumed = {{"checkpoint", context.checkpoint_file},
                     {"finished", finished},
                     {"recheck_sample_evaluations", checkpoint->recheck_samples}};
  solver_line(context, sweep.solver + ": resuming from " + context.checkpoint_file + ": " + std::to_string(finished) +
                           " of " + std::to_string(sweep.count) + " " + sweep.units + " finished");
}

// Runs subproblem i on this rank's threads: its record, its design re-evaluated with all the
// study's objectives, and its counts; nullopt when a stop request interrupted it (its counts go
// to `interrupted_*`).
std::optional<FinishedSubproblem> run_one(const Solver& solver, const Problem& problem, const SolverContext& inner,
                                          const SubSolverSweep& sweep, std::size_t i,
                                          std::atomic<long long>& interrupted_designs,
                                          std::atomic<long long>& interrupted_samples) {
  if (inner.stop_requested()) return std::nullopt;
  const auto t0 = Clock::now();
  const SolverResult r = run_sub_solver(solver, *sweep.problem(i), inner, sweep.what(i));
  std::optional<FinishedSubproblem> finished = finished_unless_stopped(r, interrupted_designs, interrupted_samples);
  if (!finished) return std::nullopt;
  FinishedSubproblem& f = *finished;
  f.record = {{sweep.key, sweep.identity(i)}, {"status", to_string(r.status)}};
  std::vector<double> objectives;
  if (r.best && evaluate_full_design(problem, r.best->design, inner.threads, objectives, f.sample_evaluations)) {
    f.point = SolutionPoint{r.best->design, objectives, problem.score(objectives)};
    f.record["design"] = problem.design_to_json(r.best->design);
    f.record["objectives"] = objectives;
  }
  f.record["seconds"] = std::chrono::duration<double>(Clock::now() - t0).count();
  return finished;
}

}  // namespace

SubSolverSweepOutcome run_sub_solver_sweep(const Solver& solver, const Problem& problem, const SolverContext& context,
                                           const SubSolverSweep& sweep) {
  SubSolverSweepOutcome outcome;
  outcome.finished.resize(sweep.count);
  resume(problem, context, sweep, outcome);
  const auto checkpoint = [&] {
    write_subproblem_checkpoint(context, sweep.solver, sweep.fingerprint, {{"finished", &outcome.finished}},
                                outcome.elapsed());
  };

  // One task per subproblem: a whole sub-solver run on one rank's threads. The subproblems are
  // independent (no warm start), so the result does not depend on where each one runs.
  const SolverContext inner = task_context(context);
  std::atomic<long long> interrupted_designs{0}, interrupted_samples{0};
  SubproblemFarm farm;
  farm.what = sweep.what;
  farm.run = [&](std::size_t i) {
    return run_one(solver, problem, inner, sweep, i, interrupted_designs, interrupted_samples);
  };
  farm.collected = [&](std::size_t) { checkpoint(); };
  farm.on_abort = checkpoint;
  // A stop that came after the last subproblem finished changes nothing.
  outcome.stopped = run_subproblem_farm(problem, context, outcome.finished, farm).stopped &&
                    finished_count(outcome.finished) < outcome.finished.size();
  if (outcome.stopped) checkpoint();

  outcome.design_evaluations = interrupted_designs;
  outcome.sample_evaluations = interrupted_samples;
  for (const std::optional<FinishedSubproblem>& f : outcome.finished) {
    if (!f) continue;
    outcome.design_evaluations += f->design_evaluations;
    outcome.sample_evaluations += f->sample_evaluations;
  }
  return outcome;
}

}  // namespace hapsyn::plugins
