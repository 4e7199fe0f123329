#pragma once
// `hapsyn view PROBLEM_OR_RESULT_DIR`: the study's page and its JSON API on a local server.
#include <hapsyn/internal/registry.hpp>

#include <string>

namespace hapsyn_cli {

/// Loads the study (view_data.hpp), prints "hapsyn view: serving <study> at http://HOST:PORT/"
/// and serves until SIGINT or SIGTERM. \return 0 after a signal.
/// \throws hapsyn::Error("view", ...) when the page's assets were not built, or the server
///         cannot listen; the study's load errors.
int view_command(const std::string& path, const std::string& host, int port, const hapsyn::Registry& registry);

}  // namespace hapsyn_cli
