#pragma once
// Structure-aware mutations of fuzz inputs ("--set path=value" lines, then a problem file): the
// hostile shapes byte-level mutation rarely reaches. The libFuzzer target uses them as its custom
// mutator (half of the time; libFuzzer's own mutations the other half), the structured fuzz test
// of the ordinary build applies them deterministically to the corpus.
//
//   deep nesting (arrays or objects, closed or not, as deep as the size limit allows), huge and
//   tiny numbers (1e400, 2^64, 4.9e-324), -0, long strings, invalid UTF-8 and lone surrogates in
//   strings and keys, duplicate members, wrong types, empty containers, truncation, and --set
//   lines with hostile values on real keys (non-dividing and tiny steps, zero weights, seeds -1,
//   threads 2^32 + 1, names and plugin names as paths, huge array indices).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace hapsyn::fuzz {

inline std::size_t below(std::mt19937_64& rng, std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(rng() % n); }

template <class T>
const T& pick(std::mt19937_64& rng, const std::vector<T>& items) {
  return items[below(rng, items.size())];
}

// Real keys of the five-bar studies (the registry of the fuzz target has only that family).
inline const std::vector<std::string>& set_paths() {
  static const std::vector<std::string> paths = {
      "design.l0.step", "design.l1.step", "design.l2.step", "design.r.step", "design.l0.lower", "design.l1.upper",
      "design.r.value", "design.l0.value", "scene.options.step", "scene.options.side", "objectives.0.weight",
      "objectives.1.weight", "objectives.0.metric", "objectives.0.sense", "objectives", "solver.plugin",
      "solver.options.prune", "solver.options", "mechanism.plugin", "mechanism.options.rho", "mechanism.options.elbow",
      "scene.plugin", "name", "description", "seed", "threads", "output.directory", "output.samples_csv",
      "objectives.100000000.weight", "objectives.-1.weight", "design", "scene.options",
  };
  return paths;
}

inline const std::vector<std::string>& hostile_values() {
  static const std::vector<std::string> values = {
      "0", "-0", "-1", "1e-20", "1e400", "-1e400", "4294967297", "-4294967297", "18446744073709551616",
      "9223372036854775807", "1.7976931348623157e308", "4.9e-324", "NaN", "null", "true", "[]", "{}", "\"\"",
      "0.07", "0.0145", "1e-9", "../../x", "y.so/../payload", "\xff\xfe", "caf\xe9", "\"\\ud800\"",
      "[{\"metric\":\"gii\",\"weight\":0},{\"metric\":\"gdi\",\"weight\":0}]", "{\"plugin\":\"grid\"}",
  };
  return values;
}

inline const std::vector<std::string>& huge_numbers() {
  static const std::vector<std::string> numbers = {
      "1e400", "-1e400", "1e-400", "18446744073709551616", "-9223372036854775809", "4.9e-324",
      "1.7976931348623157e308", "123456789012345678901234567890", "-0", "-0.0", "0e999999999", "1E+308",
  };
  return numbers;
}

// Start offsets of the values in a JSON text (after ':', '[' or ','), found textually (strings
// are skipped): good enough for mutation, exactness does not matter.
inline std::vector<std::size_t> value_starts(const std::string& s) {
  std::vector<std::size_t> starts;
  bool in_string = false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
      continue;
    }
    if (c == '"') in_string = true;
    if (c == ':' || c == '[' || c == ',') {
      std::size_t j = i + 1;
      while (j < s.size() && (s[j] == ' ' || s[j] == '\n' || s[j] == '\t' || s[j] == '\r')) ++j;
      if (j < s.size()) starts.push_back(j);
    }
  }
  return starts;
}

// One past the end of the value starting at pos.
inline std::size_t value_end(const std::string& s, std::size_t pos) {
  if (pos >= s.size()) return s.size();
  if (s[pos] == '"') {
    for (std::size_t i = pos + 1; i < s.size(); ++i) {
      if (s[i] == '\\') ++i;
      else if (s[i] == '"') return i + 1;
    }
    return s.size();
  }
  if (s[pos] == '[' || s[pos] == '{') {
    int depth = 0;
    bool in_string = false;
    for (std::size_t i = pos; i < s.size(); ++i) {
      const char c = s[i];
      if (in_string) {
        if (c == '\\') ++i;
        else if (c == '"') in_string = false;
      } else if (c == '"') {
        in_string = true;
      } else if (c == '[' || c == '{') {
        ++depth;
      } else if ((c == ']' || c == '}') && --depth == 0) {
        return i + 1;
      }
    }
    return s.size();
  }
  std::size_t i = pos;
  while (i < s.size() && s[i] != ',' && s[i] != ']' && s[i] != '}' && s[i] != '\n' && s[i] != ' ') ++i;
  return i;
}

// Offsets of the keys ("...":) of the text.
inline std::vector<std::size_t> key_starts(const std::string& s) {
  std::vector<std::size_t> keys;
  for (std::size_t pos : value_starts(s)) {
    if (s[pos] != '"') continue;
    const std::size_t end = value_end(s, pos);
    std::size_t j = end;
    while (j < s.size() && s[j] == ' ') ++j;
    if (j < s.size() && s[j] == ':') keys.push_back(pos);
  }
  return keys;
}

