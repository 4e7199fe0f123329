#pragma once
/// \file
/// Problem files as text: reading and parsing them with errors that point at the line and
/// column, and the --set overrides applied to the parsed document. Nothing here knows what a
/// valid study is (that is load_study, in study.hpp).
#include <hapsyn/json.hpp>

#include <string>

namespace hapsyn {

/// Reads and parses a problem file (see parse_problem_text).
/// \throws Error("problem: cannot read PATH: REASON") when the file cannot be read, else as
///         parse_problem_text with `source` = the path.
Json read_problem_file(const std::string& path);

/// Parses JSON text that must hold one object; `source` names it in errors.
/// \throws Error("problem: SOURCE:LINE:COLUMN: malformed JSON: REASON") on malformed JSON (the
///         column counts characters), Error("problem: SOURCE: top level = ...: must be an
///         object, not ...") for any other top-level value.
Json parse_problem_text(const std::string& text, const std::string& source);

/// Applies one override "path=value" (path with '.' separators; array elements by index,
/// "objectives.0.metric" or "objectives[0].metric"). The value is JSON when it parses as
/// JSON, else a string. Missing objects on the path are created.
/// \throws Error("set: ...") for a malformed override or a path through a non-object.
void apply_override(Json& problem, const std::string& assignment);

}  // namespace hapsyn
