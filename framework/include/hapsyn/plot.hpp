#pragma once
/// \file
/// gnuplot helpers shared by the commands that draw (scene --plot, sweep, position maps).
/// Plots are a convenience: data and script are always written first, so a missing gnuplot
/// costs the picture, never the numbers.
#include <string>
#include <vector>

namespace hapsyn {

/// True when a `gnuplot` executable is on PATH.
bool gnuplot_available();

/// Runs `gnuplot SCRIPT` inside `directory` (so relative data and output names resolve there).
/// \return an empty string on success, else why it failed (gnuplot missing, or its exit status).
std::string run_gnuplot(const std::string& directory, const std::string& script);

/// One scalar per point of a cubic lattice of `per_axis`^3 points, spacing `step` [m], centred on
/// the scene origin; index = ix + n (iy + n iz). NaN marks a point without a value.
struct LatticeField {
  int per_axis = 0;
  double step = 0.0;
  std::vector<double> values;
};

/// Writes `<name>.dat` and `<name>.gp` into `directory`: one heat-map panel per slice ix (x is
/// the slice axis; for the human_arm scene x_S points down, so each slice is one height, as in
/// Fennel 2022, Figures 3 and 5), colour range [0, colour_max], rendered to `<name>.png`.
/// \return run_gnuplot's message (empty on success). \throws Error("output") when a file cannot
/// be written.
std::string plot_lattice_slices(const std::string& directory, const std::string& name, const std::string& title,
                                const LatticeField& field, double colour_max);

}  // namespace hapsyn