inline std::string nested(std::size_t depth, bool object, bool close) {
  std::string out;
  out.reserve(depth * (object ? 6 : 2) + 1);
  for (std::size_t i = 0; i < depth; ++i) out += object ? "{\"a\":" : "[";
  if (!close) return out;
  out += "1";
  out.append(depth, object ? '}' : ']');
  return out;
}

// Splits an input into its --set lines and the problem text.
inline std::string problem_part(const std::string& input, std::string* sets) {
  std::string rest = input;
  std::string head;
  while (rest.rfind("--set ", 0) == 0) {
    const auto end = rest.find('\n');
    head += end == std::string::npos ? rest + "\n" : rest.substr(0, end + 1);
    rest = end == std::string::npos ? std::string() : rest.substr(end + 1);
  }
  if (sets) *sets = head;
  return rest;
}

// Mutates `input` in place, keeping it at most max_size bytes.
inline void mutate_structure(std::string& input, std::size_t max_size, std::mt19937_64& rng) {
  std::string sets;
  std::string s = problem_part(input, &sets);
  const std::vector<std::size_t> values = value_starts(s);
  auto replace_value = [&](const std::string& text) {
    if (values.empty()) {
      s = text;
      return;
    }
    const std::size_t pos = pick(rng, values);
    s.replace(pos, value_end(s, pos) - pos, text);
  };
  const std::size_t room = max_size > input.size() ? max_size - input.size() : 0;
  switch (below(rng, 13)) {
    case 0:  // deep nesting, as deep as the size limit allows
    case 1: {
      const bool object = below(rng, 2) == 1;
      const std::size_t unit = object ? 6 : 2;
      const std::vector<std::size_t> depths = {100, 1000, 10000, 50000, room / unit};
      const std::size_t depth = std::min(pick(rng, depths), std::max<std::size_t>(room / unit, 1));
      replace_value(nested(depth, object, below(rng, 4) != 0));
      break;
    }
    case 2:
      replace_value(pick(rng, huge_numbers()));
      break;
    case 3: {  // a long string
      const std::size_t n = std::min<std::size_t>(below(rng, 2) ? 100000 : 1000, std::max<std::size_t>(room, 1));
      replace_value("\"" + std::string(n, 'A') + "\"");
      break;
    }
    case 4: {  // invalid UTF-8 or a lone surrogate inside a string
      static const std::vector<std::string> bad = {"\xff", "\xc0\xaf", "\xed\xa0\x80", "\xf8\x88\x80\x80\x80", "\xe2\x82",
                                                   "\\ud800", "\\udc00", "\xfe\xfe", std::string(1, '\0')};
      std::vector<std::size_t> strings;
      for (std::size_t p : values) {
        if (s[p] == '"') strings.push_back(p);
      }
      const std::vector<std::size_t> keys = key_starts(s);
      if (below(rng, 3) == 0 && !keys.empty()) strings = keys;
      if (strings.empty()) break;
      const std::size_t p = pick(rng, strings);
      s.insert(p + 1, pick(rng, bad));
      break;
    }
    case 5: {  // duplicate a member: "key": value, "key": other
      const std::vector<std::size_t> keys = key_starts(s);
      if (keys.empty()) break;
      const std::size_t k = pick(rng, keys);
      const std::size_t key_end = value_end(s, k);
      const std::size_t colon = s.find(':', key_end);
      if (colon == std::string::npos) break;
      std::size_t v = colon + 1;
      while (v < s.size() && s[v] == ' ') ++v;
      const std::size_t v_end = value_end(s, v);
      static const std::vector<std::string> others = {"0", "\"other\"", "null", "{}", "[]", "{\"plugin\":\"grid\"}", "0.5"};
      const std::string member = s.substr(k, key_end - k) + ": " + (below(rng, 2) ? s.substr(v, v_end - v) : pick(rng, others));
      s.insert(v_end, ", " + member);
      break;
    }
    case 6: {  // wrong type
      static const std::vector<std::string> types = {"0", "-1", "1.5", "\"\"", "\"x\"", "true", "null", "[]", "{}", "[1,2]",
                                                     "{\"a\":1}"};
      replace_value(pick(rng, types));
      break;
    }
    case 7:
    case 8:
    case 9: {  // a --set line with a hostile value on a real key
      sets += "--set " + pick(rng, set_paths()) + "=" + pick(rng, hostile_values()) + "\n";
      break;
    }
    case 10:  // truncation
      if (!s.empty()) s.resize(below(rng, s.size()));
      break;
    case 11: {  // empty container
      std::vector<std::size_t> containers;
      for (std::size_t p : values) {
        if (s[p] == '[' || s[p] == '{') containers.push_back(p);
      }
      if (containers.empty()) break;
      const std::size_t p = pick(rng, containers);
      s.replace(p, value_end(s, p) - p, below(rng, 2) ? "{}" : "[]");
      break;
    }
    default:  // non-finite literals
      replace_value(below(rng, 2) ? "NaN" : "-Infinity");
      break;
  }
  input = sets + s;
  if (input.size() > max_size) input.resize(max_size);
}

}  // namespace hapsyn::fuzz
