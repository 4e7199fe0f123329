#pragma once
/// \file
/// Plugin options, declared once (in the spirit of OMPL's declareParam and Drake's name-value
/// visits). A plugin keeps its options in a plain struct with a static `declare` function that
/// names each member once, with its default, range or choices, unit and description:
///
///   struct CullingOptions {
///     bool seed{};
///     int start_points{};
///     double progress_interval{};
///     static void declare(hapsyn::OptionDeclarations<CullingOptions>& d) {
///       d.describe("Exact culling over the design grid ...");
///       d.add(&CullingOptions::seed, "seed", true, "Seed the reference with an SQP optimum");
///       d.add(&CullingOptions::start_points, "start_points", 5, "Points per free variable").range(2, 50);
///       d.add(&CullingOptions::progress_interval, "progress_interval", 2.0, "Between progress lines")
///           .greater_than(0).unit("s");
///     }
///   };
///
/// From that one declaration the framework derives the plugin's schema (what `hapsyn describe`
/// prints and what the problem file is validated against, with path, value, rule and
/// did-you-mean in every message), fills the struct before the plugin's constructor runs, and
/// creates sub-solvers at load. A rule relating several options is declared next to them, so that
/// `describe` shows it and it is checked before the constructor runs:
///
///       d.rule({"step", "side"}, "step <= side", [](const CullingOptions& o) { return o.step <= o.side; });
/// Member initialisers should be `{}` only: the declared default is the one default. A problem
/// file may leave out any option that has a default; besides those, a declaration may make a key
/// required (Option::required()), optional without a default (a `std::optional<T>` member, left
/// unset when the key is absent), free-form JSON (a `Json` member), a list of groups (a
/// `std::vector<Group>` member) or an unsigned 64-bit integer (a `std::uint64_t` member). The
/// framework's own schema of a problem file is declared with the same calls.
#include <hapsyn/json.hpp>
#include <hapsyn/schema.hpp>

#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

namespace hapsyn {

class Solver;

/// An option whose value names another plugin: `{"plugin": NAME, "options": {...}}`. Declared
/// with OptionDeclarations::add(SubSolver O::*, ...). The framework creates the sub-solver once,
/// when the study is loaded (its own options validated, a Pareto solver refused), and hands it
/// over here; the plugin never touches the registry.
struct SubSolver {
  std::string plugin;                    ///< the solver plugin's name, e.g. "culling"
  Json options = Json::object();         ///< its options as given in the problem file
  std::string json_path;                 ///< where it sits, e.g. "solver.options.shadow_solver"
  /// The created solver. Null only when the options were made without a registry
  /// (make_options / default_options in tests); solvers report that as a failed status.
  std::shared_ptr<const Solver> solver;
};

/// What the framework hands a plugin factory besides the resolved options.
struct PluginArguments {
  std::string plugin;     ///< the plugin's registered name (used in messages)
  std::string json_path;  ///< where its options sit, e.g. "solver.options"
  /// Sub-solvers created at load, by their option path relative to the options ("a" or "a.b").
  std::map<std::string, std::shared_ptr<const Solver>> sub_solvers;
};

/// Whether a plugin's const methods may run concurrently (pagmo's thread_safety idea). A plugin
/// class declares `static constexpr hapsyn::ThreadSafety thread_safety = ...;` when it is not
/// kConcurrent. The framework acts on it: a kSerialized metric's or mechanism's calls (local(),
/// build(), a model's solve(), ...) are made under one lock per plugin object, so a plugin that
/// wraps a non-reentrant library (an interpreter, a global state) stays correct at any thread
/// count. Scenes and solvers are called from one thread anyway.
enum class ThreadSafety {
  kConcurrent,  ///< const methods may run concurrently from several threads (the default)
  kSerialized,  ///< the framework never calls two methods of one object at the same time
};
/// "concurrent" or "serialized".
const char* to_string(ThreadSafety safety);

namespace detail {

/// One declared option of an options struct O, type-erased for the framework.
template <class O>
struct OptionDecl {
  std::string name;
  Json schema;  ///< the property's schema fragment
  /// Copies the validated value into the member. `prefix` is the option path of the enclosing
  /// group ("" at the top level), used to find sub-solvers.
  std::function<void(O&, const Json&, const PluginArguments&, const std::string& prefix)> fill;
  /// The member's value as JSON (the inverse of fill; a sub-solver as {"plugin", "options"}; null
  /// for an unset std::optional, which to_json leaves out).
  std::function<Json(const O&)> to_json;
  bool required = false;  ///< listed in the enclosing object's "required" (Option::required())
};

/// Whether T is a group of options (a struct with a static declare function).
template <class T, class = void>
struct IsGroup : std::false_type {};
template <class T>
struct IsGroup<T, std::void_t<decltype(&T::declare)>> : std::true_type {};

/// Whether T is a std::vector.
template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};

/// Whether T is a list of groups (a std::vector of a struct with a static declare function).
template <class T>
struct IsGroupList : std::false_type {};
template <class T>
struct IsGroupList<std::vector<T>> : IsGroup<T> {};

/// One declared cross-field rule of an options struct O.
template <class O>
struct RuleDecl {
  std::vector<std::string> fields;  ///< the options it relates, as paths below O ("step", "gaco.ker")
  std::string text;                 ///< the rule as shown by `describe`, e.g. "step <= side"
  /// "" when `o` keeps the rule, else what is wrong ("must be <= side (0.1)"; see OptionDeclarations::rule).
  std::function<std::string(const O&)> check;
};

std::shared_ptr<const Solver> find_sub_solver(const PluginArguments& arguments, const std::string& relative_path);

/// The member at `dotted` ("a" or "a.b") of an options object as OptionDeclarations::to_json gives it
/// (null when an optional member on the way is unset).
const Json& value_at(const Json& values, const std::string& dotted);

/// "must satisfy <text> (<other> = <value>, ...)": the message of a broken rule declared with a predicate.
std::string broken_rule(const std::string& text, const std::vector<std::string>& fields, const Json& values);

/// Throws the message of a broken rule: "<root>.<field> = <value>: <what>", or "<root>.<field><what>"
/// when `what` names an element ("[2] = 90: must be ..."). The component is the plugin when known
/// (the registry adds where its options sit), else "problem", as for a schema violation.
[[noreturn]] void throw_broken_rule(const PluginArguments& arguments, const std::string& path, const Json& value,
                                    const std::string& what);

/// Throws std::logic_error when `group` (the schema of an optional group named `name`) would be
/// filled from its options' defaults when left out (validate_and_fill fills such an object), so
/// that it could never stay absent.
void check_optional_group(const Json& group, const std::string& name);

/// Throws when a rule names a field that `schema` (an options schema) does not declare.
void check_rule_fields(const Json& schema, const std::vector<std::string>& fields, const std::string& text);

}  // namespace detail

