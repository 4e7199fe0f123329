// hapsyn merge: check that the shares belong together, combine their checkpoints, finish with
// --resume (see hapsyn/internal/merge.hpp).
#include <hapsyn/checkpoint.hpp>
#include <hapsyn/data_file.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/json_text.hpp>
#include <hapsyn/internal/merge.hpp>
#include <hapsyn/read_file.hpp>
#include <hapsyn/internal/study.hpp>

#include <boost/filesystem.hpp>

#include <algorithm>
#include <map>

namespace hapsyn {

namespace fs = boost::filesystem;

namespace {

constexpr std::uint64_t kMaxResultBytes = std::uint64_t{1} << 30;

// One share's result.json and checkpoint.json.
struct Share {
  std::string dir;
  Json result;
  Json checkpoint;
  int index = 0, count = 0;  // 1-based, as the user wrote --shard
};

std::string share_name(const Share& s) { return std::to_string(s.index) + "/" + std::to_string(s.count); }

// A member of a share's result.json that merge reads, checked for its type: the file may have
// been edited or damaged, and a wrong type must be named, not reach nlohmann's type_error.
using JsonTest = bool (Json::*)() const noexcept;
const Json& member(const Json& object, const char* key, JsonTest is, const char* rule, const std::string& file,
                   const std::string& path) {
  const auto it = object.find(key);
  const std::string name = path.empty() ? key : path + "." + key;
  if (it == object.end()) throw Error("merge", file + ": no " + name + " (" + rule + "; was the file edited?)");
  if (!((*it).*is)()) {
    throw Error("merge", file + ": " + name + " = " + render_value(*it) + ": must be " + rule + " (was the file edited?)");
  }
  return *it;
}

Share read_share(const std::string& dir) {
  Share s;
  s.dir = dir;
  const std::string result_file = (fs::path(dir) / "result.json").string();
  boost::system::error_code ec;
  if (!fs::exists(result_file, ec)) {
    throw Error("merge", dir + ": no result.json (not a finished share: run `hapsyn run FILE --shard i/N --out " + dir +
                             "` first, or resume it if it was stopped)");
  }
  s.result = parse_json_text(read_regular_file(result_file, "merge", "result", kMaxResultBytes), result_file, "merge");
  if (!s.result.is_object()) throw Error("merge", result_file + ": not a hapsyn result (not a JSON object)");
  const auto shard = s.result.find("shard");
  if (shard == s.result.end() || !shard->is_object()) {
    throw Error("merge", result_file + ": not a share's result (no \"shard\"; shares are run with --shard i/N)");
  }
  const Json& count = member(*shard, "count", &Json::is_number_integer, "an integer >= 1", result_file, "shard");
  const Json& index = member(*shard, "index", &Json::is_number_integer, "an integer from 1 to shard.count", result_file, "shard");
  if (count.get<long long>() < 1 || count.get<long long>() > 1000000 || index.get<long long>() < 1 ||
      index.get<long long>() > count.get<long long>()) {
    throw Error("merge", result_file + ": shard = " + render_value(*shard) + ": index must lie in 1..count");
  }
  s.index = index.get<int>();
  s.count = count.get<int>();
  if (!member(*shard, "complete", &Json::is_boolean, "true or false", result_file, "shard").get<bool>()) {
    throw Error("merge", dir + ": shard " + share_name(s) + " was stopped before it finished its share: resume it with "
                             "`hapsyn run FILE --shard " + share_name(s) + " --out " + dir + " --resume`");
  }
  member(*shard, "problem_file", &Json::is_string, "a string", result_file, "shard");
  member(*shard, "problem_document", &Json::is_object, "an object", result_file, "shard");
  member(s.result, "seed", &Json::is_number_unsigned, "an integer >= 0", result_file, "");
  member(s.result, "problem", &Json::is_object, "an object", result_file, "");
  member(member(s.result, "hapsyn", &Json::is_object, "an object", result_file, ""), "version", &Json::is_string,
         "a string", result_file, "hapsyn");
  const std::string checkpoint_file = (fs::path(dir) / "checkpoint.json").string();
  s.checkpoint = read_checkpoint_document(checkpoint_file, "merge");
  member(s.checkpoint, "fingerprint", &Json::is_string, "a string", checkpoint_file, "");
  return s;
}

// The first key path where two JSON documents differ ("/solver/options/prune"), "" if none.
std::string first_difference(const Json& a, const Json& b) {
  const Json patch = Json::diff(a, b);
  return patch.empty() ? std::string() : patch[0].value("path", std::string("/"));
}

// Every share of one study, each once.
void check_shares_belong_together(const std::vector<Share>& shares) {
  const Share& first = shares.front();
  std::map<int, std::string> seen;
  for (const Share& s : shares) {
    if (s.count != first.count) {
      throw Error("merge", s.dir + " is shard " + share_name(s) + ", " + first.dir + " shard " + share_name(first) +
                               ": the shard counts differ");
    }
    if (s.result["seed"] != first.result["seed"]) {
      throw Error("merge", s.dir + " ran with seed " + s.result["seed"].dump() + ", " + first.dir + " with seed " +
                               first.result["seed"].dump() + ": shares of one run share its seed (give --seed)");
    }
    if (s.result["hapsyn"]["version"] != first.result["hapsyn"]["version"]) {
      throw Error("merge", s.dir + " was run by hapsyn " + s.result["hapsyn"]["version"].dump() + ", " + first.dir +
                               " by " + first.result["hapsyn"]["version"].dump() + ": shares must come from one version");
    }
    const std::string where = first_difference(first.result["problem"], s.result["problem"]);
    if (!where.empty()) {
      throw Error("merge", s.dir + " is a share of a different problem than " + first.dir + " (they differ at " + where +
                               ")");
    }
    if (s.checkpoint["solver"] != first.checkpoint["solver"] ||
        s.checkpoint["fingerprint"] != first.checkpoint["fingerprint"]) {
      throw Error("merge", s.dir + "/checkpoint.json belongs to another study or solver than " + first.dir +
                               "/checkpoint.json (solver or fingerprint differ)");
    }
    const auto [at, fresh] = seen.emplace(s.index, s.dir);
    if (!fresh) throw Error("merge", "shard " + share_name(s) + " given twice (" + at->second + ", " + s.dir + ")");
  }
  std::string given;
  for (const auto& [index, dir] : seen) given += (given.empty() ? "" : ", ") + std::to_string(index) + "/" + std::to_string(first.count);
  for (int i = 1; i <= first.count; ++i) {
    if (seen.count(i) == 0) {
      throw Error("merge", "shard " + std::to_string(i) + "/" + std::to_string(first.count) + " is missing (given: " +
                               given + ")");
    }
  }
}

}  // namespace

void check_merge_output(const std::string& out, const std::vector<std::string>& inputs) {
  const fs::path target = fs::weakly_canonical(fs::absolute(out)).lexically_normal();
  for (const std::string& dir : inputs) {
    const fs::path share = fs::weakly_canonical(fs::absolute(dir)).lexically_normal();
    if (target == share) {
      throw Error("merge", "--out " + out + " is the share " + dir +
                               " given as input: the merged study would be written over it; choose another directory");
    }
    // Inside the share when the share's path is a prefix of the target's, component by component.
    const auto mismatch = std::mismatch(share.begin(), share.end(), target.begin(), target.end());
    if (mismatch.first == share.end()) {
      throw Error("merge", "--out " + out + " lies inside the share " + dir +
                               " given as input: the merged study would be written into it; choose another directory");
    }
  }
}

Json merge_shard_directories(const std::vector<std::string>& dirs, const Registry& registry, const RunOptions& options) {
  if (dirs.empty()) throw Error("merge", "no shard directories given");
  if (options.output_directory.empty()) throw Error("merge", "--out is required (where the merged study is written)");
  check_merge_output(options.output_directory, dirs);
  std::vector<Share> shares;
  for (const std::string& d : dirs) shares.push_back(read_share(d));
  check_shares_belong_together(shares);
  std::sort(shares.begin(), shares.end(), [](const Share& a, const Share& b) { return a.index < b.index; });

  const Share& first = shares.front();
  const std::string problem_file = first.result["shard"].value("problem_file", std::string());
  const ProblemDirectoryScope scope(problem_file);  // the shares' relative paths, as they read them
  LoadSettings settings;
  settings.threads = options.threads;
  settings.progress = options.quiet ? nullptr : options.progress;
  // The document as given: the resolved "problem" carries annotations (units) a problem file
  // may not have.
  const Json document = first.result["shard"].value("problem_document", Json());
  if (!document.is_object()) throw Error("merge", first.dir + "/result.json: the share records no problem document");
  Study study = load_study(document, registry, {}, settings);
  std::vector<Json> states;
  for (const Share& s : shares) states.push_back(s.checkpoint["state"]);
  const Json merged = study.solver->merge_shards(*study.problem, states);

  RunOptions run = options;
  run.seed = first.result["seed"].get<std::uint64_t>();
  run.resume = true;
  run.problem_file = problem_file;
  const std::string out_dir = output_directory_of(study, run);
  check_output_directory(out_dir, run);
  fs::create_directories(out_dir);
  SolverContext context;
  context.seed = *run.seed;
  context.checkpoint_file = (fs::path(out_dir) / "checkpoint.json").string();
  write_checkpoint(context, first.checkpoint["solver"].get<std::string>(),
                   first.checkpoint["fingerprint"].get<std::string>(), merged);
  return run_study(study, run);
}

}  // namespace hapsyn
