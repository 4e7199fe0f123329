#include <hapsyn/plugin.hpp>

#include "haptic6r.hpp"

HAPSYN_MECHANISM_PLUGIN(hapsyn::plugins::Haptic6R, "haptic6r", "1.0.0",
                        "SCARA-like serial 6R haptic manipulator (Fennel 2022), closed-form IK, Jacobian, inertia, gravity, actuator tables")