/// The declarations of one options struct O. Passed to O::declare; each add() returns the
/// declared option so that its rules can be chained (.range(0, 1).unit("m")).
template <class O>
class OptionDeclarations {
 public:
  /// Refinements of one declared option. Every rule also becomes part of the schema; the
  /// declared default must satisfy them (checked when the plugin is loaded).
  class Option {
   public:
    explicit Option(Json& schema) : schema_(&schema) {}
    /// `required` is the declaration's flag that required() sets.
    Option(Json& schema, bool& required) : schema_(&schema), required_(&required) {}
    /// The problem file must give this key: the enclosing object's schema lists it in "required"
    /// (a missing key is reported as "solver.options.kind: required key is missing") and the declared
    /// default is dropped, as it could never apply (pass `{}` as the default of a scalar).
    Option& required() {
      schema_->erase("default");
      if (required_) *required_ = true;
      return *this;
    }
    /// Inclusive bounds (numbers, integers; for lists of numbers: each element).
    Option& range(double lower, double upper) { return minimum(lower).maximum(upper); }
    Option& minimum(double v) { return set(numeric_target(), "minimum", v); }
    Option& maximum(double v) { return set(numeric_target(), "maximum", v); }
    /// Exclusive bounds: the value must be > v (greater_than) or < v (less_than).
    Option& greater_than(double v) { return set(numeric_target(), "exclusiveMinimum", v); }
    Option& less_than(double v) { return set(numeric_target(), "exclusiveMaximum", v); }
    /// The unit shown by `hapsyn describe` (e.g. "m", "deg", "s").
    Option& unit(const std::string& u) { return set(*schema_, "unit", u); }
    /// Allowed values of a text option (or of each element of a list of texts).
    Option& one_of(const std::vector<std::string>& values) { return set(element_target(), "enum", Json(values)); }
    /// Exact length of a list (rows of a matrix option).
    Option& size(int n) { return min_size(n).max_size(n); }
    Option& min_size(int n) { return set(*schema_, "minItems", count(n)); }
    Option& max_size(int n) { return set(*schema_, "maxItems", count(n)); }
    /// Exact length of each row of a matrix option.
    Option& row_size(int n) {
      Json& row = (*schema_)["items"];
      row["minItems"] = count(n);
      row["maxItems"] = count(n);
      return *this;
    }

