#pragma once
/// \file
/// What grid and culling share on ranks and shards (header only; both include it as
/// "shared/bounds/rank_support.hpp"): the result of ranks other than 0, and reading a shard's state for
/// merge_shards with the resume's checks.
#include <hapsyn/cluster.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/solver.hpp>

#include <cstddef>
#include <string>

namespace hapsyn::plugins {

/// The result ranks other than 0 return: the framework keeps rank 0's alone.
inline SolverResult result_of_rank_0(const SolverContext& context) {
  SolverResult result;
  result.status = SolverStatus::kStopped;
  result.message = "rank " + std::to_string(context.cluster().rank()) + ": the result is rank 0's";
  return result;
}

/// Runs read(context) on shard `shard`'s state as a resume would read it; its errors become
/// Error("merge", "shard 2/3: ...").
template <class Read>
auto merge_read(std::size_t shard, std::size_t shards, const Read& read) {
  SolverContext context;
  context.checkpoint_file = "shard " + std::to_string(shard + 1) + "/" + std::to_string(shards);
  try {
    return read(context);
  } catch (const Error& e) {
    // "checkpoint: shard 2/3: state.tally is missing; delete it, ..." -> "merge: shard 2/3: ..."
    std::string what = e.what();
    const std::string prefix = "checkpoint: ", suffix = "; delete it, or run without --resume";
    if (what.rfind(prefix, 0) == 0) what = what.substr(prefix.size());
    if (what.size() >= suffix.size() && what.compare(what.size() - suffix.size(), suffix.size(), suffix) == 0) {
      what.resize(what.size() - suffix.size());
    }
    throw Error("merge", what);
  }
}

}  // namespace hapsyn::plugins
