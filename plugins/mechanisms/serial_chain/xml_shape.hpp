// The shape of an XML text (nesting depth, element counts), measured by a linear scan before any
// parser sees it. TinyXML and urdfdom recurse once per nesting level and once per link of a
// chain, so a file that is deep enough overflows the stack inside them; the limits are decided
// here, before that work, with the line of the first element beyond them.
#pragma once

#include <cstddef>
#include <string>

namespace hapsyn::plugins {

struct XmlShapeLimits {
  int max_depth = 64;                    // nesting of elements (a URDF needs about 6)
  std::size_t max_elements = 1000000;    // elements in the whole file
  std::size_t max_robot_children = 20000;  // <link> and <joint> elements, each counted (children of the root)
};

// Throws hapsyn::Error (component `component`) naming `path`, the line and the limit when `text`
// exceeds a limit; and for what TinyXML would read wrongly without a word: a second root element
// after the first (a second <robot>), and a DOCTYPE with declarations (entities it does not
// expand). Other malformed XML is left to the parser.
void check_xml_shape(const std::string& text, const std::string& path, const char* component,
                     const XmlShapeLimits& limits = {});

}  // namespace hapsyn::plugins
