#include <hapsyn/plugin.hpp>

#include "planar_square.hpp"

HAPSYN_SCENE_PLUGIN(hapsyn::plugins::PlanarSquare, "planar_square", "1.0.0",
                    "Square of (x, y) samples on a regular grid, centred at the origin (Unal 2008)")
