#pragma once
/// \file
/// Solver checkpoints: the one file format every solver that can run long writes, and the
/// checks that make a damaged, edited or foreign checkpoint a clear error instead of a
/// trusted one.
///
/// The file (SolverContext::checkpoint_file) is one JSON document:
/// `{"format": "hapsyn-checkpoint", "version": 1, "seed": <study seed>, "solver": "<name>",
///   "fingerprint": "<hex>", "state": {...solver's own...}, "checksum": "<hex>"}`.
/// The checksum (FNV-1a 64 over the document without it) catches truncation and hand edits;
/// the fingerprint ties it to one study (problem, bounds, objectives, solver options); the
/// solver still re-checks what it can cheaply (a claimed best value is re-evaluated on resume).
#include <hapsyn/error.hpp>
#include <hapsyn/json.hpp>
#include <hapsyn/problem.hpp>
#include <hapsyn/solver.hpp>

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>

namespace hapsyn {

/// Hex FNV-1a 64 of `text`: a stable, fast hash for fingerprints and checksums (not a
/// cryptographic one: it detects accidents and edits, not a forger who recomputes it).
std::string fnv1a_hex(const std::string& text);

/// Fingerprint of a study for its checkpoints: `solver_options` (the solver's option values as
/// JSON), the scene's sample count, the free components' names, bounds, steps and integrality,
/// the objectives' names, weights and senses. A checkpoint is resumed only by a study with the
/// same fingerprint.
std::string study_fingerprint(const Problem& problem, const Json& solver_options);
/// As above, without the options named in `ignored`: those a resumed run may change without
/// changing the result (progress and checkpoint intervals, a size cap).
std::string study_fingerprint(const Problem& problem, Json solver_options, std::initializer_list<const char*> ignored);

/// Reads object[key] of a checkpoint's state as T for a solver's resume.
/// \param context the solver's context, for the message (its checkpoint file)
/// \param object  an object of the state
/// \param path    the object's path in the state, for the message ("state", "state.best")
/// \param key     the field to read
/// \throws bad_checkpoint `(context, "<path>.<key> is missing")` or `"<path>.<key> = <value>: not
///         of the expected type"` (never a raw JSON exception).
template <class T>
T checkpoint_field(const SolverContext& context, const Json& object, const std::string& path, const std::string& key);

/// Writes the checkpoint of `solver` with its `state` to context.checkpoint_file, atomically
/// (nothing when the file name is empty). Called by solvers between units of work.
/// \throws Error("output", ...) when it cannot be written.
void write_checkpoint(const SolverContext& context, const std::string& solver, const std::string& fingerprint,
                      const Json& state);

/// The state of the checkpoint to resume from: nullopt when context.resume is false, the file
/// name empty or the file absent (the solver starts over, and should log that).
/// \throws Error("checkpoint", "<file>: <what is wrong>; delete it, or run without --resume")
///         when the file is not a regular file, larger than 1 GiB, not JSON, not a hapsyn
///         checkpoint, of another format version, damaged (checksum), written by another solver
///         (`solver`), for another study (`fingerprint`) or with another seed than context.seed.
std::optional<Json> read_checkpoint(const SolverContext& context, const std::string& solver,
                                    const std::string& fingerprint);

/// A checkpoint file read whole, for `hapsyn merge`: the document (seed, solver, fingerprint,
/// state) after the format, version and checksum checks.
/// \throws Error(component, "<file>: <what is wrong>") when it is missing, not a regular file,
///         not JSON, not a hapsyn checkpoint, of another version or damaged.
Json read_checkpoint_document(const std::string& file, const std::string& component);

/// The error a solver throws when a checkpoint passed the checks above but its state does not
/// hold together (a field missing or of the wrong type, a best value that re-evaluates
/// differently): Error("checkpoint", "<file>: <detail>; delete it, or run without --resume").
Error bad_checkpoint(const SolverContext& context, const std::string& detail);

template <class T>
T checkpoint_field(const SolverContext& context, const Json& object, const std::string& path, const std::string& key) {
  if (!object.is_object() || !object.contains(key)) throw bad_checkpoint(context, path + "." + key + " is missing");
  try {
    return object.at(key).get<T>();
  } catch (const Json::exception&) {
    throw bad_checkpoint(context, path + "." + key + " = " + object.at(key).dump().substr(0, 80) +
                                      ": not of the expected type");
  }
}

}  // namespace hapsyn
