#include "ga_summary.hpp"

#include "cluster.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace hapsyn::plugins::ga {

namespace {

// Index of the feasible run with the highest score (the first of equal ones); -1 when no run
// found a feasible design.
int best_run_index(const Json& runs) {
  int best_run = -1;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!runs[i].contains("score")) continue;
    if (best_run < 0 || runs[i]["score"].get<double>() > runs[static_cast<std::size_t>(best_run)]["score"].get<double>()) {
      best_run = static_cast<int>(i);
    }
  }
  return best_run;
}

int runs_with_status(const Json& runs, const std::string& status) {
  int count = 0;
  for (const Json& run : runs) count += run["status"].get<std::string>() == status;
  return count;
}

// The best run as the result's best point, and the spread of the runs' scores.
void report_best_run(const Problem& problem, const Json& runs, int best_run, SolverResult& result, Json& statistics) {
  const Json& b = runs[static_cast<std::size_t>(best_run)];
  const std::vector<double> free = b["free"].get<std::vector<double>>();
  std::vector<double> objectives;
  for (const Objective& obj : problem.objectives()) objectives.push_back(b["objectives"][obj.name]);
  result.best = SolutionPoint{problem.full_design(free.data()), objectives, b["score"].get<double>()};
  statistics["best_run"] = b["run"];
  double lo = INFINITY, hi = -INFINITY;
  for (const Json& run : runs) {
    if (!run.contains("score")) continue;
    lo = std::min(lo, run["score"].get<double>());
    hi = std::max(hi, run["score"].get<double>());
  }
  statistics["score_range"] = {lo, hi};
}

// The free components the runs' optima are clustered over: those of options.cluster_variables,
// or every real one.
struct ClusterColumns {
  std::vector<int> free_indices;
  std::vector<std::string> names;
};

ClusterColumns cluster_columns(const Problem& problem, const GaOptions& options) {
  ClusterColumns columns;
  const DesignSpace& space = problem.design_space();
  const std::vector<std::string>& chosen_variables = options.cluster_variables;
  for (std::size_t k = 0; k < space.free_size(); ++k) {
    const DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
    const bool chosen = chosen_variables.empty()
                            ? !c.integer
                            : std::find(chosen_variables.begin(), chosen_variables.end(), c.variable) != chosen_variables.end();
    if (chosen) {
      columns.free_indices.push_back(static_cast<int>(k));
      columns.names.push_back(c.name);
    }
  }
  return columns;
}

