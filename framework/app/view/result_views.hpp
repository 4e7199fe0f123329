#pragma once
// What `hapsyn view` shows of a result directory beyond its best design: the Pareto front
// (every point's objectives, design and mechanism drawing) and the solver's runs and history. Computed once at start, like
// view_data.hpp's documents: the server cannot compute on request.
#include "view_source.hpp"

#include <hapsyn/json.hpp>

#include <optional>
#include <string>

namespace hapsyn_cli {

/// Most samples tried per front design for one it reaches (view_front_json): the drawing search
/// stays short for a large scene (a human-arm scene has 34,548 samples).
inline constexpr int kMaxDrawTries = 2000;

/// The document /api/result. "statistics": result.json's statistics.runs, .clusters, .history
/// and .algorithm where it has them (ga, nsga2; {} otherwise). "front": null for a problem file
/// or a result without a front; otherwise {"objectives": [{name, metric, sense, unit: null}], "variables": [free variable
/// names], "points": [{design (every variable, fixed ones included), objectives, score,
/// drawn_sample, segments}]}. Each point's mechanism is drawn at `drawn_sample` (the best
/// design's) when that design reaches it, else at the sample nearest it that the design reaches
/// among the kMaxDrawTries nearest (drawn_sample null and no segments when none is).
/// An objective's unit is null: the plugin API declares units of local values only.
/// \throws hapsyn::Error("view", ...) naming result.json's path (front[i].design...) when a
///         front point lacks a number for a design component.
hapsyn::Json view_result_json(const ViewSource& source, int drawn_sample);

/// A sweep's or a comparison's output directory, shown as its table (/api/result "batch") and
/// one of its runs in 3D.
struct Batch {
  std::string run_dir;  ///< the result directory shown: a sweep's last run, a comparison's first study
  hapsyn::Json table;   ///< {"kind": "sweep"|"compare", "file", "shown", "rows": [{"label", "values": {column: number|null}}]}
};

/// The batch of `dir` when it holds sweep.json or compare.json (and no result.json), else
/// nullopt. Sweep columns: run_time_s, solve_time_s, errors.*, evaluations.*, objectives.*;
/// compare columns: every number (or null) of a row. \throws hapsyn::Error("view", ...) naming
/// the file when it has no runs (rows) or cannot be read.
std::optional<Batch> find_batch(const std::string& dir);

}  // namespace hapsyn_cli
