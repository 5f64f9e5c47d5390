// The live view's HTTP and WebSocket server (see live_view.hpp; docs/live-view.md).
#include "rowloc/service/live_view.hpp"

#include "live_view_assets.hpp"
#include "rowloc/service/live_scene.hpp"

#include <boost/asio.hpp>
#include <boost/asio/awaitable.hpp>
#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <deque>
#include <functional>
#include <list>
#include <mutex>
#include <optional>

namespace rowloc::service {
namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using asio::awaitable;
using asio::use_awaitable;
using tcp = asio::ip::tcp;
using Request = http::request<http::empty_body>;

namespace {

/// The live clients' ids in their sessions' subscriber lists, apart from the socket connections'
/// (1, 2, ...): a session keeps one subscription per id.
constexpr std::uint64_t kLiveClientIdBase = std::uint64_t{1} << 63;
constexpr auto kHttpReadTimeout = std::chrono::seconds(30);
constexpr std::size_t kMaxHttpHeaderBytes = 16 * 1024;
constexpr std::size_t kMaxPageMessageBytes = 64 * 1024;
constexpr auto kSessionListPeriod = std::chrono::seconds(1);

std::string_view View(beast::string_view s) { return {s.data(), s.size()}; }

int HexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

/// %XX and + of a query value decoded; nullopt for a malformed escape.
std::optional<std::string> PercentDecoded(std::string_view text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '+') {
      out += ' ';
    } else if (text[i] != '%') {
      out += text[i];
    } else {
      if (i + 2 >= text.size() || HexValue(text[i + 1]) < 0 || HexValue(text[i + 2]) < 0) return std::nullopt;
      out += static_cast<char>(HexValue(text[i + 1]) * 16 + HexValue(text[i + 2]));
      i += 2;
    }
  }
  return out;
}

struct Target {
  std::string path;
  std::optional<std::string> token;  ///< the query's `token`
};

Target ParseTarget(std::string_view target) {
  Target parsed;
  const std::size_t question = target.find('?');
  parsed.path = std::string(target.substr(0, question));
  if (question == std::string_view::npos) return parsed;
  std::string_view query = target.substr(question + 1);
  while (!query.empty()) {
    const std::size_t amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    if (pair.rfind("token=", 0) == 0) parsed.token = PercentDecoded(pair.substr(6)).value_or("");
    query = amp == std::string_view::npos ? std::string_view() : query.substr(amp + 1);
  }
  return parsed;
}

/// The token a request presents: `Authorization: Bearer TOKEN`, else the query's `token`.
std::string PresentedToken(const Request& request, const Target& target) {
  const std::string_view authorization = View(request[http::field::authorization]);
  if (authorization.rfind("Bearer ", 0) == 0) return std::string(authorization.substr(7));
  return target.token.value_or("");
}

/// A browser's WebSocket from another site (its Origin is not this server): refused, so that a web
/// page the user visits cannot read the view through the user's browser.
bool ForeignOrigin(const Request& request) {
  const std::string_view origin = View(request[http::field::origin]);
  if (origin.empty()) return false;  // not a browser
  const std::string_view host = View(request[http::field::host]);
  return origin != "http://" + std::string(host) && origin != "https://" + std::string(host);
}

http::response<http::string_body> Response(const Request& request, http::status status, std::string_view type,
                                           std::string body) {
  http::response<http::string_body> response{status, request.version()};
  response.set(http::field::server, "rowloc live view");
  response.set(http::field::content_type, beast::string_view(type.data(), type.size()));
  response.set(http::field::cache_control, "no-store");
  response.set("X-Content-Type-Options", "nosniff");
  response.keep_alive(request.keep_alive());
  response.body() = std::move(body);
  response.prepare_payload();
  return response;
}

http::response<http::string_body> Page(const Request& request, const std::string& path) {
  if (request.method() != http::verb::get) {
    auto response = Response(request, http::status::method_not_allowed, "text/plain", "only GET\n");
    response.set(http::field::allow, "GET");
    return response;
  }
  const std::string file = path == "/" ? "/index.html" : path;
  for (const LiveViewAsset& asset : LiveViewAssets()) {
    if (asset.path == file) return Response(request, http::status::ok, asset.content_type, std::string(asset.body));
  }
  return Response(request, http::status::not_found, "text/plain", "not found: " + path + "\n");
}

/// One WebSocket client of the view: a Dispatcher client (ClientContext) whose sink keeps the newest
/// state, a bounded list of observations and of replies; a writer sends them as one frame per period.
class LiveClient : public OutputSink, public std::enable_shared_from_this<LiveClient> {
 public:
  LiveClient(websocket::stream<beast::tcp_stream> ws, Dispatcher& dispatcher, std::uint64_t id,
             std::function<void()> on_end)
      : ws_(std::move(ws)), timer_(ws_.get_executor()), dispatcher_(dispatcher), id_(id), on_end_(std::move(on_end)) {
    client_.authenticated = true;  // the upgrade request carried the token
  }

