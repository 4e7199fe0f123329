#pragma once
/// \file
/// Output plumbing shared by everything that writes a run's files (result.json, samples.csv,
/// maps, plots, sweep and compare summaries, solver checkpoints, scene caches): atomic writes,
/// and the provenance stamped into results and run logs (version, machine, time).
///
/// A leaf unit: it depends on nothing of hapsyn but Json and Error, so that any other unit
/// (maps, plots, solvers, scenes) can write files without depending on studies.
#include <hapsyn/json.hpp>

#include <cstdint>
#include <initializer_list>
#include <memory>
#include <ostream>
#include <string>
#include <string_view>

namespace hapsyn {

/// Writes `content` to `path` atomically: a temporary file in the same directory (named
/// ".tmp-<file name>-<pid>-<n>", unique per call in this process), then rename(2), so readers
/// see the old file or the new one, never a partial one. The directory must exist.
/// \throws Error `("output", "cannot write <temporary>: <reason>")` or `Error("output", "cannot
///         move <temporary> to <path>: <reason>")`; the temporary file is removed on failure.
void write_file_atomically(const std::string& path, const std::string& content);
/// The same for content in pieces, written in order (a large payload behind a header is not
/// copied into one string first).
void write_file_atomically(const std::string& path, std::initializer_list<std::string_view> parts);

/// A run's log file (run.log), opened without following symbolic links: a symbolic link at
/// `path` is refused, so a planted link can never make a run overwrite its target. Every line
/// reaches the file when it ends (a killed run keeps the lines written so far).
class LogFile {
 public:
  /// Opens `path` for writing, appending when `append` (a resumed run), else truncating.
  /// \throws Error `("output", "<path> is a symbolic link; a run log is never written through
  ///         one (remove it)")` or `Error("output", "cannot open <path>: <reason>")`.
  LogFile(const std::string& path, bool append);
  ~LogFile();
  LogFile(const LogFile&) = delete;
  LogFile& operator=(const LogFile&) = delete;
  std::ostream& stream();
  /// Empties the file (a log opened with `append` that turns out to start afresh).
  /// \throws Error `("output", "cannot truncate <path>: <reason>")`.
  void truncate();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// An exclusive lock on a directory (flock(2) on `<directory>/.lock`, which holds the owner's
/// pid), held until destruction, so that two runs never write into one output directory. The
/// lock file stays (removing it would let a third process lock a fresh file while the second
/// waits on the old one). The lock dies with its process: a killed run never leaves it taken.
class DirectoryLock {
 public:
  /// \throws Error `("output", "<directory> is in use by another hapsyn run (pid <n>)")` when
  ///         another process holds it, `Error("output", "cannot lock <directory>/.lock: <reason>")`
  ///         else.
  explicit DirectoryLock(const std::string& directory);
  ~DirectoryLock();
  DirectoryLock(const DirectoryLock&) = delete;
  DirectoryLock& operator=(const DirectoryLock&) = delete;

 private:
  int fd_ = -1;
};

/// Bytes available to this user on the file system holding `directory` (statvfs(2) f_bavail).
/// \throws Error `("output", "cannot query the free space of <directory>: <reason>")`.
std::uint64_t free_bytes(const std::string& directory);

/// Refuses a run whose outputs will not fit: less than `needed` bytes, or less than 1 MiB (the
/// floor for result.json, the log and the checkpoint), free on the file system of `directory`.
/// \param directory the run's output directory
/// \param needed    the bytes the outputs will take (estimated)
/// \param what      the outputs, for the message ("samples.csv (10201 rows x 5 columns) and maps.csv")
/// \throws Error `("output", "<directory>: only <free> free on its file system; this run's
///         outputs (<what>) need about <needed>; free some space or choose another --out")`.
void check_free_space(const std::string& directory, std::uint64_t needed, const std::string& what);

/// Moves `from` to `to` with rename(2) (same file system), replacing `to`.
/// \throws Error `("output", "cannot move <from> to <to>: <reason>")`.
void move_file(const std::string& from, const std::string& to);

/// fsync(2) of a directory, so that renames into it survive a crash (best effort: errors ignored).
void sync_directory(const std::string& directory);

/// Machine description for logs and results: host, CPU model, hardware threads, OS, compiler.
Json machine_info();

/// "0.1.0" (the project version).
const char* version();

/// The current UTC time as "YYYY-MM-DDTHH:MM:SSZ" (result.json "started", run.log lines).
std::string iso_time_now();

}  // namespace hapsyn
