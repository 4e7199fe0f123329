#include <hapsyn/plugin.hpp>

#include "point_list.hpp"

HAPSYN_SCENE_PLUGIN(hapsyn::plugins::PointList, "point_list", "1.0.0",
                    "Samples read from a CSV file: positions, optional orientations, weights and attributes")
