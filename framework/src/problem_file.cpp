#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <hapsyn/error.hpp>
#include <hapsyn/problem_file.hpp>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn {

namespace {

// nlohmann reports the line and column of some errors wrongly (column 0 after a newline) and
// reports number overflow ("1e999") without any position, so a first pass with this handler
// only records where parsing stops and why; the document itself is built by a second pass.
class ErrorFinder : public nlohmann::json_sax<Json> {
 public:
  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(std::size_t) override { return true; }
  bool key(string_t&) override { return true; }
  bool end_object() override { return true; }
  bool start_array(std::size_t) override { return true; }
  bool end_array() override { return true; }
  bool parse_error(std::size_t position, const std::string& last_token,
                   const nlohmann::detail::exception& e) override {
    failed = true;
    byte = position;
    token = last_token;
    id = e.id;
    what = e.what();
    return false;
  }

  bool failed = false;
  std::size_t byte = 0;  // count of bytes read when the error was seen
  std::string token;
  int id = 0;
  std::string what;
};

// nlohmann's messages read "[json.exception.parse_error.101] parse error at line 1, column 9:
// syntax error while parsing value - invalid literal; ..." : keep the part after the dash.
std::string short_reason(const ErrorFinder& f) {
  if (f.id == 406) return "number " + f.token + " is out of range";
  std::string reason = f.what;
  const auto column = reason.find(", column ");
  if (column != std::string::npos) {
    const auto colon = reason.find(": ", column);
    if (colon != std::string::npos) reason = reason.substr(colon + 2);
  }
  const auto dash = reason.find(" - ");
  if (reason.rfind("syntax error", 0) == 0 && dash != std::string::npos)
    reason = reason.substr(dash + 3);
  return reason;
}

std::string line_and_column(const std::string& text, std::size_t offset) {
  if (offset > text.size()) offset = text.size();
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < offset; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\n') {
      ++line;
      column = 1;
    } else if ((c & 0xC0) != 0x80) {  // columns count characters, not UTF-8 bytes
      ++column;
    }
  }
  return std::to_string(line) + ":" + std::to_string(column);
}

std::string type_name_of(const Json& value) {
  switch (value.type()) {
    case Json::value_t::object:
      return "an object";
    case Json::value_t::array:
      return "an array";
    case Json::value_t::string:
      return "a string";
    case Json::value_t::boolean:
      return "a boolean";
    case Json::value_t::null:
      return "null";
    case Json::value_t::discarded:
      return "nothing";
    default:
      return "a number";
  }
}

// ---- overrides ----

struct Segment {
  std::string key;                   // for a key, or the text of a dotted index ("0")
  std::optional<std::size_t> index;  // set for a bracketed index
};

[[noreturn]] void refuse_override(const std::string& assignment, const std::string& rule) {
  throw Error("set", "'" + assignment + "': " + rule);
}

std::optional<std::size_t> parse_index(const std::string& digits) {
  if (digits.empty()) return std::nullopt;
  std::size_t n = 0;
  for (const char c : digits) {
    if (c < '0' || c > '9') return std::nullopt;
    const std::size_t d = static_cast<std::size_t>(c - '0');
    if (n > (static_cast<std::size_t>(-1) - d) / 10) return std::nullopt;
    n = n * 10 + d;
  }
  return n;
}

std::vector<Segment> split_path(const std::string& path, const std::string& assignment) {
  std::vector<Segment> segments;
  std::size_t i = 0;
  while (true) {
    // A segment is a key followed by any number of [N].
    std::size_t end = path.find_first_of(".[", i);
    if (end == std::string::npos) end = path.size();
    const std::string key = path.substr(i, end - i);
    const bool bracket_follows = end < path.size() && path[end] == '[';
    // Only the very start may lack a key ("[0]=..."), so that it is refused as indexing into
    // the problem rather than as a malformed path.
    if (key.empty() && !(bracket_follows && i == 0)) {
      refuse_override(assignment, "empty path segment in '" + path + "'");
    }
    if (!key.empty()) segments.push_back({key, std::nullopt});
    i = end;
    while (i < path.size() && path[i] == '[') {
      const std::size_t close = path.find(']', i);
      if (close == std::string::npos) refuse_override(assignment, "unclosed '[' in '" + path + "'");
      const auto index = parse_index(path.substr(i + 1, close - i - 1));
      if (!index) {
        refuse_override(assignment, "malformed index '" + path.substr(i, close - i + 1) +
                                        "': expected [N] with N a non-negative integer");
      }
      segments.push_back({path.substr(i, close - i + 1), index});
      i = close + 1;
    }
    if (i == path.size()) return segments;
    if (path[i] != '.') {
      refuse_override(assignment, "expected '.' or '[' after ']' in '" + path + "'");
    }
    ++i;
    if (i == path.size()) refuse_override(assignment, "empty path segment in '" + path + "'");
  }
}

