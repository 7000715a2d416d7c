#include "texture/register.h"

#include "common/rotation.h"
#include "texture/color.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <string>

namespace lk {
namespace {

constexpr int kPoseGain = 8;  // omega (3), dt (3), a, b

// Separable Gaussian blur of a 1-channel float image, borders clamped.
void blur(ImageF& image, double sigma) {
  if (sigma <= 0) return;
  const int r = std::max(1, static_cast<int>(std::ceil(3 * sigma)));
  std::vector<float> k(2 * r + 1);
  float sum = 0;
  for (int i = -r; i <= r; ++i) sum += k[i + r] = static_cast<float>(std::exp(-0.5 * i * i / (sigma * sigma)));
  for (float& v : k) v /= sum;
  const int w = image.width, h = image.height;
  std::vector<float> tmp(image.pixels.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float acc = 0;
      for (int i = -r; i <= r; ++i) acc += k[i + r] * image.pixels[static_cast<size_t>(y) * w + std::clamp(x + i, 0, w - 1)];
      tmp[static_cast<size_t>(y) * w + x] = acc;
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float acc = 0;
      for (int i = -r; i <= r; ++i) acc += k[i + r] * tmp[static_cast<size_t>(std::clamp(y + i, 0, h - 1)) * w + x];
      image.pixels[static_cast<size_t>(y) * w + x] = acc;
    }
}

ImageF halve(const ImageF& im) {
  ImageF out = ImageF::make(std::max(1, im.width / 2), std::max(1, im.height / 2), 1);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      const int x0 = std::min(2 * x, im.width - 1), x1 = std::min(2 * x + 1, im.width - 1);
      const int y0 = std::min(2 * y, im.height - 1), y1 = std::min(2 * y + 1, im.height - 1);
      out.pixels[static_cast<size_t>(y) * out.width + x] =
          0.25f * (*im.at(x0, y0) + *im.at(x1, y0) + *im.at(x0, y1) + *im.at(x1, y1));
    }
  return out;
}

// Bilinear value and exact gradient of the interpolant at pixel position
// (u, v) (centres at integer + 0.5). False outside the image's inner part.
bool sample_gradient(const ImageF& g, double u, double v, double& value, Vec2& gradient) {
  const double x = u - 0.5, y = v - 0.5;
  if (!(x >= 0 && y >= 0 && x < g.width - 1 && y < g.height - 1)) return false;
  const int ix = static_cast<int>(x), iy = static_cast<int>(y);
  const double fx = x - ix, fy = y - iy;
  const double g00 = *g.at(ix, iy), g10 = *g.at(ix + 1, iy), g01 = *g.at(ix, iy + 1), g11 = *g.at(ix + 1, iy + 1);
  value = (1 - fy) * ((1 - fx) * g00 + fx * g10) + fy * ((1 - fx) * g01 + fx * g11);
  gradient = Vec2((1 - fy) * (g10 - g00) + fy * (g11 - g01), (1 - fx) * (g01 - g00) + fx * (g11 - g10));
  return true;
}

// Lattice cell of p: the four node indices and weights, and d(weights)/dp.
struct Cell {
  int node[4] = {0, 0, 0, 0};
  double weight[4] = {0, 0, 0, 0};
  double dwx[4] = {0, 0, 0, 0}, dwy[4] = {0, 0, 0, 0};
};

Cell lattice_cell(const PhotoRegistration& reg, const Vec2& p) {
  Cell c;
  const int K = reg.nodes;
  const double sx = static_cast<double>(reg.camera.width) / (K - 1), sy = static_cast<double>(reg.camera.height) / (K - 1);
  double gx = p.x() / sx, gy = p.y() / sy;
  const bool inside_x = gx >= 0 && gx <= K - 1, inside_y = gy >= 0 && gy <= K - 1;
  gx = std::clamp(gx, 0.0, K - 1 - 1e-9);
  gy = std::clamp(gy, 0.0, K - 1 - 1e-9);
  const int ix = static_cast<int>(gx), iy = static_cast<int>(gy);
  const double fx = gx - ix, fy = gy - iy;
  c.node[0] = iy * K + ix;
  c.node[1] = iy * K + ix + 1;
  c.node[2] = (iy + 1) * K + ix;
  c.node[3] = (iy + 1) * K + ix + 1;
  c.weight[0] = (1 - fx) * (1 - fy);
  c.weight[1] = fx * (1 - fy);
  c.weight[2] = (1 - fx) * fy;
  c.weight[3] = fx * fy;
  if (inside_x) {
    c.dwx[0] = -(1 - fy) / sx; c.dwx[1] = (1 - fy) / sx; c.dwx[2] = -fy / sx; c.dwx[3] = fy / sx;
  }
  if (inside_y) {
    c.dwy[0] = -(1 - fx) / sy; c.dwy[1] = -fx / sy; c.dwy[2] = (1 - fx) / sy; c.dwy[3] = fx / sy;
  }
  return c;
}

// Residual a G(q) + b - C at the level's scale (pixel positions divided by
// `scale`) and its sparse Jacobian row: the 8 pose/gain entries, then up to 8
// field entries (index into the parameter vector, value).
struct Row {
  double r = 0;
  int n = 0;
  int index[kPoseGain + 8];
  double value[kPoseGain + 8];
};

// Projection p of X, its camera-frame point xc and dp/dxc. False behind the camera.
bool project_with_jacobian(const Camera& cam, const Vec3& X, Vec2& p, Vec3& xc, Eigen::Matrix<double, 2, 3>& dp_dxc) {
  xc = cam.to_camera(X);
  if (xc.z() <= 1e-12) return false;
  const double x = xc.x() / xc.z(), y = xc.y() / xc.z();
  const double r2 = x * x + y * y, d = 1 + cam.k1 * r2 + cam.k2 * r2 * r2;
  const double dd = 2 * (cam.k1 + 2 * cam.k2 * r2);  // d(d)/dx = dd * x
  p = Vec2(cam.fx * d * x + cam.cx, cam.fy * d * y + cam.cy);
  Eigen::Matrix2d dp_dxy;
  dp_dxy << cam.fx * (d + dd * x * x), cam.fx * dd * x * y, cam.fy * dd * x * y, cam.fy * (d + dd * y * y);
  Eigen::Matrix<double, 2, 3> dxy_dxc;
  dxy_dxc << 1 / xc.z(), 0, -x / xc.z(), 0, 1 / xc.z(), -y / xc.z();
  dp_dxc = dp_dxy * dxy_dxc;
  return true;
}

bool residual_row(const ImageF& g, double scale, const PhotoRegistration& reg, const Vec3& X, double consensus,
                  Row& row) {
  Vec2 p;
  Vec3 xc;
  Eigen::Matrix<double, 2, 3> dp_dxc;
  if (!project_with_jacobian(reg.camera, X, p, xc, dp_dxc)) return false;
  Vec2 q = p;
  Eigen::Matrix2d dq_dp = Eigen::Matrix2d::Identity();
  Cell cell;
  if (reg.nodes >= 2) {
    cell = lattice_cell(reg, p);
    for (int k = 0; k < 4; ++k) {
      const Vec2& f = reg.field[cell.node[k]];
      q += cell.weight[k] * f;
      dq_dp(0, 0) += cell.dwx[k] * f.x();
      dq_dp(0, 1) += cell.dwy[k] * f.x();
      dq_dp(1, 0) += cell.dwx[k] * f.y();
      dq_dp(1, 1) += cell.dwy[k] * f.y();
    }
  }
  double value;
  Vec2 grad;
  if (!sample_gradient(g, q.x() / scale, q.y() / scale, value, grad)) return false;
  grad /= scale;
  row.r = reg.gain * value + reg.bias - consensus;
  const Eigen::RowVector2d ag = reg.gain * grad.transpose();
  const Eigen::RowVector3d dr_dxc = ag * dq_dp * dp_dxc;
  const Eigen::RowVector3d dr_domega = -dr_dxc * skew(xc);  // d(omega x xc) = -[xc]x d(omega)
  row.n = 0;
  for (int j = 0; j < 3; ++j) { row.index[row.n] = j; row.value[row.n++] = dr_domega(j); }
  for (int j = 0; j < 3; ++j) { row.index[row.n] = 3 + j; row.value[row.n++] = dr_dxc(j); }
  row.index[row.n] = 6; row.value[row.n++] = value;
  row.index[row.n] = 7; row.value[row.n++] = 1.0;
  if (reg.nodes >= 2)
    for (int k = 0; k < 4; ++k) {
      if (cell.weight[k] == 0) continue;
      row.index[row.n] = kPoseGain + 2 * cell.node[k]; row.value[row.n++] = ag(0) * cell.weight[k];
      row.index[row.n] = kPoseGain + 2 * cell.node[k] + 1; row.value[row.n++] = ag(1) * cell.weight[k];
    }
  return true;
}

struct Level {
  std::vector<ImageF> images;  // #P luminance at this level
  double scale = 1;            // level pixel = scale photo pixels
};

}  // namespace

