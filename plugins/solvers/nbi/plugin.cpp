#include "nbi.hpp"

#include <hapsyn/plugin.hpp>

HAPSYN_SOLVER_PLUGIN(hapsyn::plugins::NbiSolver, "nbi", "1.0.0",
                     "Normal Boundary Intersection (Das & Dennis): Pareto front from shadow optima and SLSQP subproblems")