// The feasible runs' optima, one row each, over the clustered columns.
Eigen::MatrixXd optima_matrix(const Json& runs, const std::vector<std::size_t>& feasible_runs, const ClusterColumns& columns) {
  const std::vector<int>& free_indices = columns.free_indices;
  Eigen::MatrixXd points(static_cast<Eigen::Index>(feasible_runs.size()), static_cast<Eigen::Index>(free_indices.size()));
  for (std::size_t i = 0; i < feasible_runs.size(); ++i) {
    const auto free = runs[feasible_runs[i]]["free"].get<std::vector<double>>();
    for (std::size_t j = 0; j < free_indices.size(); ++j) {
      points(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = free[static_cast<std::size_t>(free_indices[j])];
    }
  }
  return points;
}

std::string comma_separated(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

// Cluster c's entry of statistics.clusters.clusters; its line of the cluster table goes to `row`.
Json cluster_entry(const Problem& problem, const Json& runs, const std::vector<std::size_t>& feasible_runs,
                   const ClusterAnalysis& a, const std::vector<std::string>& names, int c, std::string& row) {
  const std::vector<Objective>& objectives = problem.objectives();
  Json members = Json::array();
  double score_sum = 0.0, score_best = -INFINITY;
  int best_member = -1;
  std::size_t best_position = 0;  // in `runs` (a shard's runs are not all runs)
  std::vector<double> objective_sum(objectives.size(), 0.0);
  for (std::size_t i = 0; i < feasible_runs.size(); ++i) {
    if (a.best.labels[i] != c) continue;
    const Json& run = runs[feasible_runs[i]];
    members.push_back(run["run"]);
    const double s = run["score"];
    score_sum += s;
    if (s > score_best) {
      score_best = s;
      best_member = run["run"];
      best_position = feasible_runs[i];
    }
    for (std::size_t q = 0; q < objectives.size(); ++q) objective_sum[q] += run["objectives"][objectives[q].name].get<double>();
  }
  const int size = a.sizes[static_cast<std::size_t>(c)];
  const double intra_distance = a.cluster_intra_distance[static_cast<std::size_t>(c)];
  Json centroid = Json::object();
  for (std::size_t j = 0; j < names.size(); ++j) centroid[names[j]] = a.best.centroids(c, static_cast<Eigen::Index>(j));
  Json mean_objectives = Json::object();
  for (std::size_t q = 0; q < objectives.size(); ++q) mean_objectives[objectives[q].name] = objective_sum[q] / size;
  Json entry;
  entry["size"] = size;
  entry["runs"] = members;
  entry["centroid"] = centroid;
  entry["intra_distance"] = intra_distance;
  entry["mean_objectives"] = mean_objectives;
  entry["mean_score"] = score_sum / size;
  entry["best_score"] = score_best;
  entry["best_run"] = best_member;
  entry["best_design"] = runs[best_position]["design"];

  std::ostringstream line;
  line << std::setw(7) << (c + 1) << "  " << std::setw(4) << size << "  " << std::setw(11) << with_digits(score_sum / size, 6)
       << "  " << std::setw(11) << with_digits(score_best, 6) << "  " << std::setw(5) << with_digits(intra_distance, 3);
  for (std::size_t j = 0; j < names.size(); ++j) {
    line << "  " << std::setw(8) << with_digits(a.best.centroids(c, static_cast<Eigen::Index>(j)), 4);
  }
  for (std::size_t q = 0; q < objectives.size(); ++q) line << "  " << std::setw(8) << with_digits(objective_sum[q] / size, 4);
  row = line.str();
  return entry;
}

// The k-means clusters of the feasible runs' optima (Fennel 2022, section VII, Table III) for
// statistics.clusters, with the table's lines appended to `report`. Null with fewer than three
// feasible runs or nothing to cluster over.
Json analyse_clusters(const Problem& problem, const GaOptions& options, const Json& runs, std::uint64_t seed,
                      std::vector<std::string>& report) {
  std::vector<std::size_t> feasible_runs;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (runs[i].contains("score")) feasible_runs.push_back(i);
  }
  if (feasible_runs.size() < 3) return nullptr;
  const ClusterColumns columns = cluster_columns(problem, options);
  if (columns.free_indices.empty()) return nullptr;
  const std::vector<std::string>& names = columns.names;
  const ClusterAnalysis a = cluster_by_silhouette(optima_matrix(runs, feasible_runs, columns), options.max_clusters, seed);
  Json clusters;
  clusters["variables"] = names;
  clusters["k"] = a.best.k;
  clusters["silhouette"] = a.silhouette;
  Json silhouettes = Json::object();
  for (std::size_t i = 0; i < a.silhouettes.size(); ++i) silhouettes[std::to_string(i + 2)] = a.silhouettes[i];
  clusters["silhouettes"] = silhouettes;
  clusters["intra_deviation"] = a.intra_deviation;
  clusters["inter_deviation"] = a.inter_deviation;
  std::ostringstream head;
  head << "cluster  runs  score(mean)  score(best)  intra";
  for (const std::string& n : names) head << "  " << std::setw(8) << n;
  for (const Objective& obj : problem.objectives()) head << "  " << std::setw(8) << obj.name;
  report.push_back("clusters of the " + std::to_string(feasible_runs.size()) + " run optima over (" +
                   comma_separated(names) + "): k = " + std::to_string(a.best.k) + " by average silhouette " +
                   with_digits(a.silhouette, 3) + "; intra-cluster deviation " + with_digits(a.intra_deviation, 4) +
                   ", inter-cluster deviation " + with_digits(a.inter_deviation, 4) + " (design units)");
  report.push_back(head.str());
  Json table = Json::array();
  for (int c = 0; c < a.best.k; ++c) {
    std::string row;
    table.push_back(cluster_entry(problem, runs, feasible_runs, a, names, c, row));
    report.push_back(row);
  }
  clusters["clusters"] = table;
  return clusters;
}

// The solve's status and message from how its runs ended.
void set_status_and_message(const GaOptions& options, const Json& runs, int best_run, bool stopped,
                            SolverResult& result) {
  const int converged = runs_with_status(runs, "converged");
  const int budget = runs_with_status(runs, "budget_exhausted");
  std::ostringstream message;
  message << runs.size() << " run(s) of " << options.algorithm << ", population " << options.population;
  if (stopped) {
    result.status = SolverStatus::kStopped;
    message << ": stopped on request";
  } else if (best_run < 0) {
    result.status = SolverStatus::kInfeasible;
    message << ": no feasible design found";
  } else if (budget > 0) {
    result.status = SolverStatus::kBudgetExhausted;
    message << ": " << budget << " run(s) reached the generation limit (" << options.generations
            << ") before stalling for " << options.stall_generations << " generations, " << converged << " converged";
  } else {
    result.status = SolverStatus::kConverged;
    message << ": every run converged (no improvement > " << options.ftol << " for " << options.stall_generations
            << " generations)";
  }
  if (best_run >= 0) {
    message << "; best score " << with_digits(runs[static_cast<std::size_t>(best_run)]["score"].get<double>(), 8)
            << " (run " << runs[static_cast<std::size_t>(best_run)]["run"].get<int>() + 1 << ")";
  }
  result.message = message.str();
}

}  // namespace

