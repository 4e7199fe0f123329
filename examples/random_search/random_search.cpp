// An out-of-tree hapsyn solver plugin: uniform random search. The smallest complete solver:
// options declared once, a seeded and reproducible run, the stop request honoured, and every
// outcome reported as a status (never an exception).
#include <hapsyn/plugin.hpp>

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace {

struct RandomSearchOptions {
  int samples{};
  static void declare(hapsyn::OptionDeclarations<RandomSearchOptions>& d) {
    d.describe(
        "Uniform random search: evaluates `samples` designs drawn uniformly within the design bounds (integer "
        "components rounded) and returns the best. Reproducible for a seed; no convergence criterion, so it "
        "ends with status budget_exhausted.");
    d.add(&RandomSearchOptions::samples, "samples", 200, "Designs drawn and evaluated").range(1, 10000000);
  }
};

class RandomSearch : public hapsyn::Solver {
 public:
  using Options = RandomSearchOptions;
  explicit RandomSearch(const RandomSearchOptions& options) : options_(options) {}

  hapsyn::SolverResult solve(const hapsyn::Problem& problem, const hapsyn::SolverContext& context) const override {
    const hapsyn::DesignSpace& space = problem.design_space();
    std::mt19937_64 rng(context.seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    auto eval_scratch = problem.make_eval_scratch();
    std::vector<double> x(space.free_size()), best_x;
    hapsyn::SolverResult result;
    for (int i = 0; i < options_.samples; ++i) {
      if (context.stop && context.stop->load()) {
        result.status = hapsyn::SolverStatus::kStopped;
        result.message = "stopped after " + std::to_string(i) + " designs";
        break;
      }
      draw(space, rng, unit, x);
      const hapsyn::Evaluation& e = problem.evaluate(x.data(), *eval_scratch);
      ++result.design_evaluations;
      result.sample_evaluations += e.samples_evaluated;
      if (e.status == hapsyn::EvalStatus::kFeasible && (!result.best || e.score > result.best->score)) {
        result.best = hapsyn::SolutionPoint{problem.full_design(x.data()), e.objectives, e.score};
      }
    }
    if (result.status != hapsyn::SolverStatus::kStopped) {
      result.status = result.best ? hapsyn::SolverStatus::kBudgetExhausted : hapsyn::SolverStatus::kInfeasible;
      result.message = result.best ? std::to_string(options_.samples) + " random designs evaluated"
                                   : "none of the " + std::to_string(options_.samples) + " random designs is feasible";
    }
    return result;
  }

 private:
  // One design uniform in the bounds; integer components take the nearest integer.
  static void draw(const hapsyn::DesignSpace& space, std::mt19937_64& rng, std::uniform_real_distribution<double>& unit,
                   std::vector<double>& x) {
    for (std::size_t k = 0; k < x.size(); ++k) {
      const hapsyn::DesignComponent& c = space.components()[static_cast<std::size_t>(space.free_indices()[k])];
      x[k] = c.lower + unit(rng) * (c.upper - c.lower);
      if (c.integer) x[k] = std::round(x[k]);
    }
  }

  RandomSearchOptions options_;
};

}  // namespace

HAPSYN_SOLVER_PLUGIN(RandomSearch, "random_search", "1.0.0", "Uniform random search within the design bounds")
