#pragma once
/// \file
/// Finding the files a problem file names by a relative path: plugin data files (arm models,
/// DH tables, actuator tables, motion data) and the framework's own (a reference front).
#include <string>

namespace hapsyn {

/// While one exists, relative paths named in a problem file are resolved against the folder of
/// that file first (find_data_file, find_data_path, resolve_problem_path), so that
/// `hapsyn run some/dir/problem.json` works from any current directory. Whoever loads a problem
/// file holds one around load_study (the command line's run/validate do). Scopes nest; the
/// innermost wins, and the previous folder is restored on destruction. One process-wide setting
/// (a plugin may resolve its files on a worker thread), so concurrent loads of problem files
/// from different folders are not supported.
class ProblemDirectoryScope {
 public:
  /// \param problem_file the problem file's path (its folder is used); "" for none
  explicit ProblemDirectoryScope(const std::string& problem_file);
  ~ProblemDirectoryScope();
  ProblemDirectoryScope(const ProblemDirectoryScope&) = delete;
  ProblemDirectoryScope& operator=(const ProblemDirectoryScope&) = delete;

 private:
  std::string previous_;
};

/// The absolute folder of the problem file being loaded (ProblemDirectoryScope), or "" outside one.
std::string problem_directory();

/// Resolves a data file named by a plugin option: an absolute path as is; a relative path
/// against the problem file's folder (inside a ProblemDirectoryScope), then the current
/// directory, then hapsyn's share/ directory in the source tree, then the installed
/// share/hapsyn. Returns an absolute path.
/// \param component  the plugin, for the error ("human_arm")
/// \param option     the option's name, for the error ("arm_file")
/// \param value      the option's value
/// \throws Error `("<component>: options.<option> = \"<value>\": no such file (tried ...)")`
std::string find_data_file(const std::string& component, const std::string& option, const std::string& value);

/// As find_data_file, but a folder is accepted too (a data set of several files).
/// \throws Error `("<component>: options.<option> = \"<value>\": no such file or folder (tried ...)")`
std::string find_data_path(const std::string& component, const std::string& option, const std::string& value);

/// A path named by the framework's part of a problem file (indicators.reference_front): an
/// absolute path as is; a relative one against the problem file's folder when it exists there,
/// else against the current directory (as before problem folders counted). Returns an absolute,
/// normalised path; the file need not exist.
std::string resolve_problem_path(const std::string& value);

}  // namespace hapsyn
