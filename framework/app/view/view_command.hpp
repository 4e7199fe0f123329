#pragma once
// `hapsyn view PROBLEM_OR_RESULT_DIR`: the study's page and its JSON API on a local server.
#include <hapsyn/internal/registry.hpp>

#include <string>

namespace hapsyn_cli {

/// Loads the study (view_data.hpp), prints "hapsyn view: serving <study> at http://HOST:PORT/"
/// and serves until SIGINT or SIGTERM: the page, /api/study, /api/samples, /api/replay
/// (replay_data.hpp, with the shoulder frame of live_session.hpp) and the WebSocket endpoints
/// /live and /live/watch (live_session.hpp, socket_session.hpp). \return 0 after a signal.
/// \throws hapsyn::Error("view", ...) when the page's assets were not built, or the server
///         cannot listen; the study's load errors.
int view_command(const std::string& path, const std::string& host, int port, const hapsyn::Registry& registry);

}  // namespace hapsyn_cli
