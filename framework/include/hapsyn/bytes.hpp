#pragma once
/// \file
/// Exact binary records for what ranks pass each other (hapsyn/cluster.hpp): task results,
/// shared pruning knowledge, broadcasts. Values are copied bit for bit (a double's bits, not
/// its decimal text), so a score found on another rank compares exactly as it would on this
/// one. The ranks of one job run the same binary on the same kind of machine, so byte order and
/// sizes agree.
#include <hapsyn/error.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

namespace hapsyn {

/// Appends fixed-size values, vectors of doubles and length-prefixed strings.
class ByteWriter {
 public:
  template <class T>
  ByteWriter& put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    append(&v, sizeof v);
    return *this;
  }
  ByteWriter& put_vector(const std::vector<double>& v) {
    put<std::uint64_t>(v.size());
    if (!v.empty()) append(v.data(), v.size() * sizeof(double));
    return *this;
  }
  ByteWriter& put_string(const std::string& s) {
    put<std::uint64_t>(s.size());
    append(s.data(), s.size());
    return *this;
  }
  /// The bytes written so far.
  const std::string& bytes() const {
    bytes_.resize(size_);
    return bytes_;
  }
  /// The bytes written so far, moved out; the writer starts over empty.
  std::string take() {
    bytes_.resize(size_);
    size_ = 0;
    std::string out = std::move(bytes_);
    bytes_.clear();
    return out;
  }

 private:
  // The buffer grows geometrically and the bytes are copied in place: std::string::append is
  // a call into the library for every value, which the grid's task records (ten values per
  // chunk) felt.
  void append(const void* from, std::size_t n) {
    if (bytes_.size() - size_ < n) bytes_.resize(std::max<std::size_t>(2 * bytes_.size(), size_ + n + 64));
    std::memcpy(&bytes_[size_], from, n);
    size_ += n;
  }

  mutable std::string bytes_;  // bytes_[0, size_) written; bytes() trims the rest
  std::size_t size_ = 0;
};

/// Reads what a ByteWriter wrote, in the same order.
/// \throws Error("cluster", ...) past the end (a truncated message: an internal error).
class ByteReader {
 public:
  explicit ByteReader(const std::string& bytes) : bytes_(bytes) {}
  template <class T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    T v;
    copy(&v, sizeof v);
    return v;
  }
  std::vector<double> get_vector() {
    std::vector<double> v(static_cast<std::size_t>(get<std::uint64_t>()));
    if (!v.empty()) copy(v.data(), v.size() * sizeof(double));
    return v;
  }
  std::string get_string() {
    const auto n = static_cast<std::size_t>(get<std::uint64_t>());
    need(n);
    std::string s = bytes_.substr(at_, n);
    at_ += n;
    return s;
  }
  bool at_end() const { return at_ == bytes_.size(); }

 private:
  void need(std::size_t n) const {
    if (n > bytes_.size() - at_) throw Error("cluster", "a task result or message from another rank is truncated (internal error)");
  }
  void copy(void* out, std::size_t n) {
    need(n);
    std::memcpy(out, bytes_.data() + at_, n);
    at_ += n;
  }
  const std::string& bytes_;
  std::size_t at_ = 0;
};

}  // namespace hapsyn
