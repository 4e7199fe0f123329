#pragma once
/// \file
/// `hapsyn merge`: the shares of a study run as a SLURM job array (`hapsyn run FILE --shard i/N`,
/// each into its own output directory) combined into the result one run gives.
///
/// Each share leaves result.json (with "shard": {"index", "count", "complete",
/// "problem_file", "problem_document"}) and checkpoint.json. merge checks that the shares belong together, lets the
/// solver combine their checkpoint states (Solver::merge_shards), writes the combined checkpoint
/// into the output directory and finishes the study there with `--resume`: the solver finds
/// every task done, re-checks every claimed value as on any resume, and writes result.json and
/// the other outputs exactly as a single run would.
#include <hapsyn/json.hpp>
#include <hapsyn/internal/registry.hpp>
#include <hapsyn/internal/study_runner.hpp>

#include <string>
#include <vector>

namespace hapsyn {

/// Merges the shard directories `dirs` (any order) into options.output_directory (required) and
/// returns its result document (as run_study). options.threads, quiet, force and progress apply
/// to the final resume; options.seed and resume are set here.
/// \throws Error("merge", ...) naming the directory and the rule when: no directory is given;
///         a directory has no result.json or checkpoint.json, or holds no shard's result; a share
///         was stopped before it finished ("resume it with ... --shard i/N --resume"); the shard
///         counts differ; a share is given twice or is missing ("shard 3/3 is missing (given:
///         1/3, 2/3)"); the shares ran different problems (the first differing key is named),
///         seeds, hapsyn versions, solvers or studies (checkpoint fingerprint); and as
///         Solver::merge_shards. Errors of the final run as run_study.
Json merge_shard_directories(const std::vector<std::string>& dirs, const Registry& registry, const RunOptions& options);

/// Refuses a merge whose output would be written over one of its inputs: `out` is one of the
/// share directories `inputs` or lies inside one (compared as absolute, normalised paths, symbolic
/// links resolved where they exist). --force does not lift it: a share is never replaced.
/// \throws Error("merge", "--out <out> is the share <dir> given as input: ...") or "... lies inside
///         the share <dir> ...".
void check_merge_output(const std::string& out, const std::vector<std::string>& inputs);

}  // namespace hapsyn
