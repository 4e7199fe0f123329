#include "socket_session.hpp"

#include <hapsyn/json.hpp>

#include <boost/asio/buffer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>

#include <deque>
#include <exception>
#include <utility>

namespace hapsyn_cli {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

class SocketSession;

class SocketHub {
 public:
  void add(const std::shared_ptr<SocketSession>& watcher) { watchers_.push_back(watcher); }
  void broadcast(const std::string& text);

 private:
  std::vector<std::weak_ptr<SocketSession>> watchers_;
};

// One WebSocket connection: reads messages one at a time, answers each; writes are queued (a
// watcher also gets the broadcast frames), one write in flight at a time, as Beast requires.
class SocketSession : public std::enable_shared_from_this<SocketSession> {
 public:
  SocketSession(tcp::socket socket, const SocketEndpoints& endpoints, bool watcher, std::shared_ptr<SocketHub> hub)
      : ws_(std::move(socket)), endpoints_(endpoints), watcher_(watcher), hub_(std::move(hub)) {
    if (!watcher_) handler_ = endpoints_.connect();
  }

  void accept(beast::http::request<beast::http::string_body> request) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& res) { res.set(beast::http::field::server, "hapsyn view"); }));
    ws_.read_message_max(endpoints_.max_frame_bytes);
    ws_.text(true);
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return;
      if (self->watcher_) self->hub_->add(self);
      self->read();
    });
  }

  // Queues a frame for a watcher, dropping the oldest beyond the limit.
  void push(const std::string& text) {
    if (!open_) return;
    // The front is being written when a write is in flight: never drop it.
    while (queue_.size() > endpoints_.max_watch_queue) queue_.erase(queue_.begin() + (writing_ ? 1 : 0));
    send(text);
  }

 private:
  void read() {
    buffer_.clear();
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

  void on_read(beast::error_code ec) {
    if (ec) {  // closed by the client, a protocol error, a message beyond max_frame_bytes, a timeout
      open_ = false;
      return;
    }
    const std::string_view message(static_cast<const char*>(buffer_.cdata().data()), buffer_.size());
    SocketReply reply;
    if (watcher_) {
      reply.text = socket_error("view: " + endpoints_.watch_target + " only sends frames; send poses to " + endpoints_.target);
    } else if (!ws_.got_text()) {
      reply.text = socket_error("view: a binary message: send JSON text");
    } else if (message.size() > endpoints_.max_message_bytes) {
      reply.text = socket_error("view: a message of " + std::to_string(message.size()) + " bytes: more than the " +
                                std::to_string(endpoints_.max_message_bytes) + " a message may have");
    } else {
      try {
        reply = handler_(message);
      } catch (const std::exception& e) {  // the server outlives a failing frame
        reply = {socket_error(std::string("view: the frame failed: ") + e.what()), false};
      }
    }
    if (reply.broadcast) hub_->broadcast(reply.text);
    send(std::move(reply.text));
    read();
  }

  void send(std::string text) {
    queue_.push_back(std::move(text));
    if (!writing_) write();
  }

  void write() {
    writing_ = true;
    ws_.async_write(asio::buffer(queue_.front()), [self = shared_from_this()](beast::error_code ec, std::size_t) {
      self->queue_.pop_front();
      self->writing_ = false;
      if (ec) {
        self->open_ = false;
        self->queue_.clear();
        return;
      }
      if (!self->queue_.empty()) self->write();
    });
  }

  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer buffer_;
  const SocketEndpoints& endpoints_;
  bool watcher_;
  std::shared_ptr<SocketHub> hub_;
  MessageHandler handler_;
  std::deque<std::string> queue_;
  bool writing_ = false;
  bool open_ = true;
};

void SocketHub::broadcast(const std::string& text) {
  std::vector<std::weak_ptr<SocketSession>> alive;
  for (const auto& w : watchers_) {
    if (const auto watcher = w.lock()) {
      watcher->push(text);
      alive.push_back(w);
    }
  }
  watchers_ = std::move(alive);
}

std::shared_ptr<SocketHub> make_socket_hub() { return std::make_shared<SocketHub>(); }

std::string socket_error(const std::string& text) { return hapsyn::Json{{"error", text}}.dump(); }

void start_socket_session(tcp::socket socket, beast::http::request<beast::http::string_body> request,
                          const SocketEndpoints& endpoints, bool watcher, const std::shared_ptr<SocketHub>& hub) {
  std::make_shared<SocketSession>(std::move(socket), endpoints, watcher, hub)->accept(std::move(request));
}

}  // namespace hapsyn_cli
