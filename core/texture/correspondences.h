// Reading the per-photo feature correspondences the user clicked
// (tarini2002 Sec. 3: "about 12-15 corresponding feature points on the mesh
// and in the image"): plain text, one point per line,
//   u v X Y Z
// with (u, v) the pixel position in the photo (origin at the top-left
// corner, v down, as Camera::project) and (X, Y, Z) the point on the head
// mesh. '#' starts a comment; blank lines are skipped. Shared by the CLI
// (files) and the web app (text from the page).
//
// Shapes: out #N correspondences in file order.
#pragma once
#include "calib/camera.h"
#include "common/status.h"

#include <cstddef>
#include <string>
#include <vector>

namespace lk {

// The largest points text accepted (files are refused from their size by
// the CLI, text from the page here): a few dozen clicked points take ~2 kB.
constexpr size_t kMaxCorrespondenceBytes = size_t(16) << 20;

// Fails with InvalidInput and a message naming the line ("line 7: expected
// 5 numbers 'u v X Y Z', found 4") on a malformed line, a non-finite number,
// a NUL byte, or trailing garbage; Empty when no point is given; TooLarge over
// kMaxCorrespondenceBytes.
Status parse_correspondences(const std::string& text, std::vector<Correspondence>& out);

// The text parse_correspondences reads (17 significant digits).
std::string format_correspondences(const std::vector<Correspondence>& points);

}  // namespace lk
