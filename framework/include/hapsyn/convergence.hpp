#pragma once
/// \file
/// A solver's convergence record for result.json (statistics.history), kept in checkpoints.
#include <hapsyn/json.hpp>

#include <cstddef>

namespace hapsyn {

/// A solver's per-generation record for result.json, of bounded size: columns of equal length,
/// one entry per kept generation. Kept are the generations that are multiples of a stride, plus
/// the latest entry; when more than `capacity` are kept the stride doubles and the entries off
/// it go, so between capacity/2 and capacity entries (plus the latest) remain however long the
/// run. The kept entries depend only on the generations added: a run resumed from json() keeps
/// the ones an uninterrupted run keeps.
class ConvergenceHistory {
 public:
  explicit ConvergenceHistory(std::size_t capacity = 1000);
  /// Adds the entry of `generation` (>= the latest one's; an equal one adds a second entry of
  /// that generation, such as a final re-ranking). `entry` maps column names to numbers,
  /// strings or null, or to objects of those (nested columns, e.g. "ideal": {"gii": 0.7}); every
  /// entry has the same keys. "generation" and "stride" are set here.
  /// \throws std::invalid_argument for a generation below the latest or keys that differ.
  void add(int generation, const Json& entry);
  /// {"stride": k, "generation": [...], "<column>": [...] or {"<name>": [...]}, ...}
  const Json& json() const { return columns_; }
  /// Entries kept.
  std::size_t size() const { return columns_.at("generation").size(); }
  /// The history from json().
  /// \throws std::invalid_argument when a column is not an array as long as "generation", the
  ///         generations are not integers in increasing order, or the stride is not >= 1.
  static ConvergenceHistory from_json(const Json& json, std::size_t capacity = 1000);

 private:
  void keep_on_stride();
  std::size_t capacity_;
  Json columns_;
};

}  // namespace hapsyn
