// Ground-truth synthetic heads: the generic head (jeong2002 Sec. 4) deformed
// the way people differ, plus a finer "truth" surface to scan. Every later
// stage (alignment, fitting Sec. 5, texturing) can then be scored against a
// known answer.
//
// A head is deformed by smooth, region-weighted displacements. Each feature
// (jaw, chin, nose, ears, lips, brow, cheeks) acts on its annotation region
// with weight 1 and fades to 0 over `falloff_m` of surface (geodesic along
// mesh edges, smoothstep), so nothing creases and nothing leaks through thin
// parts (lips, ear to scalp). Then low-frequency head-shape terms and overall
// proportions are applied. Parameters come from a small PRNG (splitmix64) and
// only +,-,*,/: the same seed gives the same bytes natively and in wasm.
//
// Shapes: generic.mesh #V by 3 and #F by 3; the synthesized head has the
// same #V, #F and triangles (only positions move). Truth: #Vt by 3, #Ft by 3
// with #Ft = 4^levels #F; truth vertex i < #V is the refined control vertex i.
#pragma once
#include "common/status.h"
#include "head/head_model.h"

#include <cstdint>
#include <string>
#include <vector>

namespace lk {

// Ranges are +- around the generic head, scaled together by `variation`.
// Fractions are relative to the feature's size; *_m are metres.
struct SynthHeadOptions {
  double variation = 1.0;          // 0 reproduces the generic head
  double proportion_range = 0.07;  // head width, height, depth, each +-7%
  double shape_range = 0.05;       // taper, crown, occiput, forehead slope (fraction of half-size)
  double jaw_width_range = 0.12;   // jaw scaled sideways +-12%
  double chin_range_m = 0.006;     // chin forward/back and down/up +-6 mm
  double nose_length_range = 0.15, nose_width_range = 0.15, nose_projection_range = 0.18;
  double ear_shift_m = 0.006;      // ears up/down, forward/back +-6 mm
  double ear_size_range = 0.12;    // ears scaled +-12%
  double lip_fullness_m = 0.002;   // each lip pushed forward/back +-2 mm
  double mouth_width_range = 0.10; // mouth corners out/in +-10%
  double brow_ridge_m = 0.003;     // brow ridge forward/back +-3 mm
  double cheek_m = 0.004;          // cheeks fuller/hollower along the normal +-4 mm
  double falloff_m = 0.025;        // geodesic blend distance around each region
  double asymmetry = 0.15;         // left/right features differ by up to this share
};

// The drawn parameters, in [-1, 1] before scaling by the option ranges
// (bell-shaped: the mean of three uniforms). Recorded for scan_info.json.
struct SynthHeadParams {
  std::uint32_t seed = 0;
  std::vector<std::pair<std::string, double>> values;  // name -> applied value (fraction or metres)
  double get(const std::string& name) const;
};

SynthHeadParams draw_synth_params(std::uint32_t seed, const SynthHeadOptions& options = {});

// The synthesized control-level head: same triangles as `generic`, moved
// positions, annotations moved with it (boxes recomputed around the vertices
// they held, eye centres and mouth centre carried by nearby vertices, clip
// planes by their nearest vertex). Fails with InvalidInput on an empty or
// invalid mesh or non-finite options.
Status synthesize_head(const GenericHead& generic, std::uint32_t seed,
                       const SynthHeadOptions& options, GenericHead& out,
                       SynthHeadParams* params = nullptr);

// Convenience form: returns a head with an empty mesh when the input is
// invalid (use the Status form to learn why).
GenericHead synthesize_head(const GenericHead& generic, std::uint32_t seed,
                            const SynthHeadOptions& options = {});

struct TruthOptions {
  int subdivision_levels = 2;        // Loop refinement steps (each x4 triangles)
  double detail_amplitude_m = 0.0005;  // skin detail: smooth noise along the normal, ~0.5 mm
  double detail_wavelength_m = 0.008;  // its feature size; keep above ~2 refined edge lengths
};

// The surface the virtual scanner sees.
struct TruthSurface {
  TriMesh mesh;                      // #Vt, #Ft
  std::vector<int> parent_triangle;  // #Ft: control triangle each fine triangle came from
  std::vector<char> hair;            // #Ft: 1 where the parent triangle is scalp (>= 2 scalp corners)
};

// Loop subdivision (Loop 1987, with the cubic B-spline boundary rule) of the
// control mesh, then detail noise seeded by `seed`. Needs a manifold mesh.
Status make_truth_surface(const GenericHead& head, std::uint32_t seed,
                          const TruthOptions& options, TruthSurface& out);

// One Loop step; exposed for tests. fine vertex i < #V is coarse vertex i
// (smoothed), then one vertex per MeshTopology edge; child k of coarse
// triangle f is fine triangle 4 f + k.
Status loop_subdivide(const TriMesh& coarse, TriMesh& fine);

}  // namespace lk
