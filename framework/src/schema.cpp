#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <hapsyn/error.hpp>
#include <hapsyn/schema.hpp>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn {

namespace {

// The validator is shared by validate_and_fill (bad options: component "problem") and
// check_schema (bad defaults: component "schema"), so it reports with a component-free message
// and each entry point wraps it.
struct Violation {
  std::string message;
};

// Functions rather than globals: safe to use from other translation units' static initializers.
const std::vector<std::string>& keywords() {
  static const std::vector<std::string> words = {
      "type",  "properties", "required", "additionalProperties", "default",
      "enum",  "minimum",    "maximum",  "exclusiveMinimum",     "exclusiveMaximum",
      "items", "minItems",   "maxItems", "description",          "unit", "plugin_kind",
      "x-rules"};
  return words;
}

const std::vector<std::string>& type_names() {
  static const std::vector<std::string> names = {"object", "number",  "integer",
                                                 "string", "boolean", "array"};
  return names;
}

std::string join_path(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

std::string index_path(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

std::string shown_path(const std::string& path) { return path.empty() ? "(top level)" : path; }

std::string join(const std::vector<std::string>& words, const std::string& separator) {
  std::string out;
  for (std::size_t i = 0; i < words.size(); ++i) out += (i ? separator : "") + words[i];
  return out;
}

[[noreturn]] void fail(const std::string& path, const Json& value, const std::string& rule) {
  throw Violation{shown_path(path) + " = " + render_value(value) + ": " + rule};
}

bool contains(const std::vector<std::string>& words, const std::string& word) {
  return std::find(words.begin(), words.end(), word) != words.end();
}

// Empty means "any type". Malformed "type" entries are ignored here: check_schema reports them.
std::vector<std::string> declared_types(const Json& schema) {
  std::vector<std::string> types;
  const auto it = schema.find("type");
  if (it == schema.end()) return types;
  if (it->is_string()) types.push_back(it->get<std::string>());
  if (it->is_array()) {
    for (const Json& t : *it) {
      if (t.is_string()) types.push_back(t.get<std::string>());
    }
  }
  return types;
}

std::optional<double> number_keyword(const Json& schema, const char* keyword) {
  const auto it = schema.find(keyword);
  if (it == schema.end() || !it->is_number()) return std::nullopt;
  return it->get<double>();
}

std::optional<std::size_t> count_keyword(const Json& schema, const char* keyword) {
  const auto it = schema.find(keyword);
  // Any non-negative integer counts, signed or unsigned (a schema built in C++ may hold either).
  if (it == schema.end() || !it->is_number_integer() || it->get<std::int64_t>() < 0) return std::nullopt;
  return static_cast<std::size_t>(it->get<std::int64_t>());
}

bool non_finite(const Json& value) {
  return value.is_number_float() && !std::isfinite(value.get<double>());
}

// Integral doubles outside int64 cannot become a JSON integer without losing the value.
bool integral_double(double x) {
  return std::isfinite(x) && x == std::floor(x) && x >= -9223372036854775808.0 &&
         x < 9223372036854775808.0;
}

bool has_type(const Json& value, const std::string& type) {
  if (type == "object") return value.is_object();
  if (type == "array") return value.is_array();
  if (type == "string") return value.is_string();
  if (type == "boolean") return value.is_boolean();
  if (type == "number") return value.is_number();
  if (type == "integer") {
    return value.is_number_integer() ||
           (value.is_number_float() && integral_double(value.get<double>()));
  }
  return false;
}

std::string type_phrase(const std::string& type) {
  if (type == "integer" || type == "array" || type == "object") return "an " + type;
  return "a " + type;
}

std::string types_phrase(const std::vector<std::string>& types) {
  std::string out;
  for (std::size_t i = 0; i < types.size(); ++i) {
    if (i > 0) out += i + 1 == types.size() ? " or " : ", ";
    out += type_phrase(types[i]);
  }
  return out;
}

std::string items_phrase(std::size_t n) {
  return std::to_string(n) + (n == 1 ? " item" : " items");
}

void check_free(const Json& value, const std::string& path) {
  if (non_finite(value)) fail(path, value, "must be finite");
  if (value.is_object()) {
    for (const auto& item : value.items()) check_free(item.value(), join_path(path, item.key()));
  } else if (value.is_array()) {
    for (std::size_t i = 0; i < value.size(); ++i) check_free(value[i], index_path(path, i));
  }
}

Json validate(const Json& schema, const Json& value, const std::string& path);

// What an absent property becomes: its default, or else a sub-object built from the defaults of
// its own properties (so that the resolved problem shows every effective option).
std::optional<Json> absent_value(const Json& schema, const std::string& path) {
  if (!schema.is_object()) return std::nullopt;
  if (const auto it = schema.find("default"); it != schema.end())
    return validate(schema, *it, path);
  const auto types = declared_types(schema);
  if (!schema.contains("properties") || !(types.empty() || contains(types, "object"))) {
    return std::nullopt;
  }
  try {
    Json filled = validate(schema, Json::object(), path);
    if (!filled.empty()) return filled;
  } catch (const Violation&) {
    // The sub-object needs keys only the user can give: leave it absent, so that the user is told
    // about it when it is required, and not at all when it is optional.
  }
  return std::nullopt;
}

Json validate_object(const Json& schema, const Json& value, const std::string& path) {
  static const Json kNoProperties = Json::object();
  const auto pit = schema.find("properties");
  const Json& properties = pit != schema.end() && pit->is_object() ? *pit : kNoProperties;
  const auto ait = schema.find("additionalProperties");
  const bool schema_additional = ait != schema.end() && ait->is_object();
  // The additionalProperties=false default needs a list of known keys to be meaningful, so it
  // applies only where "properties" is given (even empty: an object that takes no keys). A bare
  // {"type": "object"} is free-form, e.g. a plugin's options that its own schema checks later.
  const bool any_additional =
      ait != schema.end() ? ait->is_boolean() && ait->get<bool>() : pit == schema.end();

  Json result = Json::object();
  for (const auto& item : value.items()) {
    const std::string key_path = join_path(path, item.key());
    if (const auto sit = properties.find(item.key()); sit != properties.end()) {
      result[item.key()] = validate(*sit, item.value(), key_path);
    } else if (schema_additional) {
      result[item.key()] = validate(*ait, item.value(), key_path);
    } else if (any_additional) {
      check_free(item.value(), key_path);
      result[item.key()] = item.value();
    } else {
      std::vector<std::string> known;
      for (const auto& p : properties.items()) known.push_back(p.key());
      std::string message = shown_path(key_path) + ": unknown key";
      const std::string near = nearest_name(item.key(), known);
      if (!near.empty()) message += " (did you mean '" + near + "'?)";
      message +=
          known.empty() ? "; this object takes no keys" : "; known keys: " + join(known, ", ");
      throw Violation{message};
    }
  }

  if (const auto rit = schema.find("required"); rit != schema.end() && rit->is_array()) {
    for (const Json& key : *rit) {
      if (key.is_string() && !value.contains(key.get<std::string>())) {
        throw Violation{join_path(path, key.get<std::string>()) + ": required key is missing"};
      }
    }
  }

  for (const auto& p : properties.items()) {
    if (result.contains(p.key())) continue;
    if (auto filled = absent_value(p.value(), join_path(path, p.key()))) {
      result[p.key()] = std::move(*filled);
    }
  }
  return result;
}

Json validate(const Json& schema, const Json& value, const std::string& path) {
  if (!schema.is_object()) {
    check_free(value, path);
    return value;
  }
  const auto types = declared_types(schema);
  const bool numbers_allowed =
      types.empty() || contains(types, "number") || contains(types, "integer");

  if (non_finite(value) && numbers_allowed) fail(path, value, "must be finite");
  const auto matched = std::find_if(types.begin(), types.end(),
                                    [&](const std::string& t) { return has_type(value, t); });
  if (!types.empty() && matched == types.end()) fail(path, value, "must be " + types_phrase(types));

  Json result = value;
  // 3.0 given for an integer becomes 3, so that plugins can rely on is_number_integer().
  if (value.is_number_float() && matched != types.end() && *matched == "integer" &&
      !contains(types, "number")) {
    result = static_cast<std::int64_t>(value.get<double>());
  }

  if (const auto eit = schema.find("enum"); eit != schema.end() && eit->is_array()) {
    if (std::find(eit->begin(), eit->end(), value) == eit->end()) {
      std::vector<std::string> choices;
      for (const Json& choice : *eit) choices.push_back(render_value(choice));
      fail(path, value, "must be one of " + join(choices, ", "));
    }
  }

  if (value.is_number()) {
    const double x = value.get<double>();
    if (const auto bound = number_keyword(schema, "minimum"); bound && !(x >= *bound)) {
      fail(path, value, "must be >= " + render_value(schema["minimum"]));
    }
    if (const auto bound = number_keyword(schema, "maximum"); bound && !(x <= *bound)) {
      fail(path, value, "must be <= " + render_value(schema["maximum"]));
    }
    if (const auto bound = number_keyword(schema, "exclusiveMinimum"); bound && !(x > *bound)) {
      fail(path, value, "must be > " + render_value(schema["exclusiveMinimum"]));
    }
    if (const auto bound = number_keyword(schema, "exclusiveMaximum"); bound && !(x < *bound)) {
      fail(path, value, "must be < " + render_value(schema["exclusiveMaximum"]));
    }
  } else if (value.is_array()) {
    if (const auto n = count_keyword(schema, "minItems"); n && value.size() < *n) {
      fail(path, value, "must have at least " + items_phrase(*n));
    }
    if (const auto n = count_keyword(schema, "maxItems"); n && value.size() > *n) {
      fail(path, value, "must have at most " + items_phrase(*n));
    }
    const auto iit = schema.find("items");
    for (std::size_t i = 0; i < value.size(); ++i) {
      if (iit != schema.end()) {
        result[i] = validate(*iit, value[i], index_path(path, i));
      } else {
        check_free(value[i], index_path(path, i));
      }
    }
  } else if (value.is_object()) {
    result = validate_object(schema, value, path);
  }
  return result;
}

// ---- check_schema ----

class SchemaChecker {
 public:
  explicit SchemaChecker(std::string where) : where_(std::move(where)) {}

  void check(const Json& schema, const std::string& spath) {
    if (!schema.is_object())
      refuse(spath, "a schema must be an object, not " + render_value(schema));
    for (const auto& item : schema.items()) {
      if (!contains(keywords(), item.key())) {
        refuse(spath,
               "unsupported keyword '" + item.key() + "'; supported: " + join(keywords(), ", "));
      }
    }
    check_type(schema, spath);
    check_object_words(schema, spath);
    check_number_words(schema, spath);
    check_array_words(schema, spath);
    for (const char* annotation : {"description", "unit"}) {
      if (schema.contains(annotation) && !schema[annotation].is_string()) {
        refuse_value(spath, annotation, schema[annotation], "must be a string");
      }
    }
    if (const auto it = schema.find("x-rules"); it != schema.end()) check_rules(*it, spath);
    if (const auto it = schema.find("plugin_kind"); it != schema.end()) {
      // The framework creates plugin-valued options at load; only sub-solvers exist so far.
      if (*it != "solver" || schema.value("type", "") != "object")
        refuse_value(spath, "plugin_kind", *it, "must be \"solver\", on an option of type object");
    }
    if (const auto it = schema.find("enum"); it != schema.end()) {
      if (!it->is_array() || it->empty())
        refuse_value(spath, "enum", *it, "must be a non-empty array");
      // A choice the schema itself would refuse could never be picked.
      Json plain = schema;
      plain.erase("enum");
      plain.erase("default");
      for (std::size_t i = 0; i < it->size(); ++i) {
        validate_or_refuse(plain, (*it)[i], index_path(join_path(spath, "enum"), i));
      }
    }
    // Last, so that the default is validated against a schema known to be well formed.
    if (const auto it = schema.find("default"); it != schema.end()) {
      validate_or_refuse(schema, *it, join_path(spath, "default"));
    }
  }

 private:
  [[noreturn]] void refuse(const std::string& spath, const std::string& rule) const {
    throw Error("schema", where_ + ": " + shown_path(spath) + ": " + rule);
  }

  [[noreturn]] void refuse_value(const std::string& spath, const std::string& keyword,
                                 const Json& value, const std::string& rule) const {
    throw Error("schema", where_ + ": " + join_path(spath, keyword) + " = " + render_value(value) +
                              ": " + rule);
  }

  void validate_or_refuse(const Json& schema, const Json& value, const std::string& spath) const {
    try {
      validate(schema, value, spath);
    } catch (const Violation& v) {
      throw Error("schema", where_ + ": " + v.message);
    }
  }

  // "x-rules" lists the cross-field rules of an options object for `describe` (the plugin checks
  // them): [{"fields": ["a", "b"], "rule": "a < b"}, ...].
  void check_rules(const Json& rules, const std::string& spath) const {
    const auto well_formed = [](const Json& r) {
      if (!r.is_object() || r.size() != 2 || !r.contains("rule") || !r["rule"].is_string()) return false;
      const auto f = r.find("fields");
      if (f == r.end() || !f->is_array() || f->empty()) return false;
      for (const Json& name : *f) {
        if (!name.is_string()) return false;
      }
      return true;
    };
    if (!rules.is_array()) refuse_value(spath, "x-rules", rules, "must be an array of {\"fields\": [...], \"rule\": TEXT}");
    for (const Json& r : rules) {
      if (!well_formed(r)) refuse_value(spath, "x-rules", rules, "must be an array of {\"fields\": [...], \"rule\": TEXT}");
    }
  }

  void check_type(const Json& schema, const std::string& spath) const {
    const auto it = schema.find("type");
    if (it == schema.end()) return;
    const std::string rule = "must be one of " + join(type_names(), ", ") + ", or a list of them";
    if (it->is_string()) {
      if (!contains(type_names(), it->get<std::string>())) refuse_value(spath, "type", *it, rule);
      return;
    }
    if (!it->is_array() || it->empty()) refuse_value(spath, "type", *it, rule);
    std::vector<std::string> seen;
    for (const Json& t : *it) {
      if (!t.is_string() || !contains(type_names(), t.get<std::string>()))
        refuse_value(spath, "type", *it, rule);
      if (contains(seen, t.get<std::string>()))
        refuse_value(spath, "type", *it, "lists a type twice");
      seen.push_back(t.get<std::string>());
    }
  }

  void check_object_words(const Json& schema, const std::string& spath) {
    const auto pit = schema.find("properties");
    if (pit != schema.end()) {
      if (!pit->is_object())
        refuse_value(spath, "properties", *pit, "must be an object of schemas");
      for (const auto& p : pit->items())
        check(p.value(), join_path(join_path(spath, "properties"), p.key()));
    }
    bool open = pit == schema.end();  // keys outside "properties" allowed
    if (const auto ait = schema.find("additionalProperties"); ait != schema.end()) {
      if (ait->is_object()) {
        check(*ait, join_path(spath, "additionalProperties"));
        open = true;
      } else if (ait->is_boolean()) {
        open = ait->get<bool>();
      } else {
        refuse_value(spath, "additionalProperties", *ait, "must be a boolean or a schema");
      }
    }
    if (const auto rit = schema.find("required"); rit != schema.end()) {
      if (!rit->is_array()) refuse_value(spath, "required", *rit, "must be an array of key names");
      std::vector<std::string> seen;
      for (const Json& key : *rit) {
        if (!key.is_string())
          refuse_value(spath, "required", *rit, "must be an array of key names");
        const std::string name = key.get<std::string>();
        if (contains(seen, name))
          refuse_value(spath, "required", *rit, "names '" + name + "' twice");
        seen.push_back(name);
        const bool declared = pit != schema.end() && pit->contains(name);
        if (!declared && !open) {
          refuse_value(spath, "required", *rit,
                       "'" + name + "' is not in properties and additionalProperties is false");
        }
        // A required key is always given, so its default could never apply: a sign of confusion.
        if (declared && (*pit)[name].is_object() && (*pit)[name].contains("default")) {
          refuse_value(spath, "required", *rit,
                       "'" + name + "' is required and also has a default");
        }
      }
    }
  }

  void check_number_words(const Json& schema, const std::string& spath) const {
    for (const char* word : {"minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"}) {
      const auto it = schema.find(word);
      if (it == schema.end()) continue;
      if (!it->is_number()) refuse_value(spath, word, *it, "must be a number");
      if (!std::isfinite(it->get<double>())) refuse_value(spath, word, *it, "must be finite");
    }
    const auto low = number_keyword(schema, "minimum");
    const auto high = number_keyword(schema, "maximum");
    if (low && high && *low > *high) {
      refuse_value(spath, "minimum", schema["minimum"],
                   "must be <= maximum (" + render_value(schema["maximum"]) + ")");
    }
  }

  void check_array_words(const Json& schema, const std::string& spath) {
    if (const auto it = schema.find("items"); it != schema.end()) {
      if (!it->is_object()) {
        refuse_value(spath, "items", *it,
                     "must be a schema (lists of item schemas are not supported)");
      }
      check(*it, join_path(spath, "items"));
    }
    for (const char* word : {"minItems", "maxItems"}) {
      const auto it = schema.find(word);
      if (it == schema.end()) continue;
      if (!it->is_number_integer() || it->get<std::int64_t>() < 0)
        refuse_value(spath, word, *it, "must be a non-negative integer");
    }
    const auto low = count_keyword(schema, "minItems");
    const auto high = count_keyword(schema, "maxItems");
    if (low && high && *low > *high) {
      refuse_value(spath, "minItems", schema["minItems"],
                   "must be <= maxItems (" + render_value(schema["maxItems"]) + ")");
    }
  }

  std::string where_;
};

}  // namespace

void check_schema(const Json& schema, const std::string& where) {
  SchemaChecker(where).check(schema, "");
}

Json validate_and_fill(const Json& schema, const Json& value, const std::string& path) {
  try {
    return validate(schema, value, path);
  } catch (const Violation& v) {
    throw Error("problem", v.message);
  }
}

}  // namespace hapsyn
