// A batch of study cases (sweep's runs, compare's studies): reuse decided on rank 0, the cases
// as one shardable task farm, the summary made on rank 0; and the shares of a batch gathered for
// a merge.
#include <hapsyn/internal/case_batch.hpp>

#include <hapsyn/error.hpp>
#include <hapsyn/json_text.hpp>
#include <hapsyn/read_file.hpp>
#include <hapsyn/solver.hpp>

#include <boost/filesystem.hpp>

namespace hapsyn {

namespace fs = boost::filesystem;

namespace {

// A result.json is a few MB at most (a front, statistics); anything far larger is not one.
constexpr std::uint64_t kMaxResultBytes = 1ULL << 30;

// Rank 0 finds the finished cases to reuse (and refuses foreign results) before any case starts,
// then tells the other ranks which cases are done, or the error every rank throws.
void decide_reuse(const CaseBatch& batch, Cluster& cluster, CaseBatchOutcome& outcome) {
  Json decision = Json::object();
  if (cluster.root()) {
    try {
      fs::create_directories(batch.output_directory);
      for (long long c = outcome.first; c < outcome.last && !batch.force; ++c) {
        std::optional<Json> record = batch.reuse(c);
        if (!record) continue;
        outcome.records[static_cast<std::size_t>(c)] = std::move(record);
        decision["reused"].push_back(c);
      }
    } catch (const std::exception& e) {
      decision = {{"error", error_record(e, batch.component)}};
    }
  }
  std::string bytes = decision.dump();
  cluster.broadcast(bytes);
  decision = Json::parse(bytes);
  if (decision.contains("error")) throw_record(decision["error"]);
  if (decision.contains("reused")) {
    for (const Json& c : decision["reused"]) outcome.reused[c.get<std::size_t>()] = 1;
  }
}

// The cases not reused, one at a time per rank (each with the threads its run options give).
void run_remaining(const CaseBatch& batch, Cluster& cluster, CaseBatchOutcome& outcome) {
  const auto stop_requested = [&] { return batch.stop != nullptr && batch.stop->load(); };
  TaskFarm farm;
  farm.count = batch.count;
  farm.shardable = true;
  farm.done = [&](long long c) { return outcome.reused[static_cast<std::size_t>(c)] != 0; };
  farm.run = [&](long long c, int) -> std::optional<std::string> {
    if (stop_requested()) return std::nullopt;
    outcome.started[static_cast<std::size_t>(c)] = 1;
    const std::optional<Json> record = batch.run(c);
    if (!record) return std::nullopt;
    return record->dump();
  };
  farm.collect = [&](long long c, std::string&& bytes) { outcome.records[static_cast<std::size_t>(c)] = Json::parse(bytes); };
  (void)cluster.run_tasks(farm, 1);
}

// Hard-links (or, where links fail, copies) the tree `from` to `to`, leaving out a run's lock
// file and staging folders.
void link_tree(const fs::path& from, const fs::path& to) {
  fs::create_directories(to);
  for (fs::directory_iterator it(from), end; it != end; ++it) {
    const std::string name = it->path().filename().string();
    if (name == ".lock" || name.rfind(".staging-", 0) == 0) continue;
    const fs::path target = to / name;
    if (fs::is_directory(it->symlink_status())) {
      link_tree(it->path(), target);
    } else if (fs::is_regular_file(it->symlink_status())) {
      boost::system::error_code ec;
      fs::create_hard_link(it->path(), target, ec);
      if (ec) fs::copy_file(it->path(), target);
    }
  }
}

std::string share_name(const Json& summary) {
  return std::to_string(summary["shard"]["index"].get<int>()) + "/" + std::to_string(summary["shard"]["count"].get<int>());
}

// Each share's summary, read and checked to be a share's.
std::vector<Json> read_share_summaries(const std::vector<std::string>& dirs, const std::string& summary_file,
                                       const std::string& what) {
  std::vector<Json> summaries;
  for (const std::string& dir : dirs) {
    const std::string file = (fs::path(dir) / summary_file).string();
    Json s;
    try {
      s = parse_json_text(read_regular_file(file, "merge", what + " summary", kMaxResultBytes), file, "merge");
    } catch (const std::exception& e) {
      throw Error("merge", file + ": not a readable " + what + " summary (" + e.what() + ")");
    }
    const bool shard_ok = s.is_object() && s.contains("shard") && s["shard"].is_object() &&
                          s["shard"].value("index", Json()).is_number_integer() &&
                          s["shard"].value("count", Json()).is_number_integer() &&
                          s["shard"].value("cases", Json()).is_array();
    if (!shard_ok) {
      throw Error("merge", dir + " is not a shard of a " + what + " (its " + summary_file +
                               " has no \"shard\" entry: it ran without --shard)");
    }
    summaries.push_back(std::move(s));
  }
  return summaries;
}

// Per share 1..count, its position in dirs: the same share count first (the shares' numbers mean
// nothing otherwise), then each share once.
std::vector<int> share_positions(const std::vector<Json>& summaries, const std::vector<std::string>& dirs,
                                 const std::string& what) {
  const int count = summaries[0]["shard"]["count"];
  for (std::size_t i = 1; i < summaries.size(); ++i) {
    if (summaries[i]["shard"]["count"] != count) {
      throw Error("merge", dirs[i] + " (shard " + share_name(summaries[i]) + ") is not of the same " + what + " as " +
                               dirs[0] + " (shard " + share_name(summaries[0]) + "): its shard count differs");
    }
  }
  std::vector<int> given(static_cast<std::size_t>(count), -1);  // share -> position in dirs
  for (std::size_t i = 0; i < summaries.size(); ++i) {
    const int index = summaries[i]["shard"]["index"];
    if (index < 1 || index > count) {
      throw Error("merge", dirs[i] + ": shard " + share_name(summaries[i]) + " is not a share of " + std::to_string(count));
    }
    int& slot = given[static_cast<std::size_t>(index - 1)];
    if (slot >= 0) {
      throw Error("merge", "shard " + share_name(summaries[i]) + " is given twice (" + dirs[static_cast<std::size_t>(slot)] +
                               ", " + dirs[i] + ")");
    }
    slot = static_cast<int>(i);
  }
  for (int k = 0; k < count; ++k) {
    if (given[static_cast<std::size_t>(k)] >= 0) continue;
    std::string have;
    for (int j = 0; j < count; ++j) {
      if (given[static_cast<std::size_t>(j)] >= 0) have += (have.empty() ? "" : ", ") + std::to_string(j + 1) + "/" + std::to_string(count);
    }
    throw Error("merge", "shard " + std::to_string(k + 1) + "/" + std::to_string(count) + " is missing (given: " + have + ")");
  }
  return given;
}

// The shares are of one job (the `same` inputs agree), finished, and none is out_dir.
void check_same_job(const std::vector<Json>& summaries, const std::vector<std::string>& dirs, const std::string& out_dir,
                    const std::string& what, const std::vector<std::pair<std::string, std::string>>& same) {
  for (std::size_t i = 1; i < summaries.size(); ++i) {
    for (const auto& [pointer, name] : same) {
      const Json::json_pointer p(pointer);
      const Json a = summaries[0].contains(p) ? summaries[0][p] : Json(nullptr);
      const Json b = summaries[i].contains(p) ? summaries[i][p] : Json(nullptr);
      if (a == b) continue;
      const std::string detail = a.dump().size() + b.dump().size() <= 80 ? " (" + b.dump() + " there, " + a.dump() + " in " + dirs[0] + ")" : "";
      throw Error("merge", dirs[i] + " (shard " + share_name(summaries[i]) + ") is not of the same " + what + " as " +
                               dirs[0] + " (shard " + share_name(summaries[0]) + "): its " + name + " differs" + detail);
    }
  }
  for (std::size_t i = 0; i < summaries.size(); ++i) {
    if (summaries[i].value("status", "") != "finished") {
      throw Error("merge", dirs[i] + " (shard " + share_name(summaries[i]) + ") stopped before its runs finished (status " +
                               summaries[i].value("status", Json()).dump() +
                               "): run its command again to finish it, then merge");
    }
  }
  boost::system::error_code ec;
  for (std::size_t i = 0; i < summaries.size(); ++i) {
    if (fs::exists(out_dir, ec) && fs::equivalent(dirs[i], out_dir, ec)) {
      throw Error("merge", out_dir + " is shard " + share_name(summaries[i]) +
                               "'s directory: merge into another directory");
    }
  }
}

// One share's case folders linked (or copied) into out_dir, replacing folders of those names.
void link_share_cases(const Json& summary, const std::string& dir, const std::string& out_dir,
                      const std::string& summary_file) {
  boost::system::error_code ec;
  for (const Json& name : summary["shard"]["cases"]) {
    const std::string folder = name.get<std::string>();
    const fs::path from = fs::path(dir) / folder;
    if (folder.empty() || folder.find('/') != std::string::npos || folder == "." || folder == ".." ||
        !fs::is_regular_file(from / "result.json", ec)) {
      throw Error("merge", from.string() + ": missing, or without result.json (shard " + share_name(summary) +
                               "'s " + summary_file + " lists it as finished)");
    }
    const fs::path to = fs::path(out_dir) / folder;
    fs::remove_all(to);
    link_tree(from, to);
  }
}

}  // namespace

CaseBatchOutcome run_case_batch(const CaseBatch& batch, Cluster& cluster) {
  CaseBatchOutcome outcome;
  const auto range = shard_tasks(cluster, batch.count);
  outcome.first = range.first;
  outcome.last = range.second;
  const std::size_t n = static_cast<std::size_t>(batch.count);
  outcome.records.resize(n);
  outcome.reused.assign(n, 0);
  outcome.started.assign(n, 0);
  decide_reuse(batch, cluster, outcome);
  run_remaining(batch, cluster, outcome);
  return outcome;
}

void continue_in_folder(RunOptions& run, bool force) {
  if (force) {
    run.force = true;
    return;
  }
  const fs::path dir(run.output_directory);
  boost::system::error_code ec;
  fs::remove(dir / "result.json", ec);
  run.resume = fs::exists(dir / "checkpoint.json", ec);
}

std::string first_unfinished(const CaseBatchOutcome& outcome, const std::vector<std::string>& names,
                             const Cluster& cluster) {
  for (long long c = outcome.first; c < outcome.last; ++c) {
    const std::size_t i = static_cast<std::size_t>(c);
    if (outcome.records[i]) continue;
    return names[i] + (cluster.size() == 1 && !outcome.started[i] ? " (not started)" : "");
  }
  return "";
}

void add_shard_entry(Json& summary, const CaseBatchOutcome& outcome, const std::vector<std::string>& names,
                     const Cluster& cluster, const std::string& stopped_at) {
  const auto [shard_index, shard_count] = cluster.shard();
  if (shard_count <= 1) return;
  Json cases = Json::array();
  for (long long c = outcome.first; c < outcome.last; ++c) cases.push_back(names[static_cast<std::size_t>(c)]);
  summary["shard"] = {{"index", shard_index + 1}, {"count", shard_count}, {"cases", cases}};
  if (stopped_at.empty()) summary["message"] = cluster.shard_message();
}

Json summary_on_every_rank(Cluster& cluster, const std::function<Json()>& make, const std::string& component) {
  Json message = Json::object();
  if (cluster.root()) {
    try {
      message = {{"summary", make()}};
    } catch (const std::exception& e) {
      message = {{"error", error_record(e, component)}};
    }
  }
  std::string bytes = message.dump();
  cluster.broadcast(bytes);
  if (!cluster.root()) message = Json::parse(bytes);
  if (message.contains("error")) throw_record(message["error"]);
  return std::move(message["summary"]);
}

Json error_record(const std::exception& e, const std::string& fallback_component) {
  if (const auto* error = dynamic_cast<const Error*>(&e)) {
    const std::string what = error->what();
    const std::string prefix = error->component() + ": ";
    return {{"component", error->component()},
            {"message", what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what}};
  }
  return {{"component", fallback_component}, {"message", e.what()}};
}

[[noreturn]] void throw_record(const Json& record) {
  throw Error(record["component"].get<std::string>(), record["message"].get<std::string>());
}

std::pair<long long, long long> shard_tasks(const Cluster& cluster, long long count) {
  // Plain variables: a structured binding cannot be captured by a lambda in C++17.
  const std::pair<int, int> share = cluster.shard();
  const int index = share.first, shards = share.second;
  if (shards <= 1) return {0, count};
  // The split ShardCluster::run_tasks makes (contiguous shares, (count*i)/N in long double).
  const auto bound = [&](int i) { return static_cast<long long>(static_cast<long double>(count) * i / shards); };
  return {bound(index), bound(index + 1)};
}

std::optional<Json> reusable_result(const std::string& directory, const Json& resolved,
                                    const std::optional<std::uint64_t>& seed, const std::string& component,
                                    const std::string& what) {
  const fs::path file = fs::path(directory) / "result.json";
  boost::system::error_code ec;
  if (!fs::exists(file, ec)) return std::nullopt;
  const std::string remedy = "; delete it, or choose another --out";
  Json stored;
  try {
    stored = parse_json_text(read_regular_file(file.string(), component, "result", kMaxResultBytes), file.string(), component.c_str());
  } catch (const std::exception& e) {
    throw Error(component, file.string() + ": not a readable result (" + e.what() + ")" + remedy);
  }
  if (!stored.is_object() || !stored.contains("problem") || !stored.contains("status") || !stored["status"].is_string()) {
    throw Error(component, file.string() + ": not a hapsyn result (no \"problem\" or \"status\")" + remedy);
  }
  if (stored["problem"] != resolved) {
    const Json patch = Json::diff(stored["problem"], resolved);
    const std::string at = patch.empty() ? std::string("/") : patch[0].value("path", std::string("/"));
    const Json here = stored["problem"].contains(Json::json_pointer(at)) ? stored["problem"][Json::json_pointer(at)] : Json("(absent)");
    const Json there = resolved.contains(Json::json_pointer(at)) ? resolved[Json::json_pointer(at)] : Json("(absent)");
    throw Error(component, directory + " holds a result of another problem (first difference at " + at + ": " + here.dump() +
                               " there, " + there.dump() + " in " + what + ")" + remedy);
  }
  if (seed && (!stored.contains("seed") || stored["seed"] != *seed)) {
    throw Error(component, directory + " holds a result run with seed " + stored.value("seed", Json()).dump() + ", " + what +
                               " has seed " + std::to_string(*seed) + remedy);
  }
  if (stored["status"] == to_string(SolverStatus::kStopped)) return std::nullopt;
  return stored;
}

std::vector<Json> gather_shards(const std::vector<std::string>& dirs, const std::string& out_dir,
                                const std::string& summary_file, const std::string& what,
                                const std::vector<std::pair<std::string, std::string>>& same) {
  if (dirs.empty()) throw Error("merge", "no shard directory given");
  std::vector<Json> summaries = read_share_summaries(dirs, summary_file, what);
  const std::vector<int> given = share_positions(summaries, dirs, what);
  check_same_job(summaries, dirs, out_dir, what, same);
  std::vector<Json> ordered;
  fs::create_directories(out_dir);
  for (int position : given) {
    const std::size_t i = static_cast<std::size_t>(position);
    link_share_cases(summaries[i], dirs[i], out_dir, summary_file);
    ordered.push_back(std::move(summaries[i]));
  }
  return ordered;
}

}  // namespace hapsyn
