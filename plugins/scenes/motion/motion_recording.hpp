#pragma once
/// \file
/// Readers of recorded hand motion for the motion scene: the hapsyn-motion CSV format, BVH
/// motion capture files, and folders holding both. Each file becomes one Recording: the pose
/// of the hand (palm) relative to the shoulder over time, in SI units.
///
/// ## The hapsyn-motion CSV format (version 1)
///
///     # hapsyn-motion 1
///     # subject: S01
///     # activity: reaching
///     # unit: m
///     # time_unit: s
///     time,x,y,z,qw,qx,qy,qz
///     0.000000,0.1,0.2,-0.3,1,0,0,0
///     0.010000,0.1,0.2,-0.3,1,0,0,0
///
/// - **Header comments** (optional, before the column row): lines `# key: value` with the keys
///   `subject`, `activity` (labels), `unit` = `m` | `cm` | `mm` (of the positions; default m)
///   and `time_unit` = `s` | `ms` (default s); each key at most once, with a non-empty value.
///   An unknown key is refused (the message lists the known ones); so is any other `#` line
///   before the column row, except the version line `# hapsyn-motion N`, which is optional
///   but must say N = 1.
/// - **Blank lines** are skipped anywhere; after the column row, lines starting with `#` are
///   free comments.
/// - **The column row** names the columns, comma-separated, in any order: `time`, `x`, `y`,
///   `z` and the hand orientation, either as a unit quaternion `qw`, `qx`, `qy`, `qz` or as
///   a rotation matrix `r11`, `r12`, `r13`, `r21`, `r22`, `r23`, `r31`, `r32`, `r33`
///   (row-major). Missing, unknown or repeated columns, or both orientation forms, are
///   refused.
/// - **Rows**: one field per column; each field a finite number, the whole field (as strtod
///   reads it; spaces and tabs around it are ignored; no quoting). Positions are the palm in
///   the shoulder frame; the orientation rotates hand-frame vectors into the shoulder frame.
///   A quaternion's norm must be 1 within 1e-3 (it is then normalised); a rotation matrix
///   must be orthonormal (max |R^T R - I| entry) with det +1, both within 1e-4.
/// - `time` strictly increasing; at least 2 rows.
///
/// ## BVH files
///
/// The HIERARCHY (`ROOT`/`JOINT` name `{` `OFFSET` x y z `CHANNELS` n names... children...
/// `End Site { OFFSET x y z }` `}`; several ROOTs allowed), then `MOTION`, `Frames: N`,
/// `Frame Time: dt` (> 0) and exactly N non-blank frame lines, each with one finite number per
/// channel in declaration order. Channels are Xposition, Yposition, Zposition (file units) and
/// Xrotation, Yrotation, Zrotation (degrees), any subset and order, each at most once per
/// joint. Tokens are separated by spaces or tabs; CRLF line ends are accepted.
///
/// Kinematics (the common convention of CMU's files and Blender's importer): a joint's local
/// transform is the translation by OFFSET plus its position channels' values, times its
/// rotations in the order the CHANNELS line lists them (intrinsic: "Zrotation Xrotation
/// Yrotation" gives Rz * Rx * Ry); a joint's global transform is its parent's global times its
/// local (a root's parent is the world).
///
/// The result is the hand joint relative to the *shoulder frame*: the frame at the shoulder
/// joint's global position, oriented like the global frame of the shoulder joint's parent
/// (the torso side, so that the arm's own motion does not turn the reference; the world for
/// a root shoulder). With R_p the parent's global rotation, p_s the shoulder's and p_h, R_h the
/// hand's global position and rotation: position = scale * R_p^T (p_h - p_s), orientation =
/// R_p^T R_h. The body's and clavicle's motion thus enter only through R_p. Frame i has time
/// i * dt.
///
/// ## Labels
///
/// subject: the CSV `# subject:` if given; else, for a file found in a subfolder by
/// read_recordings, the first folder below the root (root/S01/a/reaching.csv -> "S01"); else
/// the file's stem. activity: the CSV `# activity:` if given, else the file's stem.
///
/// ## Limits
///
/// Files must be regular files (a directory, FIFO, socket or device is refused before
/// opening, so a FIFO never blocks) of at most kMotionMaxFileBytes, with lines of at most
/// kMotionMaxLineBytes. Lines may end in LF or CRLF; a leading UTF-8 byte order mark is
/// ignored. Messages quote at most 60 characters of an offending text.
#include <Eigen/Core>

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

