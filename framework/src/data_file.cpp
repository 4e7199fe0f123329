#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/json.hpp>

#include <boost/filesystem.hpp>

#include <vector>

namespace hapsyn {

namespace fs = boost::filesystem;

std::string find_data_file(const std::string& component, const std::string& option, const std::string& value) {
  const std::string shown = "options." + option + " = " + Json(value).dump();
  if (value.empty()) throw Error(component, shown + ": must name a file");
  const fs::path p(value);
  if (p.is_absolute()) {
    if (!fs::is_regular_file(p)) throw Error(component, shown + ": no such file");
    return p.string();
  }
  // The source tree's share/ serves the build tree; the installed copy serves an installation.
  const std::vector<fs::path> candidates = {fs::current_path() / p, fs::path(HAPSYN_SHARE_DIR) / p,
                                            fs::path(HAPSYN_INSTALL_SHARE_DIR) / p};
  std::string tried;
  for (const fs::path& c : candidates) {
    boost::system::error_code ec;
    if (fs::is_regular_file(c, ec)) return fs::absolute(c).lexically_normal().string();
    tried += (tried.empty() ? "" : ", ") + c.string();
  }
  throw Error(component, shown + ": no such file (tried " + tried + ")");
}

}  // namespace hapsyn
