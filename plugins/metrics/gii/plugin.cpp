#include <hapsyn/plugin.hpp>

#include "gii.hpp"

HAPSYN_METRIC_PLUGIN(hapsyn::plugins::Gii, "gii", "1.0.0",
                     "Global isotropy index: min sigma_min(J) / max sigma_max(J) over the scene")
