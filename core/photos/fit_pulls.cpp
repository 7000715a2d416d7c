#include "photos/fit_pulls.h"

#include "photos/contour_obs.h"
#include "photos/eye_lids.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <map>

namespace lk {

Status measure_fit_pulls(const TriMesh& start, const std::vector<Vec3>& x,
                         const std::vector<std::unique_ptr<ObservationSet>>& sets, const std::vector<double>& lambdas,
                         const std::vector<std::vector<std::string>>& row_groups, const ShapeFitOptions& options,
                         double stiffness, const std::vector<PullRegion>& regions, const Vec3& lateral,
                         double& force_unit, FitPulls& out) {
  out = {};
  const int V = start.num_vertices(), n = 3 * V;
  if (int(x.size()) != V || lambdas.size() != sets.size() || row_groups.size() != sets.size() || !(stiffness > 0))
    return Status::error(ErrorCode::InvalidInput, "fit pulls: the shape, lambdas or groups do not match");
  const std::vector<double> scales = observation_type_weights(x, sets, lambdas);
  // Rows: every set's (scaled), then the binding edges'; each row's group.
  std::vector<Eigen::Triplet<double>> trip;
  std::vector<double> res;
  std::vector<int> group_of_row;
  std::map<std::string, int> group_index;
  auto group_id = [&](const std::string& name) {
    auto it = group_index.find(name);
    if (it != group_index.end()) return it->second;
    const int id = int(out.groups.size());
    group_index[name] = id;
    out.groups.push_back({name, 0, {}, {}});
    return id;
  };
  for (size_t k = 0; k < sets.size(); ++k) {
    const int m = sets[k]->num_residuals();
    if (!row_groups[k].empty() && int(row_groups[k].size()) != m)
      return Status::error(ErrorCode::InvalidInput, "fit pulls: one group per row needed");
    Eigen::VectorXd r(m);
    std::vector<Eigen::Triplet<double>> local;
    if (m == 0) continue;
    if (!sets[k]->evaluate(x, r, 0, &local))
      return Status::error(ErrorCode::InvalidInput, "fit pulls: an observation lies behind its camera");
    const int row0 = int(res.size());
    for (const auto& t : local) trip.emplace_back(row0 + t.row(), t.col(), scales[k] * t.value());
    for (int i = 0; i < m; ++i) {
      res.push_back(scales[k] * r[i]);
      group_of_row.push_back(group_id(row_groups[k].empty() ? sets[k]->type_name() : row_groups[k][size_t(i)]));
    }
  }
  if (!options.binding_edges.empty()) {
    const double sb = std::sqrt(options.binding_weight);
    const int g = group_id("lip binding");
    for (const auto& e : options.binding_edges) {
      const int a = e[0], b = e[1];
      if (a < 0 || b < 0 || a >= V || b >= V) return Status::error(ErrorCode::InvalidInput, "fit pulls: a bad binding edge");
      const Vec3 rest = start.positions[size_t(a)] - start.positions[size_t(b)];
      const Vec3 r = sb * ((x[size_t(a)] - x[size_t(b)]) - rest);
      for (int j = 0; j < 3; ++j) {
        const int row = int(res.size());
        trip.emplace_back(row, 3 * a + j, sb);
        trip.emplace_back(row, 3 * b + j, -sb);
        res.push_back(r[j]);
        group_of_row.push_back(g);
      }
    }
  }
  if (options.symmetry_weight > 0 && !options.mirror_pairs.empty()) {
    for (const auto& e : options.mirror_pairs)
      if (e[0] < 0 || e[1] < 0 || e[0] >= V || e[1] >= V)
        return Status::error(ErrorCode::InvalidInput, "fit pulls: a bad mirror pair");
    Eigen::VectorXd rs;
    std::vector<Eigen::Triplet<double>> js;
    symmetry_residuals(start.positions, x, options.mirror_pairs, options.symmetry_weight, rs, &js);
    const int row0 = int(res.size()), g = group_id("symmetry");
    for (const auto& t : js) trip.emplace_back(row0 + t.row(), t.col(), t.value());
    for (int i = 0; i < int(rs.size()); ++i) {
      res.push_back(rs[i]);
      group_of_row.push_back(g);
    }
  }
  const int rows = int(res.size());
  // The state as the fit's: the displacements, then the regularizer's
  // similarity (options.follow > 0), which no observation row touches.
  const int e = regularizer_extra_parameters(options.follow), na = n + e;
  SparseMat J(rows, na);
  J.setFromTriplets(trip.begin(), trip.end());
  const Eigen::Map<const Eigen::VectorXd> r(res.data(), rows);
  // S = R^T R, R the regularizer's rows on the start mesh's graph (the fit's control level).
  // The follow term's weights as the fit sets them at the start of its control level.
  const SparseMat L = uniform_laplacian(start);
  std::vector<double> fw;
  if (e) fw = follow_node_weights(observed_vertices(sets, start.positions), L, options.follow_observed);
  const SparseMat Rg = regularizer_matrix(start.positions, L, stiffness, options.tether, options.follow, fw);
  const SparseMat S = SparseMat(Rg.transpose()) * Rg;
  const SparseMat H = SparseMat(SparseMat(J.transpose()) * J) + S;
  Eigen::SimplicialLDLT<SparseMat> solver(H);
  if (solver.info() != Eigen::Success) return Status::error(ErrorCode::NotConverged, "fit pulls: the normal equations are singular");
  Eigen::VectorXd D = Eigen::VectorXd::Zero(na);
  for (int v = 0; v < V; ++v) D.segment<3>(3 * v) = x[size_t(v)] - start.positions[size_t(v)];
  if (e) {  // the similarity that minimizes the regularizer at these displacements
    const SparseMat Rt = Rg.rightCols(e);
    const Eigen::MatrixXd A = Eigen::MatrixXd(SparseMat(Rt.transpose()) * Rt);
    const Eigen::VectorXd b = -(Rt.transpose() * (Rg.leftCols(n) * D.head(n)));
    D.tail(e) = A.ldlt().solve(b);
  }
  const Eigen::VectorXd w = J * D - r;  // the linearized rows at D = 0

  // Outward unit per region vertex: away from the start shape's midline along `lateral`.
  const Vec3 u = lateral.normalized();
  double mid = 0;
  for (const Vec3& p : start.positions) mid += p.dot(u);
  mid /= std::max(1, V);
  auto outward_mean = [&](const Eigen::VectorXd& field, const PullRegion& reg) {
    double sum = 0;
    int cnt = 0;
    for (int v : reg.vertices) {
      if (v < 0 || v >= V) continue;
      const double side = start.positions[size_t(v)].dot(u) - mid;
      if (side == 0) continue;
      sum += (side > 0 ? 1.0 : -1.0) * field.segment<3>(3 * v).dot(u);
      ++cnt;
    }
    return cnt ? sum / cnt : 0.0;
  };
  const size_t R = regions.size();
  for (const PullRegion& reg : regions) {
    out.displacement_m.push_back(outward_mean(D, reg));
    out.explained_m.push_back(0);
  }
  const int G = int(out.groups.size());
  std::vector<Eigen::VectorXd> forces;
  for (int g = 0; g < G; ++g) {
    Eigen::VectorXd wg = Eigen::VectorXd::Zero(rows), rg = Eigen::VectorXd::Zero(rows);
    for (int i = 0; i < rows; ++i)
      if (group_of_row[size_t(i)] == g) {
        wg[i] = w[i];
        rg[i] = r[i];
        ++out.groups[size_t(g)].rows;
      }
    const Eigen::VectorXd Dg = solver.solve(J.transpose() * wg);
    forces.push_back(-(J.transpose() * rg).head(n));
    for (size_t k = 0; k < R; ++k) {
      out.groups[size_t(g)].share_m.push_back(outward_mean(Dg, regions[k]));
      out.explained_m[k] += out.groups[size_t(g)].share_m.back();
    }
  }
  out.groups.push_back({"stiffness", 0, std::vector<double>(R, std::nan("")), {}});
  forces.push_back(-(S * D).head(n));
  if (!(force_unit > 0)) {
    force_unit = 0;
    for (int g = 0; g < G; ++g)
      for (size_t k = 0; k < R; ++k) force_unit += std::abs(outward_mean(forces[size_t(g)], regions[k]));
  }
  for (size_t g = 0; g < forces.size(); ++g)
    for (size_t k = 0; k < R; ++k)
      out.groups[g].force.push_back(force_unit > 0 ? outward_mean(forces[g], regions[k]) / force_unit : 0.0);
  return Status::success();
}

std::string landmark_pull_group(const GenericHead& generic, const SurfacePoint& point, int landmark, bool mediapipe) {
  if (mediapipe && landmark >= 0) {
    const std::vector<int>& oval = mediapipe_face_oval();
    if (std::find(oval.begin(), oval.end(), landmark) != oval.end()) return "outline";
    for (int e = 0; e < 2; ++e) {
      const LidContour& c = mediapipe_lid_contour(e);
      if (landmark == c.outer || landmark == c.inner ||
          std::find(c.upper.begin(), c.upper.end(), landmark) != c.upper.end() ||
          std::find(c.lower.begin(), c.lower.end(), landmark) != c.lower.end())
        return "lids";
    }
  }
  if (!point.valid()) return "other";
  const Vec3 p = surface_position(generic.mesh, point);
  int best = -1;
  double bd = 1e300;
  for (int v = 0; v < generic.mesh.num_vertices(); ++v) {
    const double d = (generic.mesh.positions[size_t(v)] - p).squaredNorm();
    if (d < bd) {
      bd = d;
      best = v;
    }
  }
  auto in = [&](const char* region) {
    auto it = generic.annotations.regions.find(region);
    return it != generic.annotations.regions.end() && std::find(it->second.begin(), it->second.end(), best) != it->second.end();
  };
  if (in("lips")) return "lips";
  if (in("eye_rim_left") || in("eye_rim_right")) return "eyes";
  if (in("brow")) return "brows";
  if (in("nose")) return "nose";
  if (in("cheeks")) return "cheeks";
  if (in("jaw") || in("chin")) return "jaw";
  return "other";
}

Status measure_photos_fit_pulls(const GenericHead& generic, const std::vector<SurfacePoint>& landmarks,
                                const std::vector<LandmarkPhoto>& photos, const SelfCalibResult& calib,
                                const PhotosJobOptions& options, const std::vector<Vec3>& fitted,
                                PhotosFitPulls& out, const std::vector<PhotoOutline>* outlines,
                                const StereoResult* stereo, const LandmarkSlide* slide, PullGrouping grouping) {
  out = {};
  if (options.fit.stiffness_schedule.empty())
    return Status::error(ErrorCode::InvalidInput, "fit pulls: no stiffness schedule on the control mesh");
  PhotosObservations obs;
  if (Status s = make_photos_observations(generic, landmarks, photos, calib, options, outlines, stereo, slide, obs); !s)
    return with_context(s, "fit pulls");
  const bool mediapipe = std::any_of(photos.begin(), photos.end(), [](const LandmarkPhoto& p) {
    return p.detector == kMediaPipeDetector;
  });
  std::vector<std::vector<std::string>> groups(obs.sets.size());
  std::map<int, std::string> group_of_landmark;
  std::vector<std::string> photo_of_camera;  // the feature sets' camera index -> photo name (used photos in order)
  for (size_t i = 0; i < photos.size(); ++i)
    if (calib.photos[i].used)
      photo_of_camera.push_back(photos[i].name.empty() ? "photo " + std::to_string(i + 1) : photos[i].name);
  for (size_t k = 0; k < obs.sets.size(); ++k) {
    const auto* f = dynamic_cast<const FeatureSet*>(obs.sets[k].get());
    if (!f) continue;
    for (const FeatureObservation& o : f->observations()) {
      if (grouping == PullGrouping::Photos) {
        const std::string name = size_t(o.camera) < photo_of_camera.size() ? photo_of_camera[size_t(o.camera)] : "other";
        groups[k].push_back(name);
        groups[k].push_back(name);
        continue;
      }
      auto it = group_of_landmark.find(o.landmark);
      if (it == group_of_landmark.end())
        it = group_of_landmark
                 .emplace(o.landmark, o.landmark >= 0 && size_t(o.landmark) < landmarks.size()
                                          ? landmark_pull_group(generic, landmarks[size_t(o.landmark)], o.landmark, mediapipe)
                                          : std::string("other"))
                 .first;
      const std::string name = grouping == PullGrouping::EachLandmark
                                   ? "lm " + std::to_string(o.landmark) + " (" + it->second + ")"
                                   : it->second;
      groups[k].push_back(name);
      groups[k].push_back(name);  // two rows per feature
    }
  }
  out.regions = lateral_pull_regions(generic);
  const Vec3 lateral = generic.annotations.up.cross(generic.annotations.look);
  double unit = 0;
  Status s = measure_fit_pulls(generic.mesh, generic.mesh.positions, obs.sets, obs.lambdas, groups, obs.fit,
                               obs.fit.stiffness_schedule.front(), out.regions, lateral, unit, out.start);
  if (!s) return s;
  for (auto& set : obs.sets) set->reweight(fitted);
  return measure_fit_pulls(generic.mesh, fitted, obs.sets, obs.lambdas, groups, obs.fit,
                           obs.fit.stiffness_schedule.back(), out.regions, lateral, unit, out.end);
}

std::vector<PullRegion> lateral_pull_regions(const GenericHead& generic) {
  const Vec3 lateral = generic.annotations.up.cross(generic.annotations.look).normalized();
  std::vector<PullRegion> out;
  for (const auto& [name, sources] : std::vector<std::pair<std::string, std::vector<std::string>>>{
           {"cheeks", {"cheeks"}}, {"jaw", {"jaw", "chin"}}, {"ears", {"ears"}}}) {
    PullRegion reg{name, {}};
    for (const std::string& s : sources) {
      auto it = generic.annotations.regions.find(s);
      if (it == generic.annotations.regions.end()) continue;
      for (int v : it->second)
        if (v >= 0 && v < generic.mesh.num_vertices() && std::abs(generic.mesh.positions[size_t(v)].dot(lateral)) > 0.02 &&
            std::find(reg.vertices.begin(), reg.vertices.end(), v) == reg.vertices.end())
          reg.vertices.push_back(v);
    }
    out.push_back(reg);
  }
  return out;
}

}  // namespace lk
