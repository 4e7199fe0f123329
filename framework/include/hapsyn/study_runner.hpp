#pragma once
/// \file
/// Running a loaded study (`hapsyn run`, sweeps, comparisons): the output directory and its
/// guards, the seed, the run log, the solver call and the result files (result.json,
/// samples.csv, maps.csv and plots).
#include <hapsyn/json.hpp>
#include <hapsyn/study.hpp>

#include <atomic>
#include <cstdint>
#include <ostream>
#include <optional>
#include <string>

namespace hapsyn {

struct RunOptions {
  std::string output_directory;  ///< overrides output.directory when not empty
  int threads = 0;               ///< 0 = the file's "threads", else hardware concurrency
  std::optional<std::uint64_t> seed;
  bool quiet = false;
  bool write_samples = true;     ///< per-sample CSV and position maps of the best design
  /// Overwrite a finished study (an existing result.json in the output directory).
  bool force = false;
  /// Continue from the output directory's checkpoint.json (solvers that checkpoint); the seed
  /// is the checkpoint's unless given.
  bool resume = false;
  /// Where progress lines go instead of stderr (not null; ignored when `quiet`), e.g. a stream
  /// that hands them to a Python callback.
  std::ostream* progress = nullptr;
  /// Handed to the solver as SolverContext::stop: setting it asks the run to stop (status
  /// "stopped", best so far). Null: no stop request possible.
  const std::atomic<bool>* stop = nullptr;
};

/// Runs a loaded study: solves, then writes result.json (atomically) and, for a best design,
/// samples.csv and maps.csv (and map plots when output.plots) into the output directory.
/// Returns the result document. The solver's outcome is in "status".
/// The seed is options.seed, else the checkpoint's (on resume), else the file's "seed", else
/// drawn; it is recorded in result.json. Studies with a front (or a reference front) get
/// "indicators" (see front_indicators).
/// Progress lines also go to run.log in the output directory (appended on --resume); the
/// solver's checkpoint is <output>/checkpoint.json and is removed once result.json is written.
/// \throws Error("output", ...) when the output directory holds a finished study
///         (result.json) and `force` is not set, when `resume` finds a finished
///         study, when the checkpoint's seed contradicts options.seed, when the checkpoint is
///         unreadable on resume, or when the output directory cannot be created or written.
Json run_study(Study& study, const RunOptions& options);

}  // namespace hapsyn
