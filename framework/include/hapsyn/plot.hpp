#pragma once
/// \file
/// Running gnuplot on a script the caller wrote (hapsyn sweep, scene --plot, compare).
#include <string>

namespace hapsyn {

/// True when a gnuplot executable is on the PATH.
bool gnuplot_available();

/// Runs gnuplot on `script` (a file inside `directory`) with `directory` as the working
/// directory, so the script may name its data and output files relatively. Returns "" on
/// success, else why there is no plot ("gnuplot is not installed (apt-get install
/// gnuplot-nox)" or "gnuplot failed on DIR/SCRIPT"). Never throws.
std::string run_gnuplot(const std::string& directory, const std::string& script);

}  // namespace hapsyn
