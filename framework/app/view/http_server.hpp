#pragma once
// The local HTTP server of `hapsyn view` (Boost.Beast): a fixed table of routes, each a body
// held in memory; nothing else is served, no path of a request is ever opened.
#include "socket_session.hpp"

#include <chrono>
#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

namespace hapsyn_cli {

/// One thing the server hands out: its bytes (which outlive the server) and their type.
struct Resource {
  std::string content_type;
  std::string_view body;
};

/// Where and how the server listens.
struct ServerSettings {
  std::string host = "127.0.0.1";  ///< the address to bind (loopback unless told otherwise)
  unsigned short port = 8080;      ///< 0 = any free port (ViewServer::port() tells which)
  /// Largest request head (request line and headers) [bytes]; a longer one gets 431 and the
  /// connection is closed. A request body is refused beyond max_body_bytes (413).
  std::size_t max_header_bytes = 8 * 1024;
  std::size_t max_body_bytes = 1024;
  /// A connection that sends no complete request within this time is closed.
  std::chrono::milliseconds timeout{10000};
  /// Answer only requests whose Host header names this machine's loopback ("127.0.0.1:PORT",
  /// "localhost:PORT", "[::1]:PORT"), others with 403: a web page the user visits cannot read
  /// the study through a name of its own that resolves to 127.0.0.1 (DNS rebinding).
  bool loopback_hosts_only = true;
};

/// Serves `routes` (exact request targets such as "/" or "/api/study"; a query string is
/// ignored) to GET requests: 200 with the body, 404 for any other target, 405 for any other
/// method, 400 for a malformed request, 431/413 for an oversized one, 403 for another Host
/// (ServerSettings::loopback_hosts_only). One thread, asynchronous:
/// a slow or broken client delays no other. HTTP/1.1 keep-alive is honoured.
class ViewServer {
 public:
  /// Binds and listens. \throws hapsyn::Error("view", ...) naming the address and port when
  /// the host is not an IP address or the port cannot be bound.
  /// `sockets`: WebSocket endpoints (socket_session.hpp), upgraded only on their two targets,
  /// with the Host rule of HTTP and, when the request has an Origin, only that of a page of this
  /// server ("http://" + its Host): another site's page cannot drive or watch the prototype.
  ViewServer(std::map<std::string, Resource> routes, const ServerSettings& settings,
             std::optional<SocketEndpoints> sockets = std::nullopt);
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;
  /// The port it listens on (the one the system chose for port 0).
  unsigned short port() const;
  /// Serves until SIGINT or SIGTERM arrives (then returns normally), on the calling thread.
  void run_until_signal();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hapsyn_cli