ImageF photo_luminance(const Image& image, double sigma_px) {
  ImageF g = ImageF::make(image.width, image.height, 1);
  const int c = image.channels;
  for (size_t p = 0; p < g.pixels.size(); ++p) {
    const std::uint8_t* px = &image.pixels[p * c];
    g.pixels[p] = c >= 3 ? 0.2126f * srgb8_to_linear(px[0]) + 0.7152f * srgb8_to_linear(px[1]) +
                               0.0722f * srgb8_to_linear(px[2])
                         : srgb8_to_linear(px[0]);
  }
  blur(g, sigma_px);
  return g;
}

Vec2 field_offset(const PhotoRegistration& reg, const Vec2& p) {
  if (reg.nodes < 2) return Vec2::Zero();
  const Cell c = lattice_cell(reg, p);
  Vec2 f = Vec2::Zero();
  for (int k = 0; k < 4; ++k) f += c.weight[k] * reg.field[c.node[k]];
  return f;
}

bool registered_project(const PhotoRegistration& reg, const Vec3& X, Vec2& q) {
  Vec2 p;
  if (!reg.camera.project(X, p)) return false;
  q = p + field_offset(reg, p);
  return true;
}

void apply_registration(const PhotoRegistration& reg, TexturePhoto& photo) {
  photo.camera = reg.camera;
  if (reg.nodes < 2 || reg.field_max_px == 0) return;
  const Image& src = photo.image;
  Image out = Image::make(src.width, src.height, src.channels);
  const int c = src.channels;
  for (int y = 0; y < src.height; ++y)
    for (int x = 0; x < src.width; ++x) {
      const Vec2 p(x + 0.5, y + 0.5);
      const Vec2 q = p + field_offset(reg, p);
      const double sx = std::clamp(q.x() - 0.5, 0.0, src.width - 1.0), sy = std::clamp(q.y() - 0.5, 0.0, src.height - 1.0);
      const int ix = std::min(static_cast<int>(sx), src.width - 2 < 0 ? 0 : src.width - 2);
      const int iy = std::min(static_cast<int>(sy), src.height - 2 < 0 ? 0 : src.height - 2);
      const int jx = std::min(ix + 1, src.width - 1), jy = std::min(iy + 1, src.height - 1);
      const double fx = sx - ix, fy = sy - iy;
      for (int k = 0; k < c; ++k) {
        const double v = (1 - fy) * ((1 - fx) * src.at(ix, iy)[k] + fx * src.at(jx, iy)[k]) +
                         fy * ((1 - fx) * src.at(ix, jy)[k] + fx * src.at(jx, jy)[k]);
        out.at(x, y)[k] = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
      }
    }
  photo.image = std::move(out);
}

