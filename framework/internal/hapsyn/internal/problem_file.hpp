#pragma once
/// \file
/// Problem files as text: reading and parsing them with errors that point at the line and
/// column, and the --set overrides applied to the parsed document. Nothing here knows what a
/// valid study is (that is load_study, in study.hpp).
#include <hapsyn/json.hpp>

#include <cstddef>
#include <cstdint>
#include <string>

namespace hapsyn {

/// Deepest nesting of arrays and objects accepted in any JSON text a user gives (problem files,
/// --set values, reference fronts): nlohmann's destructor, copy and dump recurse once per level,
/// so a file of 50 000 '[' would overflow the stack in every command. Problem files need < 10.
constexpr std::size_t kMaxJsonDepth = 256;

/// Largest problem (or result) file read [bytes]: far above any real one, and a bound on memory.
constexpr std::uint64_t kMaxProblemFileBytes = 64ull << 20;

/// Reads and parses a problem file (see parse_problem_text). Only a regular file of at most
/// kMaxProblemFileBytes is read (read_regular_file): a FIFO or /dev/zero is refused, not waited on.
/// \throws Error("problem: cannot read problem file PATH: REASON") when the file cannot be read,
///         Error("problem: problem file PATH is not a regular file ...") or "... is N bytes, more
///         than ...", else as parse_problem_text with `source` = the path.
Json read_problem_file(const std::string& path);

/// Parses JSON text that must hold one object; `source` names it in errors. Refused before any
/// document is built: malformed JSON, nesting deeper than kMaxJsonDepth, a key given twice in
/// one object (nlohmann would silently keep the last), invalid UTF-8 (nlohmann's lexer).
/// \throws Error("problem: SOURCE:LINE:COLUMN: malformed JSON: REASON") on malformed JSON (the
///         column counts characters), Error("problem: SOURCE:LINE:COLUMN: nesting deeper than 256
///         levels at PATH ..."), Error("problem: SOURCE:LINE:COLUMN: duplicate key \"K\" in PATH"),
///         Error("problem: SOURCE: top level = ...: must be an object, not ...") for any other
///         top-level value.
Json parse_problem_text(const std::string& text, const std::string& source);

/// Checks a document built in memory (a Python dict, a document after --set overrides): every
/// string, key or value, is valid UTF-8 (else dump() would throw after the whole solve), and
/// nesting is at most kMaxJsonDepth.
/// \param path the JSON path of `value` in messages ("" for the top level)
/// \throws Error("problem: PATH = ...: invalid UTF-8 at byte N ...") or Error("problem: PATH:
///         nesting deeper than 256 levels").
void check_json_text_rules(const Json& value, const std::string& path = "");

/// Applies one override "path=value" (path with '.' separators; array elements by index,
/// "objectives.0.metric" or "objectives[0].metric"). The value is JSON when it parses as
/// JSON, else a string. Missing objects on the path are created.
/// \throws Error("set: ...") for a malformed override or a path through a non-object, for a
///         value nested deeper than kMaxJsonDepth or with a duplicate key, and for a path or
///         string value that is not valid UTF-8.
void apply_override(Json& problem, const std::string& assignment);

}  // namespace hapsyn
