// A C++ client of the localization service (docs/service.md): connects over TCP or a Unix socket,
// sends requests and sensor messages, and reads replies and pushed lines. A background thread
// reads every line the server sends: replies wake the request that waits for their `id`, pushed
// lines (subscriptions, the shutdown notice) queue for ReadPushed, so that a client streaming a
// log fast never leaves the server's queue for it full.
//
//   rowloc::service::Client client = rowloc::service::Client::ConnectTcp("127.0.0.1", 7878);
//   client.Hello();
//   const std::string session = client.OpenSession({{"vehicle", "vineyard-ugv-4ws"}, {"map", "sample-vineyard"}});
//   client.SendMessage(session, R"({"type":"imu","t":0.01,"sensor":"imu",...})");
//   nlohmann::json state = client.GetState(session);
#pragma once

#include <nlohmann/json.hpp>

#include <chrono>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace rowloc::service {

/// An `error` reply: its code (docs/service.md §7) and message.
class ClientError : public std::runtime_error {
 public:
  ClientError(std::string code, const std::string& message, nlohmann::json reply)
      : std::runtime_error(code + ": " + message), code_(std::move(code)), reply_(std::move(reply)) {}
  const std::string& code() const { return code_; }
  const nlohmann::json& reply() const { return reply_; }

 private:
  std::string code_;
  nlohmann::json reply_;
};

class Client {
 public:
  /// Throws std::runtime_error when the server cannot be reached.
  static Client ConnectTcp(const std::string& host, unsigned short port);
  static Client ConnectUnix(const std::string& path);
  /// "HOST:PORT" or "unix:PATH".
  static Client Connect(const std::string& address);
  Client(Client&&) noexcept;
  Client& operator=(Client&&) noexcept;
  ~Client();

  /// Sends a request with a fresh integer `id` and waits for its reply (timeout: std::runtime_error).
  /// An `error` reply throws ClientError (also one to the request's line that names no id, such as
  /// line_too_long); a lost connection std::runtime_error.
  nlohmann::json Request(nlohmann::json request, std::chrono::milliseconds timeout = std::chrono::seconds(30));
  /// Sends one raw line (a newline is added), waiting for nothing.
  void SendLine(std::string_view line);
  /// Sends a sensor-log line to a session: the line with "session" added, waiting for nothing.
  void SendMessage(const std::string& session, std::string_view log_line);
  /// The next pushed line (not a reply to a Request), waiting up to timeout; nullopt on timeout or a
  /// closed connection.
  std::optional<std::string> ReadPushed(std::chrono::milliseconds timeout);
  /// Error replies to lines not sent by Request (e.g. a refused sensor message), as they came.
  std::optional<nlohmann::json> TakeError();

  nlohmann::json Hello(const std::string& token = "");
  /// open_session with these keys; returns the session's name.
  std::string OpenSession(nlohmann::json parameters);
  nlohmann::json CloseSession(const std::string& session);
  nlohmann::json GetState(const std::string& session);
  nlohmann::json Subscribe(const std::string& session, const std::string& stream = "state", double rate_hz = 0.0);
  nlohmann::json Stats();
  /// Closes the connection (also done by the destructor).
  void Close();

 private:
  class Impl;
  explicit Client(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// The sensor-log line with `"session":NAME` added at its end (a line is one JSON object).
std::string WithSessionKey(std::string_view log_line, const std::string& session);
/// The line without the `,"session":NAME` the service appends to pushed estimate lines; the line
/// unchanged when it does not end so.
std::string WithoutSessionKey(std::string_view line, const std::string& session);

}  // namespace rowloc::service
