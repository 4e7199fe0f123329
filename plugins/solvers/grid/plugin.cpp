#include "grid.hpp"

#include <hapsyn/plugin.hpp>

HAPSYN_SOLVER_PLUGIN(hapsyn::plugins::GridSolver, "grid", "1.0.0",
                     "Exhaustive, exact search of the design grid (multi-threaded)")
