// The hapsyn-motion CSV reader, and what the readers share: the bounded text file, the
// quaternion convention and the dispatch of files and folders (read_recordings).
#include "motion_recording.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/read_file.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <string_view>

namespace hapsyn::plugins::motion {
namespace {

namespace fs = std::filesystem;

constexpr const char* kComponent = "motion";
const std::vector<std::string> kRequired = {"time", "x", "y", "z"};
const std::vector<std::string> kQuaternion = {"qw", "qx", "qy", "qz"};
const std::vector<std::string> kMatrix = {"r11", "r12", "r13", "r21", "r22", "r23", "r31", "r32", "r33"};
const std::vector<std::string> kKeys = {"subject", "activity", "unit", "time_unit"};
constexpr double kQuaternionNormTolerance = 1e-3;
constexpr double kRotationTolerance = 1e-4;

std::string trim(std::string_view text) {
  const std::size_t begin = text.find_first_not_of(" \t");
  if (begin == std::string_view::npos) return "";
  return std::string(text.substr(begin, text.find_last_not_of(" \t") - begin + 1));
}

std::string join(const std::vector<std::string>& items, const char* separator = ", ") {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? separator : "") + items[i];
  return out;
}

std::string shown(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", value);
  return text;
}

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

// Splits at commas (no quoting: every field is a name or a number) and trims each field.
void split(const std::string& row, std::vector<std::string>& fields) {
  fields.clear();
  std::size_t begin = 0;
  while (true) {
    const std::size_t comma = row.find(',', begin);
    fields.push_back(trim(std::string_view(row).substr(begin, comma == std::string::npos ? comma : comma - begin)));
    if (comma == std::string::npos) return;
    begin = comma + 1;
  }
}

class CsvReader {
 public:
  CsvReader(const std::string& path, std::string subject) : file_(path), fallback_subject_(std::move(subject)) {}

  Recording read() {
    std::string text;
    std::vector<std::string> fields;
    while (file_.next(text)) {
      const std::string trimmed = trim(text);
      if (trimmed.empty()) continue;
      if (trimmed[0] == '#') {
        if (names_.empty()) header_comment(trimmed);
        continue;
      }
      split(text, fields);
      if (names_.empty()) {
        columns(fields);
      } else {
        row(fields);
      }
    }
    if (names_.empty()) {
      file_.fail_file("has no column row: expected e.g. \"time,x,y,z,qw,qx,qy,qz\" after the '#' header lines");
    }
    if (lines_.size() < 2) {
      file_.fail_file("has " + std::to_string(lines_.size()) + " data row(s): at least 2 are required");
    }
    return recording();
  }

 private:
  // "# key: value" or "# hapsyn-motion N" (before the column row).
  void header_comment(const std::string& text) {
    const std::string body = trim(std::string_view(text).substr(1));
    if (body.empty()) return;
    static const std::string kMagic = "hapsyn-motion";
    if (body.compare(0, kMagic.size(), kMagic) == 0 &&
        (body.size() == kMagic.size() || body[kMagic.size()] == ' ' || body[kMagic.size()] == '\t')) {
      const std::string version = trim(std::string_view(body).substr(kMagic.size()));
      if (version != "1") {
        file_.fail("format version " + detail::quoted(version) + " (\"# " + kMagic +
                   " N\"): this reader reads version 1 only");
      }
      return;
    }
    const std::size_t colon = body.find(':');
    if (colon == std::string::npos) {
      file_.fail("header comment " + detail::quoted(text) + ": before the column row, '#' lines must be \"# key: " +
                 "value\" (keys " + join(kKeys) + ") or \"# hapsyn-motion 1\"; free comments may follow the column row");
    }
    const std::string key = trim(std::string_view(body).substr(0, colon));
    const std::string value = trim(std::string_view(body).substr(colon + 1));
    if (std::find(kKeys.begin(), kKeys.end(), key) == kKeys.end()) {
      file_.fail("unknown header key " + detail::quoted(key) + ": the known keys are " + join(kKeys));
    }
    if (value.empty()) file_.fail("header key " + key + " has an empty value: give a value or leave the line out");
    if (const std::size_t bad = invalid_utf8_at(value); bad != std::string::npos) {
      file_.fail("header key " + key + " = " + shown_bytes(value) + ": invalid UTF-8 at byte " + std::to_string(bad) +
                 " (labels are written into result.json: they must be UTF-8)");
    }
    const auto [it, fresh] = keys_.emplace(key, std::make_pair(value, file_.line()));
    if (!fresh) {
      file_.fail("header key " + key + " given again (first on line " + std::to_string(it->second.second) +
                 "): give each key once");
    }
    if (key == "unit") {
      const std::map<std::string, double> units = {{"m", 1.0}, {"cm", 0.01}, {"mm", 0.001}};
      const auto unit = units.find(value);
      if (unit == units.end()) file_.fail("unit = " + detail::quoted(value) + ": must be m, cm or mm");
      length_scale_ = unit->second;
    } else if (key == "time_unit") {
      if (value != "s" && value != "ms") file_.fail("time_unit = " + detail::quoted(value) + ": must be s or ms");
      time_scale_ = value == "s" ? 1.0 : 0.001;
    }
  }

