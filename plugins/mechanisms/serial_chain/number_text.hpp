#pragma once
/// \file
/// number_text(v): a number as messages and summaries show it (the stream's default format:
/// 0.5, 170, 1e-12), not std::to_string's fixed six decimals.
#include <sstream>
#include <string>

namespace hapsyn::plugins {

inline std::string number_text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace hapsyn::plugins
