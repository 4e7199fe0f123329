// The BVH reader: the skeleton (HIERARCHY), then each frame reduced at once to the hand pose in
// the shoulder frame, so that memory grows with the frames, not with the skeleton's channels.
#include "motion_recording.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/json.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>

namespace hapsyn::plugins::motion {
namespace {

// Joints a skeleton may have: every frame walks them all, and a file of 100,000 nested JOINT
// blocks once took 15 s to read (bounded before the work, like the motion scene's sample count).
constexpr std::size_t kMaxBvhJoints = 1000;


constexpr const char* kComponent = "motion";
const std::array<const char*, 6> kChannelNames = {"Xposition", "Yposition", "Zposition",
                                                   "Xrotation", "Yrotation", "Zrotation"};
constexpr double kDegree = EIGEN_PI / 180.0;

// One channel: kind 0..2 the position along x, y, z; 3..5 the rotation about x, y, z.
struct Channel {
  int kind = 0;
  bool rotation() const { return kind >= 3; }
  int axis() const { return kind % 3; }
};

struct Joint {
  std::string name;
  int parent = -1;
  int line = 0;
  bool has_offset = false, has_channels = false, has_children = false;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  std::vector<Channel> channels;
  std::size_t first_value = 0;  // where its channels start in a frame line
};

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

void tokenize(const std::string& text, std::vector<std::string>& tokens) {
  tokens.clear();
  std::size_t i = 0;
  while (true) {
    while (i < text.size() && is_space(text[i])) ++i;
    if (i == text.size()) return;
    const std::size_t begin = i;
    while (i < text.size() && !is_space(text[i])) ++i;
    tokens.push_back(text.substr(begin, i - begin));
  }
}

// The whole token must be the number (strtod alone accepts "1.5abc" as 1.5) and finite: a decimal
// number as BVH writers print them ("-12.5", "1e-3", "+0.5"). std::from_chars, unlike strtod,
// takes neither hexadecimal floats ("0x1p3") nor the locale's decimal separator.
bool finite_number(const char* begin, const char* end, double& value) {
  if (begin != end && *begin == '+' && begin + 1 != end && begin[1] != '-') ++begin;
  const auto [stop, error] = std::from_chars(begin, end, value);
  return error == std::errc() && stop == end && std::isfinite(value);
}


class BvhReader {
 public:
  BvhReader(const std::string& path, const BvhOptions& options) : file_(path), options_(options) {}

  Recording read() {
    if (!(options_.scale > 0.0) || !std::isfinite(options_.scale)) {
      throw Error(kComponent, file_.path() + ": BVH scale = " + std::to_string(options_.scale) +
                                  ": must be > 0 and finite (metres per file unit)");
    }
    hierarchy();
    chain();
    motion_header();
    frames();
    return recording();
  }

 private:
  // ---- HIERARCHY ----

  // The next token of the hierarchy and its line; false at the end of the file.
  bool token(std::string& text) {
    while (next_token_ == tokens_.size()) {
      if (!file_.next(line_text_)) return false;
      tokenize(line_text_, tokens_);
      next_token_ = 0;
    }
    text = tokens_[next_token_++];
    return true;
  }

  std::string expect_token(const std::string& what) {
    std::string text;
    if (!token(text)) file_.fail_file("ends inside the HIERARCHY, where " + what + " was expected");
    return text;
  }

  double offset_value(const std::string& joint) {
    const std::string text = expect_token("an OFFSET value of " + joint);
    double value = 0;
    if (!finite_number(text.c_str(), text.c_str() + text.size(), value)) {
      file_.fail("OFFSET of " + joint + ": value " + detail::quoted(text) + ": must be a finite number");
    }
    return value;
  }