  void columns(const std::vector<std::string>& names) {
    column_line_ = file_.line();
    std::map<std::string, int> index;
    std::vector<std::string> known = kRequired;
    known.insert(known.end(), kQuaternion.begin(), kQuaternion.end());
    known.insert(known.end(), kMatrix.begin(), kMatrix.end());
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (names[i].empty()) file_.fail("column row: field " + std::to_string(i + 1) + " is empty: name every column");
      if (std::find(known.begin(), known.end(), names[i]) == known.end()) {
        file_.fail("column row: unknown column " + detail::quoted(names[i]) + ": the known columns are " + join(known));
      }
      const auto [it, fresh] = index.emplace(names[i], static_cast<int>(i));
      if (!fresh) {
        file_.fail("column row: column " + detail::quoted(names[i]) + " appears twice (fields " +
                   std::to_string(it->second + 1) + " and " + std::to_string(i + 1) + "): name each column once");
      }
    }
    const auto present = [&](const std::vector<std::string>& group, std::vector<std::string>& missing) {
      std::vector<int> found;
      for (const std::string& name : group) {
        const auto it = index.find(name);
        if (it == index.end()) missing.push_back(name); else found.push_back(it->second);
      }
      return found;
    };
    std::vector<std::string> missing, missing_quaternion, missing_matrix;
    const std::vector<int> required = present(kRequired, missing);
    const std::vector<int> quaternion = present(kQuaternion, missing_quaternion);
    const std::vector<int> matrix = present(kMatrix, missing_matrix);
    const std::string expected = "the columns are time, x, y, z and either qw, qx, qy, qz or r11 .. r33";
    if (!quaternion.empty() && !matrix.empty()) {
      file_.fail("column row: both orientation forms (quaternion qw.. and matrix r11..) are given: " + expected);
    }
    if (!matrix.empty()) {
      missing.insert(missing.end(), missing_matrix.begin(), missing_matrix.end());
    } else if (!quaternion.empty()) {
      missing.insert(missing.end(), missing_quaternion.begin(), missing_quaternion.end());
    } else {
      missing.push_back("qw, qx, qy, qz (or r11 .. r33)");
    }
    if (!missing.empty()) file_.fail("column row: missing column(s) " + join(missing) + ": " + expected);
    names_ = names;
    time_ = required[0];
    std::copy(required.begin() + 1, required.end(), position_.begin());
    orientation_ = matrix.empty() ? quaternion : matrix;
  }

  void row(const std::vector<std::string>& fields) {
    if (fields.size() != names_.size()) {
      file_.fail(std::to_string(fields.size()) + " fields, the column row (line " + std::to_string(column_line_) +
                 ") has " + std::to_string(names_.size()) + ": every row needs one field per column");
    }
    values_.resize(fields.size());
    for (std::size_t i = 0; i < fields.size(); ++i) values_[i] = number(fields[i], names_[i]);

    const double t = values_[time_] * time_scale_;
    if (!lines_.empty() && !(t > times_.back())) {
      file_.fail("time " + fields[time_] + " is not after the previous row's " + previous_time_ + " (line " +
                 std::to_string(lines_.back()) + "): time must be strictly increasing");
    }
    previous_time_ = fields[time_];
    times_.push_back(t);
    for (int axis : position_) positions_.push_back(values_[axis] * length_scale_);
    if (orientation_.size() == 4) {
      quaternion(fields);
    } else {
      matrix(fields);
    }
    lines_.push_back(file_.line());
  }

