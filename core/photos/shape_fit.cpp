#include "photos/shape_fit.h"

#include "photos/control_levels.h"
#include "photos/descent.h"

#include "photos/self_calibration.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

namespace lk {

FeatureSet::FeatureSet(const TriMesh& mesh, std::vector<Camera> cameras, std::vector<FeatureObservation> observations,
                       double huber_px)
    : triangles_(mesh.triangles), cameras_(std::move(cameras)), obs_(std::move(observations)), huber_px_(huber_px) {}

bool FeatureSet::evaluate(const std::vector<Vec3>& positions, Eigen::VectorXd& r, int row,
                          std::vector<Eigen::Triplet<double>>* jacobian) const {
  for (const FeatureObservation& o : obs_) {
    const Tri& t = triangles_[size_t(o.point.triangle)];
    const Vec3 X = o.point.barycentric[0] * positions[size_t(t[0])] + o.point.barycentric[1] * positions[size_t(t[1])] +
                   o.point.barycentric[2] * positions[size_t(t[2])] + o.point.offset;
    ProjectionJacobian pj;
    if (!projection_jacobian(cameras_[size_t(o.camera)], X, o.pixel, pj)) return false;
    const double s = std::sqrt(o.weight);
    r.segment<2>(row) = s * pj.residual;
    if (jacobian)
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 2; ++k)
          for (int j = 0; j < 3; ++j)
            jacobian->emplace_back(row + k, 3 * t[size_t(c)] + j, s * o.point.barycentric[c] * pj.d_point(k, j));
    row += 2;
  }
  return true;
}

std::vector<double> FeatureSet::errors(const std::vector<Vec3>& positions) const {
  std::vector<double> e;
  e.reserve(obs_.size());
  for (const FeatureObservation& o : obs_) {
    const Tri& t = triangles_[size_t(o.point.triangle)];
    const Vec3 X = o.point.barycentric[0] * positions[size_t(t[0])] + o.point.barycentric[1] * positions[size_t(t[1])] +
                   o.point.barycentric[2] * positions[size_t(t[2])] + o.point.offset;
    Vec2 uv;
    e.push_back(cameras_[size_t(o.camera)].project(X, uv) ? (uv - o.pixel).norm()
                                                          : std::numeric_limits<double>::infinity());
  }
  return e;
}

void FeatureSet::reweight(const std::vector<Vec3>& positions) {
  const std::vector<double> e = errors(positions);
  for (size_t i = 0; i < obs_.size(); ++i) {
    const double h = e[i] <= huber_px_ ? 1.0 : (std::isfinite(e[i]) ? huber_px_ / e[i] : 0.0);
    obs_[i].weight = obs_[i].prior_weight * h;
  }
}

void FeatureSet::inlier_pixel_errors(const std::vector<Vec3>& positions, std::vector<double>& out) const {
  const std::vector<double> e = errors(positions);
  for (size_t i = 0; i < e.size(); ++i)
    if (obs_[i].weight >= 0.5 && std::isfinite(e[i])) out.push_back(e[i]);
}

std::vector<double> observation_type_weights(const std::vector<Vec3>& positions,
                                             const std::vector<std::unique_ptr<ObservationSet>>& sets,
                                             const std::vector<double>& lambdas) {
  std::vector<double> w(sets.size(), 0.0);
  for (size_t k = 0; k < sets.size() && k < lambdas.size(); ++k) {
    const int n = sets[k]->num_residuals();
    Eigen::VectorXd r(n);
    std::vector<Eigen::Triplet<double>> trip;
    if (n == 0 || !sets[k]->evaluate(positions, r, 0, &trip)) continue;
    double sum = 0;  // each row's entries are distinct columns: the sum of squares is the rows' squared norms
    for (const auto& t : trip) sum += t.value() * t.value();
    const double G = std::sqrt(sum / n);
    w[k] = G > 0 ? lambdas[k] / G : 0;
  }
  return w;
}

