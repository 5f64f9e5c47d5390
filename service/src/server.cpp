// The socket transport of the service (see server.hpp).
#include "rowloc/service/server.hpp"

#include "rowloc/service/line_framer.hpp"
#include "rowloc/service/live_view.hpp"

#include <boost/asio.hpp>
#include <boost/asio/awaitable.hpp>
#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <deque>
#include <list>
#include <mutex>
#include <thread>

namespace rowloc::service {
namespace asio = boost::asio;
using asio::awaitable;
using asio::use_awaitable;
using tcp = asio::ip::tcp;
using unix_socket = asio::local::stream_protocol;

namespace {

/// The part of a connection the server's timer and Stop need, whatever its socket type.
class ConnectionBase : public OutputSink {
 public:
  virtual void Close() = 0;
  virtual double idle_s() const = 0;
  /// After the I/O threads ended: drops the connection's reference to itself (which its reader
  /// drops when it ends normally), so that a connection cut off by the stop is freed.
  virtual void Detach() = 0;
};

template <class Socket>
class Connection : public ConnectionBase, public std::enable_shared_from_this<Connection<Socket>> {
 public:
  Connection(Socket socket, Dispatcher& dispatcher, std::uint64_t id)
      : socket_(std::move(socket)),
        timer_(socket_.get_executor()),
        read_gate_(socket_.get_executor()),
        dispatcher_(dispatcher),
        id_(id),
        framer_(dispatcher.settings().max_line_bytes) {
    timer_.expires_at(std::chrono::steady_clock::time_point::max());
    read_gate_.expires_at(std::chrono::steady_clock::time_point::max());
  }

  void Start() {
    client_.sink = this->shared_from_this();
    auto self = this->shared_from_this();
    asio::co_spawn(socket_.get_executor(), [self]() { return self->Read(); }, asio::detached);
    asio::co_spawn(socket_.get_executor(), [self]() { return self->Write(); }, asio::detached);
  }

  std::uint64_t client_id() const override { return id_; }

  void Push(std::string line, bool pushed) override {
    bool wake = false;
    {
      std::lock_guard lock(mutex_);
      if (closing_) return;
      const Settings& s = dispatcher_.settings();
      if (pushed && pushed_queued_ >= s.max_queue_lines) {
        if (s.slow_client == SlowClientPolicy::kDisconnect) {
          spdlog::warn("connection {}: does not read its subscription; closed (slow_client disconnect)", id_);
          RequestCloseLocked();
          return;
        }
        const auto oldest = std::find_if(queue_.begin(), queue_.end(), [](const auto& q) { return q.second; });
        queue_.erase(oldest);
        --pushed_queued_;
        ++dropped_unreported_;
        dispatcher_.stats().dropped_lines.fetch_add(1, std::memory_order_relaxed);
      }
      if (queue_.size() >= 2 * s.max_queue_lines) {
        spdlog::warn("connection {}: {} replies not read; closed", id_, queue_.size());
        RequestCloseLocked();
        return;
      }
      if (pushed && dropped_unreported_ > 0 && line.size() > 1 && line.back() == '}') {
        line.pop_back();  // the client learns how many pushed lines it missed
        line += ",\"dropped\":" + std::to_string(dropped_unreported_) + "}";
        dropped_unreported_ = 0;
      }
      queue_.emplace_back(std::move(line), pushed);
      if (pushed) ++pushed_queued_;
      dispatcher_.stats().RecordQueueLength(queue_.size());
      wake = writer_waiting_;
      writer_waiting_ = false;
    }
    if (wake) asio::post(socket_.get_executor(), [self = this->shared_from_this()] { self->timer_.cancel(); });
  }

  void Close() override {
    std::lock_guard lock(mutex_);
    RequestCloseLocked();
  }

  void Detach() override { client_.sink.reset(); }

  double idle_s() const override {
    const auto last = std::chrono::steady_clock::time_point(
        std::chrono::steady_clock::duration(last_activity_.load(std::memory_order_relaxed)));
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - last).count();
  }

 private:
  using Settings = ServiceSettings;

