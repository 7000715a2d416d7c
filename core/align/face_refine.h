// Refines a whole-head alignment on the FACE alone, for scans with surfaces
// the generic head lacks (a hat, a long beard, shoulders on a pedestal).
//
// jeong2002 Sec. 4.1 matches the silhouettes of the whole head: a beret
// above the skull and a beard below the chin change the silhouettes, and the
// generic head lands tilted and off the face (docs/design/fit_real_scans.md,
// Gutenberg). The upper face (nose, eyes, brow, cheeks, forehead) is rarely
// covered, so here points spread evenly over the generic head's upper face
// (not its vertices, which crowd where the grid does) are matched to their
// closest scan points (model to scan: the scan may have any extra surface,
// the face must be on it) by iterative closest points with
// Umeyama's similarity per iteration (rotation, translation, one scale; the
// given map's stretch is dropped). Pairs beyond the knee of the sorted
// residuals do not pull (a beard over the cheeks, a brim over the brow):
// the trimmed share comes from the data. Several starts (turns about the
// horizontal and vertical axes through the face, shifts across it) are run
// and the one with the lowest clamped score is kept. That score cannot tell
// the head's pitch: Gutenberg's face lies on his scan from pitches 11-55 deg
// apart. Given a measure of the whole alignment (the share of the scan near
// the head), pitch candidates are run briefly and the measure picks the one
// that goes on (docs/design/align.md, "Choosing the pitch"). The knee trims hard:
// from a start far off it stops short of the truth (the synthetic test:
// 28.6 mm -> about 6 mm); trimming at 2.5 x the median instead converges
// there but let Gutenberg's face slide into his beret
// (docs/design/fit_real_scans.md).
//
// Shapes: generic.positions #V by 3; cloud #P by 3 (the same frame as the
// given map's output); faces: the scan's triangles over cloud (#T by 3, or
// empty for a raw cloud: matched to its points). Results map a generic point p to linear * p +
// translation.
#pragma once
#include "common/status.h"
#include "common/types.h"
#include "head/head_model.h"
#include "mesh/tri_mesh.h"

#include <functional>
#include <vector>

