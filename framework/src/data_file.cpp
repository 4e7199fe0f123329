#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/json.hpp>

#include <boost/dll/runtime_symbol_info.hpp>
#include <boost/filesystem.hpp>

#include <mutex>
#include <vector>

namespace hapsyn {

namespace fs = boost::filesystem;

namespace {
std::mutex& directory_mutex() {
  static std::mutex m;
  return m;
}

std::string& current_directory() {
  static std::string directory;
  return directory;
}

bool usable(const fs::path& p, bool directory_too) {
  boost::system::error_code ec;
  return fs::is_regular_file(p, ec) || (directory_too && fs::is_directory(p, ec));
}

// Where a relative path is looked for, in order: the problem file's folder (when loading one),
// the current directory, share/hapsyn beside this library's lib/ (an install moved elsewhere, a
// pip-installed wheel), the source tree's share/ (serves the build tree), the installed copy.
std::vector<fs::path> candidates_for(const fs::path& p) {
  std::vector<fs::path> candidates;
  const std::string problem = problem_directory();
  if (!problem.empty()) candidates.push_back(fs::path(problem) / p);
  candidates.push_back(fs::current_path() / p);
  candidates.push_back(boost::dll::this_line_location().parent_path().parent_path() / "share" / "hapsyn" / p);
  candidates.push_back(fs::path(HAPSYN_SHARE_DIR) / p);
  candidates.push_back(fs::path(HAPSYN_INSTALL_SHARE_DIR) / p);
  return candidates;
}

std::string find_data(const std::string& component, const std::string& option, const std::string& value,
                      bool directory_too) {
  const std::string shown = "options." + option + " = " + Json(value).dump();
  const std::string what = directory_too ? "file or folder" : "file";
  if (value.empty()) throw Error(component, shown + ": must name a " + what);
  const fs::path p(value);
  if (p.is_absolute()) {
    if (!usable(p, directory_too)) throw Error(component, shown + ": no such " + what);
    return p.string();
  }
  std::string tried;
  for (const fs::path& c : candidates_for(p)) {
    if (usable(c, directory_too)) return fs::absolute(c).lexically_normal().string();
    tried += (tried.empty() ? "" : ", ") + c.string();
  }
  throw Error(component, shown + ": no such " + what + " (tried " + tried + ")");
}
}  // namespace

ProblemDirectoryScope::ProblemDirectoryScope(const std::string& problem_file) {
  std::string folder;
  if (!problem_file.empty()) {
    const fs::path absolute = fs::absolute(fs::path(problem_file)).lexically_normal();
    folder = absolute.parent_path().string();
  }
  const std::lock_guard<std::mutex> lock(directory_mutex());
  previous_ = current_directory();
  current_directory() = folder;
}

ProblemDirectoryScope::~ProblemDirectoryScope() {
  const std::lock_guard<std::mutex> lock(directory_mutex());
  current_directory() = previous_;
}

std::string problem_directory() {
  const std::lock_guard<std::mutex> lock(directory_mutex());
  return current_directory();
}

std::string find_data_file(const std::string& component, const std::string& option, const std::string& value) {
  return find_data(component, option, value, false);
}

std::string find_data_path(const std::string& component, const std::string& option, const std::string& value) {
  return find_data(component, option, value, true);
}

std::string resolve_problem_path(const std::string& value) {
  const fs::path p(value);
  if (p.is_absolute()) return p.lexically_normal().string();
  const std::string problem = problem_directory();
  boost::system::error_code ec;
  if (!problem.empty() && fs::exists(fs::path(problem) / p, ec)) return (fs::path(problem) / p).lexically_normal().string();
  return fs::absolute(p).lexically_normal().string();
}

}  // namespace hapsyn