std::vector<std::array<int, 2>> mirror_vertex_pairs(const TriMesh& mesh, double tolerance_m) {
  // Sorted by x so each vertex looks for its mirror in a narrow window.
  const int n = mesh.num_vertices();
  std::vector<int> order(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) order[size_t(i)] = i;
  std::sort(order.begin(), order.end(), [&](int a, int b) { return mesh.positions[size_t(a)].x() < mesh.positions[size_t(b)].x(); });
  std::vector<double> xs(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) xs[size_t(i)] = mesh.positions[size_t(order[size_t(i)])].x();
  std::vector<std::array<int, 2>> pairs;
  for (int a = 0; a < n; ++a) {
    const Vec3& p = mesh.positions[size_t(a)];
    const Vec3 m(-p.x(), p.y(), p.z());
    int best = -1;
    double best_d = tolerance_m;
    for (auto it = std::lower_bound(xs.begin(), xs.end(), m.x() - tolerance_m);
         it != xs.end() && *it <= m.x() + tolerance_m; ++it) {
      const int b = order[size_t(it - xs.begin())];
      const double d = (mesh.positions[size_t(b)] - m).norm();
      if (d <= best_d) best = b, best_d = d;
    }
    if (best < 0) return {};
    if (a <= best) pairs.push_back({a, best});
  }
  return pairs;
}

void symmetry_residuals(const std::vector<Vec3>& start, const std::vector<Vec3>& positions,
                        const std::vector<std::array<int, 2>>& pairs, double weight, Eigen::VectorXd& r,
                        std::vector<Eigen::Triplet<double>>* jacobian) {
  const double s = std::sqrt(weight);
  r.resize(3 * long(pairs.size()));
  for (size_t k = 0; k < pairs.size(); ++k) {
    const int a = pairs[k][0], b = pairs[k][1], row = 3 * int(k);
    const Vec3 da = positions[size_t(a)] - start[size_t(a)], db = positions[size_t(b)] - start[size_t(b)];
    r.segment<3>(row) = s * (Vec3(-da.x(), da.y(), da.z()) - db);
    if (!jacobian) continue;
    for (int j = 0; j < 3; ++j) {
      const double sa = j == 0 ? -s : s;  // d/dx_a of s S x_a
      if (a != b) {
        jacobian->emplace_back(row + j, 3 * a + j, sa);
        jacobian->emplace_back(row + j, 3 * b + j, -s);
      } else if (sa != s) {
        jacobian->emplace_back(row + j, 3 * a + j, sa - s);  // on the plane: -2 s along x, 0 else
      }
    }
  }
}

SparseMat uniform_laplacian(const TriMesh& mesh) {
  const int V = mesh.num_vertices();
  std::vector<std::set<int>> nbr(static_cast<size_t>(V));
  for (const Tri& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      nbr[size_t(t[size_t(k)])].insert(t[size_t((k + 1) % 3)]);
      nbr[size_t(t[size_t((k + 1) % 3)])].insert(t[size_t(k)]);
    }
  std::vector<Eigen::Triplet<double>> trip;
  for (int i = 0; i < V; ++i) {
    if (nbr[size_t(i)].empty()) continue;
    trip.emplace_back(i, i, 1.0);
    const double w = -1.0 / double(nbr[size_t(i)].size());
    for (int j : nbr[size_t(i)]) trip.emplace_back(i, j, w);
  }
  SparseMat L(V, V);
  L.setFromTriplets(trip.begin(), trip.end());
  return L;
}

Vec3 similarity_displacement(const Vec3& x, const Vec3& centroid, const Eigen::Matrix<double, 7, 1>& theta) {
  const Vec3 d = x - centroid;
  return theta[0] * d + Vec3(theta[1], theta[2], theta[3]).cross(d) + Vec3(theta[4], theta[5], theta[6]);
}