  // The whole field must be the number (strtod alone accepts "1.5abc" as 1.5) and finite.
  double number(const std::string& field, const std::string& column) const {
    const std::string rule = ": every field must be a finite number";
    if (field.empty()) file_.fail("column " + column + " is empty" + rule);
    char* end = nullptr;
    const double value = std::strtod(field.c_str(), &end);
    if (end != field.c_str() + field.size()) file_.fail("column " + column + " = " + detail::quoted(field) + ": not a number" + rule);
    if (!std::isfinite(value)) file_.fail("column " + column + " = " + detail::quoted(field) + ": not finite" + rule);
    return value;
  }

  void quaternion(const std::vector<std::string>& fields) {
    Eigen::Vector4d q;
    for (int i = 0; i < 4; ++i) q[i] = values_[orientation_[i]];
    const double norm = q.norm();
    if (std::abs(norm - 1.0) > kQuaternionNormTolerance) {
      file_.fail("quaternion (qw, qx, qy, qz) = (" + listed(fields) + ") has norm " + shown(norm) +
                 ": must be 1 within " + shown(kQuaternionNormTolerance));
    }
    q /= norm;
    quaternions_.insert(quaternions_.end(), q.data(), q.data() + 4);
  }

  void matrix(const std::vector<std::string>& fields) {
    Eigen::Matrix3d r;
    for (int i = 0; i < 9; ++i) r(i / 3, i % 3) = values_[orientation_[i]];
    const double orthogonality = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    const double det = r.determinant();
    if (orthogonality > kRotationTolerance || std::abs(det - 1.0) > kRotationTolerance) {
      file_.fail("rotation matrix (r11 .. r33) = (" + listed(fields) + ") is not a rotation: max |R^T R - I| = " +
                 shown(orthogonality) + ", det = " + shown(det) + ": must be orthonormal with det +1 within " +
                 shown(kRotationTolerance));
    }
    Eigen::Vector4d previous;
    if (!lines_.empty()) previous = Eigen::Map<const Eigen::Vector4d>(&quaternions_[quaternions_.size() - 4]);
    const Eigen::Vector4d q = detail::quaternion_continuing(r, lines_.empty() ? nullptr : &previous);
    quaternions_.insert(quaternions_.end(), q.data(), q.data() + 4);
  }

  std::string listed(const std::vector<std::string>& fields) const {
    std::vector<std::string> items;
    for (int i : orientation_) items.push_back(fields[i]);
    return join(items);
  }

  Recording recording() const {
    Recording r = detail::recording_of(file_.path(), times_, positions_, quaternions_, lines_);
    const std::string stem = fs::path(file_.path()).stem().string();
    const auto label = [&](const char* key, const std::string& fallback) {
      const auto it = keys_.find(key);
      return it != keys_.end() ? it->second.first : fallback.empty() ? stem : fallback;
    };
    r.subject = label("subject", fallback_subject_);
    r.activity = label("activity", "");
    return r;
  }

  detail::TextFile file_;
  std::string fallback_subject_;
  std::map<std::string, std::pair<std::string, int>> keys_;  // key -> value, line
  double length_scale_ = 1.0, time_scale_ = 1.0;
  std::vector<std::string> names_;  // the column row; empty until it is read
  int column_line_ = 0;
  int time_ = -1;
  std::array<int, 3> position_{};
  std::vector<int> orientation_;  // the 4 quaternion or 9 matrix columns, in kQuaternion / kMatrix order
  std::vector<double> values_;   // the current row
  std::string previous_time_;    // as written
  std::vector<double> times_, positions_, quaternions_;
  std::vector<int> lines_;
};

}  // namespace

