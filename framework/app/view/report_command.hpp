#pragma once
// `hapsyn report RESULT_DIR [-o FILE]`: the views of `hapsyn view` as one self-contained HTML file
// (no server): the page, its scripts and three.js inlined, the API's documents embedded.
#include "view_data.hpp"

#include <hapsyn/internal/registry.hpp>

#include <string>

namespace hapsyn_cli {

/// The page of `hapsyn view` with everything inlined: the JSON documents as
/// <script type="application/json" data-route="/api/..."> elements (which the page reads instead
/// of fetching), app.js as an inline module, the other modules (three.js, its orbit controls,
/// front.js, plots.js) as data: URLs of the import map. Loads nothing from anywhere.
/// \throws hapsyn::Error("report", ...) when the page's assets were not built or app.js holds
///         "</script" or "<!--" (it could not be inlined).
std::string report_html(const ViewData& data);

/// Loads the result directory, or a sweep's or comparison's directory (view_data.hpp), and writes report_html to `output` ("" =
/// RESULT_DIR/report.html) through a temporary file beside it renamed into place, so that a
/// reader never sees half a report. Prints "hapsyn report: <file> (<size>)". \return 0.
/// \throws hapsyn::Error("report", ...) naming the path when it is not a directory or holds none
///         of result.json, sweep.json, compare.json, or the file cannot be written; the loader's
///         errors.
int report_command(const std::string& result_dir, const std::string& output, const hapsyn::Registry& registry);

}  // namespace hapsyn_cli
