#pragma once
// What `hapsyn run` and `hapsyn merge` print when a study ends, and the number formats of the
// console (result.json and the CSVs keep every digit).
#include <hapsyn/json.hpp>

#include <ostream>
#include <string>

namespace hapsyn_cli {

/// Six significant digits (objective values, option values).
std::string format_number(double v);

/// Three significant digits (durations [s]).
std::string format_seconds(double v);

/// A design value (a number or a list of them) at ten significant digits: a grid value reads
/// 0.29, not 0.29000000000000004.
std::string format_design_value(const hapsyn::Json& v);

/// The study's summary from its result.json: header (program, study, solver, threads, seed; the
/// mechanism's summary when it gives one), status, the best design and a long front's spread of
/// points, the solver's report, groups, evaluations and times, warnings, where the result is.
void print_summary(const hapsyn::Json& result, std::ostream& out);

}  // namespace hapsyn_cli
