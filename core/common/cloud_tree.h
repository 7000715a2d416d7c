// A nanoflann k-d tree over a list of points (core/multires displacements,
// core/fit's scan-to-mesh term). The adaptor holds a reference: the points
// must outlive the tree.
#pragma once
#include "common/types.h"

#include <nanoflann.hpp>
#include <vector>

namespace lk {

struct CloudAdaptor {
  const std::vector<Vec3>& pts;
  size_t kdtree_get_point_count() const { return pts.size(); }
  double kdtree_get_pt(size_t i, size_t dim) const { return pts[i][static_cast<int>(dim)]; }
  template <class BBOX>
  bool kdtree_get_bbox(BBOX&) const { return false; }
};
using CloudTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, CloudAdaptor>,
                                                      CloudAdaptor, 3, size_t>;

}  // namespace lk
