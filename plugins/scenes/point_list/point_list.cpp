#include "point_list.hpp"

#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/read_file.hpp>

#include <Eigen/Geometry>
#include <boost/filesystem.hpp>

#include <algorithm>
#include <cctype>
#include <numeric>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>

namespace hapsyn::plugins {
namespace {

namespace fs = boost::filesystem;

constexpr const char* kName = "point_list";
const std::vector<std::string> kQuaternion = {"qw", "qx", "qy", "qz"};
const std::vector<std::string> kMatrix = {"r11", "r12", "r13", "r21", "r22", "r23", "r31", "r32", "r33"};

// Quoted as JSON would quote it; text that is not UTF-8 (which JSON cannot hold) shows its
// bytes as \xHH.
std::string in_quotes(const std::string& text) {
  return invalid_utf8_at(text) == std::string::npos ? Json(text).dump() : shown_bytes(text);
}
std::string number(double value) { return render_value(Json(value)); }

std::string trim(const std::string& text) {
  const std::size_t begin = text.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  return text.substr(begin, text.find_last_not_of(" \t") - begin + 1);
}

std::string join(const std::vector<std::string>& names, const char* separator = ", ") {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) out += (i ? separator : "") + names[i];
  return out;
}

// Splits a row at commas (no quoting: every field is a name or a number) and trims each field.
void split(const std::string& row, std::vector<std::string>& fields) {
  fields.clear();
  std::size_t begin = 0;
  while (true) {
    const std::size_t comma = row.find(',', begin);
    fields.push_back(trim(row.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin)));
    if (comma == std::string::npos) return;
    begin = comma + 1;
  }
}

// The whole field must be the number (strtod alone accepts "1.5abc" as 1.5).
bool parse_number(const std::string& field, double& value) {
  if (field.empty()) return false;
  char* end = nullptr;
  value = std::strtod(field.c_str(), &end);
  return end == field.c_str() + field.size();
}

// Where each kind of column sits in a row (-1: absent), decided once from the header.
struct Layout {
  int x = -1, y = -1, z = -1, weight = -1;
  std::vector<int> quaternion, matrix;  // empty, or all 4 / all 9 indices
  std::vector<std::pair<std::string, int>> attributes;  // name, index; alphabetical
  int pose_columns() const { return z < 0 ? 2 : (quaternion.empty() && matrix.empty() ? 3 : 7); }
};

class Reader {
 public:
  explicit Reader(std::string path) : path_(std::move(path)) {}

  SampleSet read() {
    check_file();
    std::ifstream in(path_, std::ios::binary);
    if (!in) fail_file("cannot be opened for reading");
    std::string raw;
    std::vector<std::string> fields;
    std::uintmax_t consumed = 0;
    while (std::getline(in, raw)) {
      ++line_;
      consumed += raw.size() + 1;
      // The size was checked before opening; a file that grows meanwhile is still bounded.
      if (consumed > kPointListMaxBytes + 1) fail_file("grew beyond the " + cap() + " while being read");
      if (line_ == 1 && raw.compare(0, 3, "\xEF\xBB\xBF") == 0) raw.erase(0, 3);  // UTF-8 byte order mark
      if (!raw.empty() && raw.back() == '\r') raw.pop_back();
      const std::string text = trim(raw);
      if (text.empty()) continue;
      if (text[0] == '#') {
        comment(text);
        continue;
      }
      split(raw, fields);
      if (columns_.empty()) {
        header(fields);
      } else {
        row(fields);
      }
    }
    if (in.bad()) fail_file("could not be read to the end");
    if (columns_.empty()) {
      fail_file(line_ == 0 ? "is empty: a header row of column names is required"
                           : "has no header row (only comments and blank lines): a header row of column names is "
                             "required");
    }
    if (rows_ == 0) fail_file("has a header row (line " + std::to_string(header_line_) + ") but no data rows");
    return samples();
  }

