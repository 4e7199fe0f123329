#pragma once
// The fuzzed entry point: an input is zero or more lines "--set path=value" followed by a problem
// file. It goes through the same path as `hapsyn validate`: parse, overrides, full validation
// (plugins, schemas, design space, scene build). Bad input must end in hapsyn::Error; anything
// else (another exception, a crash, a sanitizer report, a hang) is a bug.
#include <hapsyn/error.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/study.hpp>

#include <boost/filesystem.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

namespace hapsyn::fuzz {

// The five-bar family only: their scenes build in bounded time, so a slow input is a finding.
inline const Registry& registry() {
  static const std::string dir = [] {
    namespace fs = boost::filesystem;
    // One directory per build tree: several checkouts on one machine must not share links
    // (a link to another build's plugins loads another plugin ABI).
    const fs::path d = fs::temp_directory_path() /
                       ("hapsyn-fuzz-plugins-" + std::to_string(std::hash<std::string>{}(HAPSYN_PLUGIN_DIR)));
    fs::create_directories(d);
    for (const char* name : {"fivebar", "planar_square", "gii", "gdi", "evaluate", "grid", "culling"}) {
      const fs::path target = fs::path(HAPSYN_PLUGIN_DIR) / (std::string("hapsyn-") + name + ".so");
      const fs::path link = d / target.filename();
      boost::system::error_code ec;
      if (!fs::exists(link, ec)) fs::create_symlink(target, link, ec);
    }
    return d.string();
  }();
  static Registry r({dir});
  return r;
}

inline int fuzz_one(const std::uint8_t* data, std::size_t size) {
  std::string input(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> sets;
  while (input.rfind("--set ", 0) == 0) {
    const auto end = input.find('\n');
    sets.push_back(input.substr(6, end == std::string::npos ? std::string::npos : end - 6));
    input = end == std::string::npos ? std::string() : input.substr(end + 1);
  }
  try {
    Json doc = parse_problem_text(input, "fuzz");
    for (const std::string& s : sets) apply_override(doc, s);
    load_study(doc, registry());
  } catch (const Error&) {
    // The expected outcome of bad input.
  }
  return 0;
}

}  // namespace hapsyn::fuzz
