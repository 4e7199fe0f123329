#pragma once
/// \file
/// The point_list scene: samples read from a CSV file (positions, optional orientations as
/// quaternions or rotation matrices, optional per-sample weights and numeric attributes). The
/// format is specified in this folder's README.md.
#include <hapsyn/options.hpp>
#include <hapsyn/scene.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// Largest file the scene reads [bytes] (1 GiB): a bounded read, checked before the file is
/// opened and again while reading (a file that grows meanwhile is refused too).
constexpr std::uintmax_t kPointListMaxBytes = std::uintmax_t{1} << 30;
/// Largest number of samples (data rows) the scene holds: a memory guard (at most 7 pose
/// numbers plus the weight and attributes per sample).
constexpr long long kPointListMaxSamples = 10000000;

/// The options of point_list (`hapsyn describe point_list`).
struct PointListOptions {
  std::string file{};  ///< path of the CSV file

  static void declare(OptionDeclarations<PointListOptions>& d) {
    d.describe(
        "Samples read from a CSV file: a header row of column names; positions x, y (2-D) or x, y, z; optionally "
        "an orientation as a unit quaternion qw, qx, qy, qz or a rotation matrix r11 .. r33 (3-D; the samples "
        "are then poses x, y, z, qw, qx, qy, qz); an optional weight column (per-sample weights of averaging "
        "metrics); any other numeric column is a per-sample attribute of that name. '#' lines are comments; "
        "'# units: length=mm' (m, cm, mm; default m) scales the positions to metres. Format: the plugin's "
        "README.md.");
    d.add(&PointListOptions::file, "file", "point_list/example_planar.csv",
          "The CSV file: an absolute path, or relative to the current directory (then to hapsyn's share "
          "directory, which holds the default example). At most 1 GiB; must be a regular file.");
  }
};

/// The samples of a point_list CSV file, read and checked (see the README for the format).
/// \param path the file as found (used as is in messages)
/// \returns poses {"x", "y"}, {"x", "y", "z"} or {"x", "y", "z", "qw", "qx", "qy", "qz"} in
///          metres (unit "m"), every non-pose column as a one-column attribute, the weight
///          column (if any) as SampleSet::weights, `info` with the file, unit and counts.
/// \throws Error("point_list: <path>[:<line>]: ...") naming the line, column, value and rule:
///         not a regular file (a directory, FIFO, device), larger than kPointListMaxBytes,
///         empty (no header), no data rows, more than kPointListMaxSamples rows, an empty or
///         duplicate column name, a column set of unknown shape (no x or y; an incomplete or
///         doubled orientation; an orientation without z), a row with another number of fields
///         than the header, a field that is not a number or not finite, a quaternion whose
///         norm differs from 1 by more than 1e-6, a rotation matrix that is not orthonormal
///         within 1e-6 or has det -1, a negative weight or all weights zero, a malformed or
///         repeated units line.
SampleSet read_point_list(const std::string& path);

/// Samples read from a CSV file (read_point_list). The file is read once, when the scene is
/// made, so that a bad file is reported at load.
///
/// Thread safety: immutable after construction; build() is const and thread-safe.
class PointList final : public Scene {
 public:
  using Options = PointListOptions;

  /// Resolves options.file (absolute; else against the current directory; else against
  /// hapsyn's share directory) and reads it.
  /// \throws Error("point_list: options.file = \"...\": must name a file") for an empty name,
  ///         Error("point_list: options.file = \"...\": no such file ...") when no candidate
  ///         exists, and read_point_list's errors.
  explicit PointList(const PointListOptions& options);

  /// The samples, with exactly the requested attributes (columns of the file).
  /// \throws Error("point_list: per-sample attribute 'a' requested: <path> has no such column
  ///         ...") for an attribute the file lacks.
  SampleSet build(const SceneRequest& request) const override;

  /// The file as found (absolute when it was found relative to a directory).
  const std::string& path() const { return path_; }
  /// The file's attribute columns, in alphabetical order.
  std::vector<std::string> attribute_names() const;

 private:
  std::string path_;
  SampleSet samples_;  // every attribute column; build() hands out the requested ones
};

}  // namespace hapsyn::plugins
