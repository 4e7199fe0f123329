#pragma once
// The WebSocket side of `hapsyn view`'s server (Boost.Beast websocket): one endpoint whose
// connections each send text messages and get one answer per message, and a watch endpoint
// whose connections receive every answer that is a frame (the page following a tracker bridge).
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/http.hpp>

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace hapsyn_cli {

/// One answer to a message: its text, and whether it is a frame the watchers get too (an error
/// answer goes to its sender only).
struct SocketReply {
  std::string text;
  bool broadcast = false;
};

/// A connection's handler: answers each text message (called on the server's thread, in order).
using MessageHandler = std::function<SocketReply(std::string_view message)>;

/// The server's WebSocket endpoints.
struct SocketEndpoints {
  std::string target;        ///< e.g. "/live": each message answered by the connection's handler
  std::string watch_target;  ///< e.g. "/live/watch": receives every broadcast answer, sends nothing
  std::function<MessageHandler()> connect;  ///< a new connection's handler (its own state)
  /// A text message longer than this [bytes] is answered with an error frame; the connection stays.
  std::size_t max_message_bytes = 4096;
  /// A message longer than this [bytes] closes the connection (close code 1009, "too big").
  std::size_t max_frame_bytes = 1 << 20;
  /// Frames a slow watcher may have queued; older ones are dropped (the newest pose matters).
  std::size_t max_watch_queue = 8;
};

class SocketHub;

/// Takes over an upgraded connection: `request` is the upgrade request the HTTP side read and
/// checked (target, Host, Origin). `watcher`: a watch connection.
void start_socket_session(boost::asio::ip::tcp::socket socket,
                          boost::beast::http::request<boost::beast::http::string_body> request,
                          const SocketEndpoints& endpoints, bool watcher, const std::shared_ptr<SocketHub>& hub);

/// Where watch connections register (one per server; single-threaded like the server).
std::shared_ptr<SocketHub> make_socket_hub();

/// The error answer {"error": text} (text JSON-escaped).
std::string socket_error(const std::string& text);

}  // namespace hapsyn_cli
