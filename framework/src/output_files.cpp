#include <hapsyn/error.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/parallel.hpp>

#include <boost/filesystem.hpp>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <streambuf>

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

namespace {

// write(2) of all of `data`, retried on EINTR and short writes.
bool write_all(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

// A stream buffer over a file descriptor that hands each finished line to write(2).
class LineFileBuffer : public std::streambuf {
 public:
  explicit LineFileBuffer(int fd) : fd_(fd) {}
  ~LineFileBuffer() override { flush_pending(); }

 protected:
  int_type overflow(int_type c) override {
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    pending_ += traits_type::to_char_type(c);
    if (c == '\n' && !flush_pending()) return traits_type::eof();
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    pending_.append(s, static_cast<std::size_t>(n));
    if (std::memchr(s, '\n', static_cast<std::size_t>(n)) != nullptr && !flush_pending()) return 0;
    return n;
  }
  int sync() override { return flush_pending() ? 0 : -1; }

 private:
  bool flush_pending() {
    const bool ok = write_all(fd_, pending_.data(), pending_.size());
    pending_.clear();
    return ok;
  }
  int fd_;
  std::string pending_;
};

std::string mebibytes(std::uint64_t bytes) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(1) << static_cast<double>(bytes) / (1024.0 * 1024.0) << " MiB";
  return s.str();
}

}  // namespace

struct LogFile::Impl {
  int fd = -1;
  std::string path;
  std::unique_ptr<LineFileBuffer> buffer;
  std::unique_ptr<std::ostream> stream;
};

LogFile::LogFile(const std::string& path, bool append) : impl_(std::make_unique<Impl>()) {
  // O_NOFOLLOW: open(2) fails with ELOOP on a symbolic link instead of writing to its target.
  const int flags = O_WRONLY | O_CREAT | O_NOFOLLOW | O_CLOEXEC | (append ? O_APPEND : O_TRUNC);
  impl_->path = path;
  impl_->fd = ::open(path.c_str(), flags, 0644);
  if (impl_->fd < 0) {
    if (errno == ELOOP) {
      throw Error("output", path + " is a symbolic link; a run log is never written through one (remove it)");
    }
    throw Error("output", "cannot open " + path + ": " + std::strerror(errno));
  }
  impl_->buffer = std::make_unique<LineFileBuffer>(impl_->fd);
  impl_->stream = std::make_unique<std::ostream>(impl_->buffer.get());
}

LogFile::~LogFile() {
  impl_->stream.reset();
  impl_->buffer.reset();
  ::close(impl_->fd);
}

std::ostream& LogFile::stream() { return *impl_->stream; }

void LogFile::truncate() {
  impl_->stream->flush();
  if (::ftruncate(impl_->fd, 0) != 0) throw Error("output", "cannot truncate " + impl_->path + ": " + std::strerror(errno));
}

DirectoryLock::DirectoryLock(const std::string& directory) {
  const std::string path = (fs::path(directory) / ".lock").string();
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd_ < 0) throw Error("output", "cannot lock " + path + ": " + std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    char text[32] = {0};
    const ssize_t n = ::pread(fd_, text, sizeof text - 1, 0);
    ::close(fd_);
    fd_ = -1;
    if (error == EWOULDBLOCK) {
      const std::string pid = n > 0 ? std::string(text, static_cast<std::size_t>(n)) : std::string("unknown");
      throw Error("output", directory + " is in use by another hapsyn run (pid " + pid.substr(0, pid.find('\n')) +
                                "); wait for it to end, or choose another --out");
    }
    throw Error("output", "cannot lock " + path + ": " + std::strerror(error));
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  // The pid is only for the message of a second run: the lock holds whether or not it is written.
  [[maybe_unused]] const bool written = ::ftruncate(fd_, 0) == 0 && write_all(fd_, pid.data(), pid.size());
}

DirectoryLock::~DirectoryLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the last descriptor releases the flock
}

std::uint64_t free_bytes(const std::string& directory) {
  struct statvfs s {};
  if (::statvfs(directory.c_str(), &s) != 0) {
    throw Error("output", "cannot query the free space of " + directory + ": " + std::strerror(errno));
  }
  return static_cast<std::uint64_t>(s.f_bavail) * static_cast<std::uint64_t>(s.f_frsize);
}

void check_free_space(const std::string& directory, std::uint64_t needed, const std::string& what) {
  constexpr std::uint64_t kFloor = 1024 * 1024;
  const std::uint64_t available = free_bytes(directory);
  if (available >= needed && available >= kFloor) return;
  throw Error("output", directory + ": only " + mebibytes(available) + " free on its file system; this run's outputs (" +
                            what + ") need about " + mebibytes(std::max(needed, kFloor)) +
                            "; free some space or choose another --out");
}

void move_file(const std::string& from, const std::string& to) {
  if (std::rename(from.c_str(), to.c_str()) != 0) {
    throw Error("output", "cannot move " + from + " to " + to + ": " + std::strerror(errno));
  }
}

void sync_directory(const std::string& directory) {
  const int fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  [[maybe_unused]] const int ignored = ::fsync(fd);
  ::close(fd);
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
