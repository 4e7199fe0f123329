#include <hapsyn/error.hpp>
#include <hapsyn/options.hpp>

#include <stdexcept>

namespace hapsyn::detail {

std::shared_ptr<const Solver> find_sub_solver(const PluginArguments& arguments, const std::string& relative_path) {
  // Absent when the options were made without a registry (make_options): the solver then
  // reports a failed status instead of running without its sub-solver.
  const auto it = arguments.sub_solvers.find(relative_path);
  return it == arguments.sub_solvers.end() ? nullptr : it->second;
}

const Json& value_at(const Json& values, const std::string& dotted) {
  // to_json leaves an unset std::optional out: a rule naming it shows null.
  static const Json kUnset;
  const Json* v = &values;
  std::string::size_type start = 0;
  while (true) {
    const auto dot = dotted.find('.', start);
    const auto it = v->find(dotted.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
    if (it == v->end()) return kUnset;
    v = &*it;
    if (dot == std::string::npos) return *v;
    start = dot + 1;
  }
}

std::string broken_rule(const std::string& text, const std::vector<std::string>& fields, const Json& values) {
  std::string others;
  for (std::size_t i = 1; i < fields.size(); ++i) {
    others += (others.empty() ? "" : ", ") + fields[i] + " = " + render_value(value_at(values, fields[i]));
  }
  return "must satisfy " + text + (others.empty() ? "" : " (" + others + ")");
}

void throw_broken_rule(const PluginArguments& arguments, const std::string& path, const Json& value,
                       const std::string& what) {
  // Inside a study the registry prefixes where the options sit ("problem: scene.options: box: "),
  // so the plugin's own messages name the path below its options, as its constructor's did.
  const bool in_study = !arguments.plugin.empty();
  const std::string root = in_study ? "options" : arguments.json_path;
  const std::string at = root.empty() ? path : root + "." + path;
  const std::string message = !what.empty() && what.front() == '[' ? at + what : at + " = " + render_value(value) + ": " + what;
  throw Error(in_study ? arguments.plugin : "problem", message);
}

void check_optional_group(const Json& group, const std::string& name) {
  // The validator gives an absent object without a default the defaults of its members, so that a
  // resolved file shows every effective option: an optional group with defaults would never be unset.
  std::string defaults;
  for (const auto& p : group.at("properties").items()) {
    if (p.value().contains("default")) defaults += (defaults.empty() ? "'" : ", '") + p.key() + "'";
  }
  if (defaults.empty()) return;
  throw std::logic_error("optional group '" + name + "': its options " + defaults +
                         " have defaults, which would fill it when left out; declare it as a group (default {}) or "
                         "give its options no defaults (required() or std::optional)");
}

void check_rule_fields(const Json& schema, const std::vector<std::string>& fields, const std::string& text) {
  // A misspelt field would make the rule's message name nothing: refuse it when the schema is made.
  if (fields.empty()) throw std::logic_error("options rule '" + text + "': names no field");
  for (const std::string& field : fields) {
    const Json* s = &schema;
    std::string::size_type start = 0;
    while (true) {
      const auto dot = field.find('.', start);
      const std::string key = field.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
      const auto properties = s->find("properties");
      if (properties == s->end() || !properties->contains(key)) {
        throw std::logic_error("options rule '" + text + "': names '" + field + "', which is not a declared option");
      }
      s = &(*properties)[key];
      if (dot == std::string::npos) break;
      start = dot + 1;
    }
  }
}

}  // namespace hapsyn::detail
