// The numbers our text writers print (OBJ, PLY, XYZ): the shortest of
// printf's "%.15g", "%.16g", "%.17g" that reads back as the same double.
// Natively append_double uses std::to_chars / from_chars for speed; this
// checks it prints the same bytes as the printf + strtod definition the
// wasm build still uses, so files written on either side are identical.
#include "io/text_scan.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>

namespace {

std::string printf_reference(double v) {
  char buf[40];
  for (int precision : {15, 16, 17}) {
    std::snprintf(buf, sizeof(buf), "%.*g", precision, v);
    if (precision == 17 || std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

}  // namespace

TEST_CASE("append_double prints what printf %.15g/16g/17g + strtod prints, and reads back exactly", "[io][text]") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-320, 308);
  std::uniform_int_distribution<std::uint64_t> bits;
  int checked = 0, needed_more_than_15 = 0;
  auto check = [&](double v) {
    std::string ours;
    lk::io_detail::append_double(ours, v);
    const std::string reference = printf_reference(v);
    INFO("value bits " << std::hex << [&] { std::uint64_t b; std::memcpy(&b, &v, 8); return b; }());
    REQUIRE(ours == reference);
    if (std::isfinite(v)) REQUIRE(std::strtod(ours.c_str(), nullptr) == v);
    ++checked;
  };
  // Coordinates as the fit writes them (metres, millimetres), every
  // magnitude, and arbitrary bit patterns (subnormals included).
  for (int i = 0; i < 60000; ++i) {
    check(0.15 * unit(rng));
    check(250.0 * unit(rng));
    check(unit(rng) * std::pow(10.0, exponent(rng)));
    std::uint64_t b = bits(rng);
    double v;
    std::memcpy(&v, &b, 8);
    if (std::isfinite(v)) check(v);
    if (printf_reference(0.15 * unit(rng)).size() > 18) ++needed_more_than_15;
  }
  for (double v : {0.0, -0.0, 1.0, -1.0, 0.1, 1e-5, 1e21, 123456789012345678.0, 5e-324, 2.2250738585072014e-308,
                   std::numeric_limits<double>::max(), std::numeric_limits<double>::lowest(),
                   std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()})
    check(v);
  CHECK(checked > 200000);
  CHECK(needed_more_than_15 > 0);  // the 16/17-digit retries were exercised
}

TEST_CASE("append_int prints as std::to_string", "[io][text]") {
  for (long long v : {0LL, 1LL, -1LL, 9LL, 10LL, 86689LL, 519552LL, -2147483648LL, 9223372036854775807LL,
                      -9223372036854775807LL - 1}) {
    std::string s = "x";
    lk::io_detail::append_int(s, v);
    CHECK(s == "x" + std::to_string(v));
  }
}
