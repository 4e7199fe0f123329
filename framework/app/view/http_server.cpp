#include "http_server.hpp"

#include <hapsyn/error.hpp>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket/rfc6455.hpp>

#include <csignal>
#include <optional>
#include <utility>

namespace hapsyn_cli {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = asio::ip::tcp;
using Routes = std::map<std::string, Resource>;
// Every body is one the server owns (a route's or a constant text): sent without a copy.
using Response = http::response<http::span_body<const char>>;

constexpr std::string_view kNotFound = "not found\n";
constexpr std::string_view kNotAllowed = "method not allowed: only GET\n";
constexpr std::string_view kBadRequest = "bad request\n";
constexpr std::string_view kHeadTooLarge = "request header too large\n";
constexpr std::string_view kBodyTooLarge = "request body too large\n";
constexpr std::string_view kForeignOrigin = "forbidden: a WebSocket's Origin must be a page of this server\n";
constexpr std::string_view kForeignHost = "forbidden: the Host header must name this machine's loopback\n";

// Whether `host` (a Host header) names the loopback at `port`.
bool loopback_host(std::string_view host, unsigned short port) {
  const std::string suffix = ":" + std::to_string(port);
  for (const char* name : {"127.0.0.1", "localhost", "[::1]"}) {
    if (host == std::string(name) + suffix || (port == 80 && host == name)) return true;
  }
  return false;
}

Response make_response(http::status status, unsigned version, std::string_view type, std::string_view body) {
  Response res{status, version};
  res.set(http::field::server, "hapsyn view");
  res.set(http::field::content_type, beast::string_view(type.data(), type.size()));
  res.set(http::field::cache_control, "no-store");
  res.set("X-Content-Type-Options", "nosniff");
  res.body() = beast::span<const char>(body.data(), body.size());
  res.prepare_payload();
  return res;
}

// One client connection: requests read one at a time, each answered from the route table.
class Session : public std::enable_shared_from_this<Session> {
 public:
  Session(tcp::socket socket, const Routes& routes, const ServerSettings& settings, unsigned short port,
          const std::optional<SocketEndpoints>& sockets, const std::shared_ptr<SocketHub>& hub)
      : stream_(std::move(socket)), routes_(routes), settings_(settings), port_(port), sockets_(sockets), hub_(hub) {}

