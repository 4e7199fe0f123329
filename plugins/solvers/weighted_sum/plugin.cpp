#include "weighted_sum.hpp"

#include <hapsyn/plugin.hpp>

HAPSYN_SOLVER_PLUGIN(hapsyn::plugins::WeightedSumSolver, "weighted_sum", "1.0.0",
                     "Pareto points from weighted sums of the objectives, each solved by a single-objective sub-solver")
