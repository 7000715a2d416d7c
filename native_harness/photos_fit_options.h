// The shape fit's levels from the command line, for `likeness photos` and
// `likeness bench --only photos`: fua1998's coarse control triangulations
// (--coarse / --photos-coarse N:S[,N:S...]: N nodes, stiffness S on the
// level's own graph, photos/control_levels.h) and the control mesh's own
// stiffness stages (--schedule / --photos-schedule S[,S...] or "none"), and
// the regularizer's follow term (--follow / --photos-follow K >= 0,
// ShapeFitOptions::follow).
#pragma once
#include "photos/shape_fit.h"

#include <string>

namespace lk::cli {

// Empty text leaves that part of `fit` as it is. False (why says what) on a
// malformed list.
bool parse_fit_levels(const std::string& coarse, const std::string& schedule, const std::string& follow,
                      ShapeFitOptions& fit, std::string& why);

}  // namespace lk::cli
