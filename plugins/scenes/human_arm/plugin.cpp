#include <hapsyn/plugin.hpp>

#include "human_arm.hpp"

HAPSYN_SCENE_PLUGIN(hapsyn::plugins::HumanArmScene, "human_arm", "1.0.0",
                    "Reachable palm poses of the 7-DOF human arm (Fennel 2022): position lattice x "
                    "orientation set, best-manipulability IK, optional M_v/M_a; cached on disk")
