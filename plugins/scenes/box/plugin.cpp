#include <hapsyn/plugin.hpp>

#include "box.hpp"

HAPSYN_SCENE_PLUGIN(hapsyn::plugins::Box, "box", "1.0.0",
                    "Rectangle (x, y) or box (x, y, z) on a regular grid, edges included, optionally with one orientation")