  void RequestCloseLocked() {
    if (closing_) return;
    closing_ = true;
    asio::post(socket_.get_executor(), [self = this->shared_from_this()] {
      boost::system::error_code ignored;
      self->socket_.close(ignored);
      self->timer_.cancel();
      self->read_gate_.cancel();
    });
  }

  void MarkActive() {
    last_activity_.store(std::chrono::steady_clock::now().time_since_epoch().count(), std::memory_order_relaxed);
  }

  awaitable<void> Read() {
    std::vector<char> buffer(64 * 1024);
    MarkActive();
    try {
      for (;;) {
        const std::size_t n = co_await socket_.async_read_some(asio::buffer(buffer), use_awaitable);
        MarkActive();
        for (const FramedLine& line : framer_.Feed(std::string_view(buffer.data(), n))) {
          if (line.kind == FramedLine::Kind::kOversized) {
            dispatcher_.HandleOversizedLine(client_, line.line_number);
          } else {
            dispatcher_.HandleLine(client_, line.text, line.line_number);
          }
        }
        dispatcher_.EndBatch(client_);
        co_await WaitWhileBacklogged();
      }
    } catch (const boost::system::system_error& e) {
      if (e.code() != asio::error::eof && e.code() != asio::error::operation_aborted &&
          e.code() != asio::error::connection_reset) {
        spdlog::debug("connection {}: read: {}", id_, e.what());
      }
    } catch (const std::exception& e) {
      spdlog::error("connection {}: {}", id_, e.what());
    }
    // A last line without its newline is a truncated request: it is not executed.
    dispatcher_.ClientGone(client_);
    dispatcher_.stats().connections.fetch_sub(1);
    client_.sink.reset();  // the connection no longer owns itself
    Close();
  }

  /// Backpressure: a client that sends faster than it reads what it asked for (replies, its own
  /// subscriptions) is not read from until its queue is below half the limit, so the lines it asked
  /// for are not dropped; TCP then slows the client down.
  awaitable<void> WaitWhileBacklogged() {
    for (;;) {
      {
        std::lock_guard lock(mutex_);
        if (closing_ || queue_.size() <= dispatcher_.settings().max_queue_lines / 2) co_return;
        reader_waiting_ = true;
      }
      boost::system::error_code ec;
      co_await read_gate_.async_wait(asio::redirect_error(use_awaitable, ec));
    }
  }

  awaitable<void> Write() {
    std::string chunk;
    try {
      for (;;) {
        std::deque<std::pair<std::string, bool>> lines;
        {
          std::lock_guard lock(mutex_);
          if (queue_.empty()) {
            if (closing_) break;
            writer_waiting_ = true;
          } else {
            lines.swap(queue_);
            pushed_queued_ = 0;
            if (reader_waiting_) {
              reader_waiting_ = false;
              read_gate_.cancel();
            }
          }
        }
        if (lines.empty()) {
          boost::system::error_code ec;
          co_await timer_.async_wait(asio::redirect_error(use_awaitable, ec));
          continue;
        }
        chunk.clear();
        for (auto& [line, pushed] : lines) {
          chunk += line;
          chunk += '\n';
        }
        co_await asio::async_write(socket_, asio::buffer(chunk), use_awaitable);
      }
    } catch (const std::exception& e) {
      spdlog::debug("connection {}: write: {}", id_, e.what());
    }
    std::lock_guard lock(mutex_);
    RequestCloseLocked();
  }

  Socket socket_;
  asio::steady_timer timer_;      ///< wakes the writer
  asio::steady_timer read_gate_;  ///< wakes a reader paused by backpressure
  Dispatcher& dispatcher_;
  std::uint64_t id_;
  LineFramer framer_;
  ClientContext client_;
  std::mutex mutex_;
  std::deque<std::pair<std::string, bool>> queue_;  ///< line, pushed (droppable)
  std::size_t pushed_queued_ = 0;
  std::size_t dropped_unreported_ = 0;  ///< dropped pushed lines not yet told in a `dropped` key
  bool writer_waiting_ = false;
  bool reader_waiting_ = false;
  bool closing_ = false;
  std::atomic<std::chrono::steady_clock::rep> last_activity_{0};
};

}  // namespace

