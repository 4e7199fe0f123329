#include <hapsyn/plugin.hpp>

#include "serial_chain.hpp"

HAPSYN_MECHANISM_PLUGIN(hapsyn::plugins::SerialChain, "serial_chain", "1.0.0",
                        "Serial manipulator (1-7 joints) from a URDF or DH table; every model parameter a design "
                        "variable; numerical IK, Jacobian, CRBA inertia, gravity, actuator tables")