namespace detail {

TextFile::TextFile(std::string path) : path_(std::move(path)) {
  // Only a regular file is opened: a FIFO would block the reader and a device might never end.
  std::error_code ec;
  const fs::file_status status = fs::status(path_, ec);
  if (status.type() == fs::file_type::not_found) fail_file("no such file");
  if (ec) fail_file("cannot be examined (" + ec.message() + ")");
  if (status.type() == fs::file_type::directory) fail_file("is a directory: a file was expected");
  if (status.type() != fs::file_type::regular) {
    fail_file("is not a regular file (a FIFO, socket or device): refused, reading it could block or never end");
  }
  const std::uintmax_t bytes = fs::file_size(path_, ec);
  if (ec) fail_file("cannot be examined (" + ec.message() + ")");
  if (bytes > kMotionMaxFileBytes) {
    fail_file(std::to_string(bytes) + " bytes: larger than the 2 GiB limit (" + std::to_string(kMotionMaxFileBytes) +
              " bytes)");
  }
  in_.open(path_, std::ios::binary);
  if (!in_) fail_file("cannot be opened for reading");
  buffer_.resize(kMotionMaxLineBytes + 2);  // one byte more than allowed tells a too long line, one for the '\0'
}

bool TextFile::next(std::string& text) {
  in_.getline(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
  const auto got = static_cast<std::size_t>(in_.gcount());
  if (in_.bad()) fail_file("could not be read to the end (after line " + std::to_string(line_) + ")");
  if (got == 0 && in_.eof()) return false;
  if (line_ == std::numeric_limits<int>::max()) fail_file("has too many lines");
  ++line_;
  consumed_ += got;
  // The size was checked before opening; a file that grows meanwhile is still bounded.
  if (consumed_ > kMotionMaxFileBytes) fail_file("grew beyond the 2 GiB limit while being read");
  // getline counts the '\n' it extracted; it sets failbit when the buffer filled first.
  const bool delimited = !in_.eof() && !in_.fail();
  const std::size_t length = delimited ? got - 1 : got;
  if (in_.fail() || length > kMotionMaxLineBytes) {
    fail("line longer than " + std::to_string(kMotionMaxLineBytes) + " bytes: refused, lines are limited to 1 MiB");
  }
  text.assign(buffer_.data(), length);
  if (!text.empty() && text.back() == '\r') text.pop_back();
  if (line_ == 1 && text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.erase(0, 3);  // UTF-8 byte order mark
  return true;
}

void TextFile::fail_at(int line, const std::string& what) const {
  throw Error(kComponent, path_ + ":" + std::to_string(line) + ": " + what);
}

void TextFile::fail_file(const std::string& what) const { throw Error(kComponent, path_ + ": " + what); }

Recording recording_of(const std::string& file, const std::vector<double>& times, const std::vector<double>& positions,
                       const std::vector<double>& quaternions, const std::vector<int>& lines) {
  const Eigen::Index n = static_cast<Eigen::Index>(lines.size());
  using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  using Rows4 = Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>;
  Recording r;
  r.file = file;
  r.time = Eigen::Map<const Eigen::VectorXd>(times.data(), n);
  r.position = Eigen::Map<const Rows3>(positions.data(), n, 3);
  r.quaternion = Eigen::Map<const Rows4>(quaternions.data(), n, 4);
  r.line = lines;
  return r;
}

std::string quoted(const std::string& text) {
  // Messages stay short and printable whatever the file holds.
  constexpr std::size_t kShown = 60;
  std::string out = "\"";
  for (std::size_t i = 0; i < std::min(text.size(), kShown); ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20 || c == 0x7f) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02x", c);
      out += escaped;
    } else {
      out += static_cast<char>(c);
    }
  }
  if (text.size() > kShown) out += "...";
  return out + "\"";
}

Eigen::Vector4d quaternion_continuing(const Eigen::Matrix3d& r, const Eigen::Vector4d* previous) {
  const Eigen::Quaterniond q = Eigen::Quaterniond(r).normalized();
  const Eigen::Vector4d v(q.w(), q.x(), q.y(), q.z());
  const bool flip = previous ? v.dot(*previous) < 0.0 : v[0] < 0.0;
  return flip ? Eigen::Vector4d(-v) : v;
}

Recording read_motion_csv(const std::string& path, const std::string& subject) {
  return CsvReader(path, subject).read();
}

static Recording read_any(const std::string& path, const BvhOptions& bvh, const std::string& subject) {
  const std::string extension = lower(fs::path(path).extension().string());
  if (extension == ".csv") return read_motion_csv(path, subject);
  if (extension == ".bvh") {
    Recording r = read_bvh(path, bvh);
    if (!subject.empty()) r.subject = subject;
    return r;
  }
  throw Error(kComponent, path + ": extension " + quoted(fs::path(path).extension().string()) +
                              ": must be .csv (hapsyn-motion) or .bvh (case ignored)");
}

// The labels a recording gives (its path, subject, activity) go into result.json and groups.csv:
// they must be UTF-8, checked here where the file is named.
static void check_labels(const std::string& path, const Recording& r) {
  for (const auto& [what, text] : {std::pair<const char*, const std::string&>{"subject", r.subject},
                                   {"activity", r.activity}}) {
    if (const std::size_t bad = invalid_utf8_at(text); bad != std::string::npos) {
      throw Error(kComponent, shown_bytes(path) + ": " + what + " " + shown_bytes(text) + ": invalid UTF-8 at byte " +
                                  std::to_string(bad) + " (labels are written into result.json: they must be UTF-8; " +
                                  "rename the file or folder)");
    }
  }
}

Recording read_file(const std::string& path, const BvhOptions& bvh, const std::string& subject) {
  if (const std::size_t bad = invalid_utf8_at(path); bad != std::string::npos) {
    throw Error(kComponent, shown_bytes(path) + ": the file's path is not valid UTF-8 (at byte " + std::to_string(bad) +
                                "): it is written into result.json; rename the file or folder");
  }
  Recording r = read_any(path, bvh, subject);
  check_labels(path, r);
  return r;
}

}  // namespace detail