  void Start(Request request) {
    client_.sink = shared_from_this();  // dropped when Run ends
    asio::co_spawn(ws_.get_executor(), [self = shared_from_this(), r = std::move(request)]() mutable {
      return self->Run(std::move(r));
    }, asio::detached);
  }

  std::uint64_t client_id() const override { return id_; }

  void Push(std::string line, bool pushed) override {
    std::lock_guard lock(mutex_);
    if (closing_) return;
    if (!pushed) {
      replies_.push_back(std::move(line));
      if (replies_.size() > LiveView::kMaxReplyLines) {
        replies_.pop_front();
        ++dropped_;
      }
    } else if (line.rfind(R"({"type":"state")", 0) == 0) {
      if (state_) ++states_skipped_;
      state_ = std::move(line);
    } else {
      observations_.push_back(std::move(line));
      if (observations_.size() > LiveView::kMaxObservationLines) {
        observations_.pop_front();
        ++dropped_;
        dispatcher_.stats().dropped_lines.fetch_add(1, std::memory_order_relaxed);
      }
    }
  }

  void Close() {
    asio::post(ws_.get_executor(), [self = shared_from_this()] {
      {
        std::lock_guard lock(self->mutex_);
        self->closing_ = true;
      }
      boost::system::error_code ignored;
      beast::get_lowest_layer(self->ws_).socket().close(ignored);
      self->timer_.cancel();
    });
  }

 private:
  awaitable<void> Run(Request request) {
    try {
      ws_.set_option(websocket::stream_base::timeout{std::chrono::seconds(30), std::chrono::seconds(60), true});
      ws_.read_message_max(kMaxPageMessageBytes);
      ws_.text(true);
      co_await ws_.async_accept(request, use_awaitable);
      asio::co_spawn(ws_.get_executor(), [self = shared_from_this()] { return self->Write(); }, asio::detached);
      co_await Read();
    } catch (const boost::system::system_error& e) {
      if (e.code() != websocket::error::closed && e.code() != asio::error::operation_aborted &&
          e.code() != asio::error::eof && e.code() != beast::error::timeout) {
        spdlog::debug("live view client {}: {}", id_ - kLiveClientIdBase, e.what());
      }
    } catch (const std::exception& e) {
      spdlog::error("live view client {}: {}", id_ - kLiveClientIdBase, e.what());
    }
    {
      std::lock_guard lock(mutex_);
      closing_ = true;
    }
    timer_.cancel();
    dispatcher_.ClientGone(client_);
    client_.sink.reset();
    on_end_();
  }

  awaitable<void> Read() {
    beast::flat_buffer buffer;
    for (;;) {
      co_await ws_.async_read(buffer, use_awaitable);
      const std::string text = beast::buffers_to_string(buffer.data());
      buffer.consume(buffer.size());
      HandlePageMessage(text);
    }
  }

  /// What the page may ask (docs/live-view.md §4): watch a session, list the sessions.
  void HandlePageMessage(const std::string& text) {
    const nlohmann::json request = nlohmann::json::parse(text, nullptr, false);
    const std::string type = request.is_object() && request.value("type", nlohmann::json()).is_string()
                                 ? request["type"].get<std::string>()
                                 : "";
    if (type == "watch" && request.contains("session") && request["session"].is_string()) {
      Watch(request["session"].get<std::string>());
    } else if (type == "list_sessions") {
      SendRequest(R"({"type":"list_sessions"})");
    } else {
      PushError("invalid_request", R"(the page may send {"type":"watch","session":NAME} or {"type":"list_sessions"})");
    }
  }

  void SendRequest(const std::string& line) { dispatcher_.HandleLine(client_, line, ++lines_); }

  void PushError(const char* code, const std::string& message) {
    Push(nlohmann::ordered_json{{"type", "error"}, {"id", nullptr}, {"code", code}, {"message", message}}.dump(
             -1, ' ', false, nlohmann::json::error_handler_t::replace),
         false);
  }