 private:
  [[noreturn]] void fail_file(const std::string& what) const { throw Error(kName, path_ + ": " + what); }
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(kName, path_ + ":" + std::to_string(line_) + ": " + what);
  }
  static std::string cap() { return "1 GiB cap (" + std::to_string(kPointListMaxBytes) + " bytes)"; }

  // Only a regular file is opened: a FIFO would block the reader and a device might never end.
  void check_file() const {
    boost::system::error_code ec;
    const fs::file_status status = fs::status(path_, ec);
    if (status.type() == fs::file_not_found) fail_file("no such file");
    if (ec) fail_file("cannot be examined (" + ec.message() + ")");
    if (status.type() == fs::directory_file) fail_file("is a directory, not a regular file");
    if (status.type() != fs::regular_file) {
      fail_file("is not a regular file (a FIFO, socket or device): refused, reading it could block or never end");
    }
    const std::uintmax_t bytes = fs::file_size(path_, ec);
    if (ec) fail_file("cannot be examined (" + ec.message() + ")");
    if (bytes > kPointListMaxBytes) fail_file(std::to_string(bytes) + " bytes: larger than the " + cap());
  }

  // "# units: length=mm" sets the length unit; every other comment is ignored, except one that
  // reads like a units line in another spelling ("# Units:", "# unit: mm", "# units : mm"): read
  // as a comment it would leave millimetres as metres without a word.
  void comment(const std::string& text) {
    const std::string body = trim(text.substr(1));
    if (body.compare(0, 6, "units:") != 0) {
      std::string word = body.substr(0, body.find(':'));
      std::transform(word.begin(), word.end(), word.begin(), [](unsigned char c) { return std::tolower(c); });
      if (body.find(':') != std::string::npos && (trim(word) == "units" || trim(word) == "unit")) {
        fail("comment " + in_quotes(text) + " reads like a units line: write it '# units: length=mm' (lower case, "
             "\"units:\" with the colon right after it), or reword the comment");
      }
      return;
    }
    const std::string shown = "units line " + in_quotes(text);
    if (units_line_ > 0) {
      fail(shown + ": the units were already given on line " + std::to_string(units_line_) + "; give them once");
    }
    units_line_ = line_;
    std::string items = body.substr(6);
    std::replace(items.begin(), items.end(), ',', ' ');
    std::size_t begin = items.find_first_not_of(' ');
    if (begin == std::string::npos) fail(shown + ": names no unit; write e.g. '# units: length=mm'");
    while (begin != std::string::npos) {
      const std::size_t end = items.find(' ', begin);
      const std::string item = items.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
      const std::size_t equals = item.find('=');
      const std::string key = item.substr(0, equals), value = equals == std::string::npos ? "" : item.substr(equals + 1);
      if (key != "length") fail(shown + ": unknown quantity " + in_quotes(key) + " (only length=m|cm|mm)");
      if (seen_length_) fail(shown + ": length is given twice; give it once");
      seen_length_ = true;
      if (value == "m") {
        scale_ = 1.0;
      } else if (value == "cm") {
        scale_ = 0.01;
      } else if (value == "mm") {
        scale_ = 0.001;
      } else {
        fail(shown + ": length = " + in_quotes(value) + ": must be m, cm or mm");
      }
      unit_ = value;
      begin = end == std::string::npos ? end : items.find_first_not_of(' ', end);
    }
  }

  void header(const std::vector<std::string>& names) {
    header_line_ = line_;
    std::map<std::string, int> index;
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (names[i].empty()) fail("header: field " + std::to_string(i + 1) + " has an empty column name");
      if (const std::size_t bad = invalid_utf8_at(names[i]); bad != std::string::npos) {
        fail("header: column " + in_quotes(names[i]) + ": invalid UTF-8 at byte " + std::to_string(bad) +
             " (column names become attribute names written into result.json: they must be UTF-8)");
      }
      const auto [it, fresh] = index.emplace(names[i], static_cast<int>(i));
      if (!fresh) {
        fail("header: column " + in_quotes(names[i]) + " appears twice (fields " + std::to_string(it->second + 1) +
             " and " + std::to_string(i + 1) + ")");
      }
    }
    columns_ = names;
    const std::string shown = "header " + in_quotes(join(names, ",")) + ": ";
    const auto find = [&](const std::string& name) {
      const auto it = index.find(name);
      return it == index.end() ? -1 : it->second;
    };
    // A group of columns that must be complete: its indices, or empty when none is present.
    const auto group = [&](const std::vector<std::string>& members, const std::string& what) {
      std::vector<int> found;
      std::vector<std::string> missing;
      for (const std::string& m : members) {
        const int i = find(m);
        if (i < 0) missing.push_back(m); else found.push_back(i);
      }
      if (!found.empty() && !missing.empty()) {
        fail(shown + what + " needs all of " + join(members) + " (missing " + join(missing) + ")");
      }
      return found;
    };
    layout_.x = find("x");
    layout_.y = find("y");
    layout_.z = find("z");
    layout_.weight = find("weight");
    if (layout_.x < 0 || layout_.y < 0) {
      fail(shown + "needs position columns x and y (then optionally z); the first row that is not a comment is "
                   "the header");
    }
    layout_.quaternion = group(kQuaternion, "a quaternion");
    layout_.matrix = group(kMatrix, "a rotation matrix");
    if (!layout_.quaternion.empty() && !layout_.matrix.empty()) {
      fail(shown + "has both a quaternion (qw, qx, qy, qz) and a rotation matrix (r11 .. r33): give one orientation");
    }
    if ((!layout_.quaternion.empty() || !layout_.matrix.empty()) && layout_.z < 0) {
      fail(shown + "an orientation needs a z column (a full pose is x, y, z, qw, qx, qy, qz)");
    }
    std::vector<std::string> reserved = {"x", "y", "z", "weight"};
    reserved.insert(reserved.end(), kQuaternion.begin(), kQuaternion.end());
    reserved.insert(reserved.end(), kMatrix.begin(), kMatrix.end());
    for (const auto& [name, i] : index) {  // std::map: alphabetical
      if (std::find(reserved.begin(), reserved.end(), name) == reserved.end()) layout_.attributes.emplace_back(name, i);
    }
    attributes_.resize(layout_.attributes.size());
    values_.resize(names.size());
  }

  void row(const std::vector<std::string>& fields) {
    if (fields.size() != columns_.size()) {
      fail(std::to_string(fields.size()) + " fields for " + std::to_string(columns_.size()) + " columns (" +
           join(columns_) + "): every row needs one value per column");
    }
    if (rows_ == kPointListMaxSamples) {
      fail("more than " + std::to_string(kPointListMaxSamples) + " samples: at most " +
           std::to_string(kPointListMaxSamples) + " are allowed");
    }
    for (std::size_t c = 0; c < fields.size(); ++c) {
      const std::string shown = "column " + in_quotes(columns_[c]) + " = " + in_quotes(fields[c]);
      if (!parse_number(fields[c], values_[c])) fail(shown + ": must be a number");
      if (!std::isfinite(values_[c])) fail(shown + ": must be finite");
    }
    const auto at = [&](int i) { return values_[static_cast<std::size_t>(i)]; };
    // Positions stay in the file's unit until the whole file is read: the units line may stand
    // anywhere, and it applies to every row (samples() scales them).
    poses_.push_back(at(layout_.x));
    poses_.push_back(at(layout_.y));
    if (layout_.z >= 0) poses_.push_back(at(layout_.z));
    if (!layout_.quaternion.empty()) quaternion();
    if (!layout_.matrix.empty()) matrix();
    if (layout_.weight >= 0) {
      const double w = at(layout_.weight);
      if (w < 0.0) fail("column \"weight\" = " + in_quotes(fields[static_cast<std::size_t>(layout_.weight)]) + ": must be >= 0");
      weights_.push_back(w);
    }
    for (std::size_t a = 0; a < layout_.attributes.size(); ++a) attributes_[a].push_back(at(layout_.attributes[a].second));
    ++rows_;
  }

  void quaternion() {
    Eigen::Vector4d q;
    for (int k = 0; k < 4; ++k) q[k] = values_[static_cast<std::size_t>(layout_.quaternion[static_cast<std::size_t>(k)])];
    const double norm = q.norm();
    if (!(std::abs(norm - 1.0) <= 1e-6)) {
      fail("quaternion (qw, qx, qy, qz) = (" + number(q[0]) + ", " + number(q[1]) + ", " + number(q[2]) + ", " +
           number(q[3]) + ") has norm " + number(norm) + ": must be 1 within 1e-6");
    }
    for (int k = 0; k < 4; ++k) poses_.push_back(q[k] / norm);
  }

  void matrix() {
    Eigen::Matrix3d r;
    for (int k = 0; k < 9; ++k) r(k / 3, k % 3) = values_[static_cast<std::size_t>(layout_.matrix[static_cast<std::size_t>(k)])];
    std::string shown = "rotation matrix (r11 .. r33) = [";
    for (int i = 0; i < 3; ++i) {
      shown += std::string(i ? ", " : "") + "[" + number(r(i, 0)) + ", " + number(r(i, 1)) + ", " + number(r(i, 2)) + "]";
    }
    shown += "]";
    const double error = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (!(error <= 1e-6)) {
      fail(shown + ": must be orthonormal within 1e-6 (max |R^T R - I| = " + number(error) + ")");
    }
    const double det = r.determinant();
    if (det < 0.0) fail(shown + ": det = " + number(det) + ": must be +1 (a rotation, not a reflection)");
    Eigen::Quaterniond q(r);
    q.normalize();
    // q and -q are the same rotation: the one with qw >= 0, so that equal matrices give equal poses.
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();
    poses_.insert(poses_.end(), {q.w(), q.x(), q.y(), q.z()});
  }

  SampleSet samples() {
    if (!weights_.empty() && std::all_of(weights_.begin(), weights_.end(), [](double w) { return w == 0.0; })) {
      fail_file("column \"weight\": every weight is 0: at least one must be > 0");
    }
    // Weighted means divide by the sum: finite weights may still overflow it.
    if (!weights_.empty() && !std::isfinite(std::accumulate(weights_.begin(), weights_.end(), 0.0))) {
      fail_file("column \"weight\": the weights sum beyond the range of doubles (to inf): scale them down (only "
                "their ratios matter)");
    }
    SampleSet set;
    set.coordinates = {"x", "y"};
    if (layout_.z >= 0) set.coordinates.push_back("z");
    const bool oriented = layout_.pose_columns() == 7;
    if (oriented) set.coordinates.insert(set.coordinates.end(), kQuaternion.begin(), kQuaternion.end());
    set.unit = "m";
    const Eigen::Index n = static_cast<Eigen::Index>(rows_), columns = layout_.pose_columns();
    set.poses = Eigen::Map<const SampleSet::RowMatrix>(poses_.data(), n, columns);
    set.poses.leftCols(layout_.z >= 0 ? 3 : 2) *= scale_;
    set.weights = std::move(weights_);
    std::vector<std::string> names;
    for (std::size_t a = 0; a < layout_.attributes.size(); ++a) {
      set.attributes[layout_.attributes[a].first] = Eigen::Map<const SampleSet::RowMatrix>(attributes_[a].data(), n, 1);
      names.push_back(layout_.attributes[a].first);
    }
    set.info = {{"file", path_},
                {"samples", rows_},
                {"length_unit", unit_},
                {"orientation", !layout_.quaternion.empty() ? "quaternion" : !layout_.matrix.empty() ? "matrix" : "none"},
                {"weighted", !set.weights.empty()},
                {"attributes", names}};
    return set;
  }

  std::string path_;
  long long line_ = 0, header_line_ = 0, units_line_ = 0, rows_ = 0;
  bool seen_length_ = false;  // the units line named the length
  double scale_ = 1.0;
  std::string unit_ = "m";
  std::vector<std::string> columns_;
  Layout layout_;
  std::vector<double> values_;   // the current row
  std::vector<double> poses_;    // row-major, layout_.pose_columns() per sample, metres
  std::vector<double> weights_;
  std::vector<std::vector<double>> attributes_;  // per attribute column, one value per sample
};

