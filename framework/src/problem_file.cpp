#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <hapsyn/error.hpp>
#include <hapsyn/json_text.hpp>
#include <hapsyn/internal/problem_file.hpp>
#include <hapsyn/read_file.hpp>
#include <iterator>
#include <memory>
#include <set>
#include <optional>
#include <string>
#include <vector>

namespace hapsyn {

namespace {

// An iterator over the text that records the offset of the last character the lexer read, so
// that the SAX callbacks (which get no position) can point at where they are.
class CountingIterator {
 public:
  using iterator_category = std::forward_iterator_tag;
  using value_type = char;
  using difference_type = std::ptrdiff_t;
  using pointer = const char*;
  using reference = const char&;

  CountingIterator(const char* begin, const char* p, std::size_t* last) : begin_(begin), p_(p), last_(last) {}
  reference operator*() const {
    *last_ = static_cast<std::size_t>(p_ - begin_);
    return *p_;
  }
  CountingIterator& operator++() {
    ++p_;
    return *this;
  }
  CountingIterator operator++(int) {
    CountingIterator old = *this;
    ++p_;
    return old;
  }
  bool operator==(const CountingIterator& o) const { return p_ == o.p_; }
  bool operator!=(const CountingIterator& o) const { return p_ != o.p_; }

 private:
  const char* begin_;
  const char* p_;
  std::size_t* last_;
};

// The first pass over a JSON text, before any document is built. nlohmann reports the line and
// column of some errors wrongly (column 0 after a newline) and reports number overflow ("1e999")
// without any position, so this handler records where parsing stops and why; it also refuses
// what nlohmann would accept but must not be: nesting deeper than kMaxJsonDepth (the DOM's
// recursive destructor would overflow the stack) and a key given twice (the last would win
// silently). The document itself is built by a second pass.
class TextChecker : public nlohmann::json_sax<Json> {
 public:
  enum class Failure { kNone, kSyntax, kDepth, kDuplicateKey };

  explicit TextChecker(const std::size_t* last_read) : last_read_(last_read) {}

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override { return open(true); }
  bool key(string_t& k) override {
    Frame& f = frames_.back();
    if (!f.keys.insert(k).second) {
      where = path();
      token = k;
      failed = Failure::kDuplicateKey;
      byte = *last_read_;  // the key's closing quote
      return false;
    }
    f.key = k;
    return true;
  }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(false); }
  bool end_array() override { return close(); }
  bool parse_error(std::size_t position, const std::string& last_token,
                   const nlohmann::detail::exception& e) override {
    failed = Failure::kSyntax;
    byte = position;
    token = last_token;
    id = e.id;
    what = e.what();
    return false;
  }

  Failure failed = Failure::kNone;
  std::size_t byte = 0;  // syntax: count of bytes read; others: offset of the offending character
  std::string token;     // syntax: the last token; duplicate: the key
  std::string where;     // depth, duplicate: the JSON path of the object or array
  int id = 0;
  std::string what;

 private:
  struct Frame {
    bool object = false;
    std::set<std::string> keys;  // keys seen so far (objects)
    std::string key;             // the current key (objects)
    std::size_t count = 0;       // elements started so far (arrays)
  };

  bool value() {
    if (!frames_.empty() && !frames_.back().object) ++frames_.back().count;
    return true;
  }
  bool open(bool object) {
    value();
    if (frames_.size() >= kMaxJsonDepth) {
      failed = Failure::kDepth;
      byte = *last_read_;
      return false;
    }
    frames_.push_back(Frame{object, {}, {}, 0});
    return true;
  }
  bool close() {
    frames_.pop_back();
    return true;
  }
  // The JSON path of the innermost open value ("design.l1", "objectives[0]"; "" at the top).
  std::string path() const {
    std::string out;
    for (std::size_t i = 0; i < frames_.size(); ++i) {
      if (i + 1 == frames_.size()) break;  // the innermost frame is where we are, not a step
      const Frame& f = frames_[i];
      if (f.object) {
        out += (out.empty() ? "" : ".") + f.key;
      } else {
        out += "[" + std::to_string(f.count - 1) + "]";
      }
    }
    return out;
  }