bool photometric_residual(const ImageF& luminance, const PhotoRegistration& reg, const Vec3& X, double consensus,
                          double& residual, std::vector<double>& jacobian) {
  Row row;
  if (!residual_row(luminance, 1.0, reg, X, consensus, row)) return false;
  residual = row.r;
  jacobian.assign(kPoseGain + 2 * std::max(0, reg.nodes) * std::max(0, reg.nodes), 0.0);
  for (int j = 0; j < row.n; ++j) jacobian[row.index[j]] += row.value[j];
  return true;
}

Status register_photos(const TriMesh& mesh, const std::vector<Vec3>& normals, const VertexBinding& binding,
                       const std::vector<TexturePhoto>& photos, const RegisterOptions& options,
                       RegisterReport& report) {
  const int np = static_cast<int>(photos.size()), nv = mesh.num_vertices();
  if (binding.num_photos != np || static_cast<int>(binding.valid.size()) != nv ||
      static_cast<int>(normals.size()) != nv)
    return Status::error(ErrorCode::InvalidInput, "registration: binding, normals and photos do not match the mesh");
  if (options.field_nodes == 1 || options.field_nodes > 32 || options.levels < 1 || options.iterations < 0)
    return Status::error(ErrorCode::InvalidInput, "registration: field nodes must be 0 or 2..32, levels >= 1");
  report = RegisterReport();
  report.photos.resize(np);
  const int K = options.field_nodes;
  for (int i = 0; i < np; ++i) {
    PhotoRegistration& reg = report.photos[i];
    reg.camera = photos[i].camera;
    reg.nodes = K;
    reg.field.assign(static_cast<size_t>(K) * K, Vec2::Zero());
  }
  if (np < 2) return Status::error(ErrorCode::Empty, "registration needs two photos or more");

  // Vertices seen twice or more, an even stride down to max_vertices.
  // Which photos take part at each vertex: valid and facing enough.
  std::vector<std::uint64_t> takes(nv, 0);
  for (int v = 0; v < nv; ++v)
    for (int i = 0; i < np; ++i)
      if (binding.is_valid(v, i) && binding.facing[static_cast<size_t>(v) * np + i] >= options.min_facing)
        takes[v] |= std::uint64_t(1) << i;
  auto part = [&](int v, int i) { return ((takes[v] >> i) & 1u) != 0; };
  std::vector<int> used;
  for (int v = 0; v < nv; ++v)
    if (takes[v] & (takes[v] - 1)) used.push_back(v);
  if (used.empty()) return Status::error(ErrorCode::Empty, "no vertex is seen by two photos");
  if (options.max_vertices > 0 && static_cast<int>(used.size()) > options.max_vertices) {
    std::vector<int> picked;
    const double step = static_cast<double>(used.size()) / options.max_vertices;
    for (int k = 0; k < options.max_vertices; ++k) picked.push_back(used[static_cast<size_t>(k * step)]);
    used.swap(picked);
  }
  report.vertices = static_cast<int>(used.size());
  // The reference: the photo that sees the shared vertices most squarely
  // (largest summed <N, V> over them; the frontal photo for a face).
  std::vector<double> facing_sum(np, 0.0);
  for (int v : used)
    for (int i = 0; i < np; ++i) facing_sum[i] += binding.facing[static_cast<size_t>(v) * np + i];
  report.reference = options.reference >= 0 && options.reference < np
                         ? options.reference
                         : static_cast<int>(std::max_element(facing_sum.begin(), facing_sum.end()) - facing_sum.begin());

  // The luminance pyramids (finest first).
  std::vector<Level> levels(options.levels);
  {
    std::vector<ImageF> current(np);
    for (int i = 0; i < np; ++i) current[i] = photo_luminance(photos[i].image, 0.0);
    for (int l = 0; l < options.levels; ++l) {
      if (l > 0)
        for (ImageF& im : current) im = halve(im);
      levels[l].scale = std::pow(2.0, l);
      levels[l].images = current;
      // The finest level unblurred: a blur smears a foreshortened view over
      // more surface than a frontal one, which biased the optimum by ~1 px
      // with true cameras (tests/texture/test_register.cpp).
      if (l > 0)
        for (ImageF& im : levels[l].images) blur(im, options.blur_px);
    }
  }

  const int nparam = kPoseGain + 2 * K * K;
  auto weight = [&](int v, int i) { return static_cast<double>(binding.facing[static_cast<size_t>(v) * np + i]); };
  // Consensus as leave-one-out means: photo i is compared with the other
  // photos' weighted mean C_-i(v), not with a mean that contains itself
  // (which halves every step with two photos and lets the pair settle on a
  // blurred average). Each photo's samples are refreshed after its step
  // (Gauss-Seidel), so later photos see the moved one.
  std::vector<double> own(used.size() * np, 0.0), sum_all(used.size(), 0.0), w_all(used.size(), 0.0);
  std::vector<char> has(used.size() * np, 0);
  auto refresh_photo = [&](const Level& level, int i) {
    for (size_t k = 0; k < used.size(); ++k) {
      const int v = used[k];
      const size_t j = k * np + i;
      if (has[j]) {
        sum_all[k] -= weight(v, i) * own[j];
        w_all[k] -= weight(v, i);
        has[j] = 0;
      }
      if (!part(v, i)) continue;
      Row row;
      if (!residual_row(level.images[i], level.scale, report.photos[i], mesh.positions[v], 0.0, row)) continue;
      own[j] = row.r;
      has[j] = 1;
      sum_all[k] += weight(v, i) * row.r;
      w_all[k] += weight(v, i);
    }
  };
  auto update_consensus = [&](const Level& level) {
    std::fill(sum_all.begin(), sum_all.end(), 0.0);
    std::fill(w_all.begin(), w_all.end(), 0.0);
    std::fill(has.begin(), has.end(), 0);
    for (int i = 0; i < np; ++i) refresh_photo(level, i);
  };
  // C_-i(v), or -1 when no other photo sampled the vertex.
  auto others = [&](size_t k, int i) {
    const size_t j = k * np + i;
    const double w = w_all[k] - (has[j] ? weight(used[k], i) : 0.0);
    if (w <= 1e-9) return -1.0;
    return (sum_all[k] - (has[j] ? weight(used[k], i) * own[j] : 0.0)) / w;
  };
  // Calls fn(weight, row) for each residual of photo i (with `reg`) against C_-i.
  auto for_each_residual = [&](const Level& level, int i, const PhotoRegistration& reg, const auto& fn) {
    for (size_t k = 0; k < used.size(); ++k) {
      const int v = used[k];
      const double c = others(k, i);
      if (c < 0 || !part(v, i)) continue;
      Row row;
      if (residual_row(level.images[i], level.scale, reg, mesh.positions[v], c, row)) fn(weight(v, i), row);
    }
  };
  // One photo's weighted photometric cost (and residual count) given C.
  auto photo_cost = [&](const Level& level, int i, const PhotoRegistration& reg, long* count) {
    double cost = 0;
    long n = 0;
    for_each_residual(level, i, reg, [&](double w, const Row& row) {
      cost += w * row.r * row.r;
      ++n;
    });
    if (count) *count = n;
    return cost;
  };
  auto field_cost = [&](const PhotoRegistration& reg, double s) {
    double e = 0;
    for (int y = 0; y < K; ++y)
      for (int x = 0; x < K; ++x) {
        const Vec2& f = reg.field[y * K + x];
        e += options.field_weight * f.squaredNorm();
        if (x + 1 < K) e += options.field_smoothness * (f - reg.field[y * K + x + 1]).squaredNorm();
        if (y + 1 < K) e += options.field_smoothness * (f - reg.field[(y + 1) * K + x]).squaredNorm();
      }
    return s * e;
  };
  auto rms_all = [&](const Level& level, std::vector<double>& per_photo, std::vector<int>& counts) {
    update_consensus(level);
    double sum = 0;
    long n = 0;
    per_photo.assign(np, 0.0);
    counts.assign(np, 0);
    for (int i = 0; i < np; ++i) {
      long m = 0;
      double e = 0;
      for_each_residual(level, i, report.photos[i], [&](double, const Row& row) {
        e += row.r * row.r;
        ++m;
      });
      per_photo[i] = m ? std::sqrt(e / m) : 0.0;
      counts[i] = static_cast<int>(m);
      sum += e;
      n += m;
    }
    return n ? std::sqrt(sum / n) : 0.0;
  };
  std::vector<double> per_photo;
  std::vector<int> counts;
  report.rms_before = rms_all(levels[0], per_photo, counts);
  for (int i = 0; i < np; ++i) {
    report.photos[i].rms_before = per_photo[i];
    report.photos[i].vertices = counts[i];
  }

  // The pose prior: the mean squared image motion of the photo's vertices,
  // theta^T P theta with P = mean of J^T J (J = dp/d(omega, dt) at the
  // starting pose), weighted so that pose_prior_px of motion costs as much
  // as a residual of 0.01 per vertex. Without it, on real photos (hair and
  // background that the head mesh does not have, a surface cm off) the
  // photometric cost has minima several degrees away.
  std::vector<Eigen::Matrix<double, 6, 6>> prior(np, Eigen::Matrix<double, 6, 6>::Zero());
  std::vector<Eigen::Matrix<double, 6, 1>> theta(np, Eigen::Matrix<double, 6, 1>::Zero());
  for (int i = 0; i < np; ++i) {
    double wsum = 0;
    for (int v : used) {
      if (!part(v, i)) continue;
      Vec2 p;
      Vec3 xc;
      Eigen::Matrix<double, 2, 3> dp_dxc;
      if (!project_with_jacobian(photos[i].camera, mesh.positions[v], p, xc, dp_dxc)) continue;
      Eigen::Matrix<double, 2, 6> J;
      J.leftCols<3>() = -dp_dxc * skew(xc);
      J.rightCols<3>() = dp_dxc;
      prior[i] += weight(v, i) * J.transpose() * J;
      wsum += weight(v, i);
    }
    if (wsum > 0) prior[i] /= wsum;
    // Its diagonal only: the full matrix is nearly singular along the trade
    // of a turn against a sideways move (no image motion), and the pose
    // wandered along it (5.8 deg in tests/texture/test_register.cpp).
    prior[i] = Eigen::Matrix<double, 6, 6>(prior[i].diagonal().asDiagonal());
  }
  const double prior_scale =
      options.pose_prior_px > 0 ? 1e-4 / (options.pose_prior_px * options.pose_prior_px) : 0.0;
  std::vector<double> damping(np, 1e-3);
  for (int l = options.levels - 1; l >= 0; --l) {
    const Level& level = levels[l];
    for (int it = 0; it < options.iterations; ++it) {
      update_consensus(level);
      for (int i = 0; i < np; ++i) {
        if (i == report.reference) continue;
        PhotoRegistration& reg = report.photos[i];
        // The gain in closed form (weighted means of the photo and of the
        // others agree), not by Gauss-Newton: a free gain and bias let a
        // photo flatten itself towards the others' mean (a -> 0), which on
        // Kira "won" with gains of 0.25-0.45 and cameras thrown 3-14 deg.
        {
          double sum_c = 0, sum_g = 0;
          for (size_t k = 0; k < used.size(); ++k) {
            const size_t j = k * np + i;
            const double c = others(k, i);
            if (c < 0 || !has[j]) continue;
            sum_c += weight(used[k], i) * c;
            sum_g += weight(used[k], i) * (own[j] - reg.bias) / reg.gain;
          }
          if (sum_g > 1e-9 && sum_c > 1e-9) {
            reg.gain = sum_c / sum_g;
            reg.bias = 0;
            refresh_photo(level, i);
          }
        }
        Eigen::MatrixXd H = Eigen::MatrixXd::Zero(nparam, nparam);
        Eigen::VectorXd b = Eigen::VectorXd::Zero(nparam);
        double cost = 0;
        long n = 0;
        for_each_residual(level, i, reg, [&](double w, const Row& row) {
          cost += w * row.r * row.r;
          ++n;
          for (int a = 0; a < row.n; ++a) {
            b(row.index[a]) += w * row.value[a] * row.r;
            for (int e = 0; e < row.n; ++e) H(row.index[a], row.index[e]) += w * row.value[a] * row.value[e];
          }
        });
        if (n < nparam) continue;  // too little overlap to move this photo
        // The field's regulariser (Gauss-Newton of a quadratic: exact).
        const double s = static_cast<double>(n) / std::max(1, K * K);
        cost += field_cost(reg, s);
        for (int y = 0; y < K; ++y)
          for (int x = 0; x < K; ++x) {
            const int a = y * K + x;
            for (int d = 0; d < 2; ++d) {
              const int ia = kPoseGain + 2 * a + d;
              H(ia, ia) += s * options.field_weight;
              b(ia) += s * options.field_weight * reg.field[a][d];
            }
            for (const int nb : {x + 1 < K ? a + 1 : -1, y + 1 < K ? a + K : -1}) {
              if (nb < 0) continue;
              for (int d = 0; d < 2; ++d) {
                const int ia = kPoseGain + 2 * a + d, ib = kPoseGain + 2 * nb + d;
                const double diff = reg.field[a][d] - reg.field[nb][d];
                H(ia, ia) += s * options.field_smoothness;
                H(ib, ib) += s * options.field_smoothness;
                H(ia, ib) -= s * options.field_smoothness;
                H(ib, ia) -= s * options.field_smoothness;
                b(ia) += s * options.field_smoothness * diff;
                b(ib) -= s * options.field_smoothness * diff;
              }
            }
          }
        const double sp = prior_scale * n;
        H.topLeftCorner<6, 6>() += sp * prior[i];
        b.head<6>() += sp * prior[i] * theta[i];
        cost += sp * theta[i].dot(prior[i] * theta[i]);
        for (int j = options.refine_pose ? 6 : 0; j < kPoseGain; ++j) {  // gain and bias (and pose) held
          H.row(j).setZero();
          H.col(j).setZero();
          H(j, j) = 1;
          b(j) = 0;
        }
        // Levenberg-Marquardt on this photo with C fixed: accept a step only
        // when it lowers the photo's cost.
        for (int attempt = 0; attempt < 6; ++attempt) {
          Eigen::MatrixXd A = H;
          for (int j = 0; j < nparam; ++j) A(j, j) += damping[i] * H(j, j) + 1e-12;
          const Eigen::VectorXd delta = A.ldlt().solve(-b);
          if (!delta.allFinite()) break;
          PhotoRegistration trial = reg;
          const Mat3 dR = rotation_from_vector(delta.segment<3>(0));
          trial.camera.R = dR * reg.camera.R;
          trial.camera.t = dR * reg.camera.t + delta.segment<3>(3);
          trial.gain += delta(6);
          trial.bias += delta(7);
          for (int a = 0; a < K * K; ++a) trial.field[a] += Vec2(delta(kPoseGain + 2 * a), delta(kPoseGain + 2 * a + 1));
          long m = 0;
          const Eigen::Matrix<double, 6, 1> trial_theta = theta[i] + delta.head<6>();
          const double trial_cost = photo_cost(level, i, trial, &m) + field_cost(trial, s) +
                                    sp * trial_theta.dot(prior[i] * trial_theta);
          if (m >= n * 0.95 && trial_cost < cost) {
            reg = std::move(trial);
            theta[i] = trial_theta;
            damping[i] = std::max(1e-6, damping[i] * 0.3);
            refresh_photo(level, i);
            break;
          }
          damping[i] *= 10;
        }
      }
    }
  }

  report.rms_after = rms_all(levels[0], per_photo, counts);
  for (int i = 0; i < np; ++i) {
    PhotoRegistration& reg = report.photos[i];
    reg.rms_after = per_photo[i];
    const Eigen::AngleAxisd turn(reg.camera.R * photos[i].camera.R.transpose());
    reg.rotation_deg = turn.angle() * 180.0 / M_PI;
    reg.translation_mm = 1000 * (reg.camera.center() - photos[i].camera.center()).norm();
    for (const Vec2& f : reg.field) reg.field_max_px = std::max(reg.field_max_px, f.norm());
  }
  return Status::success();
}

}  // namespace lk
