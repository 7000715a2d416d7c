#include "io/text_scan.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

namespace lk::io_detail {

namespace {

bool equals_nocase(const char* b, const char* e, const char* word) {
  for (; b != e && *word; ++b, ++word)
    if (std::tolower(static_cast<unsigned char>(*b)) != *word) return false;
  return b == e && *word == 0;
}

// Exactly representable powers of ten (10^22 is the largest with an exact double).
constexpr double kExactPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                  1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                  1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

bool parse_double_slow(const char* begin, const char* end, double& out) {
  char small[64];
  std::string big;
  const size_t n = static_cast<size_t>(end - begin);
  const char* s;
  if (n < sizeof(small)) {
    for (size_t i = 0; i < n; ++i) small[i] = begin[i];
    small[n] = 0;
    s = small;
  } else {
    big.assign(begin, end);
    s = big.c_str();
  }
  char* stop = nullptr;
  out = std::strtod(s, &stop);
  return stop == s + n;
}

}  // namespace

bool parse_double(const char* begin, const char* end, double& out) {
  const char* p = begin;
  if (p == end) return false;
  bool negative = false;
  if (*p == '+' || *p == '-') {
    negative = *p == '-';
    ++p;
  }
  if (p == end) return false;
  if (!(std::isdigit(static_cast<unsigned char>(*p)) || *p == '.')) {
    if (equals_nocase(p, end, "nan")) {
      out = std::numeric_limits<double>::quiet_NaN();
      return true;
    }
    if (equals_nocase(p, end, "inf") || equals_nocase(p, end, "infinity")) {
      out = negative ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
      return true;
    }
    return false;
  }
  std::uint64_t mantissa = 0;
  int digits = 0;          // significant digits kept in mantissa
  int exponent10 = 0;      // decimal exponent applied to mantissa
  bool any_digit = false;
  bool overflowed = false;  // more than 19 significant digits: use strtod
  for (; p != end && std::isdigit(static_cast<unsigned char>(*p)); ++p) {
    any_digit = true;
    if (mantissa == 0 && *p == '0') continue;  // leading zeros are not significant
    if (digits < 19) {
      mantissa = mantissa * 10 + static_cast<std::uint64_t>(*p - '0');
      ++digits;
    } else {
      overflowed = true;
    }
  }
  if (p != end && *p == '.') {
    ++p;
    for (; p != end && std::isdigit(static_cast<unsigned char>(*p)); ++p) {
      any_digit = true;
      if (mantissa == 0 && *p == '0') {
        --exponent10;
        continue;
      }
      if (digits < 19) {
        mantissa = mantissa * 10 + static_cast<std::uint64_t>(*p - '0');
        ++digits;
        --exponent10;
      } else {
        overflowed = true;
      }
    }
  }
  if (!any_digit) return false;
  if (p != end && (*p == 'e' || *p == 'E')) {
    ++p;
    bool exp_negative = false;
    if (p != end && (*p == '+' || *p == '-')) {
      exp_negative = *p == '-';
      ++p;
    }
    if (p == end || !std::isdigit(static_cast<unsigned char>(*p))) return false;
    int e = 0;
    for (; p != end && std::isdigit(static_cast<unsigned char>(*p)); ++p)
      if (e < 100000) e = e * 10 + (*p - '0');
    exponent10 += exp_negative ? -e : e;
  }
  if (p != end) return false;
  // Clinger's fast path: both the mantissa (< 2^53) and the power of ten are
  // exact doubles, so one IEEE multiply or divide rounds correctly.
  if (!overflowed && mantissa < (std::uint64_t(1) << 53) && exponent10 >= -22 && exponent10 <= 22) {
    double v = static_cast<double>(mantissa);
    v = exponent10 < 0 ? v / kExactPow10[-exponent10] : v * kExactPow10[exponent10];
    out = negative ? -v : v;
    return true;
  }
  if (mantissa == 0 && !overflowed) {
    out = negative ? -0.0 : 0.0;
    return true;
  }
  return parse_double_slow(begin, end, out);
}

Status check_input_size(size_t size, size_t limit) {
  if (size > limit)
    return Status::error(ErrorCode::TooLarge, "too large: " + std::to_string(size) + " bytes, the limit is " +
                                                  std::to_string(limit));
  return Status::success();
}

StreamBytes::StreamBytes(std::uint64_t total_size, size_t limit) : total(total_size) {
  if (total_size > limit)
    error = Status::error(ErrorCode::TooLarge, "too large: " + std::to_string(total_size) + " bytes, the limit is " +
                                                   std::to_string(limit));
}

Status StreamBytes::accept(size_t size) {
  if (!error.ok()) return error;
  if (size > total - received)
    error = Status::error(ErrorCode::InvalidInput,
                          "more bytes than the " + std::to_string(total) + " the file was declared to have");
  else
    received += size;
  return error;
}

Status StreamBytes::complete() {
  if (error.ok() && received != total)
    error = Status::error(ErrorCode::Truncated, "truncated: the data ends after " + std::to_string(received) +
                                                    " of the file's " + std::to_string(total) + " bytes");
  return error;
}

bool parse_int64(const char* begin, const char* end, std::int64_t& out) {
  if (begin != end && *begin == '+') ++begin;
  auto r = std::from_chars(begin, end, out);
  return r.ec == std::errc() && r.ptr == end;
}

std::string_view Tokenizer::next() {
  while (p_ != end_ && is_space(*p_)) {
    if (*p_ == '\n') ++line_;
    ++p_;
  }
  const char* b = p_;
  while (p_ != end_ && !is_space(*p_)) ++p_;
  return std::string_view(b, static_cast<size_t>(p_ - b));
}

std::string_view Tokenizer::next_on_line() {
  while (p_ != end_ && (*p_ == ' ' || *p_ == '\t' || *p_ == '\r')) ++p_;
  if (p_ == end_ || *p_ == '\n') return std::string_view();
  const char* b = p_;
  while (p_ != end_ && !is_space(*p_)) ++p_;
  return std::string_view(b, static_cast<size_t>(p_ - b));
}

void Tokenizer::skip_line() {
  while (p_ != end_ && *p_ != '\n') ++p_;
  if (p_ != end_) {
    ++p_;
    ++line_;
  }
}

std::string_view Tokenizer::rest_of_line() {
  while (p_ != end_ && (*p_ == ' ' || *p_ == '\t')) ++p_;
  const char* b = p_;
  while (p_ != end_ && *p_ != '\n') ++p_;
  const char* e = p_;
  while (e != b && is_space(e[-1])) --e;
  return std::string_view(b, static_cast<size_t>(e - b));
}

bool Tokenizer::at_end() {
  while (p_ != end_ && is_space(*p_)) {
    if (*p_ == '\n') ++line_;
    ++p_;
  }
  return p_ == end_;
}

std::string format_double(double v) {
  std::string s;
  append_double(s, v);
  return s;
}

void append_double(std::string& out, double v) {
  char buf[40];
  // 15 significant digits suffice for most values and keep files small;
  // 17 always round-trip.
#if defined(__cpp_lib_to_chars) && __cpp_lib_to_chars >= 201611L
  // std::to_chars with a precision writes exactly printf's "%.*g" (C++17
  // [charconv.to.chars]) and from_chars reads as strtod does (both
  // correctly rounded), so the bytes are the fallback's, ~5x faster: a
  // level-3 head's OBJ took ~0.5 s with snprintf + strtod.
  for (int precision : {15, 16, 17}) {
    const char* end = std::to_chars(buf, buf + sizeof(buf), v, std::chars_format::general, precision).ptr;
    double back = 0.0;
    if (precision == 17 || (std::from_chars(buf, end, back).ec == std::errc() && back == v)) {
      out.append(buf, static_cast<size_t>(end - buf));
      return;
    }
  }
#else
  // Emscripten 3.1.6's libc++ has no floating-point to_chars.
  for (int precision : {15, 16, 17}) {
    std::snprintf(buf, sizeof(buf), "%.*g", precision, v);
    if (precision == 17 || std::strtod(buf, nullptr) == v) break;
  }
  out += buf;
#endif
}

void append_int(std::string& out, long long v) {
  char buf[24];
  out.append(buf, std::to_chars(buf, buf + sizeof(buf), v).ptr);
}

std::string lowercase(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string lower_extension(const std::string& name) {
  const size_t slash = name.find_last_of("/\\");
  const size_t dot = name.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return lowercase(name.substr(dot + 1));
}

std::string quote(std::string_view token) {
  std::string s = "'";
  const size_t n = token.size() < 32 ? token.size() : 32;
  for (size_t i = 0; i < n; ++i) {
    const unsigned char c = static_cast<unsigned char>(token[i]);
    if (c >= 32 && c < 127) {
      s += static_cast<char>(c);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof(hex), "\\x%02x", c);
      s += hex;
    }
  }
  if (token.size() > n) s += "...";
  s += "'";
  return s;
}

}  // namespace lk::io_detail
