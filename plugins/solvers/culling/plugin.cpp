#include "culling.hpp"

#include <hapsyn/plugin.hpp>

HAPSYN_SOLVER_PLUGIN(hapsyn::plugins::CullingSolver, "culling", "1.0.0",
                     "Exact culling (branch-and-bound) over the design grid for worst-case metrics, SQP seed and polish")