namespace lk {

struct FaceRefineOptions {
  int iterations = 60;          // per start
  int polish_iterations = 0;    // more for the best start (0: none)
  double relative_tolerance = 1e-5;  // stop when the trimmed RMS changes less than this
  // Starts: turns (degrees) of the given alignment about the face's centre,
  // about the horizontal axis (head up / down) and the vertical one.
  std::vector<double> pitch_starts_deg = {0.0, 12.0, -12.0};
  std::vector<double> yaw_starts_deg = {0.0, 20.0, -20.0};
  // A head turned on its bust (Gutenberg) leaves the face's match short of
  // the turn (docs/design/fit_real_scans.md). After each search its winner
  // is turned about the face's vertical axis to where the scan's relief in
  // front of it is most mirror-symmetric (align/face_symmetry.h), where
  // that is more than symmetry_yaw_min_deg away, and run as one more start
  // (it wins by the clamped score). Among the pitch candidates, those whose
  // face looks along the scan's own (the most symmetric view within
  // symmetry_yaw_min_deg, its correlation within symmetry_margin of the
  // best such candidate's) are chosen from first. Off by default: it finds
  // Gutenberg's face, but his fit then puts his left upper lid below the
  // lower one and the face rig refuses the head (docs/design/
  // fit_real_scans.md, "The face's symmetry as a measure of its yaw").
  bool symmetry_yaw_start = false;
  double symmetry_yaw_min_deg = 10.0;
  double symmetry_margin = 0.1;
  // and shifts across the face, as fractions of its width.
  std::vector<double> shift_starts = {0.0, 0.2, -0.2};
  // At least this share of the pairs pulls.
  double min_keep_fraction = 0.3;
  // Score of a start: mean of min(d, clamp)^2 over all samples, with clamp
  // this fraction of the diagonal passed in.
  double score_clamp_fraction = 0.02;
  // About this many points spread evenly over the upper face's surface
  // (upper_face_samples) are matched, not its vertices: the match must not
  // depend on how densely the generic head's grid covers each part.
  int samples = 800;
  // With a whole-scan measure (refine_alignment_on_face's `whole`): pitch
  // candidates, turns (degrees) of the given alignment about the face's
  // centre added to every pitch start. Each candidate's starts are matched
  // for candidate_iterations; the best of them by the clamped score stands
  // for the candidate; the candidate the measure rates highest continues
  // up to `iterations` in all, kept where the measure does not drop. The
  // face's own score cannot tell the pitches apart
  // (a beard and a beret carry face-like surface: docs/design/align.md).
  std::vector<double> candidate_pitches_deg = {0.0, 15.0, -15.0, 30.0, -30.0};
  int candidate_iterations = 20;
  // Screening (successive halving): every start runs screen_iterations
  // first, and only the screen_keep best by the clamped score go on to
  // `iterations` (or candidate_iterations) and into the choice; the same
  // result to the bit whenever the start that wins the full search is
  // among them. 0: every start runs through.
  int screen_iterations = 0;
  int screen_keep = 3;
};

// One pitch candidate, as the whole-scan measure rated it.
struct FaceRefineCandidate {
  double pitch_deg = 0;
  double measure = 0;        // the whole-scan measure of its pose (higher is better)
  double score = 0;          // its best start's clamped score
  double near_fraction = 0;  // its best start's share of the face on the scan
  // Its face's most symmetric view (FaceRefineOptions::symmetry_yaw_start):
  // the turn from its own, and the correlation (-2: not measured).
  double symmetry_yaw_deg = 0;
  double symmetry_score = -2;
};

struct FaceRefineResult {
  Mat3 linear = Mat3::Identity();
  Vec3 translation = Vec3::Zero();
  double score = 0;          // see FaceRefineOptions::score_clamp_fraction (cloud units^2)
  double trimmed_rms = 0;    // over the pairs that pulled in the last iteration
  double kept_fraction = 0;  // share of the samples that pulled in the last iteration
  double near_fraction = 0;  // share of the samples within the clamp distance of a scan point
  int samples = 0;
  int iterations = 0;        // over all starts
  std::vector<FaceRefineCandidate> candidates;  // with a whole-scan measure: each pitch candidate
  int chosen = -1;                              // the one that continued (-1: no measure given)
  // The first search's winner's most symmetric view: its turn and
  // correlation (-2: not measured; FaceRefineOptions::symmetry_yaw_start).
  double symmetry_yaw_deg = 0;
  double symmetry_score = -2;
  double continued_measure = -1;                // the measure after it continued (kept when not lower)
};

// A measure of a whole alignment (world point = linear * generic point +
// translation) on the scan, higher is better: e.g. the share of the scan
// near the aligned head.
using AlignmentMeasure = std::function<double(const Mat3& linear, const Vec3& translation)>;

// The generic head's upper-face vertices used for the match: region "face"
// without the chin, jaw, lips, mouth bag and the eye pockets, facing
// forward (their normal within 72 deg of ann.look).
std::vector<int> upper_face_vertices(const TriMesh& generic, const HeadAnnotations& ann);

// About `count` points spread evenly over the upper face's surface: the
// triangles whose corners are all upper_face_vertices, sampled on their
// Phong surface (multires/surface_samples.h) together with the vertices,
// one point kept per cell of a voxel grid (common/sampling.h). Each sample
// stands for about the same area however the grid is laid out (a faired
// face's vertices crowd and thin where the cast one's did not). Always the
// same points for the same mesh.
std::vector<Vec3> upper_face_samples(const TriMesh& generic, const HeadAnnotations& ann, int count);

// The index (into sorted, ascending) of the knee of a sorted residual
// curve: the point farthest below the chord from its first to its last
// value, both axes normalized. 0 for fewer than three values.
size_t residual_knee(const std::vector<double>& sorted);

// The share of the upper face's samples (upper_face_samples, `samples` of
// them) that the map (linear, translation) puts within clamp_fraction *
// diag of the scan (its triangles when given, else its points):
// FaceRefineResult::near_fraction for a given alignment. Errors as below.
Status upper_face_near_fraction(const TriMesh& generic, const HeadAnnotations& ann, const std::vector<Vec3>& cloud,
                                const std::vector<Tri>& faces, const Mat3& linear, const Vec3& translation,
                                double diag, double clamp_fraction, double& out,
                                int samples = FaceRefineOptions{}.samples);
// With `whole` given, the pitch candidates (FaceRefineOptions::
// candidate_pitches_deg) are tried and `whole` chooses among them.
// Errors: Empty (no points or no face vertices), InvalidInput (non-finite
// input, diag <= 0, bad options), NotConverged (no start kept pairs).
Status refine_alignment_on_face(const TriMesh& generic, const HeadAnnotations& ann, const std::vector<Vec3>& cloud,
                                const std::vector<Tri>& faces, const Mat3& linear, const Vec3& translation, double diag,
                                const FaceRefineOptions& options, FaceRefineResult& out,
                                const AlignmentMeasure& whole = {});

}  // namespace lk
