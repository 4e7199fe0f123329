#include <hapsyn/error.hpp>
#include <hapsyn/internal/plot.hpp>
#include <hapsyn/output_files.hpp>

#include <boost/filesystem.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

namespace hapsyn {

bool gnuplot_available() { return std::system("command -v gnuplot > /dev/null 2>&1") == 0; }

std::string run_gnuplot(const std::string& directory, const std::string& script) {
  if (!gnuplot_available()) return "gnuplot is not installed (apt-get install gnuplot-nox)";
  const std::string command = "cd '" + directory + "' && gnuplot '" + script + "' > /dev/null 2>&1";
  const int status = std::system(command.c_str());
  if (status != 0) return "gnuplot failed on " + directory + "/" + script + " (status " + std::to_string(status) + ")";
  return "";
}

std::string gnuplot_quote(const std::string& text) {
  std::string quoted;
  for (char c : text) quoted += c == '\'' ? std::string("''") : std::string(1, c);
  return "'" + quoted + "'";
}

// One loop over the two formats: the body appears once, so the PNG and the SVG cannot differ.
std::string figure_script(const std::string& name, const std::string& title, const FigureStyle& style,
                          const std::string& body) {
  std::ostringstream size;
  size << " noenhanced size " << style.width << "," << style.height << " font '," << style.font_size << "'";
  std::ostringstream script;
  script << "# hapsyn: " << title << "\n"
         << "set encoding utf8\n"
         << "do for [format in \"png svg\"] {\n"
         << "if (format eq \"png\") {\n"
         << "set terminal pngcairo" << size.str() << "\n"
         << "} else {\n"
         << "set terminal svg" << size.str() << " background '#ffffff'\n"
         << "}\n"
         << "set output " << gnuplot_quote(name + ".") << ".format\n"
         << "set termoption noenhanced\n"
         << (style.key ? "set key outside right top\n" : "unset key\n")
         << body << (body.empty() || body.back() == '\n' ? "" : "\n")
         << "unset output\n"
         << "}\n";
  return script.str();
}

std::string render_figure(const std::string& directory, const std::string& name, const std::string& title,
                          const FigureStyle& style, const std::string& body) {
  write_file_atomically((boost::filesystem::path(directory) / (name + ".gp")).string(),
                        figure_script(name, title, style, body));
  return run_gnuplot(directory, name + ".gp");
}

LatticeSlicing lattice_slicing(const Eigen::Matrix3d& lattice_to_plot) {
  LatticeSlicing slicing;
  const Eigen::Matrix3d a = lattice_to_plot.cwiseAbs();
  bool permutation = true;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      if (!(a(r, c) < 1e-9 || a(r, c) > 1.0 - 1e-9)) permutation = false;
    }
  }
  slicing.by_height = permutation;
  a.row(2).maxCoeff(&slicing.slice_axis);
  slicing.tilt_degrees = std::acos(std::min(1.0, a(2, slicing.slice_axis))) * 180.0 / M_PI;
  return slicing;
}

namespace {

// The panels of a slice plot: axis labels, and per slice (highest first) a title and its n x n
// values (entry i n + j at the i-th horizontal and j-th vertical grid coordinate).
struct SlicePanels {
  std::string x_label, y_label;
  std::vector<std::string> titles;
  std::vector<std::vector<double>> values;
};

// The field in the plot frame, sliced by height: the plot frame's lattice is the lattice frame's
// turned by a signed permutation, so every point maps onto one point.
SlicePanels panels_by_height(const LatticeField& field) {
  const int n = field.per_axis;
  const int half = (n - 1) / 2;
  const Eigen::Matrix3d back = field.lattice_to_plot.transpose();
  SlicePanels p;
  p.x_label = "x [m]";
  p.y_label = "y [m]";
  for (int k = n - 1; k >= 0; --k) {
    std::ostringstream title;
    title << "height above " << field.origin << ": " << std::fixed;
    title.precision(2);
    title << (k - half) * field.step + 0.0 << " m";
    p.titles.push_back(title.str());
    std::vector<double> slice(static_cast<std::size_t>(n) * n, std::nan(""));
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const Eigen::Vector3d in_lattice = back * Eigen::Vector3d(i - half, j - half, k - half);
        const long ix = std::lround(in_lattice.x()) + half, iy = std::lround(in_lattice.y()) + half,
                   iz = std::lround(in_lattice.z()) + half;
        if (ix < 0 || iy < 0 || iz < 0 || ix >= n || iy >= n || iz >= n) continue;  // an even n turned
        slice[static_cast<std::size_t>(i) * n + j] =
            field.values[static_cast<std::size_t>(ix) + static_cast<std::size_t>(n) * (iy + static_cast<std::size_t>(n) * iz)];
      }
    }
    p.values.push_back(std::move(slice));
  }
  return p;
}

