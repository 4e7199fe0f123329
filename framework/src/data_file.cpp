#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/json.hpp>

#include <boost/filesystem.hpp>

#include <vector>

namespace hapsyn {

namespace fs = boost::filesystem;

namespace {
bool usable(const fs::path& p, bool directory_too) {
  boost::system::error_code ec;
  return fs::is_regular_file(p, ec) || (directory_too && fs::is_directory(p, ec));
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
  // The source tree's share/ serves the build tree; the installed copy serves an installation.
  const std::vector<fs::path> candidates = {fs::current_path() / p, fs::path(HAPSYN_SHARE_DIR) / p,
                                            fs::path(HAPSYN_INSTALL_SHARE_DIR) / p};
  std::string tried;
  for (const fs::path& c : candidates) {
    if (usable(c, directory_too)) return fs::absolute(c).lexically_normal().string();
    tried += (tried.empty() ? "" : ", ") + c.string();
  }
  throw Error(component, shown + ": no such " + what + " (tried " + tried + ")");
}
}  // namespace

std::string find_data_file(const std::string& component, const std::string& option, const std::string& value) {
  return find_data(component, option, value, false);
}

std::string find_data_path(const std::string& component, const std::string& option, const std::string& value) {
  return find_data(component, option, value, true);
}

}  // namespace hapsyn
