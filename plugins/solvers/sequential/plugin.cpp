#include "sequential.hpp"

#include <hapsyn/plugin.hpp>

HAPSYN_SOLVER_PLUGIN(hapsyn::plugins::SequentialSolver, "sequential", "1.0.0",
                     "Sequential optimization: best first objective per value of one variable, then the best second objective among those")
