#include <hapsyn/plot.hpp>

#include <cstdlib>

namespace hapsyn {

bool gnuplot_available() { return std::system("command -v gnuplot > /dev/null 2>&1") == 0; }

std::string run_gnuplot(const std::string& directory, const std::string& script) {
  if (!gnuplot_available()) return "gnuplot is not installed (apt-get install gnuplot-nox)";
  const std::string command = "cd '" + directory + "' && gnuplot '" + script + "' > /dev/null 2>&1";
  if (std::system(command.c_str()) != 0) return "gnuplot failed on " + directory + "/" + script;
  return "";
}

}  // namespace hapsyn