namespace {

Vec3 centroid_of(const std::vector<Vec3>& nodes) {
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : nodes) c += p;
  return nodes.empty() ? c : Vec3(c / double(nodes.size()));
}

}  // namespace

SparseMat regularizer_matrix(const std::vector<Vec3>& nodes, const SparseMat& laplacian, double stiffness,
                             double tether, double follow, const std::vector<double>& follow_weights) {
  const int K = int(nodes.size()), n = 3 * K, e = regularizer_extra_parameters(follow);
  const Vec3 c = centroid_of(nodes);
  // B: 3K by 7, the similarity's displacement per node coordinate; column
  // j of B is similarity_displacement with theta = e_j.
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(n, e);
  if (e)
    for (int i = 0; i < K; ++i)
      for (int j = 0; j < 7; ++j)
        B.block<3, 1>(3 * i, j) = similarity_displacement(nodes[size_t(i)], c, Eigen::Matrix<double, 7, 1>::Unit(j));
  std::vector<Eigen::Triplet<double>> trip;
  const double ss = std::sqrt(stiffness), sf = std::sqrt(follow * stiffness), st = std::sqrt(tether);
  int row = 0;
  // sqrt(k) (L x I3) delta, then minus sqrt(k) (L x I3) B theta.
  Eigen::MatrixXd LB = Eigen::MatrixXd::Zero(n, e);
  for (int k = 0; k < laplacian.outerSize(); ++k)
    for (SparseMat::InnerIterator it(laplacian, k); it; ++it)
      for (int j = 0; j < 3; ++j) {
        trip.emplace_back(row + 3 * int(it.row()) + j, 3 * int(it.col()) + j, ss * it.value());
        if (e) LB.row(3 * int(it.row()) + j) += it.value() * B.row(3 * int(it.col()) + j);
      }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < e; ++j)
      if (LB(i, j) != 0) trip.emplace_back(row + i, n + j, -ss * LB(i, j));
  row += n;
  if (e) {
    for (int i = 0; i < n; ++i) {
      const double w = sf * (follow_weights.empty() ? 1.0 : std::sqrt(follow_weights[size_t(i / 3)]));
      if (w == 0) continue;
      trip.emplace_back(row + i, i, w);
      for (int j = 0; j < e; ++j)
        if (B(i, j) != 0) trip.emplace_back(row + i, n + j, -w * B(i, j));
    }
    row += n;
  }
  for (int i = 0; i < n; ++i) trip.emplace_back(row + i, i, st);
  row += n;
  SparseMat R(row, n + e);
  R.setFromTriplets(trip.begin(), trip.end());
  return R;
}

Eigen::VectorXd regularizer_residuals(const std::vector<Vec3>& nodes, const SparseMat& laplacian, double stiffness,
                                      double tether, double follow, const Eigen::VectorXd& state,
                                      const std::vector<double>& follow_weights) {
  const int K = int(nodes.size()), n = 3 * K, e = regularizer_extra_parameters(follow);
  const Vec3 c = centroid_of(nodes);
  Eigen::Matrix<double, 7, 1> theta = Eigen::Matrix<double, 7, 1>::Zero();
  if (e) theta = state.segment<7>(n);
  // The non-similar part of each node's displacement.
  std::vector<Vec3> u(static_cast<size_t>(K));
  for (int i = 0; i < K; ++i) u[size_t(i)] = state.segment<3>(3 * i) - similarity_displacement(nodes[size_t(i)], c, theta);
  Eigen::VectorXd r = Eigen::VectorXd::Zero((e ? 3 : 2) * n);
  for (int k = 0; k < laplacian.outerSize(); ++k)
    for (SparseMat::InnerIterator it(laplacian, k); it; ++it)
      r.segment<3>(3 * int(it.row())) += std::sqrt(stiffness) * it.value() * u[size_t(it.col())];
  int row = n;
  if (e) {
    for (int i = 0; i < K; ++i)
      r.segment<3>(row + 3 * i) = std::sqrt(follow * stiffness * (follow_weights.empty() ? 1.0 : follow_weights[size_t(i)])) *
                                  u[size_t(i)];
    row += n;
  }
  r.segment(row, n) = std::sqrt(tether) * state.head(n);
  return r;
}