   private:
    // Item counts are unsigned JSON numbers, as a parsed schema has them.
    static Json count(int n) { return Json(static_cast<std::uint64_t>(n < 0 ? 0 : n)); }
    Option& set(Json& target, const char* word, Json value) {
      target[word] = std::move(value);
      return *this;
    }
    // A whole-number bound is stored as an integer, so that messages read ">= 2", not ">= 2.0".
    Option& set(Json& target, const char* word, double value) {
      const bool whole = std::abs(value) < 1e15 && value == static_cast<double>(static_cast<long long>(value));
      return set(target, word, whole ? Json(static_cast<long long>(value)) : Json(value));
    }
    // Bounds of a list apply to its elements (of a matrix: to the elements of its rows).
    Json& numeric_target() { return element_target(); }
    Json& element_target() {
      Json* s = schema_;
      while (s->value("type", "") == "array") s = &(*s)["items"];
      return *s;
    }
    Json* schema_;
    bool* required_ = nullptr;
  };

  /// The plugin's description (the schema's top-level "description"; `hapsyn describe`).
  void describe(const std::string& text) { description_ = text; }

  /// A rule relating several options, checked after the options are filled and before the
  /// plugin's constructor runs; shown by `hapsyn describe` and in the schema's "x-rules"
  /// ({"fields": [...], "rule": text}). `fields` are paths below this struct ("step", "gaco.ker");
  /// the first is the one the message names. `check` either returns a bool (true: kept; the
  /// message is then "options.<first> = <value>: must satisfy <text> (<other> = <value>, ...)")
  /// or a std::string: "" when kept, else what is wrong, so that the message reads
  /// "options.<first> = <value>: <returned>"; a returned text starting with "[" names an element
  /// of the first field instead ("[2] = 90: must be ..." gives "options.<first>[2] = 90: must be ...").
  template <class Check>
  void rule(std::vector<std::string> fields, const std::string& text, Check check) {
    using Result = std::invoke_result_t<Check, const O&>;
    static_assert(std::is_same_v<Result, bool> || std::is_same_v<Result, std::string>,
                  "a rule's check returns bool or std::string");
    std::function<std::string(const O&)> f;
    if constexpr (std::is_same_v<Result, bool>) {
      f = [check, text, fields](const O& o) {
        return check(o) ? std::string() : detail::broken_rule(text, fields, to_json(o));
      };
    } else {
      f = std::move(check);
    }
    rules_.push_back(detail::RuleDecl<O>{std::move(fields), text, std::move(f)});
  }

