#pragma once
/// \file
/// Finding the data files a plugin reads (arm models, DH tables, actuator tables).
#include <string>

namespace hapsyn {

/// Resolves a data file named by a plugin option: an absolute path as is; a relative path
/// against the current directory, then hapsyn's share/ directory in the source tree, then the
/// installed share/hapsyn. Returns an absolute path.
/// \param component  the plugin, for the error ("human_arm")
/// \param option     the option's name, for the error ("arm_file")
/// \param value      the option's value
/// \throws Error("<component>: options.<option> = \"<value>\": no such file (tried ...)")
std::string find_data_file(const std::string& component, const std::string& option, const std::string& value);

/// As find_data_file, but a folder is accepted too (a data set of several files).
/// \throws Error("<component>: options.<option> = \"<value>\": no such file or folder (tried ...)")
std::string find_data_path(const std::string& component, const std::string& option, const std::string& value);

}  // namespace hapsyn