  void hierarchy() {
    std::string text;
    if (!token(text)) file_.fail_file("is empty: a BVH file starts with HIERARCHY");
    if (text != "HIERARCHY") file_.fail(detail::quoted(text) + ": a BVH file starts with HIERARCHY");
    // The open blocks: joint indices, -1 for an End Site (no recursion: depth is the file's).
    std::vector<int> open;
    std::vector<int> open_lines;
    while (true) {
      if (!token(text)) {
        if (open.empty()) file_.fail_file("has no MOTION section after the HIERARCHY");
        file_.fail_file(block_name(open.back(), open_lines.back()) + " is not closed (the file ends): unbalanced braces");
      }
      if (text == "MOTION") {
        if (!open.empty()) {
          file_.fail("MOTION before " + block_name(open.back(), open_lines.back()) + " is closed: unbalanced braces");
        }
        if (next_token_ != tokens_.size()) file_.fail("MOTION must stand alone on its line");
        break;
      }
      if (open.empty()) {
        if (text != "ROOT") file_.fail(detail::quoted(text) + ": expected ROOT (a skeleton) or MOTION at the top level");
        begin_joint(-1, open, open_lines);
        continue;
      }
      const int current = open.back();
      if (text == "}") {
        if (current >= 0 && !joints_[current].has_offset) file_.fail("joint " + joints_[current].name + " has no OFFSET");
        if (current < 0 && !end_site_offset_) file_.fail("End Site (line " + std::to_string(open_lines.back()) + ") has no OFFSET");
        open.pop_back();
        open_lines.pop_back();
      } else if (text == "OFFSET") {
        offset(current);
      } else if (text == "CHANNELS" && current >= 0) {
        channels(joints_[current]);
      } else if (text == "JOINT" && current >= 0) {
        joints_[current].has_children = true;
        begin_joint(current, open, open_lines);
      } else if (text == "End" && current >= 0) {
        joints_[current].has_children = true;
        const int line = file_.line();
        if (expect_token("\"Site\" after End") != "Site") file_.fail("expected \"End Site\"");
        if (expect_token("\"{\" after End Site") != "{") file_.fail("expected \"{\" after End Site");
        open.push_back(-1);
        open_lines.push_back(line);
        end_site_offset_ = false;
      } else {
        file_.fail(detail::quoted(text) + " inside " + block_name(current, open_lines.back()) + ": expected " +
                   (current >= 0 ? "OFFSET, CHANNELS, JOINT, End Site or }" : "OFFSET or }"));
      }
    }
    if (total_values_ == 0) file_.fail("the skeleton has no channels: there is no motion to read");
  }

  std::string block_name(int joint, int line) const {
    return joint >= 0 ? "joint " + joints_[joint].name + " (line " + std::to_string(joints_[joint].line) + ")"
                      : "End Site (line " + std::to_string(line) + ")";
  }

  void begin_joint(int parent, std::vector<int>& open, std::vector<int>& open_lines) {
    const int line = file_.line();
    const char* keyword = parent < 0 ? "ROOT" : "JOINT";
    std::string name;
    if (!token(name) || file_.line() != line || name == "{") {
      file_.fail_at(line, std::string(keyword) + " without a name: the name follows on the same line");
    }
    if (expect_token("\"{\" after " + name) != "{") file_.fail("expected \"{\" after " + std::string(keyword) + " " + name);
    if (joints_.size() >= kMaxBvhJoints) {
      file_.fail_at(line, std::string(keyword) + " " + name + ": more than " + std::to_string(kMaxBvhJoints) +
                              " joints (a motion-capture skeleton has a few hundred at most; see docs/limits.md)");
    }
    const auto [first, fresh] = joint_index_.emplace(name, static_cast<int>(joints_.size()));
    if (!fresh) {
      file_.fail_at(line, "joint name " + detail::quoted(name) + " used again (first on line " +
                              std::to_string(joints_[static_cast<std::size_t>(first->second)].line) +
                              "): joint names must be unique");
    }
    Joint joint;
    joint.name = name;
    joint.parent = parent;
    joint.line = line;
    joints_.push_back(joint);
    open.push_back(static_cast<int>(joints_.size()) - 1);
    open_lines.push_back(line);
  }

  void offset(int current) {
    const std::string owner = current >= 0 ? joints_[current].name : "End Site";
    bool& given = current >= 0 ? joints_[current].has_offset : end_site_offset_;
    if (given) file_.fail("second OFFSET of " + owner + ": give it once");
    if (current >= 0 && joints_[current].has_children) {
      file_.fail("OFFSET of " + owner + " after its children: OFFSET and CHANNELS precede the children");
    }
    given = true;
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v[i] = offset_value(owner);
    if (current >= 0) joints_[current].offset = v;
  }