  Option& add(bool O::*member, const std::string& name, bool def, const std::string& description) {
    return plain(member, name, "boolean", Json(def), description);
  }
  Option& add(int O::*member, const std::string& name, int def, const std::string& description) {
    return plain(member, name, "integer", Json(def), description);
  }
  Option& add(long long O::*member, const std::string& name, long long def, const std::string& description) {
    return plain(member, name, "integer", Json(def), description);
  }
  /// An unsigned 64-bit integer (e.g. a seed): an integer in [0, 18446744073709551615]; a larger
  /// or a negative value is refused.
  Option& add(std::uint64_t O::*member, const std::string& name, std::uint64_t def, const std::string& description) {
    Option& o = plain(member, name, "integer", Json(def), description);
    Json& schema = decls_.back().schema;
    schema["minimum"] = std::uint64_t{0};
    schema["maximum"] = std::numeric_limits<std::uint64_t>::max();
    return o;
  }
  Option& add(double O::*member, const std::string& name, double def, const std::string& description) {
    return plain(member, name, "number", Json(def), description);
  }
  Option& add(std::string O::*member, const std::string& name, const std::string& def,
              const std::string& description) {
    return plain(member, name, "string", Json(def), description);
  }
  Option& add(std::vector<double> O::*member, const std::string& name, const std::vector<double>& def,
              const std::string& description) {
    return list(member, name, "number", Json(def), description);
  }
  Option& add(std::vector<int> O::*member, const std::string& name, const std::vector<int>& def,
              const std::string& description) {
    return list(member, name, "integer", Json(def), description);
  }
  Option& add(std::vector<std::string> O::*member, const std::string& name, const std::vector<std::string>& def,
              const std::string& description) {
    return list(member, name, "string", Json(def), description);
  }
  /// A matrix (a list of rows of numbers), e.g. a rotation as 3 rows of 3.
  Option& add(std::vector<std::vector<double>> O::*member, const std::string& name,
              const std::vector<std::vector<double>>& def, const std::string& description) {
    Option& o = list(member, name, "array", Json(def), description);
    decls_.back().schema["items"]["items"] = Json{{"type", "number"}};
    return o;
  }
  /// A group of options (a nested object), declared by Group::declare. Its default is the
  /// defaults of its members; the problem file may give any subset of them.
  template <class Group>
  Option& add(Group O::*member, const std::string& name, const std::string& description) {
    static_assert(!std::is_same_v<Group, SubSolver>, "a sub-solver option needs a default plugin name");
    Json schema = schema_of_group<Group>();
    schema["default"] = Json::object();
    schema["description"] = description;
    return push(
        name, std::move(schema),
        [member, name](O& o, const Json& v, const PluginArguments& a, const std::string& prefix) {
          o.*member = OptionDeclarations<Group>::fill(v, a, join(prefix, name));
        },
        [member](const O& o) { return OptionDeclarations<Group>::to_json(o.*member); });
  }
  /// A list of groups (an array of objects, each declared by Group::declare and filled with its
  /// defaults), default `[]`. A message about an element names it: "objectives[1].sense = ...".
  /// Sub-solvers inside the elements are not created. Chain .min_size(n) for a least length (with
  /// .required() when the default `[]` would break it).
  template <class Group>
  Option& add(std::vector<Group> O::*member, const std::string& name, const std::string& description) {
    static_assert(detail::IsGroup<Group>::value,
                  "a list without a default is a list of groups (Group::declare); give other lists a default");
    Json schema{{"type", "array"}, {"items", schema_of_group<Group>()}, {"default", Json::array()},
                {"description", description}};
    return push(
        name, std::move(schema),
        [member, name](O& o, const Json& v, const PluginArguments& a, const std::string& prefix) {
          o.*member = value_of<std::vector<Group>>(v, a, join(prefix, name));
        },
        [member](const O& o) { return json_of(o.*member); });
  }
  /// Free-form JSON (an object the framework does not check, e.g. another plugin's options that
  /// its own schema checks later), default `{}`.
  Option& add(Json O::*member, const std::string& name, const std::string& description) {
    Json schema{{"type", "object"}, {"default", Json::object()}, {"description", description}};
    return push(
        name, std::move(schema),
        [member](O& o, const Json& v, const PluginArguments&, const std::string&) { o.*member = v; },
        [member](const O& o) { return o.*member; });
  }
  /// An optional key without a default: absent in the problem file, it stays absent in the
  /// resolved options and the member stays std::nullopt. T is any type add() takes (bool, int,
  /// long long, std::uint64_t, double, std::string, lists of those, a matrix, Json, a group, a
  /// list of groups); its schema is T's, without "default". An optional group must have no
  /// option with a default (each is required or optional itself), else the validator would fill it
  /// from those defaults: refused with std::logic_error when the schema is made.
  template <class T>
  Option& add(std::optional<T> O::*member, const std::string& name, const std::string& description) {
    Json schema = value_schema<T>();
    if constexpr (detail::IsGroup<T>::value) detail::check_optional_group(schema, name);
    schema["description"] = description;
    return push(
        name, std::move(schema),
        [member, name](O& o, const Json& v, const PluginArguments& a, const std::string& prefix) {
          o.*member = value_of<T>(v, a, join(prefix, name));
        },
        [member](const O& o) { return (o.*member).has_value() ? json_of(*(o.*member)) : Json(); });
  }
  /// A sub-solver: `{"plugin": NAME, "options": {...}}`, default `{"plugin": default_plugin,
  /// "options": {}}`. The framework creates it at load (see SubSolver).
  Option& add(SubSolver O::*member, const std::string& name, const std::string& default_plugin,
              const std::string& description) {
    Json schema{{"type", "object"},
                {"plugin_kind", "solver"},
                {"default", {{"plugin", default_plugin}, {"options", Json::object()}}},
                {"description", description}};
    return push(
        name, std::move(schema),
        [member, name](O& o, const Json& v, const PluginArguments& a, const std::string& prefix) {
          SubSolver s;
          s.plugin = v.value("plugin", "");
          s.options = v.contains("options") ? v["options"] : Json::object();
          const std::string relative = join(prefix, name);
          s.json_path = a.json_path.empty() ? relative : a.json_path + "." + relative;
          s.solver = detail::find_sub_solver(a, relative);
          o.*member = std::move(s);
        },
        [member](const O& o) { return Json{{"plugin", (o.*member).plugin}, {"options", (o.*member).options}}; });
  }

