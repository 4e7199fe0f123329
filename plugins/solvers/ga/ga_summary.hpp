#pragma once
/// \file
/// The summary of a `ga` solve over its finished runs (internal to the plugin): the best run as
/// the result, the statistics (runs, score range, the k-means clusters of the runs' optima:
/// Fennel 2022, section VII, Table III), the status and the message.
#include "ga_options.hpp"

#include "shared/pagmo_adapter.hpp"

#include <hapsyn/json.hpp>
#include <hapsyn/problem.hpp>
#include <hapsyn/solver.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace hapsyn::plugins::ga {

/// `v` with `digits` significant digits: the solver's number format in messages, progress lines
/// and the cluster table.
std::string with_digits(double v, int digits = 6);

/// What the summary reports of the solve besides the runs.
struct SolveFigures {
  bool stopped = false;             ///< the stop flag ended the solve
  double solve_seconds = 0.0;       ///< including the time before a resume [s]
  long long design_evaluations = 0;
  long long sample_evaluations = 0;
  long long cache_hits = 0;
  Json repair;                      ///< pagmo_adapter::Encoding::describe_repair
  std::size_t subset_samples = 0;   ///< samples of the multi-fidelity subset (unused without one)
  std::size_t refine_samples = 0;   ///< samples of the refine subset (unused without one)
};

/// The solve's result from its finished runs.
/// \param runs one record per finished run, in run order (an infeasible run has no "score"; a
///        feasible one has "run", "score", "free", "design", "objectives" keyed by objective name)
/// \param run_seconds the runs' times [s]
/// \param seed the study seed (the k-means initialisation)
/// \param reporter receives the cluster table's lines (also in statistics.report)
SolverResult summarise_runs(const Problem& problem, const GaOptions& options, const Json& runs,
                            const std::vector<double>& run_seconds, const SolveFigures& figures, std::uint64_t seed,
                            pagmo_adapter::ProgressReporter& reporter);

}  // namespace hapsyn::plugins::ga
