#include <hapsyn/plugin.hpp>

#include "motion_feasibility.hpp"

HAPSYN_METRIC_PLUGIN(hapsyn::plugins::MotionFeasibility, "motion_feasibility", "1.0.0",
                     "Share of recorded motion a design reaches, and serves within its velocity and torque limits")