std::vector<double> follow_node_weights(const std::vector<bool>& observed_nodes, const SparseMat& laplacian,
                                        double observed_weight) {
  Eigen::VectorXd w(long(observed_nodes.size()));
  for (size_t i = 0; i < observed_nodes.size(); ++i) w[long(i)] = observed_nodes[i] ? observed_weight : 1.0;
  for (int pass = 0; pass < 3; ++pass) w -= 0.5 * (laplacian * w);
  return std::vector<double>(w.data(), w.data() + w.size());
}

std::vector<bool> observed_vertices(const std::vector<std::unique_ptr<ObservationSet>>& sets,
                                    const std::vector<Vec3>& positions) {
  std::vector<bool> seen(positions.size(), false);
  for (const auto& set : sets) {
    Eigen::VectorXd r(set->num_residuals());
    std::vector<Eigen::Triplet<double>> trip;
    if (r.size() == 0 || !set->evaluate(positions, r, 0, &trip)) continue;
    for (const auto& t : trip)
      if (t.value() != 0 && size_t(t.col() / 3) < seen.size()) seen[size_t(t.col() / 3)] = true;
  }
  return seen;
}

namespace {

// State: displacements delta of the current level's nodes (3 K), then the
// regularizer's similarity (options.follow > 0); the vertices are base + A
// delta (eq. 3, control_levels.h; A = I on the control mesh). Residuals: the
// scaled observation sets, the binding edges (over vertices, like the
// observations), then the regularizer's rows (regularizer_matrix) on the
// level's own graph.
class ShapeProblem : public LeastSquaresProblem {
 public:
  ShapeProblem(const TriMesh& control, std::vector<std::unique_ptr<ObservationSet>>& sets,
               const std::vector<std::array<int, 2>>& binding_edges, double binding_weight,
               const std::vector<std::array<int, 2>>& mirror_pairs, double symmetry_weight)
      : base_(control.positions), start_(control.positions), sets_(sets), binding_(binding_edges),
        binding_weight_(binding_weight), mirror_(mirror_pairs), symmetry_weight_(symmetry_weight) {
    if (!(symmetry_weight_ > 0)) mirror_ = {};
    scales_.assign(sets_.size(), 1.0);
    for (const auto& e : binding_)
      rest_.push_back(control.positions[size_t(e[0])] - control.positions[size_t(e[1])]);
  }

  double tether = 1e-4, follow = 0, follow_observed = 0;
  std::vector<double> scales_;

  // Starts a level from the current shape: its displacements at zero.
  void set_level(const ControlLevel& level) {
    base_ = positions();
    level_ = &level;
    nodes_.clear();
    for (int v : level.nodes) nodes_.push_back(base_[size_t(v)]);
    num_delta_ = 3 * level.num_nodes();
    // The follow term's weight per node: follow_observed where a vertex of
    // the node's cell is observed, 1 elsewhere, smoothed.
    weights_.clear();
    if (follow > 0) {
      const std::vector<bool> seen = observed_vertices(sets_, base_);
      std::vector<bool> seen_node(size_t(level.num_nodes()), false);
      for (size_t v = 0; v < seen.size(); ++v)
        if (seen[v]) seen_node[size_t(level.cell[v])] = true;
      weights_ = follow_node_weights(seen_node, level.laplacian, follow_observed);
    }
    delta_ = Eigen::VectorXd::Zero(num_delta_ + regularizer_extra_parameters(follow));
    set_stiffness(stiffness_);
  }
  void set_stiffness(double k) {
    stiffness_ = k;
    if (level_) R_ = regularizer_matrix(nodes_, level_->laplacian, stiffness_, tether, follow, weights_);
  }

