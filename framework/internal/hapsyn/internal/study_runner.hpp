#pragma once
/// \file
/// Running a loaded study (`hapsyn run`, sweeps, comparisons): the output directory and its
/// guards, the seed, the run log, the solver call and the result files (result.json,
/// samples.csv, maps.csv, groups.csv, front.csv and plots).
///
/// The output directory's contract:
/// - result.json is the commit point. It exists only when a run has ended (any status), and
///   every other output file beside it (samples.csv, maps.csv, groups.csv, front.csv, map_*,
///   timeline.*) is from that same run: a run writes them into `<out>/.staging-<pid>` and moves
///   them into place once complete, result.json first. A run that starts removes the previous
///   result.json first, then the previous run's output files (it only starts when that is
///   allowed: see check_output_directory). A killed run thus leaves the old study untouched
///   (it never started), no result.json, or its own result.json with the files moved so far
///   (one it names may be missing; never one of another run).
/// - run.log and checkpoint.json live in the directory itself: the checkpoint must survive a
///   stop or a kill, and the log shows how far a failed run got (its error is its last line).
/// - `<out>/.lock` is flock'ed for the whole run: a second run into the directory fails at once.
#include <hapsyn/cluster.hpp>
#include <hapsyn/json.hpp>
#include <hapsyn/solver.hpp>
#include <hapsyn/internal/study.hpp>

#include <atomic>
#include <cstdint>
#include <ostream>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn {

struct RunOptions {
  std::string output_directory;  ///< overrides output.directory when not empty
  /// 0 = the file's "threads", else hardware concurrency; either is capped to 4 x the hardware
  /// threads (at most 1024) with a warning.
  int threads = 0;
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
  /// The processes of the run (an MPI job or a shard; hapsyn/cluster.hpp); null: this one.
  /// Under MPI every rank calls run_study: rank 0 does everything below, the others take part
  /// in the solve of a distributed solver (SolverSpecs::distributed; else rank 0 solves alone) and
  /// return rank 0's result document.
  Cluster* cluster = nullptr;
  /// Under MPI: the flag this rank's signal handlers set (`stop` is then the agreed flag the
  /// cluster sets inside task farms). A solver that runs on rank 0 alone watches this one.
  const std::atomic<bool>* signal = nullptr;
  /// The problem file's path (recorded for `hapsyn merge` in a share's result.json, which loads
  /// the resolved problem again with relative paths resolved as the run resolved them).
  std::string problem_file;
  /// The problem document as given (after --set overrides, before defaults): what a share's
  /// result.json records for `hapsyn merge` to load the study again.
  Json problem_document;
  /// Seconds the caller spent loading the study (validation and the scene build): result.json's
  /// "phases.scene_s", counted in "wall_time_s". 0 when not measured.
  double scene_time_s = 0.0;
};

/// The output directory of a run: options.output_directory, else the file's output.directory.
std::string output_directory_of(const Study& study, const RunOptions& options);

/// The checks run_study makes on the output directory before any work, without creating or
/// changing anything (`hapsyn validate` makes them too). A result.json with status "stopped" is
/// an unfinished study: --resume continues it, --force starts over; any other result.json is a
/// finished study: only --force replaces it.
/// \throws Error("output", ...) naming the directory when it is empty, not a directory, not
///         writable, cannot be created (the nearest existing ancestor not a writable directory,
///         a name longer than the file system allows), holds a finished study without `force`
///         (with `resume`: "has finished; there is nothing to resume"), or a stopped study
///         without `resume` or `force`.
void check_output_directory(const std::string& out_dir, const RunOptions& options);

/// The worker threads of a run: options.threads, else the file's "threads", else the hardware
/// threads; above min(1024, 4 x hardware threads) capped, with a warning appended to `warnings`
/// ("--threads 1000: capped to 8 (4 x the 2 hardware threads)").
/// \throws Error("problem", "threads = <v>: must be an integer in [0, 2147483647] ...") for a
///         file value out of range, Error("output", ...) for a negative options.threads.
int run_threads(const Json& resolved, const RunOptions& options, std::vector<std::string>& warnings);

/// Warnings on a result whose best design, or some front points, lie on a bound of a free
/// continuous or grid component (within half a step of the grid's end, or 1e-9 of the range):
/// "design.l1 = 0.3 is at its upper bound: the optimum may lie beyond it; widen design.l1.upper
/// to check"; for the front "design.l1 is at its upper bound in 3 of 12 front points: ...".
/// Integer components (codes, sizes) are skipped: their ends are choices, not hints; so is a
/// bound that is the mechanism's hard limit (VariableDecl::hard_lower/upper: a length's 0), which
/// cannot be widened.
std::vector<std::string> bound_warnings(const Problem& problem, const SolverResult& result);

/// Runs a loaded study: checks and locks the output directory, solves, then writes result.json
/// and, as the file and options ask, samples.csv, maps.csv, groups.csv and plots of the best
/// design, and front.csv (one row per front point: design.<component> columns, then the
/// objectives) when there is a front, all committed as the header describes.
/// Returns the result document. The solver's outcome is in "status"; "phases" holds scene_s
/// (options.scene_time_s), solve_s and outputs_s, "wall_time_s" their sum; "warnings" the
/// thread cap and bound_warnings (also in run.log).
/// The seed is options.seed, else the checkpoint's (on resume), else the file's "seed", else
/// drawn; it is recorded in result.json. Studies with a front (or a reference front) get
/// "indicators" (see front_indicators).
/// Progress lines also go to run.log in the output directory (appended on --resume; opened
/// without following a symbolic link). The solver's checkpoint is <output>/checkpoint.json:
/// removed once result.json is written, except when the status is "stopped" (it is what
/// --resume continues from).
/// \throws Error("output", ...) as check_output_directory, when another run holds the
///         directory ("<out> is in use by another hapsyn run (pid N)"), when the free space is
///         below 1 MiB or the estimated size of the outputs, when the checkpoint's seed
///         contradicts options.seed or is unreadable on resume, when run.log is a symbolic link,
///         and when an output cannot be written (naming the file and the cause; if result.json
///         could be staged it is committed with "output_errors" before the throw). Any error
///         after the log is open is its last line.
Json run_study(Study& study, const RunOptions& options);

}  // namespace hapsyn
