#include <algorithm>
#include <cmath>
#include <cstddef>
#include <hapsyn/json.hpp>
#include <string>
#include <vector>

namespace hapsyn {

namespace {

constexpr std::size_t kMaxRendered = 60;
constexpr const char* kEllipsis = "...";
constexpr std::size_t kEllipsisSize = 3;

// Json::dump writes non-finite numbers as null, which would hide the very value an error is
// about, so numbers are rendered here and everything else is delegated to dump().
void render_into(const Json& value, std::string& out) {
  switch (value.type()) {
    case Json::value_t::object: {
      out += '{';
      bool first = true;
      for (const auto& item : value.items()) {
        if (!first) out += ',';
        first = false;
        out += Json(item.key()).dump(-1, ' ', false, Json::error_handler_t::replace);
        out += ':';
        render_into(item.value(), out);
        if (out.size() > kMaxRendered) return;  // the rest would be cut anyway
      }
      out += '}';
      return;
    }
    case Json::value_t::array: {
      out += '[';
      bool first = true;
      for (const auto& element : value) {
        if (!first) out += ',';
        first = false;
        render_into(element, out);
        if (out.size() > kMaxRendered) return;
      }
      out += ']';
      return;
    }
    case Json::value_t::number_float: {
      const double x = value.get<double>();
      if (std::isnan(x)) {
        out += "nan";
      } else if (std::isinf(x)) {
        out += x > 0 ? "inf" : "-inf";
      } else {
        out += value.dump();
      }
      return;
    }
    default:
      // Strings from the command line may hold invalid UTF-8; an error message must not throw.
      out += value.dump(-1, ' ', false, Json::error_handler_t::replace);
      return;
  }
}

bool is_utf8_continuation(char c) { return (static_cast<unsigned char>(c) & 0xC0) == 0x80; }

}  // namespace

std::string render_value(const Json& value) {
  std::string out;
  render_into(value, out);
  if (out.size() <= kMaxRendered) return out;
  std::size_t cut = kMaxRendered - kEllipsisSize;
  // Never split a multi-byte character: the message is shown on a terminal.
  while (cut > 0 && is_utf8_continuation(out[cut])) --cut;
  out.resize(cut);
  return out + kEllipsis;
}

std::string nearest_name(const std::string& word, const std::vector<std::string>& candidates) {
  // Optimal string alignment distance: Levenshtein plus adjacent transpositions, the most
  // common typo in a key ("stpe" for "step").
  const auto distance = [](const std::string& a, const std::string& b) {
    const std::size_t n = a.size(), m = b.size();
    std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1, 0));
    for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
    for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
    for (std::size_t i = 1; i <= n; ++i) {
      for (std::size_t j = 1; j <= m; ++j) {
        const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
        d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
        if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
          d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
        }
      }
    }
    return d[n][m];
  };

  const std::size_t limit = std::max<std::size_t>(1, word.size() / 3);
  std::string best;
  std::size_t best_distance = limit + 1;
  for (const auto& candidate : candidates) {
    const std::size_t dist = distance(word, candidate);
    if (dist < best_distance) {  // strict: the first of equally close candidates wins
      best = candidate;
      best_distance = dist;
    }
  }
  return best;
}

}  // namespace hapsyn
