#include <hapsyn/plugin.hpp>

#include "fivebar.hpp"

HAPSYN_MECHANISM_PLUGIN(hapsyn::plugins::FiveBar, "fivebar", "1.0.0",
                        "Symmetric planar five-bar (Unal 2008)")