  std::vector<Vec3> positions(const Eigen::VectorXd& state) const {
    return level_ ? attached_positions(*level_, base_, state.head(num_delta_)) : base_;
  }
  std::vector<Vec3> positions() const { return positions(delta_); }

  int num_parameters() const override { return int(delta_.size()); }
  // The nodes' displacements alone (no similarity's parameters: follow off).
  bool vertex_blocks() const override { return num_parameters() == num_delta_; }
  int observation_rows() const {
    int n = 3 * int(binding_.size() + mirror_.size());
    for (const auto& s : sets_) n += s->num_residuals();
    return n;
  }

  void normalize(const std::vector<double>& lambdas) { scales_ = observation_type_weights(positions(), sets_, lambdas); }

  bool residuals(const Eigen::VectorXd& delta, Eigen::VectorXd& r, std::vector<Eigen::Triplet<double>>* trip) const {
    const std::vector<Vec3> p = positions(delta);
    const int nobs = observation_rows();
    r.setZero(nobs + R_.rows());
    int row = 0;
    std::vector<Eigen::Triplet<double>> over_vertices;  // observation rows by 3 #V
    for (size_t k = 0; k < sets_.size(); ++k) {
      std::vector<Eigen::Triplet<double>> local;
      Eigen::VectorXd rk(sets_[k]->num_residuals());
      if (!sets_[k]->evaluate(p, rk, 0, trip ? &local : nullptr)) return false;
      r.segment(row, rk.size()) = scales_[k] * rk;
      for (const auto& t : local) over_vertices.emplace_back(row + t.row(), t.col(), scales_[k] * t.value());
      row += int(rk.size());
    }
    const double sb = std::sqrt(binding_weight_);
    for (size_t e = 0; e < binding_.size(); ++e) {
      const int a = binding_[e][0], b = binding_[e][1];
      r.segment<3>(row) = sb * ((p[size_t(a)] - p[size_t(b)]) - rest_[e]);
      for (int j = 0; j < 3; ++j) {
        over_vertices.emplace_back(row + j, 3 * a + j, sb);
        over_vertices.emplace_back(row + j, 3 * b + j, -sb);
      }
      row += 3;
    }
    if (!mirror_.empty()) {
      Eigen::VectorXd rs;
      std::vector<Eigen::Triplet<double>> js;
      symmetry_residuals(start_, p, mirror_, symmetry_weight_, rs, trip ? &js : nullptr);
      r.segment(row, rs.size()) = rs;
      for (const auto& t : js) over_vertices.emplace_back(row + t.row(), t.col(), t.value());
      row += int(rs.size());
    }
    if (trip) {
      if (level_->identity) {
        trip->insert(trip->end(), over_vertices.begin(), over_vertices.end());
      } else {
        SparseMat Jv(nobs, 3 * long(p.size()));
        Jv.setFromTriplets(over_vertices.begin(), over_vertices.end());
        const SparseMat Jd = attach_jacobian(*level_, Jv);
        for (int k = 0; k < Jd.outerSize(); ++k)
          for (SparseMat::InnerIterator it(Jd, k); it; ++it) trip->emplace_back(int(it.row()), int(it.col()), it.value());
      }
    }
    r.segment(row, R_.rows()) = R_ * delta;
    if (trip)
      for (int k = 0; k < R_.outerSize(); ++k)
        for (SparseMat::InnerIterator it(R_, k); it; ++it)
          trip->emplace_back(row + int(it.row()), int(it.col()), it.value());
    return true;
  }