// The field sliced along the lattice axis closest to the vertical, panels in the other two
// lattice axes (a lattice turned by a general rotation has no planes of constant height).
SlicePanels panels_along_lattice_axis(const LatticeField& field, const LatticeSlicing& slicing) {
  const int n = field.per_axis;
  const int half = (n - 1) / 2;
  const int axis = slicing.slice_axis, first = (axis + 1) % 3, second = (axis + 2) % 3;
  const char* names[] = {"x", "y", "z"};
  const bool upward = field.lattice_to_plot(2, axis) >= 0.0;
  SlicePanels p;
  p.x_label = std::string(names[first]) + "_" + field.lattice_frame + " [m]";
  p.y_label = std::string(names[second]) + "_" + field.lattice_frame + " [m]";
  for (int step = 0; step < n; ++step) {
    const int k = upward ? n - 1 - step : step;
    std::ostringstream title;
    title << names[axis] << "_" << field.lattice_frame << " = " << std::fixed;
    title.precision(2);
    title << (k - half) * field.step + 0.0 << " m (" << std::setprecision(0) << slicing.tilt_degrees
          << " deg from the vertical)";
    p.titles.push_back(title.str());
    std::vector<double> slice(static_cast<std::size_t>(n) * n);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        int index[3];
        index[axis] = k;
        index[first] = i;
        index[second] = j;
        slice[static_cast<std::size_t>(i) * n + j] =
            field.values[static_cast<std::size_t>(index[0]) +
                         static_cast<std::size_t>(n) * (index[1] + static_cast<std::size_t>(n) * index[2])];
      }
    }
    p.values.push_back(std::move(slice));
  }
  return p;
}

}  // namespace

std::string plot_lattice_slices(const std::string& directory, const std::string& name, const std::string& title,
                                const LatticeField& field, double colour_max) {
  namespace fs = boost::filesystem;
  const int n = field.per_axis;
  const double step = field.step;
  const int half = (n - 1) / 2;
  const LatticeSlicing slicing = lattice_slicing(field.lattice_to_plot);
  const SlicePanels panels = slicing.by_height ? panels_by_height(field) : panels_along_lattice_axis(field, slicing);
  std::ostringstream data;
  data << "# " << title << "\n# one block per slice (highest first), rows of (" << panels.x_label << ", "
       << panels.y_label << ", value); NaN = no value\n";
  for (std::size_t s = 0; s < panels.values.size(); ++s) {
    data << "# " << panels.titles[s] << "\n";
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const double v = panels.values[s][static_cast<std::size_t>(i) * n + j];
        data << (i - half) * step << " " << (j - half) * step << " ";
        // NaN keeps the image grid complete and is drawn as a blank pixel.
        if (std::isfinite(v)) {
          data << v << "\n";
        } else {
          data << "NaN\n";
        }
      }
      data << "\n";
    }
    data << "\n";
  }
  const int columns = static_cast<int>(std::ceil(std::sqrt(n)));
  const int rows = (n + columns - 1) / columns;
  std::ostringstream body;
  body << "set multiplot layout " << rows << "," << columns << " title " << gnuplot_quote(title) << "\n"
       << "set cbrange [0:" << (colour_max > 0.0 ? colour_max : 1.0) << "]\n"
       << "set palette rgbformulae 33,13,10\nset size ratio -1\n"
       << "set xlabel " << gnuplot_quote(panels.x_label) << "\nset ylabel " << gnuplot_quote(panels.y_label) << "\n"
       << "set cblabel " << gnuplot_quote(field.value_label) << "\n"
       // Fixed ranges: a slice without any value must still draw (as an empty panel).
       << "set xrange [" << -(half + 0.5) * step << ":" << (half + 0.5) * step << "]\n"
       << "set yrange [" << -(half + 0.5) * step << ":" << (half + 0.5) * step << "]\n";
  for (std::size_t s = 0; s < panels.titles.size(); ++s) {
    body << "set title " << gnuplot_quote(panels.titles[s]) << "\n"
         << "plot " << gnuplot_quote(name + ".dat") << " index " << s << " using 1:2:3 with image\n";
  }
  body << "unset multiplot\n";
  write_file_atomically((fs::path(directory) / (name + ".dat")).string(), data.str());
  FigureStyle style;
  style.width = 320 * columns;
  style.height = 300 * rows;
  style.font_size = 9;
  return render_figure(directory, name, title, style, body.str());
}

