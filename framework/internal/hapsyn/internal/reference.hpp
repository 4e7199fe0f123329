#pragma once
/// \file
/// The declarations the documentation's reference pages are generated from (docs/reference/,
/// scripts/gen-reference.py through `hapsyn reference`): the problem file's keys and
/// result.json's fields. Each is declared once, here in the code, so the pages cannot drift:
/// the problem schema is the one load_study validates with, and the result fields are checked
/// against the result.json of shipped studies by the tests (tests/docs/check_reference.py).
#include <hapsyn/json.hpp>

#include <string>
#include <vector>

namespace hapsyn {

/// The framework's schema of a problem file (the rules load_study applies before the plugins'
/// own), in the schema language of the plugins' options.
const Json& problem_file_schema();

/// One field of result.json. `path` is dotted; `*` stands for a name the study chooses (an
/// objective, a design variable, a group) and `[]` for every element of an array.
struct ResultField {
  std::string path;
  std::string type;         ///< JSON type(s): "string", "number", "integer", "object", "array", "boolean"
  std::string when;         ///< when the field is present ("always" or the condition)
  std::string description;  ///< what it holds, with its unit
};

/// Every field run, merge and the Python Study.run write into result.json, in document order.
const std::vector<ResultField>& result_json_fields();

}  // namespace hapsyn
