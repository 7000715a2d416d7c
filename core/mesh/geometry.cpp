#include "mesh/geometry.h"

#include <Eigen/LU>
#include <cmath>

namespace lk {

BBox bounding_box(const std::vector<Vec3>& points) {
  BBox b;
  for (const Vec3& p : points) b.extend(p);
  return b;
}

Vec3 face_normal_area(const TriMesh& mesh, int f) {
  const Tri& t = mesh.triangles[f];
  const Vec3& a = mesh.positions[t[0]];
  return (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a);
}

int count_turned_triangles(const std::vector<Tri>& triangles, const std::vector<Vec3>& positions,
                           const std::vector<Vec3>& reference) {
  int turned = 0;
  for (const Tri& t : triangles) {
    const Vec3 n = (positions[t[1]] - positions[t[0]]).cross(positions[t[2]] - positions[t[0]]);
    const Vec3 n0 = (reference[t[1]] - reference[t[0]]).cross(reference[t[2]] - reference[t[0]]);
    turned += n.dot(n0) < 0;
  }
  return turned;
}

std::vector<Vec3> vertex_normals(const TriMesh& mesh) {
  std::vector<Vec3> n(mesh.positions.size(), Vec3::Zero());
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    const Vec3 fn = face_normal_area(mesh, f);
    for (int v : mesh.triangles[f]) n[v] += fn;
  }
  for (Vec3& v : n) {
    const double len = v.norm();
    if (len > 0) v /= len;
  }
  return n;
}

std::vector<Vec3> face_normals(const TriMesh& mesh) {
  std::vector<Vec3> n(mesh.triangles.size());
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    n[f] = face_normal_area(mesh, f);
    const double len = n[f].norm();
    if (len > 0) n[f] /= len;
  }
  return n;
}

double surface_area(const TriMesh& mesh) {
  double a = 0;
  for (int f = 0; f < mesh.num_triangles(); ++f) a += 0.5 * face_normal_area(mesh, f).norm();
  return a;
}

double mean_edge_length(const TriMesh& mesh) { return mean_edge_length(mesh.positions, mesh.triangles); }

double mean_edge_length(const std::vector<Vec3>& positions, const std::vector<Tri>& triangles) {
  if (triangles.empty()) return 0;
  double sum = 0;
  for (const Tri& t : triangles)
    for (int k = 0; k < 3; ++k) sum += (positions[t[k]] - positions[t[(k + 1) % 3]]).norm();
  return sum / (3.0 * triangles.size());
}

bool is_valid(const TriMesh& mesh, std::string* why) {
  auto fail = [&](const std::string& s) {
    if (why) *why = s;
    return false;
  };
  for (const Vec3& p : mesh.positions)
    if (!p.allFinite()) return fail("a vertex position is not finite");
  const int nv = mesh.num_vertices();
  for (const Tri& t : mesh.triangles)
    for (int v : t)
      if (v < 0 || v >= nv) return fail("a triangle index is out of range");
  if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size())
    return fail("normals count differs from vertex count");
  if (!mesh.colors.empty() && mesh.colors.size() != mesh.positions.size())
    return fail("colors count differs from vertex count");
  if (!mesh.uvs.empty()) {
    const size_t want = mesh.uv_per_corner ? 3 * mesh.triangles.size() : mesh.positions.size();
    if (mesh.uvs.size() != want) return fail("uv count differs from what the mesh needs");
  }
  return true;
}

void transform(TriMesh& mesh, const Mat3& A, const Vec3& t) {
  for (Vec3& p : mesh.positions) p = A * p + t;
  if (!mesh.normals.empty()) {
    const Mat3 N = A.inverse().transpose();
    for (Vec3& n : mesh.normals) {
      n = N * n;
      const double len = n.norm();
      if (len > 0) n /= len;
    }
  }
}

}  // namespace lk
