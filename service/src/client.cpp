// The C++ client of the service (see client.hpp).
#include "rowloc/service/client.hpp"

#include "rowloc/service/line_framer.hpp"

#include <boost/asio.hpp>

#include <netinet/in.h>
#include <netinet/tcp.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

namespace rowloc::service {
namespace asio = boost::asio;

std::string WithSessionKey(std::string_view log_line, const std::string& session) {
  std::string line(log_line);
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r' || line.back() == ' ')) line.pop_back();
  if (line.empty() || line.back() != '}') throw std::invalid_argument("not a JSON object line");
  line.pop_back();
  line += ",\"session\":" + nlohmann::json(session).dump() + "}";
  return line;
}

std::string WithoutSessionKey(std::string_view line, const std::string& session) {
  const std::string suffix = ",\"session\":" + nlohmann::json(session).dump() + "}";
  if (line.size() < suffix.size() || line.substr(line.size() - suffix.size()) != suffix) return std::string(line);
  return std::string(line.substr(0, line.size() - suffix.size())) + "}";
}

class Client::Impl {
 public:
  /// Connects to the first endpoint that answers; throws std::runtime_error (naming `what`).
  Impl(const std::vector<asio::generic::stream_protocol::endpoint>& endpoints, const std::string& what)
      : framer_(64u << 20) {
    boost::system::error_code ec = asio::error::host_not_found;
    for (const auto& endpoint : endpoints) {
      stream_.close(ec);
      stream_.connect(endpoint, ec);
      if (!ec) break;
    }
    if (ec) throw std::runtime_error("cannot connect to " + what + ": " + ec.message());
    reader_ = std::thread([this] { ReadLoop(); });
  }
  ~Impl() { Close(); }

  void Close() {
    {
      std::lock_guard lock(mutex_);
      if (closed_by_us_) return;
      closed_by_us_ = true;
    }
    boost::system::error_code ignored;
    stream_.shutdown(asio::socket_base::shutdown_both, ignored);
    if (reader_.joinable()) reader_.join();
    stream_.close(ignored);
  }

