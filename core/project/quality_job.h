// The checks of a fitted head (pipeline/fit_quality.h), as `likeness fit`
// prints them and the page shows them: the finest level's turned-over,
// degenerate and self-intersecting triangles, and the face measured the
// other way round, to the scan where scanned, with its distance map.
#pragma once
#include "project/project.h"

namespace lk {

// Measures project.quality on the rest pose (the project is put back at
// rest first), once: a later call keeps the first figures. Fails only when
// the project has no fit or cannot be put at rest; the checks' own
// failures are in quality.status and quality.to_scan_status.
Status measure_project_quality(HeadProject& project, const GenericHead& generic);

}  // namespace lk
