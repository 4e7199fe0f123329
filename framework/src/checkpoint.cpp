// The checkpoint file format (hapsyn/checkpoint.hpp): write with a checksum, read with every
// check before a solver sees the state.
#include <hapsyn/cluster.hpp>
#include <hapsyn/checkpoint.hpp>
#include <hapsyn/error.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/read_file.hpp>

#include <boost/filesystem.hpp>

#include <sstream>

namespace hapsyn {

namespace {

constexpr int kFormatVersion = 1;
constexpr std::uint64_t kMaxCheckpointBytes = 1ULL << 30;

// The checksum covers every field but itself, in nlohmann's sorted-key dump.
std::string checksum_of(Json document) {
  document.erase("checksum");
  return fnv1a_hex(document.dump());
}

std::string refuse(const std::string& file, const std::string& detail) {
  return file + ": " + detail + "; delete it, or run without --resume";
}

}  // namespace

std::string fnv1a_hex(const std::string& text) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  std::ostringstream s;
  s << std::hex << h;
  return s.str();
}

std::string study_fingerprint(const Problem& problem, const Json& solver_options) {
  std::ostringstream s;
  s.precision(17);
  s << solver_options.dump() << "|" << problem.samples().size() << "|";
  for (int k : problem.design_space().free_indices()) {
    const DesignComponent& c = problem.design_space().components()[static_cast<std::size_t>(k)];
    s << c.name << ":" << c.lower << ":" << c.upper << ":" << c.step << ":" << c.integer << ";";
  }
  for (const Objective& o : problem.objectives()) s << o.name << ":" << o.weight << ":" << (o.sense == Sense::kMaximize) << ";";
  return fnv1a_hex(s.str());
}

std::string study_fingerprint(const Problem& problem, Json solver_options, std::initializer_list<const char*> ignored) {
  for (const char* name : ignored) solver_options.erase(name);
  return study_fingerprint(problem, solver_options);
}

void write_checkpoint(const SolverContext& context, const std::string& solver, const std::string& fingerprint,
                      const Json& state) {
  if (context.checkpoint_file.empty() || !context.cluster().root()) return;  // rank 0 owns the files
  Json c;
  c["format"] = "hapsyn-checkpoint";
  c["version"] = kFormatVersion;
  c["seed"] = context.seed;
  c["solver"] = solver;
  c["fingerprint"] = fingerprint;
  c["state"] = state;
  c["checksum"] = checksum_of(c);
  write_file_atomically(context.checkpoint_file, c.dump() + "\n");
}

Error bad_checkpoint(const SolverContext& context, const std::string& detail) {
  return Error("checkpoint", refuse(context.checkpoint_file, detail));
}

std::optional<Json> read_checkpoint(const SolverContext& context, const std::string& solver,
                                    const std::string& fingerprint) {
  const std::string& file = context.checkpoint_file;
  if (!context.resume || file.empty()) return std::nullopt;
  // Under MPI rank 0 reads the file and every rank parses rank 0's bytes: all ranks resume from
  // the same state, even when rank 0 writes the next checkpoint while another still reads.
  // "N": no file; "T<text>"; "E<error>".
  std::string message;
  if (context.cluster().root()) {
    boost::system::error_code ec;
    if (!boost::filesystem::exists(file, ec)) {
      message = "N";
    } else {
      try {
        message = "T" + read_regular_file(file, "checkpoint", "checkpoint", kMaxCheckpointBytes);
      } catch (const Error& e) {
        message = "E" + std::string(e.what()).substr(std::string("checkpoint: ").size());
      }
    }
  }
  context.cluster().broadcast(message);
  if (message.empty() || message[0] == 'N') return std::nullopt;
  if (message[0] == 'E') throw Error("checkpoint", message.substr(1) + "; delete it, or run without --resume");
  Json c = Json::parse(message.begin() + 1, message.end(), nullptr, false);
  if (c.is_discarded()) throw bad_checkpoint(context, "not valid JSON (truncated or damaged)");
  if (!c.is_object() || c.value("format", Json()) != "hapsyn-checkpoint") {
    throw bad_checkpoint(context, "not a hapsyn checkpoint (no \"format\": \"hapsyn-checkpoint\")");
  }
  if (!c.contains("version") || c["version"] != kFormatVersion) {
    throw bad_checkpoint(context, "checkpoint format version " + c.value("version", Json()).dump() + ", this hapsyn reads " +
                                      std::to_string(kFormatVersion));
  }
  if (!c.contains("checksum") || !c["checksum"].is_string() || c["checksum"] != checksum_of(c)) {
    throw bad_checkpoint(context, "damaged or edited (its checksum does not match its content)");
  }
  if (c.value("solver", Json()) != solver) {
    throw bad_checkpoint(context, "written by solver " + c.value("solver", Json()).dump() + ", this study's solver is \"" +
                                      solver + "\"");
  }
  if (c.value("fingerprint", Json()) != fingerprint) {
    throw bad_checkpoint(context, "written for another study (fingerprint " + c.value("fingerprint", Json()).dump() +
                                      ", this study " + fingerprint + ": problem, bounds, objectives or solver options differ)");
  }
  if (!c.contains("seed") || !c["seed"].is_number_unsigned() || c["seed"].get<std::uint64_t>() != context.seed) {
    throw bad_checkpoint(context, "written with seed " + c.value("seed", Json()).dump() + ", this run has seed " +
                                      std::to_string(context.seed));
  }
  if (!c.contains("state") || !c["state"].is_object()) throw bad_checkpoint(context, "no \"state\" object");
  return std::move(c["state"]);
}

Json read_checkpoint_document(const std::string& file, const std::string& component) {
  boost::system::error_code ec;
  if (!boost::filesystem::exists(file, ec)) throw Error(component, file + ": missing");
  const std::string text = read_regular_file(file, component, "checkpoint", kMaxCheckpointBytes);
  Json c = Json::parse(text, nullptr, false);
  if (c.is_discarded()) throw Error(component, file + ": not valid JSON (truncated or damaged)");
  if (!c.is_object() || c.value("format", Json()) != "hapsyn-checkpoint") {
    throw Error(component, file + ": not a hapsyn checkpoint (no \"format\": \"hapsyn-checkpoint\")");
  }
  if (!c.contains("version") || c["version"] != kFormatVersion) {
    throw Error(component, file + ": checkpoint format version " + c.value("version", Json()).dump() +
                               ", this hapsyn reads " + std::to_string(kFormatVersion));
  }
  if (!c.contains("checksum") || !c["checksum"].is_string() || c["checksum"] != checksum_of(c)) {
    throw Error(component, file + ": damaged or edited (its checksum does not match its content)");
  }
  if (!c.contains("state") || !c["state"].is_object() || !c.contains("seed") || !c["seed"].is_number_unsigned() ||
      !c.contains("solver") || !c["solver"].is_string() || !c.contains("fingerprint")) {
    throw Error(component, file + ": a checkpoint needs \"seed\", \"solver\", \"fingerprint\" and a \"state\" object");
  }
  return c;
}

}  // namespace hapsyn
