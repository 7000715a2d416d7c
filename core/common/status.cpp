#include "common/status.h"

namespace lk {

const char* to_string(ErrorCode code) {
  switch (code) {
    case ErrorCode::Ok: return "ok";
    case ErrorCode::InvalidInput: return "invalid input";
    case ErrorCode::Truncated: return "truncated";
    case ErrorCode::Unsupported: return "unsupported";
    case ErrorCode::Empty: return "empty";
    case ErrorCode::TooLarge: return "too large";
    case ErrorCode::NotAHead: return "not a head";
    case ErrorCode::NotConverged: return "not converged";
    case ErrorCode::Cancelled: return "cancelled";
    case ErrorCode::Internal: return "internal error";
  }
  return "unknown error";
}

}  // namespace lk
