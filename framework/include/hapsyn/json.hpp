#pragma once
/// \file
/// JSON type used across the framework and plugins, and small helpers for clear errors.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hapsyn {

using Json = nlohmann::json;

/// A value rendered for an error message: compact JSON, truncated to 60 characters.
std::string render_value(const Json& value);

/// The closest candidate to `word` by edit distance, or "" when none is close
/// (used for "unknown key 'stpe' (did you mean 'step'?)").
std::string nearest_name(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace hapsyn