  void linearize(Eigen::VectorXd& r, SparseMat& J) override {
    std::vector<Eigen::Triplet<double>> trip;
    residuals(delta_, r, &trip);  // the current state is valid: LM only accepts valid states
    J.resize(r.size(), num_parameters());
    J.setFromTriplets(trip.begin(), trip.end());
  }
  double cost_after(const Eigen::VectorXd& step) override {
    Eigen::VectorXd r;
    if (!residuals(delta_ + step, r, nullptr)) return std::numeric_limits<double>::infinity();
    return r.squaredNorm();
  }
  void apply(const Eigen::VectorXd& step) override { delta_ += step; }

 private:
  std::vector<Vec3> base_;
  std::vector<Vec3> start_;  // the control mesh given to the fit (the symmetry's reference)
  std::vector<std::unique_ptr<ObservationSet>>& sets_;
  const std::vector<std::array<int, 2>>& binding_;
  double binding_weight_;
  std::vector<std::array<int, 2>> mirror_;
  double symmetry_weight_;
  std::vector<Vec3> rest_;  // each binding edge's x_a - x_b on the start shape
  const ControlLevel* level_ = nullptr;
  std::vector<Vec3> nodes_;  // the level's nodes on its start shape
  std::vector<double> weights_;  // the follow term's per node
  int num_delta_ = 0;
  double stiffness_ = 1;
  Eigen::VectorXd delta_;    // the state: node displacements, then the similarity
  SparseMat R_;              // the regularizer's rows (regularizer_matrix)
};

double feature_rms(const std::vector<std::unique_ptr<ObservationSet>>& sets, const std::vector<Vec3>& p) {
  std::vector<double> e;
  for (const auto& s : sets) s->inlier_pixel_errors(p, e);
  double sum = 0;
  for (double x : e) sum += x * x;
  return e.empty() ? 0 : std::sqrt(sum / double(e.size()));
}

}  // namespace

