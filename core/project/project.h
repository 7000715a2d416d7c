// The head project: what the app and the CLI hold between jobs, as plain
// data. Inputs (the scan and the fit's options), the fitted head with its
// levels and displacements, the scan <-> head frame, the animation rig and
// pose, the texture and the fit's checks. The jobs on it live beside it
// (fit_job.h, pose.h, quality_job.h, export.h, texture_job.h, parts.h);
// none keeps state of its own, so a project is saved and loaded as it is
// (project_file.h).
//
// Frames: the fit works in the HEAD frame (metres, +y up, +z facing,
// pipeline/fit_head.h); what is shown and exported lies over the scan, in
// the SCAN frame (its units and orientation).
#pragma once
#include "image/image.h"
#include "io/io.h"
#include "mesh/tri_mesh.h"
#include "pipeline/fit_head.h"
#include "pipeline/fit_quality.h"

#include <string>
#include <vector>

namespace lk {

// scan_to_head's inverse: head-frame points back onto the scan.
struct HeadFrame {
  Mat3 head_to_scan = Mat3::Identity();  // inverse of scan_to_head.A
  Vec3 head_offset = Vec3::Zero();       // scan_to_head.t

  static HeadFrame from(const AffineMap& scan_to_head) {
    return {scan_to_head.A.inverse(), scan_to_head.t};
  }
  Vec3 to_scan(const Vec3& p) const { return head_to_scan * (p - head_offset); }
  std::vector<Vec3> to_scan(const std::vector<Vec3>& points) const;
  // The mesh in the scan frame, normals dropped (they would need the
  // inverse transpose; viewers recompute them).
  TriMesh to_scan(const TriMesh& mesh) const;
};

// Control vertices an animation moves, their rest positions (head frame)
// and how: brow vertices are lifted by weight (a smooth falloff around the
// "brow" region), jaw vertices rotate about jaw_pivot (pose.h).
struct AnimationRig {
  enum class Kind { Brow, Jaw };
  std::vector<int> moved;
  std::vector<Vec3> rest;
  std::vector<Kind> kind;
  std::vector<double> weight;  // brow falloff in [0, 1]; 1 for the jaw
  Vec3 jaw_pivot = Vec3::Zero();
  double head_size = 0.25;     // the control mesh's bbox diagonal, metres
};

// The chart on the finest level (a coarser level's uvs are its prefix,
// texture/refine_uv.h) and the skin image; empty until textured.
struct ProjectTexture {
  std::vector<Vec2> uvs;
  Image skin;
  bool empty() const { return uvs.empty() || skin.empty(); }
};

// The eyeballs' and teeth's textures made from the user's eye and smile
// photos (parts.h: iris synthesis, teeth_photo_texture), with the photos'
// names; empty: the generic ones. Kept with the head so a saved project
// shows and exports the same eyes and teeth without the photos.
struct ProjectParts {
  Image eye_texture;    // the eyeball texture (RGB)
  std::string eye_source;
  Image teeth_texture;  // the teeth composite (RGBA, voids transparent)
  std::string teeth_source;
};

// A photo the user dropped, kept so the head can be made again from a
// reopened project (project file version 3): the file's own bytes (JPEG or
// PNG, never re-encoded), its name and role, and its face points as the
// page's likeness-landmarks JSON text (photos/landmarks.h), which marks the
// user's drags as "corrected": [indices]; empty while it has none.
struct ProjectPhoto {
  std::string name;
  std::string role = "face";  // "face", "eye" or "smile" (the page's photo roles)
  Bytes bytes;
  std::string points;
};

// What the user put on the page besides the head: the photos, and the
// page's options as a JSON object's text (empty: none kept). The core
// checks the object and keeps its text; the page reads its members.
struct ProjectInputs {
  std::vector<ProjectPhoto> photos;
  std::string page_options;
  bool empty() const { return photos.empty() && page_options.empty(); }
};

// The finest level's checks at rest (quality_job.h), measured once.
struct ProjectQuality {
  bool measured = false;
  Status status;              // of measure_fit_quality
  FitQuality fit;
  Status to_scan_status;      // of measure_fit_to_scan (face region)
  CoveredDistances to_scan;
  std::vector<Vec3> to_scan_colors;  // the finest level's distance map (distance_colors)
};

struct HeadProject {
  PointCloud scan;          // the scan's positions (scan frame) and its faces when it came as a mesh
  FitHeadOptions options;
  FitHeadResult fit;        // head frame
  HeadFrame frame;
  AnimationRig rig;
  double pose = 0;          // the animation amount the multires state holds (0: rest)
  ProjectTexture texture;
  ProjectParts parts;
  ProjectInputs inputs;
  ProjectQuality quality;
  int file_version = 0;     // the version of the file it was read from (0: not read from a file)
};

}  // namespace lk