class Server::Impl {
 public:
  explicit Impl(Dispatcher& dispatcher)
      : dispatcher_(dispatcher), settings_(dispatcher.settings()), io_(settings_.threads), tick_(io_) {}

  void Listen() {
    boost::system::error_code ec;
    const asio::ip::address address = asio::ip::make_address(settings_.listen == "localhost" ? "127.0.0.1"
                                                                                             : settings_.listen, ec);
    if (ec) throw std::runtime_error("listen: '" + settings_.listen + "' is not an IP address");
    tcp_.emplace(io_);
    const tcp::endpoint endpoint(address, static_cast<unsigned short>(settings_.port));
    tcp_->open(endpoint.protocol());
    tcp_->set_option(tcp::acceptor::reuse_address(true));
    tcp_->bind(endpoint, ec);
    if (ec) throw std::runtime_error("cannot listen on " + settings_.listen + ":" + std::to_string(settings_.port) +
                                     ": " + ec.message());
    tcp_->listen();
    if (!settings_.unix_socket.empty()) {
      std::error_code fs_ec;
      if (std::filesystem::is_socket(settings_.unix_socket, fs_ec)) std::filesystem::remove(settings_.unix_socket);
      unix_.emplace(io_);
      unix_->open();
      unix_->bind(unix_socket::endpoint(settings_.unix_socket), ec);
      if (ec) throw std::runtime_error("cannot listen on " + settings_.unix_socket + ": " + ec.message());
      unix_->listen();
    }
    if (settings_.http_port >= 0) {
      live_.emplace(dispatcher_, io_);
      live_->Listen();
    }
  }

  std::string live_view_url() const { return live_ ? live_->url() : ""; }

  std::string tcp_endpoint() const {
    const tcp::endpoint e = tcp_->local_endpoint();
    return e.address().to_string() + ":" + std::to_string(e.port());
  }

  std::string unix_socket() const { return settings_.unix_socket; }

  void CatchSignals() {
    if (catching_signals_) return;
    signals_.add(SIGINT);
    signals_.add(SIGTERM);
    catching_signals_ = true;
  }

  void Run(bool handle_signals) {
    if (handle_signals) {
      CatchSignals();
      signals_.async_wait([this](const boost::system::error_code& ec, int signal) {
        if (ec) return;
        spdlog::info("signal {}: stopping", signal);
        Stop();
      });
    }
    asio::co_spawn(io_, Accept(*tcp_), asio::detached);
    if (unix_) asio::co_spawn(io_, Accept(*unix_), asio::detached);
    if (live_) live_->Start();
    ScheduleTick();
    std::vector<std::thread> threads;
    for (int i = 1; i < settings_.threads; ++i) threads.emplace_back([this] { io_.run(); });
    io_.run();
    for (std::thread& t : threads) t.join();
    for (const auto& connection : Connections()) connection->Detach();
  }

  void Stop() {
    if (stopping_.exchange(true)) return;
    asio::post(io_, [this] {
      boost::system::error_code ignored;
      if (tcp_) tcp_->close(ignored);
      if (unix_) unix_->close(ignored);
      if (live_) live_->Stop();
      dispatcher_.Shutdown();
      for (const auto& connection : Connections()) {
        connection->Push(R"({"type":"shutdown","message":"the server is stopping; sessions resume from their journals"})",
                         false);
      }
      // Give the writers a moment to send the notice, then close everything.
      tick_.cancel();
      auto timer = std::make_shared<asio::steady_timer>(io_, std::chrono::milliseconds(200));
      timer->async_wait([this, timer](const boost::system::error_code&) {
        for (const auto& connection : Connections()) connection->Close();
        boost::system::error_code cancel_error;
        signals_.cancel(cancel_error);
        StopWhenClosed(std::chrono::steady_clock::now() + std::chrono::seconds(1));
      });
    });
  }