std::string with_digits(double v, int digits) {
  std::ostringstream s;
  s << std::setprecision(digits) << v;
  return s.str();
}

SolverResult summarise_runs(const Problem& problem, const GaOptions& options, const Json& runs,
                            const std::vector<double>& run_seconds, const SolveFigures& figures, std::uint64_t seed,
                            pagmo_adapter::ProgressReporter& reporter) {
  SolverResult result;
  result.design_evaluations = figures.design_evaluations;
  result.sample_evaluations = figures.sample_evaluations;
  Json statistics;
  statistics["algorithm"] = options.algorithm;
  statistics["runs"] = runs;
  statistics["run_seconds"] = run_seconds;
  statistics["solve_seconds"] = figures.solve_seconds;
  statistics["cache_hits"] = figures.cache_hits;
  statistics["repair"] = figures.repair;
  statistics["evaluation"] = {{"parallel_over", options.parallel_over}, {"sample_chunks", options.sample_chunks}};
  if (options.fidelity.generations > 0) {
    statistics["fidelity"] = {{"subset_fraction", options.fidelity.subset_fraction},
                              {"subset_samples", figures.subset_samples},
                              {"generations", options.fidelity.generations}};
    if (options.fidelity.refine_fraction < 1.0) {
      statistics["fidelity"]["refine_fraction"] = options.fidelity.refine_fraction;
      statistics["fidelity"]["refine_samples"] = figures.refine_samples;
      statistics["fidelity"]["final_candidates"] = options.fidelity.final_candidates;
    }
  }
  const int best_run = best_run_index(runs);
  if (best_run >= 0) report_best_run(problem, runs, best_run, result, statistics);

  std::vector<std::string> report;
  const Json clusters = analyse_clusters(problem, options, runs, seed, report);
  if (!clusters.is_null()) statistics["clusters"] = clusters;
  statistics["report"] = report;
  for (const std::string& line : report) reporter.line(line, true);

  set_status_and_message(options, runs, best_run, figures.stopped, result);
  result.statistics = statistics;
  return result;
}

}  // namespace hapsyn::plugins::ga