Recording read_motion_csv(const std::string& path) { return detail::read_motion_csv(path, ""); }

namespace {

// The .csv and .bvh files below `root`, relative to it, sorted.
std::vector<fs::path> motion_files(const std::string& root) {
  const auto fail = [&](const std::string& what) { throw Error(kComponent, root + ": " + what); };
  std::vector<fs::path> found;
  std::error_code ec;
  // Without follow_directory_symlink a link loop is never entered.
  fs::recursive_directory_iterator it(root, fs::directory_options::none, ec);
  if (ec) fail("cannot be listed (" + ec.message() + ")");
  while (it != fs::recursive_directory_iterator()) {
    const std::string extension = lower(it->path().extension().string());
    std::error_code ignored;
    if ((extension == ".csv" || extension == ".bvh") && !it->is_directory(ignored)) {
      found.push_back(it->path().lexically_relative(root));
      if (found.size() > kMotionMaxFiles) {
        fail("holds more than " + std::to_string(kMotionMaxFiles) + " .csv/.bvh files: refused, read fewer at a time");
      }
    }
    it.increment(ec);
    if (ec) fail("cannot be listed (" + ec.message() + ")");
  }
  if (found.empty()) fail("is a folder without .csv or .bvh files (searched recursively): nothing to read");
  std::sort(found.begin(), found.end(),
            [](const fs::path& a, const fs::path& b) { return a.generic_string() < b.generic_string(); });
  return found;
}

}  // namespace

std::vector<Recording> read_recordings(const std::string& path, const BvhOptions& bvh) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (status.type() == fs::file_type::not_found) throw Error(kComponent, path + ": no such file or folder");
  if (ec) throw Error(kComponent, path + ": cannot be examined (" + ec.message() + ")");
  if (status.type() != fs::file_type::directory) return {detail::read_file(path, bvh, "")};
  std::vector<Recording> recordings;
  for (const fs::path& relative : motion_files(path)) {
    // Nested files are labelled by their first folder below the root (the subject's folder).
    const bool nested = std::next(relative.begin()) != relative.end();
    recordings.push_back(
        detail::read_file((fs::path(path) / relative).string(), bvh, nested ? relative.begin()->string() : ""));
  }
  return recordings;
}

}  // namespace hapsyn::plugins::motion
