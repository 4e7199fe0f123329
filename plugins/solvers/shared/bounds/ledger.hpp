#pragma once
/// \file
/// Which units of a grid sweep are finished (grid's chunks, culling's lines), as the checkpoint
/// and `hapsyn merge` need it (header only; both include it as "shared/bounds/ledger.hpp").
///
/// Finished units are kept as disjoint ranges: a run that hands its units out in order has a
/// finished prefix and a few units beyond it, and one share of a `--shard i/N` split has one
/// range in the middle of the grid, which a list of unit numbers would spell out unit by unit.
/// In the checkpoint's state: `finished_prefix` (units 0 .. prefix-1), `<units>` (the single
/// units beyond it, e.g. `finished_chunks`) and `finished_ranges` (the longer runs beyond it,
/// [first, end) pairs; absent in checkpoints written before it existed).
#include <hapsyn/checkpoint.hpp>
#include <hapsyn/json.hpp>

#include <algorithm>
#include <iterator>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace hapsyn::plugins {

/// How many consecutive units one task of a sweep's task farm covers: one for up to 511 units,
/// then about units/256 (at most 256), so that a sweep is about 256 tasks until its tasks reach
/// 256 units, and more beyond. Tasks this large keep the round trip a task costs under MPI (tens
/// of microseconds) and its record and collection small against its work, and give each thread
/// long stretches of the grid (about a thousand tasks made the pruned 10 mm five-bar grid 10 %
/// slower on 2 threads: docs/design.md section 12.2). It depends on the sweep alone, never on the
/// rank or thread count: a --shard share is whole tasks.
inline long long units_per_task(long long units) { return std::clamp(units / 256, 1LL, 256LL); }

class RangeLedger {
 public:
  RangeLedger() = default;
  explicit RangeLedger(long long units) : units_(units) {}

  /// Number of units of the sweep (0 .. units-1).
  long long units() const { return units_; }
  bool finished(long long unit) const {
    auto it = ranges_.upper_bound(unit);
    if (it == ranges_.begin()) return false;
    --it;
    return unit < it->second;
  }
  /// Marks a unit finished (again: nothing changes).
  void finish(long long unit) { add(unit, unit + 1); }
  /// Marks [first, end) finished.
  void add(long long first, long long end) {
    if (first >= end) return;
    auto it = ranges_.upper_bound(first);
    if (it != ranges_.begin() && std::prev(it)->second >= first) {
      --it;
      first = it->first;
      end = std::max(end, it->second);
      it = ranges_.erase(it);
    }
    while (it != ranges_.end() && it->first <= end) {
      end = std::max(end, it->second);
      it = ranges_.erase(it);
    }
    ranges_.emplace(first, end);
  }
  /// Units 0 .. prefix()-1 are all finished.
  long long prefix() const { return !ranges_.empty() && ranges_.begin()->first == 0 ? ranges_.begin()->second : 0; }
  /// Number of finished units.
  long long count() const {
    long long n = 0;
    for (const auto& [first, end] : ranges_) n += end - first;
    return n;
  }
  bool complete() const { return prefix() >= units_; }
  /// The finished ranges [first, end), in order.
  const std::map<long long, long long>& ranges() const { return ranges_; }
  /// The first unit finished in both ledgers, or -1.
  long long first_overlap(const RangeLedger& other) const {
    for (const auto& [first, end] : other.ranges_) {
      auto it = ranges_.upper_bound(first);
      if (it != ranges_.begin() && std::prev(it)->second > first) return first;
      if (it != ranges_.end() && it->first < end) return it->first;
    }
    return -1;
  }

  /// Writes finished_prefix, `singles_key` and finished_ranges into `state`.
  void write(Json& state, const char* singles_key) const {
    std::vector<long long> singles;
    Json ranges = Json::array();
    const long long p = prefix();
    for (const auto& [first, end] : ranges_) {
      if (first == 0) continue;
      if (end - first == 1) {
        singles.push_back(first);
      } else {
        ranges.push_back({first, end});
      }
    }
    state["finished_prefix"] = p;
    state[singles_key] = singles;
    state["finished_ranges"] = ranges;
  }

  /// Reads what write() wrote, for a sweep of `units` units.
  /// \throws bad_checkpoint naming the field when a unit lies outside (prefix, units).
  static RangeLedger read(const SolverContext& context, const Json& state, const char* singles_key, const char* unit,
                          long long units) {
    RangeLedger ledger(units);
    const long long p = checkpoint_field<long long>(context, state, "state", "finished_prefix");
    if (p < 0 || p > units) {
      throw bad_checkpoint(context, "state.finished_prefix = " + std::to_string(p) + ": must lie in [0, " +
                                        std::to_string(units) + "]");
    }
    ledger.add(0, p);
    const auto outside = [&](const std::string& field, long long u) {
      return bad_checkpoint(context, "state." + field + ": " + unit + " " + std::to_string(u) + " must lie in (" +
                                         std::to_string(p) + ", " + std::to_string(units) + ")");
    };
    for (long long u : checkpoint_field<std::vector<long long>>(context, state, "state", singles_key)) {
      if (u <= p || u >= units) throw outside(singles_key, u);
      ledger.finish(u);
    }
    if (state.contains("finished_ranges")) {
      for (const auto& r : checkpoint_field<std::vector<std::pair<long long, long long>>>(context, state, "state",
                                                                                          "finished_ranges")) {
        if (r.first <= p || r.first >= units) throw outside("finished_ranges", r.first);
        if (r.second <= r.first || r.second > units) throw outside("finished_ranges", r.second - 1);
        ledger.add(r.first, r.second);
      }
    }
    return ledger;
  }

 private:
  long long units_ = 0;
  std::map<long long, long long> ranges_;  // first -> end, disjoint and not touching
};

}  // namespace hapsyn::plugins