  void read() {
    parser_.emplace();
    parser_->header_limit(static_cast<std::uint32_t>(settings_.max_header_bytes));
    parser_->body_limit(settings_.max_body_bytes);
    stream_.expires_after(settings_.timeout);
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

 private:
  void on_read(beast::error_code ec) {
    if (!ec) {
      const auto& request = parser_->get();
      if (beast::websocket::is_upgrade(request) && sockets_) return upgrade();
      return send(answer(request), request.keep_alive());
    }
    if (ec == http::error::header_limit) return send(make_response(http::status::request_header_fields_too_large, 11, "text/plain", kHeadTooLarge), false);
    if (ec == http::error::body_limit) return send(make_response(http::status::payload_too_large, 11, "text/plain", kBodyTooLarge), false);
    // The client went away, stalled or sent half a request: nobody to answer.
    if (ec == http::error::end_of_stream || ec == http::error::partial_message || ec == beast::error::timeout ||
        ec.category() == asio::error::get_system_category() || ec.category() == asio::error::get_misc_category()) {
      return close();
    }
    send(make_response(http::status::bad_request, 11, "text/plain", kBadRequest), false);
  }

  // A WebSocket upgrade: handed to socket_session.cpp on the endpoints' targets only.
  void upgrade() {
    http::request<http::string_body> request = parser_->release();
    const unsigned version = request.version();
    const std::string_view target(request.target().data(), request.target().size());
    const bool watch = target == sockets_->watch_target;
    const auto host = request[http::field::host];
    const std::string_view host_name(host.data(), host.size());
    const auto origin = request[http::field::origin];
    if (target != sockets_->target && !watch) {
      return send(make_response(http::status::not_found, version, "text/plain", kNotFound), false);
    }
    if (settings_.loopback_hosts_only && !loopback_host(host_name, port_)) {
      return send(make_response(http::status::forbidden, version, "text/plain", kForeignHost), false);
    }
    if (!origin.empty() && std::string_view(origin.data(), origin.size()) != "http://" + std::string(host_name)) {
      return send(make_response(http::status::forbidden, version, "text/plain", kForeignOrigin), false);
    }
    stream_.expires_never();  // the WebSocket keeps its own timeouts
    start_socket_session(stream_.release_socket(), std::move(request), *sockets_, watch, hub_);
  }

  Response answer(const http::request<http::string_body>& request) const {
    const unsigned version = request.version();
    if (request.method() != http::verb::get) {
      Response res = make_response(http::status::method_not_allowed, version, "text/plain", kNotAllowed);
      res.set(http::field::allow, "GET");
      return res;
    }
    const auto host = request[http::field::host];
    if (settings_.loopback_hosts_only && !loopback_host(std::string_view(host.data(), host.size()), port_)) {
      return make_response(http::status::forbidden, version, "text/plain", kForeignHost);
    }
    // Only the exact targets of the table: the request's path is compared, never opened.
    const std::string_view target(request.target().data(), request.target().size());
    const auto route = routes_.find(std::string(target.substr(0, target.find('?'))));
    if (route == routes_.end()) return make_response(http::status::not_found, version, "text/plain", kNotFound);
    return make_response(http::status::ok, version, route->second.content_type, route->second.body);
  }

  void send(Response response, bool keep_alive) {
    response.keep_alive(keep_alive);
    response_.emplace(std::move(response));
    stream_.expires_after(settings_.timeout);
    http::async_write(stream_, *response_, [self = shared_from_this(), keep_alive](beast::error_code ec, std::size_t) {
      if (ec || !keep_alive) return self->close();
      self->read();
    });
  }

  void close() {
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
    stream_.socket().close(ignored);
  }

  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  std::optional<Response> response_;
  const Routes& routes_;
  const ServerSettings& settings_;
  unsigned short port_;  // the server's, for the Host check
  const std::optional<SocketEndpoints>& sockets_;
  std::shared_ptr<SocketHub> hub_;
};

}  // namespace

struct ViewServer::Impl {
  Impl(Routes r, const ServerSettings& s, std::optional<SocketEndpoints> e)
      : routes(std::move(r)), settings(s), sockets(std::move(e)), acceptor(context), signals(context, SIGINT, SIGTERM) {}

  void accept() {
    acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
      if (!acceptor.is_open()) return;
      if (!ec) std::make_shared<Session>(std::move(socket), routes, settings, port, sockets, hub)->read();
      accept();  // an error on one connection (a reset before accept) stops no other
    });
  }

  Routes routes;
  ServerSettings settings;
  std::optional<SocketEndpoints> sockets;
  std::shared_ptr<SocketHub> hub = make_socket_hub();
  unsigned short port = 0;  // bound
  asio::io_context context{1};
  tcp::acceptor acceptor;
  asio::signal_set signals;
};

ViewServer::ViewServer(Routes routes, const ServerSettings& settings, std::optional<SocketEndpoints> sockets)
    : impl_(std::make_unique<Impl>(std::move(routes), settings, std::move(sockets))) {
  beast::error_code ec;
  const asio::ip::address address = asio::ip::make_address(settings.host, ec);
  if (ec) throw hapsyn::Error("view", "--host " + settings.host + ": not an IP address (e.g. 127.0.0.1, ::1, 0.0.0.0)");
  const tcp::endpoint endpoint(address, settings.port);
  tcp::acceptor& a = impl_->acceptor;
  a.open(endpoint.protocol(), ec);
  if (!ec) a.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) a.bind(endpoint, ec);
  if (!ec) a.listen(asio::socket_base::max_listen_connections, ec);
  if (!ec) impl_->port = a.local_endpoint(ec).port();
  if (ec) {
    throw hapsyn::Error("view", "cannot listen on " + settings.host + " port " + std::to_string(settings.port) + ": " +
                                    ec.message() + (settings.port ? " (choose another with --port, or --port 0)" : ""));
  }
}

ViewServer::~ViewServer() = default;

unsigned short ViewServer::port() const { return impl_->port; }

void ViewServer::run_until_signal() {
  impl_->signals.async_wait([this](beast::error_code, int) {
    beast::error_code ignored;
    impl_->acceptor.close(ignored);
    impl_->context.stop();
  });
  impl_->accept();
  impl_->context.run();
}

}  // namespace hapsyn_cli
