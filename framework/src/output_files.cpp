#include <hapsyn/error.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/parallel.hpp>

#include <boost/filesystem.hpp>

#include <sys/utsname.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <sstream>

#ifndef HAPSYN_VERSION
#define HAPSYN_VERSION "0.0.0"
#endif

namespace hapsyn {

namespace fs = boost::filesystem;

const char* version() { return HAPSYN_VERSION; }

void write_file_atomically(const std::string& path, const std::string& content) {
  write_file_atomically(path, {std::string_view(content)});
}

void write_file_atomically(const std::string& path, std::initializer_list<std::string_view> parts) {
  // The pid separates processes, the counter separates threads of this one that write the
  // same file (two builds of one scene cache).
  static std::atomic<unsigned long long> calls{0};
  const fs::path target(path);
  const fs::path temp = target.parent_path() / (".tmp-" + target.filename().string() + "-" +
                                                std::to_string(::getpid()) + "-" + std::to_string(calls++));
  {
    std::ofstream out(temp.string(), std::ios::binary | std::ios::trunc);
    if (!out) throw Error("output", "cannot write " + temp.string() + ": " + std::strerror(errno));
    for (const std::string_view part : parts) out.write(part.data(), static_cast<std::streamsize>(part.size()));
    out.flush();
    if (!out) {
      const std::string reason = std::strerror(errno);
      out.close();
      boost::system::error_code ignored;
      fs::remove(temp, ignored);
      throw Error("output", "cannot write " + temp.string() + ": " + reason);
    }
  }
  // rename(2) replaces the target in one step: readers see the old file or the new one.
  if (std::rename(temp.string().c_str(), target.string().c_str()) != 0) {
    const std::string reason = std::strerror(errno);
    boost::system::error_code ignored;
    fs::remove(temp, ignored);
    throw Error("output", "cannot move " + temp.string() + " to " + path + ": " + reason);
  }
}

Json machine_info() {
  Json m;
  char host[256] = {0};
  if (::gethostname(host, sizeof host - 1) == 0) m["host"] = host;
  std::ifstream cpu("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpu, line)) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) m["cpu"] = line.substr(colon + 2);
      break;
    }
  }
  m["hardware_threads"] = hardware_threads();
  struct utsname u;
  if (::uname(&u) == 0) m["os"] = std::string(u.sysname) + " " + u.release + " " + u.machine;
#if defined(__clang__)
  m["compiler"] = std::string("clang ") + __clang_version__;
#elif defined(__GNUC__)
  m["compiler"] = std::string("gcc ") + __VERSION__;
#endif
  return m;
}

std::string iso_time_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  std::ostringstream s;
  s << std::put_time(&tm, "%Y-%m-%dT%H:%M:%SZ");
  return s.str();
}

}  // namespace hapsyn
