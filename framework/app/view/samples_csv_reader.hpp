#pragma once
// A result's samples.csv read back for `hapsyn view`: the columns `hapsyn run` wrote.
#include <hapsyn/internal/maps.hpp>

#include <string>

namespace hapsyn_cli {

/// samples.csv as SampleRecords: the status and the local-value columns (local_columns) by name;
/// a sample with an empty cell has no local values.
/// \throws hapsyn::Error("view", ...) naming the file: a missing column, a row whose cell count
///         differs from the header's, more or fewer rows than the scene's samples.
hapsyn::SampleRecords read_samples_csv(const std::string& file, const hapsyn::Problem& problem);

}  // namespace hapsyn_cli
