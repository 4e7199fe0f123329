#include <hapsyn/plugin.hpp>

#include "coverage.hpp"

HAPSYN_METRIC_PLUGIN(hapsyn::plugins::Coverage, "coverage", "1.0.0",
                     "Coverage of the human arm's poses, velocities, accelerations and forces (Fennel 2022, eqs. 9-18)")
