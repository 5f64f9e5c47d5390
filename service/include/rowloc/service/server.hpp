// The socket transport of `rowloc serve` (docs/service.md): Boost.Asio, a TCP listener (loopback by
// default) and optionally a Unix-socket listener, each connection read and written by two
// coroutines on its own strand; every line goes to the Dispatcher. Several threads run the I/O
// and the filters; a connection waits only for its own sessions.
//
// Memory stays bounded whatever a client does: a line is at most max_line_bytes (LineFramer), a
// connection's outgoing queue holds at most max_queue_lines pushed lines (the slow-client policy
// drops the oldest or disconnects), and a connection whose queue reaches twice that (a client
// that sends requests but never reads replies) is closed. Connections above max_connections are
// told `limit_exceeded` and closed; a connection idle for connection_idle_timeout_s is closed.
// Stop (SIGINT, SIGTERM) stops accepting, tells every client (`{"type":"shutdown"}`), syncs the
// journals and ends Run. With an http_port the same threads also serve the live view (live_view.hpp).
#pragma once

#include "rowloc/service/dispatcher.hpp"

#include <memory>
#include <string>

namespace rowloc::service {

class Server {
 public:
  /// The dispatcher must outlive the server.
  explicit Server(Dispatcher& dispatcher);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// Binds the listeners of the settings. Throws std::runtime_error when an address cannot be used.
  void Listen();
  /// "127.0.0.1:PORT" of the bound TCP listener (the real port when the settings said 0).
  std::string tcp_endpoint() const;
  /// The Unix socket path, or "".
  std::string unix_socket() const;
  /// "http://ADDRESS:PORT/" of the live view (live_view.hpp), or "" when http_port is -1 (off).
  std::string live_view_url() const;

  /// Catches SIGINT and SIGTERM from now on (they stop Run gracefully once it runs). `rowloc serve`
  /// calls it before it prints where it listens, so that a script that sends SIGTERM as soon as it
  /// has read that line gets a graceful stop, not the default action (death by the signal).
  void CatchSignals();
  /// Serves until Stop (or SIGINT/SIGTERM when handle_signals), on settings().threads threads.
  void Run(bool handle_signals = true);
  /// Graceful stop; may be called from any thread.
  void Stop();

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rowloc::service
