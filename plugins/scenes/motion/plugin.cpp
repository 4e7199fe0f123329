#include <hapsyn/plugin.hpp>

#include "motion_scene.hpp"

HAPSYN_SCENE_PLUGIN(hapsyn::plugins::MotionScene, "motion", "1.0.0",
                    "Recorded hand motion (hapsyn-motion CSV, BVH) with the twist and twist rate of every sample")
