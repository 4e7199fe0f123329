// ConvergenceHistory: a bounded per-generation record (hapsyn/convergence.hpp).
#include <hapsyn/convergence.hpp>

#include <stdexcept>
#include <string>

namespace hapsyn {

namespace {

// Applies `f` to every column array of a history (nested columns included), "stride" skipped.
template <class F>
void for_each_column(Json& columns, F&& f) {
  for (auto it = columns.begin(); it != columns.end(); ++it) {
    if (it.key() == "stride") continue;
    if (it->is_object()) {
      for_each_column(*it, f);
    } else {
      f(*it);
    }
  }
}

// Appends `entry`'s values to `columns`, which must have the same keys (an empty object takes them).
void append_entry(Json& columns, const Json& entry, bool first) {
  for (auto it = entry.begin(); it != entry.end(); ++it) {
    if (!first && !columns.contains(it.key())) throw std::invalid_argument("history: new column " + it.key());
    if (it->is_object()) {
      if (first) columns[it.key()] = Json::object();
      append_entry(columns[it.key()], *it, first);
    } else {
      if (first) columns[it.key()] = Json::array();
      columns[it.key()].push_back(*it);
    }
  }
}

// Checks that every column is an array of `length` entries.
void check_columns(const Json& columns, std::size_t length) {
  for (auto it = columns.begin(); it != columns.end(); ++it) {
    if (it.key() == "stride") continue;
    if (it->is_object()) {
      check_columns(*it, length);
    } else if (!it->is_array() || it->size() != length) {
      throw std::invalid_argument("history." + it.key() + " is not an array of " + std::to_string(length) + " entries");
    }
  }
}

}  // namespace

ConvergenceHistory::ConvergenceHistory(std::size_t capacity)
    : capacity_(std::max<std::size_t>(2, capacity)), columns_({{"stride", 1}, {"generation", Json::array()}}) {}

void ConvergenceHistory::add(int generation, const Json& entry) {
  Json& generations = columns_["generation"];
  const long long stride = columns_["stride"].get<long long>();
  if (!generations.empty()) {
    const int latest = generations.back().get<int>();
    if (generation < latest) throw std::invalid_argument("history: generation " + std::to_string(generation) + " after " + std::to_string(latest));
    // The latest entry stays only on the stride (or as the first of two entries of one generation).
    if (latest < generation && latest % stride != 0) {
      for_each_column(columns_, [](Json& column) { column.erase(column.size() - 1); });
    }
  }
  Json row = entry;
  row.erase("generation");
  row.erase("stride");
  append_entry(columns_, row, generations.empty() && columns_.size() == 2);
  generations.push_back(generation);
  check_columns(columns_, generations.size());  // an entry without every column
  if (generations.size() > capacity_) keep_on_stride();
}

// Doubles the stride until at most capacity entries remain: those on it and the latest
// generation's.
void ConvergenceHistory::keep_on_stride() {
  const Json& generations = columns_["generation"];
  const long long latest = generations.back().get<long long>();
  long long stride = columns_["stride"].get<long long>();
  std::vector<char> keep;
  std::size_t kept = 0;
  do {
    stride *= 2;
    keep.clear();
    kept = 0;
    for (const Json& g : generations) {
      const long long v = g.get<long long>();
      keep.push_back(v % stride == 0 || v == latest);
      kept += keep.back();
    }
  } while (kept > capacity_);
  columns_["stride"] = stride;
  for_each_column(columns_, [&keep](Json& column) {
    Json kept_values = Json::array();
    for (std::size_t i = 0; i < column.size(); ++i) {
      if (keep[i]) kept_values.push_back(column[i]);
    }
    column = std::move(kept_values);
  });
}

ConvergenceHistory ConvergenceHistory::from_json(const Json& json, std::size_t capacity) {
  if (!json.is_object()) throw std::invalid_argument("history is not an object");
  const long long stride = json.at("stride").get<long long>();
  if (stride < 1) throw std::invalid_argument("history.stride = " + std::to_string(stride) + ": must be >= 1");
  const Json& generations = json.at("generation");
  if (!generations.is_array()) throw std::invalid_argument("history.generation is not an array");
  long long previous = -1;
  for (const Json& g : generations) {
    const long long v = g.get<long long>();
    if (v < previous) throw std::invalid_argument("history.generation is not in increasing order");
    previous = v;
  }
  check_columns(json, generations.size());
  ConvergenceHistory history(capacity);
  history.columns_ = json;
  return history;
}

}  // namespace hapsyn