  /// TCP: send small requests at once (Nagle off); other sockets ignore it.
  void SetNoDelay() {
    const int one = 1;
    ::setsockopt(stream_.native_handle(), IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  }

  void SendLine(std::string_view line) {
    std::lock_guard lock(write_mutex_);
    WriteLineLocked(line);
  }

  nlohmann::json Request(nlohmann::json request, std::chrono::milliseconds timeout) {
    const std::int64_t id = next_id_++;
    request["id"] = id;
    const std::string text = request.dump();
    {
      // The request is awaited by its id and by its line number on this connection: an error the
      // server gives before it could read the id (line_too_long) names only the line.
      std::lock_guard write_lock(write_mutex_);
      {
        std::lock_guard lock(mutex_);
        awaited_[id] = lines_sent_ + 1;  // dump() escapes newlines: one line
      }
      try {
        WriteLineLocked(text);
      } catch (...) {
        std::lock_guard lock(mutex_);
        awaited_.erase(id);
        throw;
      }
    }
    std::unique_lock lock(mutex_);
    const bool answered = ready_.wait_for(lock, timeout, [&] { return replies_.contains(id) || eof_; });
    awaited_.erase(id);  // a reply after a timeout is not kept (it goes to ReadPushed or TakeError)
    if (!answered) {
      throw std::runtime_error("no reply to " + request.value("type", std::string("request")) + " within " +
                               std::to_string(timeout.count()) + " ms");
    }
    const auto it = replies_.find(id);
    if (it == replies_.end()) throw std::runtime_error("the server closed the connection");
    nlohmann::json reply = std::move(it->second);
    replies_.erase(it);
    if (reply.value("type", "") == "error") {
      throw ClientError(reply.value("code", "internal"), reply.value("message", ""), reply);
    }
    return reply;
  }

  std::optional<std::string> ReadPushed(std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    ready_.wait_for(lock, timeout, [&] { return !pushed_.empty() || eof_; });
    if (pushed_.empty()) return std::nullopt;
    std::string line = std::move(pushed_.front());
    pushed_.pop_front();
    return line;
  }

  std::optional<nlohmann::json> TakeError() {
    std::lock_guard lock(mutex_);
    if (errors_.empty()) return std::nullopt;
    nlohmann::json e = std::move(errors_.front());
    errors_.pop_front();
    return e;
  }

 private:
  /// Writes one line and counts the lines sent (the server numbers every newline-terminated line).
  void WriteLineLocked(std::string_view line) {
    std::string text(line);
    text.push_back('\n');
    asio::write(stream_, asio::buffer(text));
    lines_sent_ += static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
  }

  void ReadLoop() {
    std::vector<char> buffer(64 * 1024);
    boost::system::error_code ec;
    for (;;) {
      const std::size_t n = stream_.read_some(asio::buffer(buffer), ec);
      if (ec) break;
      for (FramedLine& line : framer_.Feed(std::string_view(buffer.data(), n))) Deliver(std::move(line.text));
    }
    std::lock_guard lock(mutex_);
    eof_ = true;
    ready_.notify_all();
  }

  /// The reply to a waiting Request (its id, or for an error without an id its line number), an
  /// error to another line, or a pushed line.
  void Deliver(std::string line) {
    const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    std::lock_guard lock(mutex_);
    const bool is_error = j.is_object() && j.value("type", "") == "error";
    if (const std::optional<std::int64_t> request = AwaitedRequest(j, is_error)) {
      replies_[*request] = j;
    } else if (is_error) {
      errors_.push_back(j);
    } else {
      pushed_.push_back(std::move(line));
    }
    ready_.notify_all();
  }

  /// The id of the waiting Request this line answers, if any (mutex_ held).
  std::optional<std::int64_t> AwaitedRequest(const nlohmann::json& j, bool is_error) const {
    if (!j.is_object()) return std::nullopt;
    const auto id = j.find("id");
    if (id != j.end() && id->is_number_integer()) {
      const std::int64_t value = id->get<std::int64_t>();
      if (awaited_.contains(value)) return value;
      return std::nullopt;
    }
    const auto line = j.find("line");
    if (!is_error || (id != j.end() && !id->is_null()) || line == j.end() || !line->is_number_unsigned()) {
      return std::nullopt;
    }
    for (const auto& [request, line_number] : awaited_) {
      if (line_number == line->get<std::size_t>()) return request;
    }
    return std::nullopt;
  }

  asio::io_context io_;
  asio::generic::stream_protocol::socket stream_{io_};
  LineFramer framer_;
  std::thread reader_;
  std::mutex write_mutex_;
  std::mutex mutex_;
  std::condition_variable ready_;
  std::size_t lines_sent_ = 0;                     ///< guarded by write_mutex_
  std::map<std::int64_t, std::size_t> awaited_;    ///< waiting Request: id -> its line number
  std::map<std::int64_t, nlohmann::json> replies_;
  std::deque<std::string> pushed_;
  std::deque<nlohmann::json> errors_;
  std::atomic<std::int64_t> next_id_{1};
  bool eof_ = false;
  bool closed_by_us_ = false;
};

Client::Client(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Client::Client(Client&&) noexcept = default;
Client& Client::operator=(Client&&) noexcept = default;
Client::~Client() = default;

Client Client::ConnectTcp(const std::string& host, unsigned short port) {
  asio::io_context io;
  boost::system::error_code ec;
  asio::ip::tcp::resolver resolver(io);
  const std::string what = host + ":" + std::to_string(port);
  std::vector<asio::generic::stream_protocol::endpoint> endpoints;
  for (const auto& entry : resolver.resolve(host, std::to_string(port), ec)) endpoints.emplace_back(entry.endpoint());
  if (ec) throw std::runtime_error("cannot resolve " + what + ": " + ec.message());
  auto impl = std::make_unique<Impl>(endpoints, what);
  impl->SetNoDelay();
  return Client(std::move(impl));
}

Client Client::ConnectUnix(const std::string& path) {
  const asio::generic::stream_protocol::endpoint endpoint{asio::local::stream_protocol::endpoint(path)};
  return Client(std::make_unique<Impl>(std::vector{endpoint}, path));
}

Client Client::Connect(const std::string& address) {
  if (address.rfind("unix:", 0) == 0) return ConnectUnix(address.substr(5));
  const std::size_t colon = address.rfind(':');
  if (colon == std::string::npos) throw std::invalid_argument("address '" + address + "': expected HOST:PORT or unix:PATH");
  const std::string port = address.substr(colon + 1);
  std::size_t used = 0;
  int value = -1;
  try {
    value = std::stoi(port, &used);
  } catch (const std::exception&) {
  }
  if (used != port.size() || value <= 0 || value > 65535) {
    throw std::invalid_argument("address '" + address + "': the port must be 1-65535");
  }
  std::string host = address.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  return ConnectTcp(host, static_cast<unsigned short>(value));
}

nlohmann::json Client::Request(nlohmann::json request, std::chrono::milliseconds timeout) {
  return impl_->Request(std::move(request), timeout);
}
void Client::SendLine(std::string_view line) { impl_->SendLine(line); }
void Client::SendMessage(const std::string& session, std::string_view log_line) {
  impl_->SendLine(WithSessionKey(log_line, session));
}
std::optional<std::string> Client::ReadPushed(std::chrono::milliseconds timeout) { return impl_->ReadPushed(timeout); }
std::optional<nlohmann::json> Client::TakeError() { return impl_->TakeError(); }
void Client::Close() {
  if (impl_) impl_->Close();
}

nlohmann::json Client::Hello(const std::string& token) {
  nlohmann::json request{{"type", "hello"}, {"protocol", "rowloc-service/1"}, {"client", "rowloc C++ client"}};
  if (!token.empty()) request["token"] = token;
  return Request(std::move(request));
}

std::string Client::OpenSession(nlohmann::json parameters) {
  parameters["type"] = "open_session";
  return Request(std::move(parameters)).at("session").get<std::string>();
}

nlohmann::json Client::CloseSession(const std::string& session) {
  return Request({{"type", "close_session"}, {"session", session}}, std::chrono::minutes(10));
}

nlohmann::json Client::GetState(const std::string& session) {
  return Request({{"type", "get_state"}, {"session", session}});
}

nlohmann::json Client::Subscribe(const std::string& session, const std::string& stream, double rate_hz) {
  nlohmann::json request{{"type", "subscribe"}, {"session", session}, {"stream", stream}};
  if (rate_hz > 0) request["rate_hz"] = rate_hz;
  return Request(std::move(request));
}

nlohmann::json Client::Stats() { return Request({{"type", "stats"}}); }

}  // namespace rowloc::service
