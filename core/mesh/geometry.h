// Simple geometric queries on meshes and point clouds.
#pragma once
#include "mesh/tri_mesh.h"

namespace lk {

BBox bounding_box(const std::vector<Vec3>& points);

// Unnormalized face normal (length = 2 * area).
Vec3 face_normal_area(const TriMesh& mesh, int f);

// Area-weighted vertex normals, unit length (zero for isolated vertices). #V.
std::vector<Vec3> vertex_normals(const TriMesh& mesh);

// Unit face normals. #F.
std::vector<Vec3> face_normals(const TriMesh& mesh);

double surface_area(const TriMesh& mesh);

// Triangles whose normal at `positions` points against their normal at
// `reference` (the same triangles at other positions; both indexed by
// `triangles`). A zero-area triangle at either is not counted.
int count_turned_triangles(const std::vector<Tri>& triangles, const std::vector<Vec3>& positions,
                           const std::vector<Vec3>& reference);

// Mean edge length over all triangle edges (each counted per triangle); 0
// without triangles.
double mean_edge_length(const TriMesh& mesh);
double mean_edge_length(const std::vector<Vec3>& positions, const std::vector<Tri>& triangles);

// True when every coordinate is finite and every index is in range.
bool is_valid(const TriMesh& mesh, std::string* why = nullptr);

// Applies p -> A p + t to positions, and transforms normals accordingly.
void transform(TriMesh& mesh, const Mat3& A, const Vec3& t);

}  // namespace lk