 private:
  template <class Acceptor>
  awaitable<void> Accept(Acceptor& acceptor) {
    for (;;) {
      boost::system::error_code ec;
      auto socket = co_await acceptor.async_accept(asio::make_strand(io_), asio::redirect_error(use_awaitable, ec));
      if (ec) {
        if (ec == asio::error::operation_aborted || stopping_) co_return;
        spdlog::warn("accept: {}", ec.message());
        continue;
      }
      if (dispatcher_.stats().connections.load() >= settings_.max_connections) {
        const std::string refusal =
            nlohmann::ordered_json{{"type", "error"},
                                   {"id", nullptr},
                                   {"code", "limit_exceeded"},
                                   {"message", "the server has max_connections (" +
                                                   std::to_string(settings_.max_connections) + ") connections"},
                                   {"line", 0}}
                .dump() +
            "\n";
        asio::write(socket, asio::buffer(refusal), ec);
        dispatcher_.stats().CountReject(ErrorCode::kLimitExceeded);
        socket.close(ec);
        continue;
      }
      using Socket = decltype(socket);
      if constexpr (std::is_same_v<Acceptor, tcp::acceptor>) {
        socket.set_option(tcp::no_delay(true), ec);  // replies are small: no Nagle delay
      }
      auto connection = std::make_shared<Connection<Socket>>(std::move(socket), dispatcher_, ++next_id_);
      {
        std::lock_guard lock(connections_mutex_);
        connections_.push_back(connection);
      }
      dispatcher_.stats().connections.fetch_add(1);
      dispatcher_.stats().connections_total.fetch_add(1);
      connection->Start();
    }
  }

  /// Stops the I/O when every connection's coroutines have ended (their sockets closed), or at the
  /// deadline; checked every 10 ms.
  void StopWhenClosed(std::chrono::steady_clock::time_point deadline) {
    if (Connections().empty() || std::chrono::steady_clock::now() >= deadline) {
      io_.stop();
      return;
    }
    auto timer = std::make_shared<asio::steady_timer>(io_, std::chrono::milliseconds(10));
    timer->async_wait([this, timer, deadline](const boost::system::error_code&) { StopWhenClosed(deadline); });
  }

  std::vector<std::shared_ptr<ConnectionBase>> Connections() {
    std::lock_guard lock(connections_mutex_);
    std::vector<std::shared_ptr<ConnectionBase>> alive;
    for (auto it = connections_.begin(); it != connections_.end();) {
      if (auto c = it->lock()) {
        alive.push_back(std::move(c));
        ++it;
      } else {
        it = connections_.erase(it);
      }
    }
    return alive;
  }

  void ScheduleTick() {
    tick_.expires_after(std::chrono::seconds(1));
    tick_.async_wait([this](const boost::system::error_code& ec) {
      if (ec || stopping_) return;
      dispatcher_.Tick();
      if (settings_.connection_idle_timeout_s > 0) {
        for (const auto& connection : Connections()) {
          if (connection->idle_s() > settings_.connection_idle_timeout_s) {
            spdlog::info("connection {}: idle for {} s, closed", connection->client_id(),
                         settings_.connection_idle_timeout_s);
            connection->Close();
          }
        }
      }
      ScheduleTick();
    });
  }

  Dispatcher& dispatcher_;
  const ServiceSettings& settings_;
  asio::io_context io_;
  asio::signal_set signals_{io_};
  asio::steady_timer tick_;
  std::optional<tcp::acceptor> tcp_;
  std::optional<unix_socket::acceptor> unix_;
  std::optional<LiveView> live_;  ///< with an http_port; destroyed before io_
  std::mutex connections_mutex_;
  std::list<std::weak_ptr<ConnectionBase>> connections_;
  std::atomic<std::uint64_t> next_id_{0};
  std::atomic<bool> stopping_{false};
  bool catching_signals_ = false;
};

Server::Server(Dispatcher& dispatcher) : impl_(std::make_unique<Impl>(dispatcher)) {}
Server::~Server() = default;
void Server::Listen() { impl_->Listen(); }
std::string Server::tcp_endpoint() const { return impl_->tcp_endpoint(); }
std::string Server::unix_socket() const { return impl_->unix_socket(); }
std::string Server::live_view_url() const { return impl_->live_view_url(); }
void Server::CatchSignals() { impl_->CatchSignals(); }
void Server::Run(bool handle_signals) { impl_->Run(handle_signals); }
void Server::Stop() { impl_->Stop(); }

}  // namespace rowloc::service