  /// The schema of O's declarations: {"type": "object", "description", "properties", ...}.
  static Json schema() { return schema_of_group<O>(); }

  /// The values of `options` as a JSON object, one key per declared option (nested groups as
  /// objects; an unset std::optional left out): what a problem file would give to reproduce them
  /// (e.g. for a checkpoint's fingerprint or a log).
  static Json to_json(const O& options) {
    Json out = Json::object();
    for (const auto& d : instance().decls_) {
      Json value = d.to_json(options);
      if (!value.is_null()) out[d.name] = std::move(value);
    }
    return out;
  }

  /// O filled from options already validated against schema() (defaults present), its rules
  /// (those of its groups first) checked. A key absent without a default (an optional one) leaves
  /// its member as value-initialised (std::nullopt).
  /// \throws Error naming the first broken rule (see rule())
  static O fill(const Json& resolved, const PluginArguments& arguments, const std::string& prefix = "") {
    O out{};
    for (const auto& d : instance().decls_) {
      const auto it = resolved.find(d.name);
      const auto def = d.schema.find("default");
      if (it != resolved.end()) {
        d.fill(out, *it, arguments, prefix);
      } else if (def != d.schema.end()) {
        d.fill(out, *def, arguments, prefix);
      }
    }
    check_rules(out, arguments, prefix);
    return out;
  }

 private:
  using Fill = std::function<void(O&, const Json&, const PluginArguments&, const std::string&)>;