  const std::size_t* last_read_;
  std::vector<Frame> frames_;
};

// nlohmann's messages read "[json.exception.parse_error.101] parse error at line 1, column 9:
// syntax error while parsing value - invalid literal; ..." : keep the part after the dash.
std::string short_reason(const TextChecker& f) {
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

// The first pass over `text` (see TextChecker).
TextChecker check_text(const std::string& text) {
  std::size_t last_read = 0;
  TextChecker checker(&last_read);
  const char* begin = text.data();
  Json::sax_parse(CountingIterator(begin, begin, &last_read), CountingIterator(begin, begin + text.size(), &last_read),
                  &checker);
  return checker;
}

// Where the checker's failure is, as an offset into `text`.
std::size_t error_offset(const std::string& text, const TextChecker& f) {
  if (f.failed == TextChecker::Failure::kSyntax) {
    // For a number out of range the position is its last character: point at its first.
    std::size_t offset = f.byte > 0 ? f.byte - 1 : 0;
    if (f.id == 406 && offset + 1 >= f.token.size()) offset = offset + 1 - f.token.size();
    return offset;
  }
  if (f.failed == TextChecker::Failure::kDuplicateKey) {
    // From the key's closing quote back to its opening one (an escaped quote is part of the key).
    std::size_t i = std::min(f.byte, text.size());
    while (i-- > 0) {
      if (text[i] != '"') continue;
      std::size_t backslashes = 0;
      while (i > backslashes && text[i - 1 - backslashes] == '\\') ++backslashes;
      if (backslashes % 2 == 0) return i;
    }
  }
  return f.byte;
}

// What is wrong, after "SOURCE:LINE:COLUMN: ".
std::string problem_of(const TextChecker& f) {
  switch (f.failed) {
    case TextChecker::Failure::kDepth:
      return "nesting deeper than " + std::to_string(kMaxJsonDepth) +
             " levels (arrays and objects inside each other): refused before it is built";
    case TextChecker::Failure::kDuplicateKey:
      return "duplicate key " + Json(f.token).dump(-1, ' ', true, Json::error_handler_t::replace) + " in " +
             (f.where.empty() ? std::string("the top level") : f.where) + " (each key may appear once)";
    default:
      return "malformed JSON: " + short_reason(f);
  }
}

void refuse_invalid_utf8(const std::string& s, const std::string& path, const char* what) {
  const std::size_t bad = invalid_utf8_at(s);
  if (bad == std::string::npos) return;
  throw Error("problem", (path.empty() ? std::string("(top level)") : path) + " " + what + " " + shown_bytes(s) +
                             ": invalid UTF-8 at byte " + std::to_string(bad) + " (text must be UTF-8)");
}

void check_strings(const Json& value, const std::string& path, std::size_t depth) {
  if (value.is_string()) {
    refuse_invalid_utf8(value.get_ref<const std::string&>(), path, "=");
    return;
  }
  if (!value.is_structured()) return;
  if (depth >= kMaxJsonDepth) {
    throw Error("problem", (path.empty() ? std::string("(top level)") : path.substr(0, 200)) +
                               ": nesting deeper than " + std::to_string(kMaxJsonDepth) + " levels");
  }
  if (value.is_object()) {
    for (auto it = value.begin(); it != value.end(); ++it) {
      const std::string child = path.empty() ? it.key() : path + "." + it.key();
      refuse_invalid_utf8(it.key(), path, "has key");
      check_strings(it.value(), child, depth + 1);
    }
  } else {
    for (std::size_t i = 0; i < value.size(); ++i) check_strings(value[i], path + "[" + std::to_string(i) + "]", depth + 1);
  }
}

// ---- overrides ----

struct Segment {
  std::string key;                   // for a key, or the text of a dotted index ("0")
  std::optional<std::size_t> index;  // set for a bracketed index
};

[[noreturn]] void refuse_override(const std::string& assignment, const std::string& rule) {
  const std::string shown = assignment.size() > 200 ? assignment.substr(0, 200) + "..." : assignment;
  throw Error("set", "'" + shown + "': " + rule);
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
  return parse_problem_text(read_regular_file(path, "problem", "problem file", kMaxProblemFileBytes), path);
}

void check_json_text(const std::string& text, const std::string& source, const char* component) {
  // nlohmann's lexer takes a NUL byte for the end of the input: whatever follows one would be
  // ignored without a word.
  if (const std::size_t nul = text.find('\0'); nul != std::string::npos) {
    throw Error(component, source + ":" + line_and_column(text, nul) + ": a NUL byte: JSON text may not contain one (" +
                               "is this a binary file?)");
  }
  const TextChecker finder = check_text(text);
  if (finder.failed != TextChecker::Failure::kNone) {
    throw Error(component, source + ":" + line_and_column(text, error_offset(text, finder)) + ": " + problem_of(finder));
  }
}

Json parse_json_text(const std::string& text, const std::string& source, const char* component) {
  check_json_text(text, source, component);
  Json document = Json::parse(text, nullptr, false);
  if (document.is_discarded()) throw Error(component, source + ": malformed JSON");
  return document;
}

Json parse_problem_text(const std::string& text, const std::string& source) {
  Json document = parse_json_text(text, source, "problem");
  if (!document.is_object()) {
    throw Error("problem", source + ": top level = " + render_value(document) +
                               ": must be an object, not " + type_name_of(document));
  }
  return document;
}

void check_json_text_rules(const Json& value, const std::string& path) { check_strings(value, path, 0); }

void apply_override(Json& problem, const std::string& assignment) {
  // Before anything echoes it: a message must itself be valid UTF-8.
  if (const std::size_t bad = invalid_utf8_at(assignment); bad != std::string::npos) {
    throw Error("set", shown_bytes(assignment) + ": invalid UTF-8 at byte " + std::to_string(bad) +
                           " (paths and values must be UTF-8)");
  }
  const auto equals = assignment.find('=');
  if (equals == std::string::npos) refuse_override(assignment, "expected path=value (no '=')");
  const std::string path = trim(assignment.substr(0, equals));
  if (path.empty()) refuse_override(assignment, "empty path before '='");
  const std::string text = assignment.substr(equals + 1);

  // NaN and Infinity are not JSON and an out-of-range number is refused by the parser: all stay
  // strings, which the schema then refuses with the value in view.
  // Text that is JSON but must not be (too deep, a duplicate key) is refused, not taken as a string.
  const TextChecker checked = check_text(text);
  if (checked.failed == TextChecker::Failure::kDepth || checked.failed == TextChecker::Failure::kDuplicateKey) {
    refuse_override(assignment,
                    "value at " + line_and_column(text, error_offset(text, checked)) + ": " + problem_of(checked));
  }
  Json value = checked.failed == TextChecker::Failure::kNone ? Json::parse(text, nullptr, false) : Json(text);
  if (value.is_discarded()) value = text;

  // Each segment is one level of the document: a longer path could only be refused later, after
  // work quadratic in its length (the name of every prefix is built for messages).
  const std::size_t separators = std::count(path.begin(), path.end(), '.') + std::count(path.begin(), path.end(), '[');
  if (separators >= kMaxJsonDepth) {
    refuse_override(assignment, "path of more than " + std::to_string(kMaxJsonDepth) +
                                    " segments: a problem file nests at most that deep");
  }
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
