// The error codes of the service protocol (docs/service.md §7) and the exception that carries one.
// Codes are stable strings: clients switch on them, so a code is never renamed or reused.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace rowloc::service {

enum class ErrorCode {
  kMalformedJson,
  kNotAnObject,
  kLineTooLong,
  kMissingField,
  kInvalidField,
  kUnknownType,
  kUnsupportedProtocol,
  kUnauthorized,
  kUnknownSession,
  kSessionExists,
  kInvalidName,
  kUnknownVehicle,
  kUnknownMap,
  kUnknownFilter,
  kInvalidConfig,
  kTooOld,
  kRejected,
  kLimitExceeded,
  kShuttingDown,
  kInternal,
};

/// Every code, in declaration order (for tests and statistics).
inline constexpr ErrorCode kAllErrorCodes[] = {
    ErrorCode::kMalformedJson,  ErrorCode::kNotAnObject,    ErrorCode::kLineTooLong,   ErrorCode::kMissingField,
    ErrorCode::kInvalidField,   ErrorCode::kUnknownType,    ErrorCode::kUnsupportedProtocol,
    ErrorCode::kUnauthorized,   ErrorCode::kUnknownSession, ErrorCode::kSessionExists, ErrorCode::kInvalidName,
    ErrorCode::kUnknownVehicle, ErrorCode::kUnknownMap,     ErrorCode::kUnknownFilter, ErrorCode::kInvalidConfig,
    ErrorCode::kTooOld,         ErrorCode::kRejected,       ErrorCode::kLimitExceeded, ErrorCode::kShuttingDown,
    ErrorCode::kInternal,
};

/// The protocol's name of a code, e.g. "unknown_session".
std::string_view ErrorCodeName(ErrorCode code);

/// A request that cannot be served; the dispatcher turns it into one `error` line.
class ServiceError : public std::runtime_error {
 public:
  ServiceError(ErrorCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  ErrorCode code() const { return code_; }

 private:
  ErrorCode code_;
};

}  // namespace rowloc::service
