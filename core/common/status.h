// Errors as values: every stage returns a Status (or fills one) instead of
// throwing, so nothing crosses the wasm boundary as an exception.
#pragma once
#include <string>
#include <utility>

namespace lk {

enum class ErrorCode {
  Ok = 0,
  InvalidInput,   // malformed bytes, NaN/inf, inconsistent counts
  Truncated,      // the data ends before what its header declares
  Unsupported,    // a valid but unsupported variant (format, property type)
  Empty,          // nothing to work with (empty file, no points)
  TooLarge,       // a declared size beyond what we accept
  NotAHead,       // the input does not look like a head / face
  NotConverged,   // an optimizer could not reach a usable answer
  Cancelled,      // the progress callback asked to stop
  Internal,       // a bug: an invariant of ours failed
};

const char* to_string(ErrorCode code);

struct Status {
  ErrorCode code = ErrorCode::Ok;
  std::string message;  // for people: names the input and the problem

  bool ok() const { return code == ErrorCode::Ok; }
  explicit operator bool() const { return ok(); }

  static Status success() { return {}; }
  static Status error(ErrorCode c, std::string msg) { return Status{c, std::move(msg)}; }
};

// Prefixes a status message with a context (usually a file name).
inline Status with_context(Status s, const std::string& context) {
  if (!s.ok() && !context.empty()) s.message = context + ": " + s.message;
  return s;
}

}  // namespace lk
