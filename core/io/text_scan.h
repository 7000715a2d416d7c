// Internal helpers shared by the readers: a whitespace tokenizer over bytes in
// memory, a fast number parser, shortest round-trip number formatting, and
// how a geometry file's format is told.
// Not part of the public API (include "io/io.h" instead).
//
// Why not iostreams or std::from_chars<double>: iostreams are ~10x slower on
// 300k-point files, and Emscripten 3.1.6's libc++ (LLVM 14) has no
// floating-point from_chars. Integer from_chars is available everywhere.
#pragma once
#include "common/status.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <new>
#include <string>
#include <string_view>
#include <vector>

namespace lk::io_detail {

// TooLarge when a reader is handed more than its kind's limit (io.h), before
// a byte is parsed.
Status check_input_size(size_t size, size_t limit);

// Runs a reader body; an allocation failure (which the readers' bounds on
// declared counts should make impossible) becomes a TooLarge status instead
// of an exception escaping the reader. The wasm build has no exceptions.
template <typename Body>
Status guard_allocation(Body&& body) {
#if defined(__cpp_exceptions)
  try {
    return body();
  } catch (const std::bad_alloc&) {
    return Status::error(ErrorCode::TooLarge, "too large: out of memory while reading");
  }
#else
  return body();
#endif
}

// One push of a stream reader that parses whole items: process(data, size,
// offset, final, used) -> Status consumes the items that are complete in
// [data, data + size) (file offset `offset`) and says how many bytes it
// used. The unfinished tail is carried (carry, at file offset carry_base)
// and finished first with as few of the new bytes as it needs (the offer
// grows, so a long item costs linear time); the rest of the new bytes is
// processed in place, without copying. data_base: the new bytes' offset.
template <typename Process>
Status push_carried(std::vector<std::uint8_t>& carry, std::uint64_t& carry_base, std::uint64_t data_base,
                    const std::uint8_t* data, size_t size, Process&& process) {
  size_t pos = 0;
  while (!carry.empty() && pos < size) {
    const size_t old = carry.size();
    const size_t take = std::min(size - pos, std::max<size_t>(old, 64 * 1024));
    carry.insert(carry.end(), data + pos, data + pos + take);
    pos += take;
    size_t used = 0;
    if (Status e = process(carry.data(), carry.size(), carry_base, false, used); !e) return e;
    if (used >= old) {
      pos -= carry.size() - used;  // those new bytes are offered again below
      carry.clear();
    } else {
      carry.erase(carry.begin(), carry.begin() + static_cast<std::ptrdiff_t>(used));
      carry_base += used;
    }
  }
  if (carry.empty() && pos < size) {
    size_t used = 0;
    if (Status e = process(data + pos, size - pos, data_base + pos, false, used); !e) return e;
    carry.assign(data + pos + used, data + size);
    carry_base = data_base + pos + used;
  }
  return Status::success();
}

inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

// Parses the whole of [begin, end) as a decimal floating-point number
// (also "nan", "inf", "infinity" in any case, so callers can reject them with
// a clear message instead of "not a number"). Correctly rounded: short
// mantissas take Clinger's exact fast path, the rest go to strtod.
bool parse_double(const char* begin, const char* end, double& out);

// Parses the whole of [begin, end) as a base-10 signed integer.
bool parse_int64(const char* begin, const char* end, std::int64_t& out);

// Walks whitespace-separated tokens, counting lines for messages.
class Tokenizer {
 public:
  Tokenizer(const char* begin, const char* end) : p_(begin), end_(end) {}

  // Next token, or an empty view at the end of the data.
  std::string_view next();
  // The token next() would return, without consuming it.
  std::string_view peek() const {
    Tokenizer copy = *this;
    return copy.next();
  }
  // Next token only if it lies on the current line (for optional trailing
  // fields); returns an empty view at the end of the line.
  std::string_view next_on_line();
  // Skips the rest of the current line, including its newline.
  void skip_line();
  // The rest of the current line without the newline or trailing spaces.
  std::string_view rest_of_line();
  bool at_end();  // true when only whitespace remains
  int line() const { return line_; }
  const char* position() const { return p_; }
  size_t remaining() const { return static_cast<size_t>(end_ - p_); }

 private:
  const char* p_;
  const char* end_;
  int line_ = 1;
};

// Cuts bytes pushed in chunks into lines (split at '\n', the newline not
// included): only an unfinished line is carried between pushes, so the line
// readers (OBJ, XYZ) see the same lines whatever the chunks. on_line returns
// a Status; the first error stops the push.
class LineSplitter {
 public:
  template <typename OnLine>
  Status push(const std::uint8_t* data, size_t size, OnLine&& on_line) {
    const char* p = reinterpret_cast<const char*>(data);
    const char* end = p + size;
    if (!carry_.empty()) {
      const char* nl = static_cast<const char*>(std::memchr(p, '\n', size));
      if (!nl) {
        carry_.append(p, end);
        return Status::success();
      }
      carry_.append(p, nl);
      std::string line;
      line.swap(carry_);
      if (Status s = on_line(std::string_view(line)); !s) return s;
      p = nl + 1;
    }
    while (p < end) {
      const char* nl = static_cast<const char*>(std::memchr(p, '\n', static_cast<size_t>(end - p)));
      if (!nl) {
        carry_.assign(p, end);
        break;
      }
      if (Status s = on_line(std::string_view(p, static_cast<size_t>(nl - p))); !s) return s;
      p = nl + 1;
    }
    return Status::success();
  }
  // After the last push: the last line when the bytes do not end with '\n'.
  template <typename OnLine>
  Status finish(OnLine&& on_line) {
    if (carry_.empty()) return Status::success();
    std::string line;
    line.swap(carry_);
    return on_line(std::string_view(line));
  }
  void clear() { std::string().swap(carry_); }

 private:
  std::string carry_;
};

// What every stream reader checks of the bytes it is pushed: the size the
// caller declared (within kind's limit), no more bytes than that, and all of
// them by the end; once an error is set, every later call returns it.
struct StreamBytes {
  StreamBytes(std::uint64_t total_size, size_t limit);
  // Before a push of size bytes: the sticky error, or more than declared.
  Status accept(size_t size);
  // At finish: the sticky error, or fewer bytes than declared.
  Status complete();
  std::uint64_t total = 0, received = 0;
  Status error;
};

// Shortest "%.Ng" text that reads back as exactly the same double.
std::string format_double(double v);
void append_double(std::string& out, double v);
void append_int(std::string& out, long long v);  // decimal, as std::to_string

std::string lowercase(std::string s);
// A file name's extension after its last dot, lowercased ("" when none).
std::string lower_extension(const std::string& name);
// How read_geometry picks a reader (geometry_io.cpp): by the name's
// extension ("ply", "obj", "xyz" for .xyz/.txt/.pts/.asc/.xyzn/.xyzrgb,
// "vtk"; "" for any other), else by the first bytes ("" when unknown).
std::string geometry_format_by_name(const std::string& name);
std::string sniff_geometry_format(const std::uint8_t* data, size_t size);
// Quotes a token for an error message, shortened if long or binary.
std::string quote(std::string_view token);

}  // namespace lk::io_detail
