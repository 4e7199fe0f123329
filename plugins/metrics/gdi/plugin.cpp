#include <hapsyn/plugin.hpp>

#include "gdi.hpp"

HAPSYN_METRIC_PLUGIN(hapsyn::plugins::Gdi, "gdi", "1.0.0",
                     "Global dynamic index: 1 / (1 + max sigma_max(M)) over the scene, M the effective mass")
