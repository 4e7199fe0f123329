#include <hapsyn/error.hpp>
#include <hapsyn/plot.hpp>
#include <hapsyn/output_files.hpp>

#include <boost/filesystem.hpp>

#include <cmath>
#include <cstdlib>
#include <sstream>

namespace hapsyn {

bool gnuplot_available() { return std::system("command -v gnuplot > /dev/null 2>&1") == 0; }

std::string run_gnuplot(const std::string& directory, const std::string& script) {
  if (!gnuplot_available()) return "gnuplot is not installed (apt-get install gnuplot-nox)";
  const std::string command = "cd '" + directory + "' && gnuplot '" + script + "' > /dev/null 2>&1";
  const int status = std::system(command.c_str());
  if (status != 0) return "gnuplot failed on " + directory + "/" + script + " (status " + std::to_string(status) + ")";
  return "";
}

std::string plot_lattice_slices(const std::string& directory, const std::string& name, const std::string& title,
                                const LatticeField& field, double colour_max) {
  namespace fs = boost::filesystem;
  const int n = field.per_axis;
  const double step = field.step;
  const int half = (n - 1) / 2;
  std::ostringstream data;
  data << "# " << title << "\n# one block per slice x = k * step, rows of (y, z, value); NaN = no value\n";
  for (int ix = 0; ix < n; ++ix) {
    data << "# x = " << (ix - half) * step << "\n";
    for (int iy = 0; iy < n; ++iy) {
      for (int iz = 0; iz < n; ++iz) {
        const double v = field.values[static_cast<std::size_t>(ix) + static_cast<std::size_t>(n) * (iy + static_cast<std::size_t>(n) * iz)];
        data << (iy - half) * step << " " << (iz - half) * step << " ";
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
  std::ostringstream script;
  script << "# hapsyn: " << title << "\n"
         << "set terminal pngcairo size " << 320 * columns << "," << 300 * rows << " font ',9'\n"
         << "set output '" << name << ".png'\n"
         << "set termoption noenhanced\n"
         << "set multiplot layout " << rows << "," << columns << " title '" << title << "'\n"
         << "set cbrange [0:" << (colour_max > 0.0 ? colour_max : 1.0) << "]\n"
         << "set palette rgbformulae 33,13,10\nset size ratio -1\n"
         << "set xlabel 'y_S [m]'\nset ylabel 'z_S [m]'\nunset key\n"
         // Fixed ranges: a slice without any value must still draw (as an empty panel).
         << "set xrange [" << -(half + 0.5) * step << ":" << (half + 0.5) * step << "]\n"
         << "set yrange [" << -(half + 0.5) * step << ":" << (half + 0.5) * step << "]\n";
  for (int ix = 0; ix < n; ++ix) {
    script << "set title sprintf('height %.2f m', " << -(ix - half) * step << ")\n"
           << "plot '" << name << ".dat' index " << ix << " using 1:2:3 with image\n";
  }
  script << "unset multiplot\n";
  write_file_atomically((fs::path(directory) / (name + ".dat")).string(), data.str());
  write_file_atomically((fs::path(directory) / (name + ".gp")).string(), script.str());
  return run_gnuplot(directory, name + ".gp");
}

}  // namespace hapsyn
