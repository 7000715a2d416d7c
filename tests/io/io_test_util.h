// Helpers for the io tests: bytes from text, hand-built binary data in either
// byte order, and a probe that records the largest single allocation (to show
// that readers do not reserve what a lying header declares).
#pragma once
#include "io/io.h"

#include <catch2/catch.hpp>

#include <cstdint>
#include <cstring>
#include <string>

namespace lk::test {

inline Bytes bytes_of(const std::string& s) { return Bytes(s.begin(), s.end()); }

// Appends values in a chosen byte order.
struct ByteWriter {
  Bytes bytes;
  bool big_endian = false;

  explicit ByteWriter(const std::string& header, bool big = false) : bytes(header.begin(), header.end()), big_endian(big) {}
  template <typename T>
  ByteWriter& put(T v) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    const std::uint16_t probe = 1;
    unsigned char first;
    std::memcpy(&first, &probe, 1);
    const bool host_little = first == 1;
    if (big_endian == host_little)
      for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    bytes.insert(bytes.end(), b, b + sizeof(T));
    return *this;
  }
};

// A reader's error: the code and a fragment of the message a user would read.
inline void require_error(const Status& s, ErrorCode code, const std::string& fragment) {
  INFO("message: " << s.message);
  REQUIRE_FALSE(s.ok());
  CHECK(s.code == code);
  CHECK(s.message.find(fragment) != std::string::npos);
}

// n bytes of deterministic noise: no file format's magic, no text.
inline Bytes garbage_bytes(size_t n) {
  Bytes garbage(n);
  for (size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<std::uint8_t>((i * 7919 + 13) % 251);
  return garbage;
}

// Largest single operator-new request since reset (counted in alloc_probe.cpp).
void reset_largest_allocation();
size_t largest_allocation();

}  // namespace lk::test
