// Ground-truth scan set-ups shared by the tests (jeong2002 Sec. 3 input made
// from a known surface): the embedded generic head, a synthetic person
// deformed from it (synth/synth_head.h), that person's finer truth surface,
// and a virtual structured-light scan of it (synth/scanner.h).
//
// Each helper REQUIREs that its step succeeds (with the Status message), so
// a broken stage fails the test that set it up. The same seeds and options
// give the same bytes as calling synthesize_head, make_truth_surface and
// scan_virtual directly: porting a test to these helpers keeps its data.
//
// Shapes: head.mesh #V by 3 (the generic head's triangles); truth.mesh #Vt
// by 3, #Ft by 3 (4^levels #F); scan.positions/normals #P by 3.
#pragma once
#include "head/generic_head_builder.h"
#include "head/head_model.h"
#include "mesh/tri_mesh.h"
#include "synth/scanner.h"
#include "synth/synth_head.h"

#include <cstdint>
#include <functional>

namespace lk::test {

// The embedded generic head (load_generic_head), loaded once per test binary.
const GenericHead& generic_head();

// The generic head as the asset was until 22 Nov 2026: the eye rings'
// corners at 45 deg of the square (GenericHeadBuildOptions::
// even_eye_corners off; even_back_rows and regular_nape off as well), with a 4.6 mm edge
// over each brow. Fits with it fold where the asset's do not, which the
// tests of the fold relief, the fold creases and the fold limiter's second
// pass need as subjects.
// Built once per test binary.
const GenericHead& corner45_generic_head();

// build_generic_head(options), failing the test on an error.
GenericHead built_generic_head(const GenericHeadBuildOptions& options);

// The generic head as the asset was from 8518b1e (even rows at the back) to
// the regular nape (GenericHeadBuildOptions::regular_nape off): the head
// whose synthetic seed 6 sent the local fit's mouth box into a wrong basin.
// Built once per test binary.
const GenericHead& back_rows_generic_head();

// A synthetic person: `generic` deformed by synthesize_head(seed, options).
GenericHead make_test_head(std::uint32_t seed, const SynthHeadOptions& options = {},
                           const GenericHead& generic = generic_head());

// The surface the scanner sees: make_truth_surface(head, seed, options).
TruthSurface make_test_truth(const GenericHead& head, std::uint32_t seed,
                             const TruthOptions& options = {});

// scan_virtual of truth.mesh with `options`, except that target_points is
// `points` and the hair mask is the truth's own (so the scalp returns junk,
// as every scan test wants).
PointCloud scan_test_truth(const TruthSurface& truth, std::uint32_t seed, int points,
                           ScannerOptions options = {}, ScanStats* stats = nullptr);

struct TestScanOptions {
  SynthHeadOptions head;                 // synthesize_head's ranges (defaults)
  TruthOptions truth;                    // make_truth_surface's (defaults: 2 Loop steps, 0.5 mm detail)
  ScannerOptions scanner;                // target_points and hair_triangles are set from the call
  const GenericHead* generic = nullptr;  // the head to deform; nullptr: the embedded generic head
};

struct TestScan {
  GenericHead head;         // the synthetic person, control level
  TruthSurface truth;       // what was scanned
  ScannerOptions scanner;   // the options the scan used (target and hair mask filled in)
  PointCloud scan;
  ScanStats stats;
};

// Person, skin detail and scan all from `seed` (how most tests draw them),
// about `points` points.
TestScan make_test_scan(std::uint32_t seed, int points, const TestScanOptions& options = {});

// `count` points uniformly over the square [0, size]^2 on the height field
// z = surface(x, y), with Gaussian depth noise sigma (a scanner seen from
// above, for displacement tests on flat patches).
PointCloud scan_height_field(const std::function<double(double, double)>& surface, double size,
                             int count, double sigma, unsigned seed);

// The mean position of mesh's vertices `indices` (an eye rim's centre).
Vec3 vertices_centroid(const TriMesh& mesh, const std::vector<int>& indices);

}  // namespace lk::test
