#include "evaluate.hpp"

#include <hapsyn/plugin.hpp>

HAPSYN_SOLVER_PLUGIN(hapsyn::plugins::EvaluateSolver, "evaluate", "1.0.0",
                     "Evaluates the study's fixed design (every design variable given a value)")
