// The photos fit's pulls on the face's sides (photos/fit_pulls.h) as a
// table for `likeness photos --pulls` and `likeness bench --only photos
// --photos-detected DIR --photos-pulls`, and as report.json's `fit_pulls`.
#pragma once
#include "photos/fit_pulls.h"

#include <nlohmann/json.hpp>
#include <string>

namespace lk::cli {

// Rows per group: the first step's outward share, the fitted displacement's
// share (mm) and the force at the end (% of the start's total), per region;
// then their sums and the fit's own outward displacement.
// max_groups > 0: only that many groups, those with the largest fitted
// share on the first region (most outward first), then the most inward 3.
std::string fit_pulls_table(const PhotosFitPulls& pulls, const std::string& indent, int max_groups = 0);
nlohmann::json fit_pulls_json(const PhotosFitPulls& pulls);

}  // namespace lk::cli