namespace hapsyn::plugins::motion {

/// One recorded trajectory of the hand (palm) relative to the shoulder.
struct Recording {
  std::string file;              ///< path as read
  std::string subject, activity;  ///< labels (see "Labels" above)
  Eigen::VectorXd time;          ///< n, [s], strictly increasing, n >= 2
  Eigen::MatrixXd position;      ///< n x 3 [m], the palm in the recording's shoulder frame
  /// n x 4 (w, x, y, z), unit: the rotation hand frame -> shoulder frame. CSV quaternions keep
  /// the recorded sign; quaternions derived from matrices (CSV r11.., BVH) take the sign that
  /// continues the previous row (q_i . q_{i-1} >= 0; the first with w >= 0), so a trajectory
  /// has no sign jumps.
  Eigen::MatrixXd quaternion;
  std::vector<int> line;  ///< per row: the 1-based line of the file it came from
};

/// Largest file the readers read [bytes] (2 GiB), checked before opening and while reading.
constexpr std::uintmax_t kMotionMaxFileBytes = std::uintmax_t{2} << 30;
/// Longest line the readers accept [bytes] (1 MiB), without the line end.
constexpr std::size_t kMotionMaxLineBytes = std::size_t{1} << 20;
/// Most files read_recordings reads from one folder.
constexpr std::size_t kMotionMaxFiles = 100000;

/// Reads a hapsyn-motion CSV file (format above). Labels: header, else the file's stem.
/// \param path the file (used as is in messages and Recording::file)
/// \throws Error("motion: <path>[:<line>]: <what>: <rule>") naming the value and the rule: not a
///         regular file or too large, a line too long, a bad header comment (unknown key, bad
///         unit, repeated key, version != 1), a bad column row (missing, unknown, repeated
///         columns, both orientation forms), a row with a wrong field count, a field that is
///         empty, not a number or not finite, a quaternion norm off by > 1e-3, a rotation
///         matrix that is not a rotation within 1e-4, time not strictly increasing (both lines
///         and values), fewer than 2 rows.
Recording read_motion_csv(const std::string& path);

/// Which joints of a BVH skeleton are the shoulder and the hand, and the file's length unit.
struct BvhOptions {
  std::string shoulder_joint = "RightArm";  ///< the joint at the shoulder (the upper arm's joint)
  std::string hand_joint = "RightHand";     ///< the joint at the palm; must be below the shoulder
  double scale = 0.01;                      ///< [m per file unit]: 0.01 for centimetres; > 0, finite
};

/// Reads a BVH file (format and kinematics above). Labels: the file's stem.
/// \param path the file (used as is in messages and Recording::file)
/// \throws Error("motion: <path>[:<line>]: <what>: <rule>"): not a regular file or too large, a
///         line too long, a structural error (unbalanced braces, a missing or misplaced keyword,
///         a bad OFFSET or CHANNELS, an unknown or repeated channel, a repeated joint name), a
///         bad Frames or Frame Time (<= 0, not finite), a frame line with the wrong number of
///         values or a value that is not a finite number, fewer or more frame lines than
///         Frames says, fewer than 2 frames; a shoulder or hand joint the file lacks (listing
///         the joints it has, with a close name if any); a hand that is not below the shoulder;
///         options.scale not > 0 and finite.
Recording read_bvh(const std::string& path, const BvhOptions& options);

/// Reads one file or every file of a folder.
/// \param path a file: read by its extension (.csv: read_motion_csv, .bvh: read_bvh; case
///        ignored; other extensions refused). A folder: every *.csv and *.bvh below it,
///        recursively, in the order of their paths relative to `path` (byte-wise), each labelled
///        as described above. Symbolic links to folders are not followed (a link loop cannot
///        hang the reader); links to files are read.
/// \param bvh the options of the BVH files
/// \returns one Recording per file; Recording::file is `path` joined with the relative path
/// \throws Error("motion: <path>: ...") for a path that does not exist or is neither a file nor
///         a folder, an unknown extension, a folder without .csv/.bvh files, more than
///         kMotionMaxFiles files, a folder that cannot be listed; and the readers' errors.
std::vector<Recording> read_recordings(const std::string& path, const BvhOptions& bvh);

namespace detail {

/// A text file read line by line within the limits above (shared by the readers).
class TextFile {
 public:
  /// Checks that `path` is a regular file of at most kMotionMaxFileBytes, then opens it.
  /// \throws Error("motion: <path>: ...") otherwise
  explicit TextFile(std::string path);

  /// The next line, without its line end ("\n" or "\r\n") or a leading UTF-8 byte order mark.
  /// \returns false at the end of the file
  /// \throws Error for a line longer than kMotionMaxLineBytes, a file that grew beyond
  ///         kMotionMaxFileBytes, or a read error
  bool next(std::string& text);

  const std::string& path() const { return path_; }
  /// The 1-based number of the line last returned by next() (0 before the first).
  int line() const { return line_; }
  /// \throws Error("motion: <path>:<line>: <what>") for the current line
  [[noreturn]] void fail(const std::string& what) const { fail_at(line_, what); }
  /// \throws Error("motion: <path>:<line>: <what>") for the given line
  [[noreturn]] void fail_at(int line, const std::string& what) const;
  /// \throws Error("motion: <path>: <what>") for the whole file
  [[noreturn]] void fail_file(const std::string& what) const;

 private:
  std::string path_;
  std::ifstream in_;
  std::vector<char> buffer_;
  int line_ = 0;
  std::uintmax_t consumed_ = 0;
};

/// `text` in double quotes, with JSON escapes (for messages).
std::string quoted(const std::string& text);

/// The rows a reader collected (times [s]; positions 3 and quaternions 4 per row, row-major;
/// lines) as a Recording of `file`; labels are left to the caller.
Recording recording_of(const std::string& file, const std::vector<double>& times, const std::vector<double>& positions,
                       const std::vector<double>& quaternions, const std::vector<int>& lines);

/// The Recording of `path` by its extension; `subject` replaces the stem as the fallback subject
/// when not empty (a CSV header subject still wins).
Recording read_file(const std::string& path, const BvhOptions& bvh, const std::string& subject);

/// The CSV reader with a fallback subject (empty: the file's stem).
Recording read_motion_csv(const std::string& path, const std::string& subject);

/// The unit quaternion (w, x, y, z) of rotation `r` with the sign that continues `previous`
/// (q . previous >= 0), or with w >= 0 when there is no previous row (nullptr).
Eigen::Vector4d quaternion_continuing(const Eigen::Matrix3d& r, const Eigen::Vector4d* previous);

}  // namespace detail
}  // namespace hapsyn::plugins::motion
