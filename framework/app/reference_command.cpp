// `hapsyn reference` (reference_command.hpp): the CLI as CLI11 holds it, the problem schema and
// result.json's fields as the framework declares them, the plugins as the registry finds them.
#include "reference_command.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/internal/reference.hpp>
#include <hapsyn/options.hpp>
#include <hapsyn/output_files.hpp>

#include <string>

namespace hapsyn_cli {

using hapsyn::Json;

namespace {

// One option or positional: what `--help` shows, as fields.
Json option_reference(const CLI::Option& o) {
  Json j;
  j["name"] = o.get_positional() ? o.get_name(true) : o.get_name();
  Json names = Json::array();
  for (const std::string& s : o.get_snames()) names.push_back("-" + s);
  for (const std::string& l : o.get_lnames()) names.push_back("--" + l);
  j["names"] = names;
  j["positional"] = o.get_positional() && o.get_lnames().empty() && o.get_snames().empty();
  j["description"] = o.get_description();
  j["flag"] = o.get_items_expected_max() == 0;
  j["type"] = o.get_items_expected_max() == 0 ? "" : o.get_type_name();
  j["default"] = o.get_default_str();
  j["required"] = o.get_required();
  // CLI11 keeps "unlimited" as a large sentinel: say "repeatable" instead of the number.
  j["repeatable"] = o.get_items_expected_max() > 1 || o.get_expected_max() > 1;
  return j;
}

Json command_reference(const CLI::App& command) {
  Json j;
  j["name"] = command.get_name();
  j["description"] = command.get_description();
  Json options = Json::array();
  for (const CLI::Option* o : command.get_options()) {
    if (o->get_group().empty()) continue;  // hidden
    if (o->get_name() == "--help") continue;
    options.push_back(option_reference(*o));
  }
  j["options"] = options;
  return j;
}

// A mechanism's design variables and constraints with its default options; when it cannot be
// created without options (serial_chain needs a chain file) the reason instead.
Json design_reference(const std::string& name, const hapsyn::Registry& registry) {
  Json j;
  try {
    const auto mechanism = registry.create_mechanism(name, Json::object(), "mechanism");
    Json variables = Json::array();
    for (const hapsyn::VariableDecl& v : mechanism->variables()) {
      variables.push_back({{"name", v.name},
                           {"description", v.description},
                           {"unit", v.unit},
                           {"size", v.size},
                           {"integer", v.integer},
                           {"default_lower", v.default_lower},
                           {"default_upper", v.default_upper},
                           {"hard_lower", v.hard_lower},
                           {"hard_upper", v.hard_upper}});
    }
    Json constraints = Json::array();
    for (const hapsyn::ConstraintDecl& c : mechanism->constraints()) {
      constraints.push_back({{"name", c.name}, {"description", c.description}});
    }
    j["variables"] = variables;
    j["constraints"] = constraints;
  } catch (const hapsyn::Error& e) {
    j["needs_options"] = e.what();
  }
  return j;
}

}  // namespace

Json cli_reference(const CLI::App& app) {
  Json j;
  j["description"] = app.get_description();
  Json commands = Json::array();
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App* s) { return !s->get_group().empty(); })) {
    commands.push_back(command_reference(*sub));
  }
  j["commands"] = commands;
  return j;
}

Json reference_document(const CLI::App& app, const hapsyn::Registry& registry) {
  Json doc;
  doc["version"] = hapsyn::version();
  doc["cli"] = cli_reference(app);
  doc["problem_file"] = hapsyn::problem_file_schema();
  Json fields = Json::array();
  for (const hapsyn::ResultField& f : hapsyn::result_json_fields()) {
    fields.push_back({{"path", f.path}, {"type", f.type}, {"when", f.when}, {"description", f.description}});
  }
  doc["result_json"] = fields;
  Json plugins = Json::array();
  for (const hapsyn::PluginRecord& r : registry.list()) {
    Json p{{"name", r.name},
           {"kind", r.kind},
           {"version", r.version},
           {"description", r.description},
           {"thread_safety", hapsyn::to_string(r.thread_safety)},
           {"schema", r.schema}};
    if (r.kind == "mechanism") p["design"] = design_reference(r.name, registry);
    plugins.push_back(p);
  }
  doc["plugins"] = plugins;
  return doc;
}

}  // namespace hapsyn_cli
