#pragma once
/// \file
/// JSON text a user gives (problem files, data files of plugins, stored results read back) checked
/// before any document is built. nlohmann's parser, destructor, copy and dump recurse once per
/// nesting level, so a file of 100 000 '[' would overflow the stack in whatever reads it; and it
/// silently keeps the last of a key given twice.
#include <hapsyn/json.hpp>

#include <string>

namespace hapsyn {

/// Refuses, before any document is built: a NUL byte, malformed JSON, nesting deeper than
/// kMaxJsonDepth (problem_file.hpp) and a key given twice in one object.
/// \param text      the JSON text
/// \param source    names the text in messages (a file path)
/// \param component the prefix of the error ("problem", "merge", "sweep")
/// \throws Error(component, "SOURCE:LINE:COLUMN: malformed JSON: REASON"), "...: nesting deeper
///         than 256 levels ...", "...: duplicate key \"K\" in PATH ...", "...: a NUL byte ...".
void check_json_text(const std::string& text, const std::string& source, const char* component);

/// check_json_text, then the document (any top-level value).
Json parse_json_text(const std::string& text, const std::string& source, const char* component);

}  // namespace hapsyn
