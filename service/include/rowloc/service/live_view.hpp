// The live view of `rowloc serve` (docs/live-view.md): an HTTP server (Boost.Beast) on the service's
// address and `http_port` that serves one page (service/web/, embedded in the binary at build time)
// and a WebSocket (`/ws`, RFC 6455: Fette and Melnikov 2011) that streams the watched session to it.
//
// Every WebSocket client is a client of the Dispatcher like a socket connection: it subscribes with
// `stream: "live"` (state lines plus GNSS fixes and echo rays, service_session.hpp) and lists the
// sessions once a second with `list_sessions`. It never blocks a session: what the session pushes
// goes into the client's bounded buffers (the newest state replaces the previous one; at most
// kMaxObservationLines fixes and echoes and kMaxReplyLines replies, the oldest dropped and counted),
// and a writer sends what is there as one `frame` at most live_view_rate_hz times a second (wall
// clock). A client that does not read only stalls its own writer; one silent for 60 s (no pong) is
// closed.
//
// Access: the same rule as the socket API (docs/service.md §9): without a token file the service
// listens on loopback only; with one, every HTTP request and the WebSocket upgrade must carry the
// token (`?token=...` or `Authorization: Bearer ...`), else 401.
#pragma once

#include "rowloc/service/dispatcher.hpp"

#include <boost/asio/io_context.hpp>

#include <cstddef>
#include <memory>
#include <string>

namespace rowloc::service {

class LiveView {
 public:
  static constexpr std::size_t kMaxObservationLines = 512;
  static constexpr std::size_t kMaxReplyLines = 256;

  /// The dispatcher and the io_context must outlive the view.
  LiveView(Dispatcher& dispatcher, boost::asio::io_context& io);
  ~LiveView();
  LiveView(const LiveView&) = delete;
  LiveView& operator=(const LiveView&) = delete;

  /// Binds settings().listen : settings().http_port. Throws std::runtime_error.
  void Listen();
  /// "http://ADDRESS:PORT/" of the bound listener (the real port when http_port was 0).
  std::string url() const;
  /// Starts accepting (on the io_context's threads).
  void Start();
  /// Stops accepting and closes every connection; may be called from any thread.
  void Stop();

 private:
  class Impl;
  std::shared_ptr<Impl> impl_;
};

}  // namespace rowloc::service
