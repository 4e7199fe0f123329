#pragma once
// Helpers shared by the tests: the in-tree plugin registry and error-message assertions. It also
// brings the study API every test uses: problem files, load_study, run_study.
#include <hapsyn/error.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/study.hpp>
#include <hapsyn/internal/study_runner.hpp>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <sys/wait.h>

namespace hapsyn::test {

/// What `hapsyn ARGS` printed (stdout and stderr together) and its exit code (-1 when killed).
struct Output {
  int code = -1;
  std::string out;
};

/// Runs the build tree's `hapsyn` with `args` (a shell command line fragment).
inline Output hapsyn_cli(const std::string& args) {
  const std::string command = std::string(HAPSYN_BINARY_DIR) + "/bin/hapsyn " + args + " 2>&1";
  Output o;
  FILE* pipe = ::popen(command.c_str(), "r");
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe)) o.out += buffer.data();
  const int status = ::pclose(pipe);
  o.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

/// A registry over the build tree's plugins only (independent of HAPSYN_PLUGIN_PATH).
inline const Registry& registry() {
  static Registry r({HAPSYN_PLUGIN_DIR});
  return r;
}

/// The full what() of the hapsyn::Error thrown by `f`, or "(no error)" when it throws nothing.
inline std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

/// Number of lines of a text file.
inline long count_lines(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  long n = 0;
  while (std::getline(in, line)) ++n;
  return n;
}

/// Runs fn and expects a hapsyn::Error whose message contains every fragment.
template <class Fn>
void expect_error(Fn&& fn, std::initializer_list<std::string> fragments) {
  try {
    fn();
    ADD_FAILURE() << "expected a hapsyn::Error";
  } catch (const Error& e) {
    const std::string what = e.what();
    for (const std::string& f : fragments) {
      EXPECT_NE(what.find(f), std::string::npos) << "message: " << what << "\nmissing: " << f;
    }
  }
}

/// A five-bar study document (coarse, fast) that tests modify.
inline Json fivebar_study(const std::string& solver = "grid") {
  return Json::parse(R"({
    "name": "test",
    "mechanism": {"plugin": "fivebar", "options": {"rho": 1.08}},
    "scene": {"plugin": "planar_square", "options": {"side": 0.1, "step": 0.025}},
    "design": {
      "l0": {"lower": 0.0, "upper": 0.3, "step": 0.1},
      "l1": {"lower": 0.05, "upper": 0.3, "step": 0.05},
      "l2": {"lower": 0.05, "upper": 0.3, "step": 0.05},
      "r":  {"lower": 0.0, "upper": 0.6, "step": 0.1}
    },
    "objectives": [{"metric": "gii"}],
    "solver": {"plugin": ")" + solver + R"("}
  })");
}

/// A random sub-box of the paper's five-bar bounds (l0 in [0, 0.3], l1 and l2 in [0.05, 0.3],
/// r in [0.05, 0.6]) on a grid of the given step, each variable over min_points to max_points
/// points, solved by `solver`.
inline Json fivebar_random_box(std::mt19937& rng, double step, int min_points, int max_points,
                               const std::string& solver = "culling") {
  Json doc = fivebar_study(solver);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::vector<std::tuple<std::string, double, double>> vars = {
      {"l0", 0.0, 0.3}, {"l1", 0.05, 0.3}, {"l2", 0.05, 0.3}, {"r", 0.05, 0.6}};
  for (const auto& [name, lo, hi] : vars) {
    const int points = min_points + static_cast<int>(u(rng) * (max_points - min_points + 1));
    const double width = step * (points - 1);
    const double lower = lo + std::floor(u(rng) * (hi - lo - width) / step) * step;
    doc["design"][name] = {{"lower", lower}, {"upper", lower + width}, {"step", step}};
  }
  return doc;
}

/// A random sub-box with long lines of r (block bounds act on runs of a line): r on a 5 mm grid
/// over 30 to 100 points, l0, l1, l2 over 2 to 4 points of 20 mm, a 20 mm workspace grid.
inline Json fivebar_random_long_lines(std::mt19937& rng, const std::string& solver = "culling") {
  Json doc = fivebar_random_box(rng, 0.02, 2, 4, solver);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int points = 30 + static_cast<int>(u(rng) * 71);
  const double width = 0.005 * (points - 1);
  const double lower = 0.005 * std::floor(u(rng) * (0.6 - width) / 0.005);
  doc["design"]["r"] = {{"lower", lower}, {"upper", lower + width}, {"step", 0.005}};
  doc["scene"]["options"]["step"] = 0.02;
  return doc;
}

}  // namespace hapsyn::test
