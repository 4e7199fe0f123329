#pragma once
/// \file
/// The bytes grid and culling pass between ranks (header only; both include it as
/// "shared/bounds/task_bytes.hpp"): a task's result (TaskFarm::run -> collect) and the pruning knowledge
/// (TaskFarm::share -> learn), written with hapsyn/bytes.hpp (bit for bit).
#include "shared/bounds/worst_case_check.hpp"

#include <hapsyn/bytes.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/json.hpp>

#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

namespace hapsyn::plugins {

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
