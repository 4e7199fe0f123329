#include "ga.hpp"

#include <hapsyn/plugin.hpp>

HAPSYN_SOLVER_PLUGIN(hapsyn::plugins::GaSolver, "ga", "1.0.0",
                     "pagmo mixed-integer genetic algorithm (sga, gaco): runs, clusters, checkpoints, multi-fidelity")