Status fit_shape(const TriMesh& control, std::vector<std::unique_ptr<ObservationSet>>& sets,
                 const std::vector<double>& lambdas, const ShapeFitOptions& options, ShapeFitResult& result) {
  result = {};
  if (lambdas.size() != sets.size())
    return Status::error(ErrorCode::InvalidInput, "shape fit: one lambda per observation type needed");
  for (double l : lambdas)
    if (!(l >= 0) || !std::isfinite(l)) return Status::error(ErrorCode::InvalidInput, "shape fit: lambda out of range");
  if ((options.stiffness_schedule.empty() && options.coarse_levels.empty()) || !(options.tether > 0) ||
      options.reweighting_rounds < 1)
    return Status::error(ErrorCode::InvalidInput, "shape fit: an option is out of range");
  for (double s : options.stiffness_schedule)
    if (!(s > 0) || !std::isfinite(s)) return Status::error(ErrorCode::InvalidInput, "shape fit: stiffness must be > 0");
  for (const ShapeFitOptions::CoarseLevel& c : options.coarse_levels)
    if (!(c.stiffness > 0) || !std::isfinite(c.stiffness) || c.nodes < 4)
      return Status::error(ErrorCode::InvalidInput, "shape fit: a coarse level needs >= 4 nodes and a stiffness > 0");
  if (!(options.follow >= 0) || !std::isfinite(options.follow) || !(options.follow_observed >= 0) ||
      !std::isfinite(options.follow_observed))
    return Status::error(ErrorCode::InvalidInput, "shape fit: follow must be >= 0");
  if (control.num_vertices() == 0) return Status::error(ErrorCode::InvalidInput, "shape fit: empty control mesh");
  if (!(options.binding_weight >= 0) || !std::isfinite(options.binding_weight))
    return Status::error(ErrorCode::InvalidInput, "shape fit: the binding weight must be >= 0");
  for (const auto& e : options.binding_edges)
    if (e[0] < 0 || e[1] < 0 || e[0] >= control.num_vertices() || e[1] >= control.num_vertices() || e[0] == e[1])
      return Status::error(ErrorCode::InvalidInput, "shape fit: a binding edge names a vertex the mesh does not have");
  if (!(options.symmetry_weight >= 0) || !std::isfinite(options.symmetry_weight))
    return Status::error(ErrorCode::InvalidInput, "shape fit: the symmetry weight must be >= 0");
  if (options.symmetry_weight > 0 && options.mirror_pairs.empty())
    return Status::error(ErrorCode::InvalidInput, "shape fit: a symmetry weight without mirror pairs");
  for (const auto& e : options.mirror_pairs)
    if (e[0] < 0 || e[1] < 0 || e[0] >= control.num_vertices() || e[1] >= control.num_vertices())
      return Status::error(ErrorCode::InvalidInput, "shape fit: a mirror pair names a vertex the mesh does not have");
  // The levels, coarse to fine: each coarse one, then the control mesh for the schedule.
  std::vector<ControlLevel> levels(options.coarse_levels.size() + (options.stiffness_schedule.empty() ? 0 : 1));
  struct Stage {
    size_t level;
    double stiffness;
  };
  std::vector<Stage> stages;
  for (size_t i = 0; i < options.coarse_levels.size(); ++i) {
    Status s = build_control_level(control, options.coarse_levels[i].nodes, levels[i]);
    if (!s) return with_context(s, "shape fit");
    stages.push_back({i, options.coarse_levels[i].stiffness});
  }
  if (!options.stiffness_schedule.empty()) {
    Status s = build_control_level(control, control.num_vertices(), levels.back());
    if (!s) return with_context(s, "shape fit");
    for (double k : options.stiffness_schedule) stages.push_back({levels.size() - 1, k});
  }
  ShapeProblem problem(control, sets, options.binding_edges, options.binding_weight, options.mirror_pairs,
                       options.symmetry_weight);
  problem.tether = options.tether;
  problem.follow = options.follow;
  problem.follow_observed = options.follow_observed;
  problem.set_level(levels[0]);
  {
    Eigen::VectorXd r;
    if (!problem.residuals(Eigen::VectorXd::Zero(problem.num_parameters()), r, nullptr))
      return Status::error(ErrorCode::InvalidInput, "shape fit: a feature lies behind its camera on the start shape");
  }
  result.initial_rms_px = feature_rms(sets, problem.positions());
  for (size_t si = 0; si < stages.size(); ++si) {
    if (si > 0 && stages[si].level != stages[si - 1].level) problem.set_level(levels[stages[si].level]);
    ShapeFitStage stage;
    stage.nodes = levels[stages[si].level].num_nodes();
    stage.stiffness = stages[si].stiffness;
    problem.set_stiffness(stages[si].stiffness);
    for (int round = 0; round < options.reweighting_rounds; ++round) {
      if (round > 0 || si > 0)
        for (auto& s : sets) s->reweight(problem.positions());
      problem.normalize(lambdas);
      LmReport rep;
      if (options.optimizer == ShapeFitOptions::Optimizer::LevenbergMarquardt) {
        LmOptions lo;
        lo.max_iterations = options.max_lm_iterations;
        lo.relative_tolerance = options.relative_tolerance;
        rep = levenberg_marquardt(problem, lo);
      } else {
        DescentOptions d;
        d.max_iterations = options.max_descent_iterations;
        d.relative_tolerance = options.relative_tolerance;
        rep = options.optimizer == ShapeFitOptions::Optimizer::GradientDescent ? gradient_descent(problem, d)
                                                                               : quasi_newton(problem, d);
      }
      if (round == 0) stage.initial_cost = rep.initial_cost;
      stage.final_cost = rep.final_cost;
      stage.lm_iterations += rep.iterations;
    }
    result.stages.push_back(stage);
  }
  result.mesh = control;
  result.mesh.positions = problem.positions();
  result.mesh.normals.clear();
  result.final_rms_px = feature_rms(sets, result.mesh.positions);
  return Status::success();
}

}  // namespace lk
