// A single pass over the bytes: markup that cannot hold elements (comments, CDATA, processing
// instructions, declarations) is skipped whole, quoted attribute values may contain '>' and are
// skipped too. Anything malformed ends the scan quietly: the parser reports it with its own line.
#include "xml_shape.hpp"

#include <hapsyn/error.hpp>

#include <cstring>

namespace hapsyn::plugins {
namespace {

struct Scan {
  const std::string& text;
  std::size_t line = 1;

  // Position just past `end` at or after `from` (lines counted), or npos.
  std::size_t skip_past(std::size_t from, const char* end) {
    const std::size_t at = text.find(end, from);
    if (at == std::string::npos) return at;
    count_lines(from, at);
    return at + std::strlen(end);
  }
  void count_lines(std::size_t from, std::size_t to) {
    for (std::size_t i = from; i < to; ++i) line += text[i] == '\n';
  }
  // Position of the '>' closing the tag opened at `from`, quoted values skipped, or npos.
  std::size_t tag_end(std::size_t from) {
    char quote = 0;
    for (std::size_t i = from; i < text.size(); ++i) {
      const char c = text[i];
      if (c == '\n') ++line;
      if (quote) {
        if (c == quote) quote = 0;
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (c == '>') {
        return i;
      }
    }
    return std::string::npos;
  }
};

bool starts(const std::string& text, std::size_t at, const char* prefix) {
  return text.compare(at, std::strlen(prefix), prefix) == 0;
}

// The element name of the tag whose '<' is at `at`.
std::string name_at(const std::string& text, std::size_t at) {
  std::size_t end = at + 1;
  while (end < text.size() && !std::strchr(" \t\r\n/>", text[end])) ++end;
  return text.substr(at + 1, end - at - 1);
}

[[noreturn]] void refuse(const std::string& path, const char* component, std::size_t line, const std::string& what) {
  throw Error(component, path + ": line " + std::to_string(line) + ": " + what);
}

[[noreturn]] void refuse_limit(const std::string& path, const char* component, std::size_t line, const std::string& what) {
  refuse(path, component, line, what + " (refused before it is parsed; the limits are in docs/limits.md)");
}

}  // namespace

void check_xml_shape(const std::string& text, const std::string& path, const char* component,
                     const XmlShapeLimits& limits) {
  Scan scan{text};
  int depth = 0;
  std::size_t elements = 0;
  std::size_t robot_children = 0;
  std::size_t roots = 0;  // elements at the top level
  std::size_t counted = 0;  // lines are counted up to here
  std::size_t i;
  while ((i = text.find('<', counted)) != std::string::npos) {
    scan.count_lines(counted, i);
    std::size_t next;
    if (starts(text, i, "<!--")) {
      next = scan.skip_past(i + 4, "-->");
    } else if (starts(text, i, "<![CDATA[")) {
      next = scan.skip_past(i + 9, "]]>");
    } else if (starts(text, i, "<?")) {
      next = scan.skip_past(i + 2, "?>");
    } else if (starts(text, i, "<!DOCTYPE") || starts(text, i, "<!ENTITY")) {
      // TinyXML skips a DTD, so urdfdom then misses the robot or reads "&L;" for a number: an
      // internal subset (entity declarations) is refused with what it is.
      const std::size_t end = scan.tag_end(i + 2);
      if (starts(text, i, "<!ENTITY") || text.find('[', i) < end) {
        refuse(path, component, scan.line, "a DOCTYPE with declarations (entities): they are not read; write the values "
                                           "in place and remove the DOCTYPE");
      }
      next = end == std::string::npos ? end : end + 1;
    } else if (starts(text, i, "<!") || starts(text, i, "</")) {
      const std::size_t end = scan.tag_end(i + 2);
      if (text[i + 1] == '/') --depth;
      next = end == std::string::npos ? end : end + 1;
    } else {
      const std::size_t line = scan.line;
      const std::string name = name_at(text, i);
      if (depth == 0 && ++roots > 1) {
        refuse(path, component, line, "<" + name + "> after the root element has ended: a file holds one XML document "
                                      "(one <robot>)");
      }
      const std::size_t end = scan.tag_end(i + 1);
      if (end == std::string::npos) return;
      const bool empty = text[end - 1] == '/';
      if (++elements > limits.max_elements) {
        refuse_limit(path, component, line,
               "more than " + std::to_string(limits.max_elements) + " XML elements: at most that many are read");
      }
      if (depth == 1 && (name == "link" || name == "joint") && ++robot_children > limits.max_robot_children) {
        refuse_limit(path, component, line,
               "more than " + std::to_string(limits.max_robot_children) + " <link> and <joint> elements: at most that many are read");
      }
      if (!empty && ++depth > limits.max_depth) {
        refuse_limit(path, component, line,
               "<" + name + "> is nested " + std::to_string(depth) + " elements deep: at most " +
                   std::to_string(limits.max_depth) + " levels are read");
      }
      next = end + 1;
    }
    if (next == std::string::npos) return;
    counted = next;
  }
}

}  // namespace hapsyn::plugins