  void channels(Joint& joint) {
    if (joint.has_channels) file_.fail("second CHANNELS of " + joint.name + ": give it once");
    if (joint.has_children) file_.fail("CHANNELS of " + joint.name + " after its children: OFFSET and CHANNELS precede the children");
    joint.has_channels = true;
    const std::string count = expect_token("the channel count of " + joint.name);
    if (count.size() != 1 || count[0] < '0' || count[0] > '6') {
      file_.fail("CHANNELS count of " + joint.name + " = " + detail::quoted(count) +
                 ": must be an integer 0 to 6 (each channel at most once)");
    }
    joint.first_value = total_values_;
    for (int i = 0; i < count[0] - '0'; ++i) {
      const std::string name = expect_token("a channel name of " + joint.name);
      const auto known = std::find(kChannelNames.begin(), kChannelNames.end(), name);
      if (known == kChannelNames.end()) {
        file_.fail("unknown channel " + detail::quoted(name) + " of " + joint.name +
                   ": the channels are Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation");
      }
      const Channel channel{static_cast<int>(known - kChannelNames.begin())};
      for (const Channel& c : joint.channels) {
        if (c.kind == channel.kind) file_.fail("channel " + name + " of " + joint.name + " given twice: give each once");
      }
      joint.channels.push_back(channel);
    }
    total_values_ += joint.channels.size();
  }

  // ---- the shoulder and the hand ----

  int find_joint(const std::string& role, const std::string& name) const {
    for (std::size_t i = 0; i < joints_.size(); ++i) {
      if (joints_[i].name == name) return static_cast<int>(i);
    }
    std::string list;
    std::vector<std::string> names;
    for (const Joint& j : joints_) {
      list += (list.empty() ? "" : ", ") + j.name;
      names.push_back(j.name);
    }
    const std::string close = nearest_name(name, names);
    file_.fail_file(role + " joint " + detail::quoted(name) + " not found" +
                    (close.empty() ? "" : " (did you mean " + detail::quoted(close) + "?)") + ": the file's joints are " +
                    list);
  }

  // The joints from a root down to the hand; the shoulder's place in it.
  void chain() {
    const int shoulder = find_joint("shoulder", options_.shoulder_joint);
    const int hand = find_joint("hand", options_.hand_joint);
    for (int j = hand; j >= 0; j = joints_[j].parent) chain_.insert(chain_.begin(), j);
    const auto at = std::find(chain_.begin(), chain_.end(), shoulder);
    if (at == chain_.end() || hand == shoulder) {
      std::string path;
      for (int j : chain_) path += (path.empty() ? "" : " > ") + joints_[j].name;
      file_.fail_file("hand joint " + detail::quoted(options_.hand_joint) + " is not below the shoulder joint " +
                      detail::quoted(options_.shoulder_joint) + ": the hand must be a descendant of the shoulder (the " +
                      "hand's chain is " + path + ")");
    }
    shoulder_in_chain_ = static_cast<std::size_t>(at - chain_.begin());
  }

  // ---- MOTION ----

  // The next non-blank line's tokens; false at the end of the file.
  bool next_line() {
    while (file_.next(line_text_)) {
      tokenize(line_text_, tokens_);
      if (!tokens_.empty()) return true;
    }
    return false;
  }

  void motion_header() {
    if (!next_line()) file_.fail_file("ends after MOTION: expected \"Frames: N\"");
    if (tokens_.size() != 2 || tokens_[0] != "Frames:") file_.fail("expected \"Frames: N\" after MOTION");
    char* end = nullptr;
    errno = 0;
    const long long frames = std::strtoll(tokens_[1].c_str(), &end, 10);
    if (end != tokens_[1].c_str() + tokens_[1].size() || errno != 0 || frames < 0 || tokens_[1][0] == '+') {
      file_.fail("Frames: " + detail::quoted(tokens_[1]) + ": must be a whole number >= 0");
    }
    frames_ = frames;
    frames_line_ = file_.line();
    if (!next_line()) file_.fail_file("ends after Frames: expected \"Frame Time: dt\"");
    if (tokens_.size() != 3 || tokens_[0] != "Frame" || tokens_[1] != "Time:") {
      file_.fail("expected \"Frame Time: dt\" after Frames");
    }
    if (!finite_number(tokens_[2].c_str(), tokens_[2].c_str() + tokens_[2].size(), frame_time_) || !(frame_time_ > 0)) {
      file_.fail("Frame Time: " + detail::quoted(tokens_[2]) + ": must be a finite number > 0 [s]");
    }
    if (frames_ < 2) file_.fail_at(frames_line_, "Frames: " + std::to_string(frames_) + ": at least 2 frames are required");
  }

