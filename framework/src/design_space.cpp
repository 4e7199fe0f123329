#include <hapsyn/design_space.hpp>
#include <hapsyn/error.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>

namespace hapsyn {

DesignSpace::DesignSpace(std::vector<DesignComponent> components) : components_(std::move(components)) {
  for (std::size_t i = 0; i < components_.size(); ++i) {
    if (!components_[i].fixed) free_.push_back(static_cast<int>(i));
  }
}

void DesignSpace::expand(const double* free_values, double* full) const {
  std::size_t k = 0;
  for (std::size_t i = 0; i < components_.size(); ++i) {
    full[i] = components_[i].fixed ? components_[i].lower : free_values[k++];
  }
}

Eigen::VectorXd DesignSpace::expand(const Eigen::VectorXd& free_values) const {
  assert(static_cast<std::size_t>(free_values.size()) == free_.size());
  Eigen::VectorXd full(static_cast<Eigen::Index>(components_.size()));
  expand(free_values.data(), full.data());
  return full;
}

long long DesignSpace::grid_count(std::size_t free_k) const {
  const DesignComponent& c = components_[static_cast<std::size_t>(free_[free_k])];
  assert(c.step > 0.0);
  // The tolerance keeps an upper bound that lies on the grid (0.3 = 0.01 + 29 * 0.01) on it,
  // despite (upper - lower) / step evaluating to 28.999999999999996. In long double and checked:
  // a tiny step (1e-20) must not overflow into a 1-point axis.
  const long double n = (static_cast<long double>(c.upper) - c.lower) / c.step;
  const long double count = std::floor(n + 1e-9L * std::max(1.0L, n)) + 1;
  if (!(count <= static_cast<long double>(kMaxGridAxisPoints))) {
    std::ostringstream message;
    message << "design." << c.name << ": a step of " << c.step << " makes more than " << kMaxGridAxisPoints
            << " grid points on this variable";
    throw Error("problem", message.str());
  }
  return static_cast<long long>(count);
}

double DesignSpace::grid_value(std::size_t free_k, long long i) const {
  const DesignComponent& c = components_[static_cast<std::size_t>(free_[free_k])];
  // lower + i * step, not repeated addition, so that every grid value is reproducible.
  return std::min(c.upper, c.lower + static_cast<double>(i) * c.step);
}

long long DesignSpace::check_grid(const std::string& component, double max_designs) const {
  long double total = 1;
  std::string axes;
  for (std::size_t k = 0; k < free_.size(); ++k) {
    const DesignComponent& c = components_[static_cast<std::size_t>(free_[k])];
    if (!(c.step > 0.0)) {
      throw Error(component, "design." + c.variable + " has no step: searching the design grid needs a \"step\" for "
                             "every free design variable (or a \"value\" to fix it)");
    }
    total *= static_cast<long double>(grid_count(k));
    axes += (axes.empty() ? "" : " x ") + c.name + ": " + std::to_string(grid_count(k));
  }
  // Linear grid indices are long long: refuse what they cannot number.
  if (total > static_cast<long double>(kMaxGridPoints)) {
    throw Error(component, "the design grid has more than 9e18 points; use larger steps");
  }
  if (max_designs > 0.0 && total > static_cast<long double>(max_designs)) {
    std::ostringstream message;
    message.precision(3);
    message << "the design grid has " << static_cast<double>(total) << " designs (" << axes
            << "), more than solver.options.max_designs = ";
    message.precision(12);
    message << max_designs
            << "; use larger steps or fix variables, or raise max_designs deliberately";
    throw Error(component, message.str());
  }
  return static_cast<long long>(total);
}

std::vector<long long> DesignSpace::grid_counts() const {
  std::vector<long long> counts(free_.size());
  for (std::size_t k = 0; k < counts.size(); ++k) counts[k] = grid_count(k);
  return counts;
}

void DesignSpace::grid_point(long long index, const std::vector<long long>& counts, double* free_values) const {
  for (std::size_t k = counts.size(); k-- > 0;) {
    free_values[k] = grid_value(k, index % counts[k]);
    index /= counts[k];
  }
}

int DesignSpace::find(const std::string& name) const {
  for (std::size_t i = 0; i < components_.size(); ++i) {
    if (components_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

// ---- resolution of a problem file's "design" section ----

namespace {

std::string number(double v) {
  std::ostringstream s;
  s.precision(12);
  s << v;
  return s.str();
}

// A value as it is, in as few digits as name it exactly: a value of 0.30000000000000004 refused
// against a bound of 0.3 must not read "0.3" (number() rounds, for suggestions a user types).
std::string exact_number(double v) {
  for (int digits = 12;; ++digits) {
    std::ostringstream s;
    s.precision(digits);
    s << v;
    if (digits == 17 || !std::isfinite(v) || std::strtod(s.str().c_str(), nullptr) == v) return s.str();
  }
}

// Reads a per-component number of a design entry: a number (broadcast) or an array of `size`.
std::vector<double> components_of(const Json& value, int size, const std::string& path, bool integer) {
  std::vector<double> out;
  if (value.is_number()) {
    out.assign(static_cast<std::size_t>(size), value.get<double>());
  } else if (value.is_array()) {
    if (static_cast<int>(value.size()) != size) {
      throw Error("problem", path + " = " + render_value(value) + ": must have " + std::to_string(size) +
                                 " entries (one per component), or be a single number");
    }
    for (std::size_t i = 0; i < value.size(); ++i) {
      if (!value[i].is_number()) {
        throw Error("problem", path + "[" + std::to_string(i) + "] = " + render_value(value[i]) + ": must be a number");
      }
      out.push_back(value[i].get<double>());
    }
  } else {
    throw Error("problem", path + " = " + render_value(value) + ": must be a number" +
                               (size > 1 ? " or an array of " + std::to_string(size) + " numbers" : ""));
  }
  for (std::size_t i = 0; i < out.size(); ++i) {
    const std::string p = value.is_array() ? path + "[" + std::to_string(i) + "]" : path;
    if (!std::isfinite(out[i])) throw Error("problem", p + " = " + number(out[i]) + ": must be finite");
    if (integer && out[i] != std::floor(out[i])) {
      throw Error("problem", p + " = " + number(out[i]) + ": must be an integer (the variable is integer-valued)");
    }
  }
  return out;
}

double pick(const std::vector<double>& v, std::size_t i) { return v.size() == 1 ? v[0] : v[i]; }

// Refuses keys of "design" that name no variable of the mechanism, and entries that are not objects.
void check_design_keys(const Json& design, const std::vector<VariableDecl>& decls) {
  std::vector<std::string> names;
  for (const VariableDecl& d : decls) names.push_back(d.name);
  for (auto it = design.begin(); it != design.end(); ++it) {
    if (std::find(names.begin(), names.end(), it.key()) == names.end()) {
      std::string message = "design." + it.key() + ": unknown design variable";
      const std::string near = nearest_name(it.key(), names);
      if (!near.empty()) message += " (did you mean '" + near + "'?)";
      std::string known;
      for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
      throw Error("problem", message + "; the mechanism's variables are: " + known);
    }
    if (!it.value().is_object()) {
      throw Error("problem", "design." + it.key() + " = " + render_value(it.value()) +
                                 ": must be an object with \"lower\"/\"upper\"/\"step\", or \"value\"");
    }
  }
}

// One variable's entry, read into per-component lists (a list is empty when its key is absent;
// lower and upper fall back to the declared defaults).
struct EntryValues {
  bool has_value = false;
  std::vector<double> lower, upper, value, step;
};

EntryValues read_entry(const Json& entry, const VariableDecl& d, const std::string& path) {
  static const std::vector<std::string> kKeys = {"lower", "upper", "step", "value"};
  for (auto it = entry.begin(); it != entry.end(); ++it) {
    if (std::find(kKeys.begin(), kKeys.end(), it.key()) == kKeys.end()) {
      std::string message = path + "." + it.key() + ": unknown key";
      const std::string near = nearest_name(it.key(), kKeys);
      if (!near.empty()) message += " (did you mean '" + near + "'?)";
      throw Error("problem", message + "; known keys: lower, upper, step, value");
    }
  }
  EntryValues e;
  e.has_value = entry.contains("value");
  if (e.has_value && entry.contains("step")) {
    throw Error("problem", path + ".step: a fixed variable (with \"value\") takes no step");
  }
  e.lower = entry.contains("lower") ? components_of(entry["lower"], d.size, path + ".lower", false) : d.default_lower;
  e.upper = entry.contains("upper") ? components_of(entry["upper"], d.size, path + ".upper", false) : d.default_upper;
  if (e.has_value) e.value = components_of(entry["value"], d.size, path + ".value", d.integer);
  if (entry.contains("step")) e.step = components_of(entry["step"], d.size, path + ".step", d.integer);
  return e;
}

// A grid step must make a sane number of points (kMaxGridAxisPoints) and divide upper - lower:
// otherwise the grid silently never visits the upper bound (0.07 over [0.01, 0.3] stops at 0.29).
void check_step_divides(const DesignComponent& c, const std::string& path) {
  if (!(c.upper > c.lower)) return;
  const long double range = static_cast<long double>(c.upper) - c.lower;
  const long double n = range / c.step;
  if (!(n + 1 <= static_cast<long double>(kMaxGridAxisPoints))) {
    std::ostringstream message;
    message.precision(3);
    message << path << " = " << number(c.step) << ": makes " << static_cast<double>(n + 1) << " grid points on ["
            << number(c.lower) << ", " << number(c.upper) << "], more than the " << static_cast<double>(kMaxGridAxisPoints)
            << " a design variable may have; use a larger step";
    throw Error("problem", message.str());
  }
  const long double k = std::round(n);
  if (std::fabs(n - k) <= 1e-9L * std::max(1.0L, n)) return;
  const long double below = std::floor(n), above = std::ceil(n);
  std::ostringstream message;
  message << path << " = " << number(c.step) << ": does not divide [" << number(c.lower) << ", " << number(c.upper)
          << "] (";
  message << std::fixed;
  message.precision(2);
  message << static_cast<double>(n) << " steps), so the grid would never visit the upper bound: ";
  message.unsetf(std::ios::floatfield);
  if (!c.integer) {
    message << "use " << number(static_cast<double>(range / below)) << " (" << static_cast<long long>(below)
            << " steps) or " << number(static_cast<double>(range / above)) << " (" << static_cast<long long>(above)
            << " steps), or ";
  }
  message << "set upper to " << number(static_cast<double>(c.lower + below * c.step));
  throw Error("problem", message.str());
}

// Refuses a design grid with more points than kMaxGridPoints (linear grid indices are long long).
void check_grid_size(const std::vector<DesignComponent>& components) {
  long double total = 1;
  std::string factors;
  for (const DesignComponent& c : components) {
    if (c.fixed || !(c.step > 0.0)) continue;
    const long double n = (static_cast<long double>(c.upper) - c.lower) / c.step;
    const long double count = std::floor(n + 1e-9L * std::max(1.0L, n)) + 1;  // as grid_count
    total *= count;
    factors += (factors.empty() ? "" : " x ") + c.name + ": " + number(static_cast<double>(count));
  }
  if (total <= static_cast<long double>(kMaxGridPoints)) return;
  std::ostringstream message;
  message.precision(3);
  message << "design: the grid has " << static_cast<double>(total) << " points (" << factors << "), more than the "
          << static_cast<double>(kMaxGridPoints) << " a design grid may have; use larger steps or fix variables";
  throw Error("problem", message.str());
}

// Component i of variable d, checked against the mechanism's hard limits.
DesignComponent resolve_component(const VariableDecl& d, const Json& entry, const EntryValues& e, int i,
                                  const std::string& path) {
  const std::size_t ui = static_cast<std::size_t>(i);
  const std::string suffix = d.size > 1 ? "[" + std::to_string(i) + "]" : "";
  DesignComponent c;
  c.name = d.size > 1 ? d.name + "[" + std::to_string(i) + "]" : d.name;
  c.variable = d.name;
  c.index = i;
  c.integer = d.integer;
  c.lower = pick(e.lower, ui);
  c.upper = pick(e.upper, ui);
  const double hard_lower = d.hard_lower.empty() ? -INFINITY : pick(d.hard_lower, ui);
  const double hard_upper = d.hard_upper.empty() ? INFINITY : pick(d.hard_upper, ui);
  if (c.lower < hard_lower) {
    throw Error("problem", path + ".lower" + suffix + " = " + number(c.lower) + ": must be >= " + number(hard_lower) +
                               " (the mechanism's limit for " + d.name + ")");
  }
  if (c.upper > hard_upper) {
    throw Error("problem", path + ".upper" + suffix + " = " + number(c.upper) + ": must be <= " + number(hard_upper) +
                               " (the mechanism's limit for " + d.name + ")");
  }
  if (c.lower > c.upper) {
    throw Error("problem", path + ".upper" + suffix + " = " + number(c.upper) + ": must be >= lower (" +
                               number(c.lower) + ")");
  }
  if (e.has_value) {
    const double v = pick(e.value, ui);
    // A component fixed by default (a URDF's or DH table's parameter: bounds [nominal, nominal])
    // is moved by a value anywhere within the mechanism's limits; a value of a component with a
    // default range must lie in it, unless lower/upper widen it.
    const bool moves_a_fixed_default = !entry.contains("lower") && !entry.contains("upper") && c.lower == c.upper;
    if (moves_a_fixed_default) {
      if (!(v >= hard_lower && v <= hard_upper)) {
        throw Error("problem", path + ".value" + suffix + " = " + exact_number(v) + ": must lie within the mechanism's "
                                   "limits [" + number(hard_lower) + ", " + number(hard_upper) + "] for " + d.name);
      }
      c.lower = c.upper = v;
    }
    if (v < c.lower || v > c.upper) {
      throw Error("problem", path + ".value" + suffix + " = " + exact_number(v) + ": must lie within the bounds [" +
                                 number(c.lower) + ", " + number(c.upper) + "]" +
                                 (entry.contains("lower") || entry.contains("upper")
                                      ? ""
                                      : " (give \"lower\"/\"upper\" to widen them, within the mechanism's limits)"));
    }
    c.lower = c.upper = v;
    c.fixed = true;
  } else if (!e.step.empty()) {
    c.step = pick(e.step, ui);
    if (!(c.step > 0.0)) throw Error("problem", path + ".step" + suffix + " = " + number(c.step) + ": must be > 0");
    if (c.upper > c.lower && c.step > (c.upper - c.lower) * (1 + 1e-12)) {
      throw Error("problem", path + ".step" + suffix + " = " + number(c.step) +
                                 ": must not exceed the range upper - lower (" + number(c.upper - c.lower) + ")");
    }
    check_step_divides(c, path + ".step" + suffix);
    if (c.upper == c.lower) c.fixed = true;
  } else if (c.integer) {
    c.step = 1.0;
  }
  if (c.integer && (c.lower != std::floor(c.lower) || c.upper != std::floor(c.upper))) {
    throw Error("problem", path + suffix + ": bounds [" + number(c.lower) + ", " + number(c.upper) +
                               "] of an integer variable must be integers");
  }
  if (!e.has_value && c.lower == c.upper) c.fixed = true;
  return c;
}

// The entry as result.json records it: a fixed variable as written, else its bounds and step
// (defaults filled in); the unit when the mechanism declares one.
Json resolved_entry(const Json& entry, const VariableDecl& d, const EntryValues& e) {
  Json resolved = Json::object();
  if (e.has_value) {
    resolved["value"] = entry["value"];
    if (entry.contains("lower")) resolved["lower"] = entry["lower"];
    if (entry.contains("upper")) resolved["upper"] = entry["upper"];
  } else {
    auto as_json = [&](const std::vector<double>& v) { return v.size() == 1 ? Json(v[0]) : Json(v); };
    resolved["lower"] = as_json(e.lower);
    resolved["upper"] = as_json(e.upper);
    if (!e.step.empty()) resolved["step"] = as_json(e.step);
  }
  if (!d.unit.empty()) resolved["unit"] = d.unit;
  return resolved;
}

}  // namespace

DesignSpace build_design_space(const Json& design, const std::vector<VariableDecl>& decls, Json& resolved_design) {
  check_design_keys(design, decls);
  std::vector<DesignComponent> components;
  resolved_design = Json::object();
  for (const VariableDecl& d : decls) {
    const std::string path = "design." + d.name;
    const Json entry = design.contains(d.name) ? design.at(d.name) : Json::object();
    const EntryValues e = read_entry(entry, d, path);
    for (int i = 0; i < d.size; ++i) components.push_back(resolve_component(d, entry, e, i, path));
    resolved_design[d.name] = resolved_entry(entry, d, e);
  }
  check_grid_size(components);
  return DesignSpace(std::move(components));
}

}  // namespace hapsyn
