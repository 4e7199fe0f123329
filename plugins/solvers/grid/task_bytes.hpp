#pragma once
/// \file
/// The bytes grid and culling pass between ranks (header only; culling includes it as
/// "grid/task_bytes.hpp"): a task's result (TaskFarm::run -> collect) and the pruning knowledge
/// (TaskFarm::share -> learn). Values are copied bit for bit (a double's bits, not its decimal
/// text), so a score found on another rank compares exactly as it would on this one. The ranks
/// of one job run the same binary on the same kind of machine (byte order and sizes agree).
#include "worst_case_check.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/json.hpp>

#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

namespace hapsyn::plugins {

/// Appends fixed-size values and length-prefixed strings.
class ByteWriter {
 public:
  template <class T>
  ByteWriter& put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes_.append(reinterpret_cast<const char*>(&v), sizeof v);
    return *this;
  }
  ByteWriter& put_string(const std::string& s) {
    put<std::uint64_t>(s.size());
    bytes_ += s;
    return *this;
  }
  std::string take() { return std::move(bytes_); }

 private:
  std::string bytes_;
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
    need(sizeof v);
    std::memcpy(&v, bytes_.data() + at_, sizeof v);
    at_ += sizeof v;
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
    if (n > bytes_.size() - at_) throw Error("cluster", "a task result or shared message is truncated (internal error)");
  }
  const std::string& bytes_;
  std::size_t at_ = 0;
};

/// A monotonicity breach found in a task, carried to rank 0 (absent: a 0 flag).
inline void put_breach(ByteWriter& out, const std::optional<MonotonicityBreach>& breach) {
  out.put<char>(breach ? 1 : 0);
  if (!breach) return;
  out.put(breach->objective).put(breach->subset_value).put(breach->full_value).put(breach->subset_samples);
  out.put_string(breach->design.dump());
}

inline std::optional<MonotonicityBreach> get_breach(ByteReader& in) {
  if (in.get<char>() == 0) return std::nullopt;
  MonotonicityBreach b;
  b.objective = in.get<int>();
  b.subset_value = in.get<double>();
  b.full_value = in.get<double>();
  b.subset_samples = in.get<long long>();
  b.design = Json::parse(in.get_string());
  return b;
}

}  // namespace hapsyn::plugins
