// The registration of planar_2r: the one translation unit of the plugin library that includes
// hapsyn/plugin.hpp (the model is in planar_2r.cpp, shared with planar_2r_test).
#include <hapsyn/plugin.hpp>

#include "planar_2r.hpp"

HAPSYN_MECHANISM_PLUGIN(planar_2r_example::Planar2R, "planar_2r", "1.0.0",
                        "Planar serial arm of two revolute joints (l1, l2), closed-form inverse kinematics")