  void Watch(const std::string& name) {
    using Json = nlohmann::json;
    if (!watched_.empty()) SendRequest(Json{{"type", "unsubscribe"}, {"session", watched_}}.dump());
    watched_.clear();
    const std::shared_ptr<ServiceSession> session = dispatcher_.FindSession(name);
    if (!session) {
      PushError("unknown_session", "session '" + name + "' is not open");
      return;
    }
    std::shared_ptr<const geometry::RowMap> map;
    std::string map_error;
    if (!session->spec().map.empty()) {
      try {
        map = dispatcher_.LoadMap(session->spec().map);
      } catch (const std::exception& e) {
        map_error = e.what();
      }
    }
    {
      std::lock_guard lock(mutex_);
      state_.reset();
      observations_.clear();
    }
    Push(LiveSceneLine(*session, map.get(), map_error), false);
    SendRequest(Json{{"type", "subscribe"}, {"session", name}, {"stream", "live"}}.dump());
    SendRequest(Json{{"type", "get_state"}, {"session", name}}.dump());  // an idle session's state too
    watched_ = name;
  }

  /// Everything buffered as one `frame` message (docs/live-view.md §4), or "" when nothing is.
  std::string TakeFrame() {
    std::lock_guard lock(mutex_);
    if (replies_.empty() && observations_.empty() && !state_) return "";
    std::string frame = R"({"type":"frame","dropped":)" + std::to_string(dropped_) +
                        R"(,"states_skipped":)" + std::to_string(states_skipped_) + R"(,"lines":[)";
    bool first = true;
    const auto add = [&](const std::string& line) {
      if (!first) frame += ',';
      frame += line;
      first = false;
    };
    for (const std::string& line : replies_) add(line);
    for (const std::string& line : observations_) add(line);
    if (state_) add(*state_);
    frame += "]}";
    replies_.clear();
    observations_.clear();
    state_.reset();
    dropped_ = 0;
    states_skipped_ = 0;
    return frame;
  }

  awaitable<void> Write() {
    const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(1.0 / dispatcher_.settings().live_view_rate_hz));
    auto next_list = std::chrono::steady_clock::now();
    try {
      for (;;) {
        if (std::chrono::steady_clock::now() >= next_list) {
          SendRequest(R"({"type":"list_sessions"})");
          next_list = std::chrono::steady_clock::now() + kSessionListPeriod;
        }
        const std::string frame = TakeFrame();
        if (!frame.empty()) co_await ws_.async_write(asio::buffer(frame), use_awaitable);
        timer_.expires_after(period);
        boost::system::error_code ec;
        co_await timer_.async_wait(asio::redirect_error(use_awaitable, ec));
        std::lock_guard lock(mutex_);
        if (closing_) break;
      }
    } catch (const std::exception& e) {
      spdlog::debug("live view client {}: write: {}", id_ - kLiveClientIdBase, e.what());
    }
    boost::system::error_code ignored;
    beast::get_lowest_layer(ws_).socket().close(ignored);
  }

  websocket::stream<beast::tcp_stream> ws_;
  asio::steady_timer timer_;
  Dispatcher& dispatcher_;
  std::uint64_t id_;
  std::function<void()> on_end_;
  ClientContext client_;
  std::size_t lines_ = 0;
  std::string watched_;
  std::mutex mutex_;
  std::deque<std::string> replies_;
  std::deque<std::string> observations_;
  std::optional<std::string> state_;
  std::size_t dropped_ = 0;         ///< replies and observations dropped since the last frame
  std::size_t states_skipped_ = 0;  ///< states replaced by a newer one since the last frame
  bool closing_ = false;
};

}  // namespace

class LiveView::Impl : public std::enable_shared_from_this<LiveView::Impl> {
 public:
  Impl(Dispatcher& dispatcher, asio::io_context& io) : dispatcher_(dispatcher), io_(io), acceptor_(io) {}

  void Listen() {
    const ServiceSettings& s = dispatcher_.settings();
    boost::system::error_code ec;
    const asio::ip::address address = asio::ip::make_address(s.listen == "localhost" ? "127.0.0.1" : s.listen, ec);
    if (ec) throw std::runtime_error("listen: '" + s.listen + "' is not an IP address");
    const tcp::endpoint endpoint(address, static_cast<unsigned short>(s.http_port));
    acceptor_.open(endpoint.protocol());
    acceptor_.set_option(tcp::acceptor::reuse_address(true));
    acceptor_.bind(endpoint, ec);
    if (ec) {
      throw std::runtime_error("live view: cannot listen on " + s.listen + ":" + std::to_string(s.http_port) + ": " +
                               ec.message());
    }
    acceptor_.listen();
  }

  std::string url() const {
    const tcp::endpoint e = acceptor_.local_endpoint();
    const std::string host = e.address().is_v6() ? "[" + e.address().to_string() + "]" : e.address().to_string();
    return "http://" + host + ":" + std::to_string(e.port()) + "/";
  }

  void Start() {
    asio::co_spawn(io_, [self = shared_from_this()] { return self->Accept(); }, asio::detached);
  }

