#include "texture/correspondences.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace lk {

Status parse_correspondences(const std::string& text, std::vector<Correspondence>& out) {
  out.clear();
  if (text.size() > kMaxCorrespondenceBytes)
    return Status::error(ErrorCode::TooLarge, "too large: " + std::to_string(text.size()) + " bytes, the limit is " +
                                                  std::to_string(kMaxCorrespondenceBytes));
  size_t pos = 0;
  int line_no = 0;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    // strtod below stops at a NUL and would silently drop the rest of the line.
    if (line.find('\0') != std::string::npos)
      return Status::error(ErrorCode::InvalidInput, "line " + std::to_string(line_no) + ": a NUL byte (not text)");
    double v[5];
    int count = 0;
    const char* p = line.c_str();
    bool garbage = false;
    while (true) {
      while (*p == ' ' || *p == '\t' || *p == '\r' || *p == ',') ++p;
      if (*p == '\0') break;
      char* next = nullptr;
      const double d = std::strtod(p, &next);
      if (next == p) {
        garbage = true;
        break;
      }
      if (count < 5) v[count] = d;
      ++count;
      // Overflow reads as infinity; an underflow (1e-400) is a fine zero.
      if (!std::isfinite(d))
        return Status::error(ErrorCode::InvalidInput,
                             "line " + std::to_string(line_no) + ": a number is not finite");
      p = next;
    }
    if (count == 0 && !garbage) continue;  // blank or comment
    if (garbage)
      return Status::error(ErrorCode::InvalidInput, "line " + std::to_string(line_no) +
                                                        ": expected 5 numbers 'u v X Y Z', found text '" +
                                                        std::string(p).substr(0, 20) + "'");
    if (count != 5)
      return Status::error(ErrorCode::InvalidInput, "line " + std::to_string(line_no) +
                                                        ": expected 5 numbers 'u v X Y Z', found " +
                                                        std::to_string(count));
    Correspondence c;
    c.pixel = Vec2(v[0], v[1]);
    c.point = Vec3(v[2], v[3], v[4]);
    out.push_back(c);
  }
  if (out.empty()) return Status::error(ErrorCode::Empty, "no correspondences (lines 'u v X Y Z')");
  return Status::success();
}

std::string format_correspondences(const std::vector<Correspondence>& points) {
  std::string out = "# u v X Y Z: pixel (origin top-left, v down) and point on the head\n";
  char buf[256];
  for (const Correspondence& c : points) {
    std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g %.17g %.17g\n", c.pixel.x(), c.pixel.y(), c.point.x(),
                  c.point.y(), c.point.z());
    out += buf;
  }
  return out;
}

}  // namespace lk
