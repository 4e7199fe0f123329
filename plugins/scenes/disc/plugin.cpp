#include <hapsyn/plugin.hpp>

#include "disc.hpp"

HAPSYN_SCENE_PLUGIN(hapsyn::plugins::Disc, "disc", "1.0.0",
                    "Grid points in a disc (x, y) or ball (x, y, z), optionally with one orientation")