  static const OptionDeclarations& instance() {
    static const OptionDeclarations declarations = [] {
      OptionDeclarations d;
      O::declare(d);
      return d;
    }();
    return declarations;
  }
  template <class Group>
  static Json schema_of_group() {
    const auto& d = OptionDeclarations<Group>::instance();
    Json properties = Json::object();
    Json required = Json::array();
    for (const auto& decl : d.decls_) {
      properties[decl.name] = decl.schema;
      if (decl.required) required.push_back(decl.name);
    }
    Json schema{{"type", "object"}, {"additionalProperties", false}, {"properties", properties}};
    if (!required.empty()) schema["required"] = std::move(required);
    if (!d.description_.empty()) schema["description"] = d.description_;
    if (!d.rules_.empty()) {
      Json rules = Json::array();
      for (const auto& r : d.rules_) {
        detail::check_rule_fields(schema, r.fields, r.text);
        rules.push_back(Json{{"fields", r.fields}, {"rule", r.text}});
      }
      schema["x-rules"] = std::move(rules);
    }
    return schema;
  }
  static void check_rules(const O& options, const PluginArguments& arguments, const std::string& prefix) {
    const auto& rules = instance().rules_;
    if (rules.empty()) return;
    for (const auto& r : rules) {
      const std::string what = r.check(options);
      if (what.empty()) continue;
      const std::string& first = r.fields.front();
      throw_broken_rule(arguments, join(prefix, first), detail::value_at(to_json(options), first), what);
    }
  }
  [[noreturn]] static void throw_broken_rule(const PluginArguments& arguments, const std::string& path,
                                             const Json& value, const std::string& what) {
    detail::throw_broken_rule(arguments, path, value, what);
  }
  static std::string join(const std::string& prefix, const std::string& name) {
    return prefix.empty() ? name : prefix + "." + name;
  }
  // The schema of a value of type T, without default or description (see add(std::optional<T>)).
  template <class T>
  static Json value_schema() {
    if constexpr (std::is_same_v<T, bool>) {
      return Json{{"type", "boolean"}};
    } else if constexpr (std::is_same_v<T, std::uint64_t>) {
      return Json{{"type", "integer"},
                  {"minimum", std::uint64_t{0}},
                  {"maximum", std::numeric_limits<std::uint64_t>::max()}};
    } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, long long>) {
      return Json{{"type", "integer"}};
    } else if constexpr (std::is_same_v<T, double>) {
      return Json{{"type", "number"}};
    } else if constexpr (std::is_same_v<T, std::string>) {
      return Json{{"type", "string"}};
    } else if constexpr (std::is_same_v<T, Json>) {
      return Json{{"type", "object"}};
    } else if constexpr (detail::IsVector<T>::value) {
      return Json{{"type", "array"}, {"items", value_schema<typename T::value_type>()}};
    } else {
      static_assert(detail::IsGroup<T>::value, "an optional option's type must be one add() takes");
      return schema_of_group<T>();
    }
  }
  // A validated value as T; `path` is its option path (for a group's rules and sub-solvers).
  template <class T>
  static T value_of(const Json& v, const PluginArguments& arguments, const std::string& path) {
    if constexpr (std::is_same_v<T, Json>) {
      return v;
    } else if constexpr (detail::IsGroup<T>::value) {
      return OptionDeclarations<T>::fill(v, arguments, path);
    } else if constexpr (detail::IsGroupList<T>::value) {
      T out;
      for (std::size_t i = 0; i < v.size(); ++i) {
        out.push_back(value_of<typename T::value_type>(v[i], arguments, path + "[" + std::to_string(i) + "]"));
      }
      return out;
    } else {
      return v.get<T>();
    }
  }
  // The inverse of value_of.
  template <class T>
  static Json json_of(const T& value) {
    if constexpr (detail::IsGroup<T>::value) {
      return OptionDeclarations<T>::to_json(value);
    } else if constexpr (detail::IsGroupList<T>::value) {
      Json out = Json::array();
      for (const auto& element : value) out.push_back(json_of(element));
      return out;
    } else {
      return Json(value);
    }
  }
  template <class T>
  Option& plain(T O::*member, const std::string& name, const char* type, Json def, const std::string& description) {
    Json schema{{"type", type}, {"default", std::move(def)}, {"description", description}};
    return push(
        name, std::move(schema),
        [member](O& o, const Json& v, const PluginArguments&, const std::string&) { o.*member = v.get<T>(); },
        [member](const O& o) { return Json(o.*member); });
  }
  template <class T>
  Option& list(T O::*member, const std::string& name, const char* item_type, Json def,
               const std::string& description) {
    Json schema{{"type", "array"}, {"items", {{"type", item_type}}}, {"default", std::move(def)},
                {"description", description}};
    return push(
        name, std::move(schema),
        [member](O& o, const Json& v, const PluginArguments&, const std::string&) { o.*member = v.get<T>(); },
        [member](const O& o) { return Json(o.*member); });
  }
  Option& push(const std::string& name, Json schema, Fill fill, std::function<Json(const O&)> to_json) {
    decls_.push_back(detail::OptionDecl<O>{name, std::move(schema), std::move(fill), std::move(to_json), false});
    options_.emplace_back(decls_.back().schema, decls_.back().required);
    return options_.back();
  }

  template <class>
  friend class OptionDeclarations;

  std::string description_;
  std::deque<detail::OptionDecl<O>> decls_;  // deque: Option keeps a pointer into each schema
  std::deque<Option> options_;
  std::vector<detail::RuleDecl<O>> rules_;
};

/// A plugin without options: `using Options = hapsyn::NoOptions;` (the default when a plugin
/// class declares no Options type).
struct NoOptions {
  static void declare(OptionDeclarations<NoOptions>&) {}
};

/// The schema of an options struct (what `hapsyn describe` prints and files are checked against).
template <class O>
Json options_schema() {
  return OptionDeclarations<O>::schema();
}

/// Validates `options` (a problem file's "options" object; null = {}) against O's declarations,
/// fills the defaults and returns the struct. Sub-solvers stay uncreated (SubSolver::solver is
/// null): this is for tests and for code that builds a plugin directly, without a registry.
/// \param options   the options object of the problem file (null = {})
/// \param json_path where the options sit, for messages (e.g. "solver.options")
/// \throws Error `("problem: <json_path>.<key> = <value>: <rule>")`
template <class O>
O make_options(const Json& options = Json::object(), const std::string& json_path = "options");

/// The values of an options struct as JSON (see OptionDeclarations::to_json).
template <class O>
Json options_to_json(const O& options) {
  return OptionDeclarations<O>::to_json(options);
}

/// O with every declared default.
template <class O>
O default_options() {
  return make_options<O>(Json::object(), "options");
}

template <class O>
O make_options(const Json& options, const std::string& json_path) {
  const Json resolved = validate_and_fill(options_schema<O>(), options.is_null() ? Json::object() : options, json_path);
  PluginArguments arguments;
  arguments.json_path = json_path;
  return OptionDeclarations<O>::fill(resolved, arguments);
}

}  // namespace hapsyn
