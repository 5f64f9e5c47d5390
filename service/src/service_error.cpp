// Names of the service's error codes (see service_error.hpp).
#include "rowloc/service/service_error.hpp"

namespace rowloc::service {

std::string_view ErrorCodeName(ErrorCode code) {
  switch (code) {
    case ErrorCode::kMalformedJson: return "malformed_json";
    case ErrorCode::kNotAnObject: return "not_an_object";
    case ErrorCode::kLineTooLong: return "line_too_long";
    case ErrorCode::kMissingField: return "missing_field";
    case ErrorCode::kInvalidField: return "invalid_field";
    case ErrorCode::kUnknownType: return "unknown_type";
    case ErrorCode::kUnsupportedProtocol: return "unsupported_protocol";
    case ErrorCode::kUnauthorized: return "unauthorized";
    case ErrorCode::kUnknownSession: return "unknown_session";
    case ErrorCode::kSessionExists: return "session_exists";
    case ErrorCode::kInvalidName: return "invalid_name";
    case ErrorCode::kUnknownVehicle: return "unknown_vehicle";
    case ErrorCode::kUnknownMap: return "unknown_map";
    case ErrorCode::kUnknownFilter: return "unknown_filter";
    case ErrorCode::kInvalidConfig: return "invalid_config";
    case ErrorCode::kTooOld: return "too_old";
    case ErrorCode::kRejected: return "rejected";
    case ErrorCode::kLimitExceeded: return "limit_exceeded";
    case ErrorCode::kShuttingDown: return "shutting_down";
    case ErrorCode::kInternal: return "internal";
  }
  return "internal";
}

}  // namespace rowloc::service