  void Stop() {
    asio::post(io_, [self = shared_from_this()] {
      self->stopping_ = true;
      boost::system::error_code ignored;
      self->acceptor_.close(ignored);
      std::lock_guard lock(self->clients_mutex_);
      for (const auto& weak : self->clients_) {
        if (const auto client = weak.lock()) client->Close();
      }
    });
  }

 private:
  awaitable<void> Accept() {
    for (;;) {
      boost::system::error_code ec;
      tcp::socket socket =
          co_await acceptor_.async_accept(asio::make_strand(io_), asio::redirect_error(use_awaitable, ec));
      if (ec) {
        if (ec == asio::error::operation_aborted || stopping_) co_return;
        spdlog::warn("live view: accept: {}", ec.message());
        continue;
      }
      socket.set_option(tcp::no_delay(true), ec);
      asio::co_spawn(socket.get_executor(),
                     [self = shared_from_this(), s = std::move(socket)]() mutable { return self->Serve(std::move(s)); },
                     asio::detached);
    }
  }

  /// One HTTP connection: pages until it upgrades to the WebSocket, closes, or times out.
  awaitable<void> Serve(tcp::socket socket) {
    beast::tcp_stream stream(std::move(socket));
    beast::flat_buffer buffer;
    try {
      for (;;) {
        http::request_parser<http::empty_body> parser;
        parser.header_limit(kMaxHttpHeaderBytes);
        stream.expires_after(kHttpReadTimeout);
        co_await http::async_read(stream, buffer, parser, use_awaitable);
        Request request = parser.release();
        const Target target = ParseTarget(View(request.target()));
        if (!dispatcher_.TokenMatches(PresentedToken(request, target))) {
          co_await Send(stream, Response(request, http::status::unauthorized, "text/plain",
                                         "this server needs its token: open the view as /?token=TOKEN\n"));
        } else if (!websocket::is_upgrade(request)) {
          co_await Send(stream, Page(request, target.path));
        } else if (target.path != "/ws") {
          co_await Send(stream, Response(request, http::status::not_found, "text/plain", "the WebSocket is /ws\n"));
        } else if (ForeignOrigin(request)) {
          co_await Send(stream, Response(request, http::status::forbidden, "text/plain",
                                         "a WebSocket from another origin\n"));
        } else if (live_clients_.load() >= dispatcher_.settings().max_connections) {
          co_await Send(stream, Response(request, http::status::service_unavailable, "text/plain",
                                         "max_connections live view clients\n"));
        } else {
          stream.expires_never();
          Upgrade(std::move(stream), std::move(request));
          co_return;
        }
        if (!request.keep_alive()) break;
      }
    } catch (const boost::system::system_error& e) {
      if (e.code() != http::error::end_of_stream && e.code() != beast::error::timeout) {
        spdlog::debug("live view: http: {}", e.what());
      }
    } catch (const std::exception& e) {
      spdlog::debug("live view: http: {}", e.what());
    }
    boost::system::error_code ignored;
    stream.socket().shutdown(tcp::socket::shutdown_send, ignored);
  }

  static awaitable<void> Send(beast::tcp_stream& stream, http::response<http::string_body> response) {
    co_await http::async_write(stream, response, use_awaitable);
  }

  void Upgrade(beast::tcp_stream stream, Request request) {
    ++live_clients_;
    const std::uint64_t id = kLiveClientIdBase + ++next_id_;
    auto client = std::make_shared<LiveClient>(websocket::stream<beast::tcp_stream>(std::move(stream)), dispatcher_,
                                               id, [self = shared_from_this()] { --self->live_clients_; });
    {
      std::lock_guard lock(clients_mutex_);
      clients_.remove_if([](const std::weak_ptr<LiveClient>& c) { return c.expired(); });
      clients_.push_back(client);
    }
    client->Start(std::move(request));
  }

  Dispatcher& dispatcher_;
  asio::io_context& io_;
  tcp::acceptor acceptor_;
  std::atomic<bool> stopping_{false};
  std::atomic<std::size_t> live_clients_{0};
  std::atomic<std::uint64_t> next_id_{0};
  std::mutex clients_mutex_;
  std::list<std::weak_ptr<LiveClient>> clients_;
};

LiveView::LiveView(Dispatcher& dispatcher, boost::asio::io_context& io)
    : impl_(std::make_shared<Impl>(dispatcher, io)) {}
LiveView::~LiveView() = default;
void LiveView::Listen() { impl_->Listen(); }
std::string LiveView::url() const { return impl_->url(); }
void LiveView::Start() { impl_->Start(); }
void LiveView::Stop() { impl_->Stop(); }

}  // namespace rowloc::service