std::string prefix_name(const std::vector<Segment>& segments, std::size_t n) {
  std::string out;
  for (std::size_t i = 0; i < n; ++i) {
    if (!out.empty() && !segments[i].index) out += '.';
    out += segments[i].key;
  }
  return out.empty() ? "the problem" : out;
}

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

}  // namespace

Json read_problem_file(const std::string& path) {
  errno = 0;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"),
                                                       &std::fclose);
  if (!file) throw Error("problem", "cannot read " + path + ": " + std::strerror(errno));
  std::string text;
  char buffer[65536];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, file.get())) > 0) text.append(buffer, n);
  // fopen succeeds on a directory on Linux; the read then fails with EISDIR.
  if (std::ferror(file.get()))
    throw Error("problem", "cannot read " + path + ": " + std::strerror(errno));
  return parse_problem_text(text, path);
}

Json parse_problem_text(const std::string& text, const std::string& source) {
  ErrorFinder finder;
  Json::sax_parse(text, &finder);
  if (finder.failed) {
    // For a number out of range the position is its last character: point at its first.
    std::size_t offset = finder.byte > 0 ? finder.byte - 1 : 0;
    if (finder.id == 406 && offset + 1 >= finder.token.size())
      offset = offset + 1 - finder.token.size();
    throw Error("problem", source + ":" + line_and_column(text, offset) +
                               ": malformed JSON: " + short_reason(finder));
  }
  Json document = Json::parse(text, nullptr, false);
  if (document.is_discarded()) throw Error("problem", source + ": malformed JSON");
  if (!document.is_object()) {
    throw Error("problem", source + ": top level = " + render_value(document) +
                               ": must be an object, not " + type_name_of(document));
  }
  return document;
}

void apply_override(Json& problem, const std::string& assignment) {
  const auto equals = assignment.find('=');
  if (equals == std::string::npos) refuse_override(assignment, "expected path=value (no '=')");
  const std::string path = trim(assignment.substr(0, equals));
  if (path.empty()) refuse_override(assignment, "empty path before '='");
  const std::string text = assignment.substr(equals + 1);

  // NaN and Infinity are not JSON and an out-of-range number is refused by the parser: all stay
  // strings, which the schema then refuses with the value in view.
  Json value = Json::parse(text, nullptr, false);
  if (value.is_discarded()) value = text;

  const std::vector<Segment> segments = split_path(path, assignment);
  // Work on a copy: a refused override must not leave objects half created on its path.
  Json updated = problem.is_null() ? Json::object() : problem;

  Json* node = &updated;
  for (std::size_t s = 0; s < segments.size(); ++s) {
    const Segment& segment = segments[s];
    const bool last = s + 1 == segments.size();
    const std::string here = prefix_name(segments, s);

    std::optional<std::size_t> index = segment.index;
    if (!index && node->is_array()) {
      index = parse_index(segment.key);
      if (!index) {
        refuse_override(assignment, here + " is an array: '" + segment.key +
                                        "' must be an index (e.g. " + here + ".0 or " + here +
                                        "[0])");
      }
    }

    if (index) {
      if (!node->is_array()) {
        refuse_override(assignment,
                        "cannot index into " + here + ": " +
                            (node->is_null() ? std::string("it is missing")
                                             : render_value(*node) + " is not an array"));
      }
      if (*index > node->size()) {
        refuse_override(assignment, "index " + std::to_string(*index) + " is out of range: " +
                                        here + " has " + std::to_string(node->size()) + " element" +
                                        (node->size() == 1 ? "" : "s") + " (use " +
                                        std::to_string(node->size()) + " to append)");
      }
      if (*index == node->size()) node->push_back(nullptr);
      Json& element = (*node)[*index];
      if (last) {
        element = std::move(value);
        break;
      }
      node = &element;
    } else {
      if (!node->is_object()) {
        refuse_override(assignment, "cannot set '" + segment.key + "' inside " + here + ": " +
                                        render_value(*node) + " is not an object");
      }
      Json& member = (*node)[segment.key];
      if (last) {
        member = std::move(value);
        break;
      }
      node = &member;
    }
    // Keys are always strings, so a missing intermediate is an object even when the next
    // segment is all digits.
    if (node->is_null() && !segments[s + 1].index) *node = Json::object();
  }
  problem = std::move(updated);
}

}  // namespace hapsyn
