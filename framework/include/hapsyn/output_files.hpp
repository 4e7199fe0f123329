#pragma once
/// \file
/// Output plumbing shared by everything that writes a run's files (result.json, samples.csv,
/// maps, plots, sweep and compare summaries, solver checkpoints, scene caches): atomic writes,
/// and the provenance stamped into results and run logs (version, machine, time).
///
/// A leaf unit: it depends on nothing of hapsyn but Json and Error, so that any other unit
/// (maps, plots, solvers, scenes) can write files without depending on studies.
#include <hapsyn/json.hpp>

#include <initializer_list>
#include <string>
#include <string_view>

namespace hapsyn {

/// Writes `content` to `path` atomically: a temporary file in the same directory (named
/// ".tmp-<file name>-<pid>-<n>", unique per call in this process), then rename(2), so readers
/// see the old file or the new one, never a partial one. The directory must exist.
/// \throws Error("output", "cannot write <temporary>: <reason>") or Error("output", "cannot move
///         <temporary> to <path>: <reason>"); the temporary file is removed on failure.
void write_file_atomically(const std::string& path, const std::string& content);
/// The same for content in pieces, written in order (a large payload behind a header is not
/// copied into one string first).
void write_file_atomically(const std::string& path, std::initializer_list<std::string_view> parts);

/// Machine description for logs and results: host, CPU model, hardware threads, OS, compiler.
Json machine_info();

/// "0.1.0" (the project version).
const char* version();

/// The current UTC time as "YYYY-MM-DDTHH:MM:SSZ" (result.json "started", run.log lines).
std::string iso_time_now();

}  // namespace hapsyn
