// What a successful read promises, checked after every fuzz input: any
// violation stops the fuzzer with a crash (__builtin_trap), so a wrong
// "success" counts as a finding just like a sanitizer report.
//
// Memory bounded by the input: the sanitizer's malloc/free hooks track the
// live heap while a reader runs; its peak above the start may not exceed
// kBytesPerInputByte per input byte plus a fixed allowance (messages, small
// vectors). A reader that reserves what a header merely declares fails here
// long before it could exhaust memory.
#pragma once
#include "io/io.h"

#include <sanitizer/allocator_interface.h>

#include <cmath>
#include <cstddef>
#include <cstdint>

namespace lk::fuzz {

// Worst cases by design (each is output the bytes justify): an OBJ face
// "f 1 1 1 ..." makes a 12-byte triangle and 36 bytes of corners per 2 input
// bytes, doubled while a vector grows.
constexpr size_t kBytesPerInputByte = 64;
constexpr size_t kFixedAllowance = size_t(1) << 20;

inline void require(bool ok) {
  if (!ok) __builtin_trap();
}

struct HeapWatch {
  static inline bool active = false;
  static inline size_t live = 0, peak = 0;

  static void on_malloc(const volatile void*, size_t size) {
    if (!active) return;
    live += size;
    if (live > peak) peak = live;
  }
  static void on_free(const volatile void* p) {
    if (!active || !p) return;
    const size_t size = __sanitizer_get_allocated_size(const_cast<const void*>(p));
    live = size > live ? 0 : live - size;
  }
  static void install() {
    static const bool installed = __sanitizer_install_malloc_and_free_hooks(on_malloc, on_free) != 0;
    (void)installed;
  }
};

// Runs a read with the heap watched and checks the peak against the input.
template <typename Read>
Status watched(size_t input_size, Read&& read) {
  HeapWatch::install();
  HeapWatch::live = HeapWatch::peak = 0;
  HeapWatch::active = true;
  Status s = read();
  HeapWatch::active = false;
  require(HeapWatch::peak <= kBytesPerInputByte * input_size + kFixedAllowance);
  return s;
}

inline void check_vec3s(const std::vector<Vec3>& v) {
  for (const Vec3& p : v) require(p.allFinite());
}

// A successful mesh read: vertices, indices in range, attribute arrays of the
// sizes TriMesh documents, every number finite, the kind matching the faces.
inline void check_mesh(const Status& s, const TriMesh& m, GeometryKind kind) {
  if (!s) {
    require(!s.message.empty());
    require(m.positions.empty() && m.triangles.empty());  // never half a mesh
    return;
  }
  const size_t nv = m.positions.size();
  require(nv > 0);
  check_vec3s(m.positions);
  for (const Tri& t : m.triangles)
    for (int k = 0; k < 3; ++k) require(t[k] >= 0 && static_cast<size_t>(t[k]) < nv);
  require(m.normals.empty() || m.normals.size() == nv);
  require(m.colors.empty() || m.colors.size() == nv);
  check_vec3s(m.normals);
  check_vec3s(m.colors);
  if (m.uv_per_corner) require(m.uvs.size() == 3 * m.triangles.size());
  else require(m.uvs.empty() || m.uvs.size() == nv);
  for (const Vec2& uv : m.uvs) require(uv.allFinite());
  require((kind == GeometryKind::Mesh) == !m.triangles.empty());
}

inline void check_cloud(const Status& s, const PointCloud& c) {
  if (!s) {
    require(!s.message.empty());
    require(c.positions.empty());
    return;
  }
  const size_t n = c.positions.size();
  require(n > 0);
  check_vec3s(c.positions);
  require(c.normals.empty() || c.normals.size() == n);
  require(c.colors.empty() || c.colors.size() == n);
  check_vec3s(c.normals);
  check_vec3s(c.colors);
}

}  // namespace lk::fuzz
