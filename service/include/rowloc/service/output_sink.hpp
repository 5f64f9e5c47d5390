// Where the service's lines for one client go: a connection's outgoing queue (server.cpp) or, in
// tests and the fuzz target, a plain list. Push may be called from any thread.
#pragma once

#include <cstdint>
#include <string>

namespace rowloc::service {

class OutputSink {
 public:
  virtual ~OutputSink() = default;
  /// Queues one line (without its newline). `pushed`: a subscription's line, which the slow-client
  /// policy may drop; replies are never dropped.
  virtual void Push(std::string line, bool pushed) = 0;
  /// A number that identifies the client in its session's subscriber list.
  virtual std::uint64_t client_id() const = 0;
};

}  // namespace rowloc::service
