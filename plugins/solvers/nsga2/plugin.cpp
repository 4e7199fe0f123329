#include "nsga2.hpp"

#include <hapsyn/plugin.hpp>

HAPSYN_SOLVER_PLUGIN(hapsyn::plugins::Nsga2Solver, "nsga2", "1.0.0",
                     "pagmo NSGA-II (mixed integer): the Pareto front of the study's objectives")
