#pragma once
/// \file
/// Validation of plugin options against a plugin's options schema (derived from its option
/// declarations, hapsyn/options.hpp).
///
/// The supported subset of JSON Schema (draft 7 words): "type" (object, number, integer,
/// string, boolean, array, or a list of them), "properties", "required",
/// "additionalProperties" (false is the default here: unknown keys are errors, with the nearest
/// known name suggested), "default", "enum", "minimum", "maximum", "exclusiveMinimum",
/// "exclusiveMaximum", "items", "minItems", "maxItems", "description", plus hapsyn's "unit" and "plugin_kind" ("solver": the value is
/// `{"plugin": NAME, "options": {...}}`, a sub-solver the framework creates at load).
/// Numbers must be finite everywhere.
#include <hapsyn/json.hpp>

#include <string>

namespace hapsyn {

/// Checks that a schema only uses the supported words. \throws Error("schema: ...").
void check_schema(const Json& schema, const std::string& where);

/// Validates `value` against `schema` and returns it with defaults filled in (recursively for
/// objects).
/// \param schema the schema (check_schema() accepted it)
/// \param value  the JSON value to check
/// \param path   JSON path of `value` in the problem file, e.g. "scene.options"
/// \throws Error `("problem: <path>.<key> = <value>: <rule>")` on the first violation.
Json validate_and_fill(const Json& schema, const Json& value, const std::string& path);

}  // namespace hapsyn