// An absolute path as is; a relative one against the current directory when something of that
// name is there (read_point_list then refuses it if it is not a regular file), else against
// hapsyn's share directory (find_data_file, whose error lists the places tried).
std::string resolve(const std::string& value) {
  const std::string shown = "options.file = " + in_quotes(value);
  if (value.empty()) throw Error(kName, shown + ": must name a file");
  const fs::path p(value);
  boost::system::error_code ec;
  if (p.is_absolute()) {
    if (fs::status(p, ec).type() == fs::file_not_found) throw Error(kName, shown + ": no such file");
    return p.string();
  }
  const fs::path here = fs::current_path() / p;
  const fs::file_type type = fs::status(here, ec).type();
  if (type != fs::file_not_found && type != fs::status_error) return here.lexically_normal().string();
  return find_data_file(kName, "file", value);
}

}  // namespace

SampleSet read_point_list(const std::string& path) { return Reader(path).read(); }

PointList::PointList(const PointListOptions& options) : path_(resolve(options.file)), samples_(read_point_list(path_)) {}

std::vector<std::string> PointList::attribute_names() const {
  std::vector<std::string> names;
  for (const auto& entry : samples_.attributes) names.push_back(entry.first);
  return names;
}

SampleSet PointList::build(const SceneRequest& request) const {
  SampleSet set;
  set.coordinates = samples_.coordinates;
  set.unit = samples_.unit;
  set.poses = samples_.poses;
  set.weights = samples_.weights;
  set.info = samples_.info;
  for (const std::string& name : request.attributes) {
    const auto it = samples_.attributes.find(name);
    if (it == samples_.attributes.end()) {
      const std::vector<std::string> names = attribute_names();
      throw Error(kName, "per-sample attribute '" + name + "' requested: " + path_ + " has no such column (" +
                             (names.empty() ? std::string("it has no attribute columns")
                                            : "attribute columns: " + join(names)) +
                             ")");
    }
    set.attributes[name] = it->second;
  }
  return set;
}

}  // namespace hapsyn::plugins
