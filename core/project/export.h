// A head project's levels as file bytes: one level as OBJ or binary PLY,
// the checks' distance map as a coloured PLY, and the textured head as
// OBJ + MTL + PNG. No files are written here; the shells do that.
#pragma once
#include "io/io.h"
#include "project/project.h"

#include <string>

namespace lk {

enum class ExportFrame { Scan, Head };

// Level `level` (0 = the control mesh) of the current pose in the frame
// asked for (Scan: normals dropped). InvalidInput on a missing level.
Status project_level_mesh(HeadProject& project, int level, ExportFrame frame, TriMesh& out);

enum class LevelFormat { Obj, Ply, DistanceMap };

// The bytes of a level. DistanceMap: the finest level (whatever level
// says) at rest, coloured by measure_project_quality's distance map, as
// binary PLY; InvalidInput before the map is measured.
Status export_level(HeadProject& project, int level, LevelFormat format, ExportFrame frame, Bytes& out);

struct TexturedFiles {
  std::string obj;  // "mtllib <base>.mtl", per-vertex uvs
  std::string mtl;  // map_Kd <base>.png
  Bytes png;        // the skin
};

// Level `level` of the current pose with the texture's uvs. InvalidInput
// before the project is textured.
Status export_textured(HeadProject& project, int level, const std::string& base, ExportFrame frame,
                       TexturedFiles& out);

}  // namespace lk