std::string plot_front(const std::string& directory, const std::vector<std::string>& objectives,
                       const std::vector<std::string>& senses, const std::vector<std::vector<double>>& points) {
  const std::size_t m = objectives.size();
  if (m < 2) return "";
  std::ostringstream data;
  data.precision(12);
  data << "#";
  for (const std::string& o : objectives) data << " " << o;
  data << "\n";
  for (const std::vector<double>& p : points) {
    for (std::size_t k = 0; k < m; ++k) data << (k ? " " : "") << p[k];
    data << "\n";
  }
  // Pairs of objectives drawn: the one plane of two, else the three planes of the first three.
  std::vector<std::pair<std::size_t, std::size_t>> pairs = {{0, 1}};
  if (m >= 3) pairs = {{0, 1}, {0, 2}, {1, 2}};
  // Objectives carry no unit of their own here: each axis names its objective and sense.
  const auto label = [&](std::size_t k) {
    return gnuplot_quote(objectives[k] + (k < senses.size() ? " (" + senses[k] + ")" : ""));
  };
  const std::string title = gnuplot_quote("Pareto front: " + std::to_string(points.size()) + " points");
  std::ostringstream body;
  body << "set grid\n";
  if (pairs.size() > 1) body << "set multiplot layout 1," << pairs.size() << " title " << title << "\n";
  for (const auto& [a, b] : pairs) {
    body << "set xlabel " << label(a) << "\nset ylabel " << label(b) << "\n"
         << "set title " << (pairs.size() > 1 ? "''" : title) << "\n"
         << "plot 'front.dat' using " << a + 1 << ":" << b + 1 << " with points pt 7 ps 0.8 lc rgb '#1f5fa8'\n";
  }
  if (pairs.size() > 1) body << "unset multiplot\n";
  FigureStyle style;
  style.width = pairs.size() > 1 ? 1500 : 760;
  style.height = pairs.size() > 1 ? 520 : 600;
  write_file_atomically((boost::filesystem::path(directory) / "front.dat").string(), data.str());
  return render_figure(directory, "front", "Pareto front", style, body.str());
}

std::string plot_convergence(const std::string& directory, const ConvergenceFigure& figure) {
  if (figure.curves.empty() || figure.panels.empty()) return "";
  std::ostringstream data;
  data.precision(12);
  data << "# " << figure.title << "\n# one block per curve (gnuplot index): design evaluations, value (NaN: none)\n";
  bool key = false;
  for (std::size_t c = 0; c < figure.curves.size(); ++c) {
    const ConvergenceCurve& curve = figure.curves[c];
    key = key || !curve.title.empty();
    data << (c ? "\n\n" : "") << "# " << curve.title << "\n";
    for (std::size_t i = 0; i < curve.evaluations.size() && i < curve.values.size(); ++i) {
      data << curve.evaluations[i] << " ";
      if (std::isfinite(curve.values[i])) {
        data << curve.values[i] << "\n";
      } else {
        data << "NaN\n";
      }
    }
  }
  const std::size_t panels = figure.panels.size();
  std::ostringstream body;
  body << "set datafile missing 'NaN'\nset grid\nset xlabel 'design evaluations'\n";
  if (panels > 1) body << "set multiplot layout " << panels << ",1 title " << gnuplot_quote(figure.title) << "\n";
  for (std::size_t p = 0; p < panels; ++p) {
    body << "set title " << (panels > 1 ? "''" : gnuplot_quote(figure.title)) << "\n"
         << "set ylabel " << gnuplot_quote(figure.panels[p]) << "\nplot ";
    bool first = true;
    for (std::size_t c = 0; c < figure.curves.size(); ++c) {
      const ConvergenceCurve& curve = figure.curves[c];
      if (curve.panel != p) continue;
      body << (first ? "" : ", ") << "'convergence.dat' index " << c << " using 1:2 with lines lw 1.5 lc "
           << curve.colour % 8 + 1 << " dt " << (curve.dashed ? 2 : 1) << " "
           << (curve.title.empty() ? std::string("notitle") : "title " + gnuplot_quote(curve.title));
      first = false;
    }
    body << (first ? "NaN notitle" : "") << "\n";
  }
  if (panels > 1) body << "unset multiplot\n";
  FigureStyle style;
  style.width = key ? 1000 : 850;
  style.height = static_cast<int>(std::min<std::size_t>(panels, 6)) * 280 + 120;
  style.key = key;
  write_file_atomically((boost::filesystem::path(directory) / "convergence.dat").string(), data.str());
  return render_figure(directory, "convergence", figure.title, style, body.str());
}

}  // namespace hapsyn
