#pragma once
/// \file
/// gnuplot helpers shared by the commands that draw (scene --plot, sweep, compare, position
/// maps, Pareto fronts, convergence). Plots are a convenience: data and script are always
/// written first, so a missing gnuplot costs the picture, never the numbers. Every figure is
/// drawn by one script (figure_script) into `<name>.png` and `<name>.svg` with the same look:
/// a title, axis labels with units, names printed as written (`noenhanced`: an `_` is no
/// subscript), the key outside the data area or none.
#include <hapsyn/convergence.hpp>
#include <hapsyn/json.hpp>

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

namespace hapsyn {

/// True when a `gnuplot` executable is on PATH.
bool gnuplot_available();

/// Runs `gnuplot SCRIPT` inside `directory` (so relative data and output names resolve there).
/// \return an empty string on success, else why it failed (gnuplot missing, or its exit status).
std::string run_gnuplot(const std::string& directory, const std::string& script);

/// `text` as a gnuplot single-quoted string: 'it''s' (no other character is special there).
std::string gnuplot_quote(const std::string& text);

/// The size and legend of a figure; the rest of its look is shared (figure_script).
struct FigureStyle {
  int width = 800;     ///< [px] (the SVG has the same size)
  int height = 600;    ///< [px]
  int font_size = 11;  ///< [pt]
  bool key = false;    ///< a legend outside the data area (right, top); false: none (one series)
};

/// The gnuplot script that draws `body` twice, into `<name>.png` (pngcairo) and `<name>.svg`,
/// after the preamble every hapsyn figure shares: terminal with the style's size and font,
/// `noenhanced` text, the key. `body` sets its own titles and labels (one `set title`, or the
/// multiplot's title) and ends any multiplot it starts; `title` heads the script as a comment.
std::string figure_script(const std::string& name, const std::string& title, const FigureStyle& style,
                          const std::string& body);

/// Writes `<name>.gp` (figure_script) into `directory` and runs it there; the data files the
/// body reads must be written first.
/// \return run_gnuplot's message (empty on success). \throws Error("output") when the script
/// cannot be written.
std::string render_figure(const std::string& directory, const std::string& name, const std::string& title,
                          const FigureStyle& style, const std::string& body);

/// One scalar per point of a cubic lattice of `per_axis`^3 points, spacing `step` [m], centred on
/// the scene origin; index = ix + n (iy + n iz) in the lattice frame. NaN marks a point without a
/// value.
struct LatticeField {
  int per_axis = 0;
  double step = 0.0;
  std::vector<double> values;
  /// Rotation from the lattice frame to the frame the plot is drawn in, whose z is the vertical
  /// (human_arm: C_S^B, the base frame B with gravity along -z).
  Eigen::Matrix3d lattice_to_plot = Eigen::Matrix3d::Identity();
  std::string origin = "the lattice centre";  ///< for "height above <origin>"
  std::string lattice_frame = "L";            ///< the lattice frame's name, for axis labels (human_arm: "S")
  std::string value_label;                    ///< the colour bar's label (the value's name and unit); empty: none
};

/// How plot_lattice_slices cuts a field: by height (z of the plot frame) when lattice_to_plot
/// maps lattice axes onto plot axes (a signed permutation within 1e-9), else along the lattice
/// axis closest to the vertical.
struct LatticeSlicing {
  bool by_height = false;      ///< slices are planes of constant z in the plot frame
  int slice_axis = 0;          ///< without by_height: the lattice axis sliced along (0, 1, 2)
  double tilt_degrees = 0.0;   ///< without by_height: angle between that axis and the vertical
};
LatticeSlicing lattice_slicing(const Eigen::Matrix3d& lattice_to_plot);

/// Writes `<name>.dat` and `<name>.gp` into `directory`: one heat-map panel per slice, the highest
/// first (Fennel 2022, Figures 3 and 5: each slice one height above the shoulder), panels drawn
/// in the plot frame's x and y [m], colour range [0, colour_max], rendered to `<name>.png` and
/// `<name>.svg`.
/// \return run_gnuplot's message (empty on success). \throws Error("output") when a file cannot
/// be written.
std::string plot_lattice_slices(const std::string& directory, const std::string& name, const std::string& title,
                                const LatticeField& field, double colour_max);

/// A Pareto front as `front.{dat,gp,png,svg}` in `directory`: the points in the plane of two
/// objectives, or one panel per pair of the first three, each axis named by its objective and
/// its sense ("gii (maximize)"). `points`: one row of objective values per front point.
/// \return run_gnuplot's message (empty on success); "" without writing for fewer than two
/// objectives. \throws Error("output") when a file cannot be written.
std::string plot_front(const std::string& directory, const std::vector<std::string>& objectives,
                       const std::vector<std::string>& senses, const std::vector<std::vector<double>>& points);

/// One curve of a convergence figure.
struct ConvergenceCurve {
  std::string title;                ///< its key entry; empty: none
  std::size_t panel = 0;            ///< index into ConvergenceFigure::panels
  int colour = 0;                   ///< colour index (a run's best and mean share one)
  bool dashed = false;
  std::vector<double> evaluations;  ///< x: design evaluations so far
  std::vector<double> values;       ///< y; NaN: no value (a gap)
};

/// A convergence figure: panels one under another, each its curves against design evaluations.
struct ConvergenceFigure {
  std::string title;
  std::vector<std::string> panels;  ///< each panel's y-axis label
  std::vector<ConvergenceCurve> curves;
};

/// convergence.{dat,gp,png,svg} in `directory`: the dat file one block per curve (gnuplot index,
/// "# title" first), the key shown when a curve has a title.
/// \return run_gnuplot's message (empty on success); "" without writing for a figure without
/// curves. \throws Error("output") when a file cannot be written.
std::string plot_convergence(const std::string& directory, const ConvergenceFigure& figure);

}  // namespace hapsyn
