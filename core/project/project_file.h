// The head project as one file, bytes in and out (the shells do the files).
// A GLB (glTF 2.0 binary), not a zip: its scene is the finest level at rest,
// textured when the project is, so any glTF viewer shows the head, and the
// project rides in its extras ("likeness"), arrays as bufferViews of exact
// doubles. tinygltf (Debian) writes and parses it; docs/design/project_file.md.
#pragma once
#include "io/io.h"
#include "project/project.h"

#include <cstddef>
#include <cstdint>

namespace lk {

// The format's name in extras.likeness.format, and its version: a reader
// refuses a newer version and anything without the name.
extern const char* const kProjectFormat;  // "likeness-project"
// Version 2 adds the eyes' and teeth's textures (parts), version 3 the
// photos (their files, roles, face points) and the page's options
// (inputs). Versions 1 and 2 still open (without them); a newer version is
// refused by its number.
constexpr int kProjectFileVersion = 3;

// The project's bytes. Stored: the scan's positions and faces, the fit's
// options the CLI and page set, the fitted head (control mesh at rest, the
// current control positions, creases, displacements of every level, the
// alignment's meshes and the fit's report figures), the frame, the rig, the
// pose, the texture's chart and skin (PNG), the eyes' and teeth's textures
// made from photos (PNG, with the photos' names), the photos the user
// dropped (their own bytes, roles, face points) and the page's options.
// Not stored: the checks (measure_project_quality measures them again).
// InvalidInput when the project has no fit.
Status save_project(const HeadProject& project, Bytes& out);

// Rebuilds a saved project without fitting: the levels are evaluated from
// the stored control positions and displacements, so the loaded levels are
// bit-identical to the saved project's evaluated ones. Every count, index
// and offset is checked against the bytes before anything is allocated;
// errors say why a file is refused ("not a Likeness project: ...",
// "made by a newer Likeness (project version 2); this one reads version 1").
// The file carries a checksum of its project (FNV-1a over the extras and
// the binary chunk), so a damaged file is refused rather than loaded
// wrong; verify_checksum false skips it (the fuzz tests reach the checks
// behind it). out is left untouched on an error.
Status load_project(const std::uint8_t* data, std::size_t size, HeadProject& out, bool verify_checksum = true);

}  // namespace lk