  void frames() {
    std::vector<double> values(total_values_);
    long long read = 0;
    while (file_.next(line_text_)) {
      if (!frame_values(values)) continue;  // blank
      if (read == frames_) {
        file_.fail("frame line beyond the " + std::to_string(frames_) + " frames that Frames: (line " +
                   std::to_string(frames_line_) + ") announces");
      }
      pose(values);
      times_.push_back(static_cast<double>(read) * frame_time_);
      lines_.push_back(file_.line());
      ++read;
    }
    if (read != frames_) {
      file_.fail_at(frames_line_, "Frames: " + std::to_string(frames_) + " but " + std::to_string(read) +
                                      " frame line(s) follow: the count must match the lines present");
    }
  }

  // Parses a frame line into `values`; false for a blank line.
  bool frame_values(std::vector<double>& values) const {
    std::size_t count = 0;
    const char* p = line_text_.c_str();
    const char* const end = p + line_text_.size();
    while (true) {
      while (p != end && is_space(*p)) ++p;
      if (p == end) break;
      const char* const begin = p;
      while (p != end && !is_space(*p)) ++p;
      double value = 0;
      if (count < values.size() && !finite_number(begin, p, value)) {
        file_.fail("value " + std::to_string(count + 1) + " (" + channel_name(count) + ") = " +
                   detail::quoted(std::string(begin, p)) + ": every value must be a finite number");
      }
      if (count < values.size()) values[count] = value;
      ++count;
    }
    if (count == 0) return false;
    if (count != values.size()) {
      file_.fail(std::to_string(count) + " values on the frame line: the HIERARCHY declares " +
                 std::to_string(values.size()) + " channels");
    }
    return true;
  }

  std::string channel_name(std::size_t value) const {
    for (const Joint& j : joints_) {
      if (value >= j.first_value && value < j.first_value + j.channels.size()) {
        return j.name + " " + kChannelNames[j.channels[value - j.first_value].kind];
      }
    }
    return "?";
  }

  // The hand in the shoulder frame for one frame: down the chain, global = parent global * local.
  void pose(const std::vector<double>& values) {
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // the global frame of the joint before
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    Eigen::Matrix3d parent_rotation = rotation;
    Eigen::Vector3d shoulder = position;
    for (std::size_t k = 0; k < chain_.size(); ++k) {
      const Joint& joint = joints_[chain_[k]];
      if (k == shoulder_in_chain_) parent_rotation = rotation;
      Eigen::Vector3d translation = joint.offset;
      Eigen::Matrix3d local = Eigen::Matrix3d::Identity();
      for (std::size_t c = 0; c < joint.channels.size(); ++c) {
        const Channel channel = joint.channels[c];
        const double value = values[joint.first_value + c];
        if (channel.rotation()) {
          // Intrinsic, in the listed order: R = R_c1 * R_c2 * ...
          local = local * Eigen::AngleAxisd(value * kDegree, Eigen::Vector3d::Unit(channel.axis())).toRotationMatrix();
        } else {
          translation[channel.axis()] += value;
        }
      }
      position += rotation * translation;
      rotation = rotation * local;
      if (k == shoulder_in_chain_) shoulder = position;
    }
    const Eigen::Vector3d p = options_.scale * (parent_rotation.transpose() * (position - shoulder));
    Eigen::Vector4d previous;
    if (!quaternions_.empty()) previous = Eigen::Map<const Eigen::Vector4d>(&quaternions_[quaternions_.size() - 4]);
    const Eigen::Vector4d q =
        detail::quaternion_continuing(parent_rotation.transpose() * rotation, quaternions_.empty() ? nullptr : &previous);
    positions_.insert(positions_.end(), p.data(), p.data() + 3);
    quaternions_.insert(quaternions_.end(), q.data(), q.data() + 4);
  }

  Recording recording() const {
    Recording r = detail::recording_of(file_.path(), times_, positions_, quaternions_, lines_);
    r.subject = r.activity = std::filesystem::path(file_.path()).stem().string();
    return r;
  }

  detail::TextFile file_;
  const BvhOptions& options_;
  std::string line_text_;
  std::vector<std::string> tokens_;  // of line_text_
  std::size_t next_token_ = 0;
  std::vector<Joint> joints_;
  std::map<std::string, int> joint_index_;  // name -> index in joints_
  bool end_site_offset_ = false;  // of the End Site being read
  std::size_t total_values_ = 0;
  std::vector<int> chain_;
  std::size_t shoulder_in_chain_ = 0;
  long long frames_ = 0;
  int frames_line_ = 0;
  double frame_time_ = 0;
  std::vector<double> times_, positions_, quaternions_;
  std::vector<int> lines_;
};

}  // namespace

Recording read_bvh(const std::string& path, const BvhOptions& options) { return BvhReader(path, options).read(); }

}  // namespace hapsyn::plugins::motion
