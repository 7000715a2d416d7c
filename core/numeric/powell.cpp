// Powell's method after Numerical Recipes 10.5 (with 10.1 mnbrak, 10.2 brent).
// Two deliberate departures from the book, both for non-smooth objectives
// such as silhouette pixel counts:
//  - NR's linmin rescales each direction by the step it found; a zero step on
//    a plateau would then erase the direction for good. We keep the lengths
//    given by the caller (and the natural length of each new direction).
//  - Brent's absolute tolerance is an option (NR: 1e-10), so plateaus near
//    t = 0 need not cost dozens of evaluations.
#include "numeric/powell.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace lk {

namespace {

constexpr double kGold = 1.618034;        // golden ratio magnification of mnbrak
constexpr double kGrowLimit = 100.0;      // largest parabolic step in mnbrak
constexpr double kTiny = 1e-20;
constexpr double kCGold = 0.3819660;      // golden section fraction of brent
constexpr int kBrentMaxSteps = 100;

double sanitize(double v) { return std::isnan(v) ? std::numeric_limits<double>::infinity() : v; }

double sign_of(double a, double b) { return b >= 0.0 ? std::fabs(a) : -std::fabs(a); }

// Calls g while counting; past the budget it returns +inf so every loop ends.
struct CountedLine {
  const std::function<double(double)>& g;
  int& evaluations;
  int max_evaluations;
  double operator()(double t) {
    if (evaluations >= max_evaluations) return std::numeric_limits<double>::infinity();
    ++evaluations;
    return sanitize(g(t));
  }
};

// NR mnbrak: from a = 0 (value fa) and b = 1, walks downhill until
// f(b) <= f(a), f(c). On plateaus it may stop with f(b) == f(c), which
// brent accepts as an (unproved) bracket.
void bracket(CountedLine& g, double fa_known, double& ax, double& bx, double& cx,
             double& fa, double& fb, double& fc) {
  ax = 0.0; bx = 1.0;
  fa = fa_known;
  fb = g(bx);
  if (fb > fa) { std::swap(ax, bx); std::swap(fa, fb); }
  cx = bx + kGold * (bx - ax);
  fc = g(cx);
  while (fb > fc && g.evaluations < g.max_evaluations) {
    const double r = (bx - ax) * (fb - fc);
    const double q = (bx - cx) * (fb - fa);
    double u = bx - ((bx - cx) * q - (bx - ax) * r) /
                        (2.0 * sign_of(std::max(std::fabs(q - r), kTiny), q - r));
    const double ulim = bx + kGrowLimit * (cx - bx);
    double fu;
    if ((bx - u) * (u - cx) > 0.0) {  // parabolic u between b and c
      fu = g(u);
      if (fu < fc) { ax = bx; bx = u; fa = fb; fb = fu; return; }
      if (fu > fb) { cx = u; fc = fu; return; }
      u = cx + kGold * (cx - bx);
      fu = g(u);
    } else if ((cx - u) * (u - ulim) > 0.0) {  // between c and its limit
      fu = g(u);
      if (fu < fc) {
        bx = cx; cx = u; u = cx + kGold * (cx - bx);
        fb = fc; fc = fu; fu = g(u);
      }
    } else if ((u - ulim) * (ulim - cx) >= 0.0) {
      u = ulim;
      fu = g(u);
    } else {
      u = cx + kGold * (cx - bx);
      fu = g(u);
    }
    ax = bx; bx = cx; cx = u;
    fa = fb; fb = fc; fc = fu;
  }
}

// NR brent on the bracket (ax, bx, cx) with f(bx) = fb known.
void brent(CountedLine& g, double ax, double bx, double cx, double fb, double tolerance,
           double abs_tol, double& xmin, double& fmin) {
  double a = std::min(ax, cx), b = std::max(ax, cx);
  double x = bx, w = bx, v = bx;
  double fx = fb, fw = fb, fv = fb;
  double d = 0.0, e = 0.0;
  for (int step = 0; step < kBrentMaxSteps && g.evaluations < g.max_evaluations; ++step) {
    const double xm = 0.5 * (a + b);
    const double tol1 = tolerance * std::fabs(x) + abs_tol;
    const double tol2 = 2.0 * tol1;
    if (std::fabs(x - xm) <= tol2 - 0.5 * (b - a)) break;
    if (std::fabs(e) > tol1) {  // try a parabola through x, w, v
      const double r = (x - w) * (fx - fv);
      double q = (x - v) * (fx - fw);
      double p = (x - v) * q - (x - w) * r;
      q = 2.0 * (q - r);
      if (q > 0.0) p = -p;
      q = std::fabs(q);
      const double etemp = e;
      e = d;
      if (std::fabs(p) >= std::fabs(0.5 * q * etemp) || p <= q * (a - x) || p >= q * (b - x)) {
        e = (x >= xm) ? a - x : b - x;
        d = kCGold * e;
      } else {
        d = p / q;
        const double u = x + d;
        if (u - a < tol2 || b - u < tol2) d = sign_of(tol1, xm - x);
      }
    } else {
      e = (x >= xm) ? a - x : b - x;
      d = kCGold * e;
    }
    const double u = (std::fabs(d) >= tol1) ? x + d : x + sign_of(tol1, d);
    const double fu = g(u);
    if (fu <= fx) {
      if (u >= x) a = x; else b = x;
      v = w; w = x; x = u;
      fv = fw; fw = fx; fx = fu;
    } else {
      if (u < x) a = u; else b = u;
      if (fu <= fw || w == x) {
        v = w; w = u; fv = fw; fw = fu;
      } else if (fu <= fv || v == x || v == w) {
        v = u; fv = fu;
      }
    }
  }
  xmin = x;
  fmin = fx;
}

}  // namespace

void line_minimize(const std::function<double(double)>& g, double g0, double tolerance,
                   double& t_out, double& value_out, int& evaluations, int max_evaluations,
                   double absolute_tolerance) {
  CountedLine counted{g, evaluations, max_evaluations};
  double ax, bx, cx, fa, fb, fc;
  bracket(counted, sanitize(g0), ax, bx, cx, fa, fb, fc);
  // The best of the bracket points is the fallback if brent runs dry.
  double best_t = 0.0, best_f = sanitize(g0);
  if (fa < best_f) { best_t = ax; best_f = fa; }
  if (fb < best_f) { best_t = bx; best_f = fb; }
  if (fc < best_f) { best_t = cx; best_f = fc; }
  double xmin = bx, fmin = fb;
  brent(counted, ax, bx, cx, fb, tolerance, std::max(absolute_tolerance, 1e-12), xmin, fmin);
  if (fmin < best_f) { best_t = xmin; best_f = fmin; }
  t_out = best_t;
  value_out = best_f;
}

Status powell_minimize(const ObjectiveFn& f, const Eigen::VectorXd& x0,
                       const PowellOptions& options, PowellResult& out,
                       const ProgressFn& progress) {
  out = PowellResult{};
  const int n = static_cast<int>(x0.size());
  if (n == 0) return Status::error(ErrorCode::InvalidInput, "powell: no parameters to optimize");
  if (!x0.allFinite()) return Status::error(ErrorCode::InvalidInput, "powell: start point is not finite");
  Eigen::VectorXd step = options.initial_step.size() == 0 ? Eigen::VectorXd::Ones(n)
                                                          : options.initial_step;
  if (step.size() != n)
    return Status::error(ErrorCode::InvalidInput, "powell: initial_step has " +
                         std::to_string(step.size()) + " entries for " + std::to_string(n) + " parameters");
  if (!step.allFinite() || (step.array() == 0.0).any())
    return Status::error(ErrorCode::InvalidInput, "powell: initial_step must be finite and non-zero");
  if (!(options.tolerance > 0.0) || !(options.line_tolerance > 0.0) || !(options.line_absolute_tolerance >= 0.0))
    return Status::error(ErrorCode::InvalidInput, "powell: tolerances must be positive");

  int evals = 0;
  const int max_evals = std::max(1, options.max_evaluations);
  auto eval = [&](const Eigen::VectorXd& x) {
    if (evals >= max_evals) return std::numeric_limits<double>::infinity();
    ++evals;
    return sanitize(f(x));
  };

  Eigen::VectorXd p = x0;
  double fret = eval(p);
  out.x = p;
  out.value = fret;
  out.evaluations = evals;
  if (!std::isfinite(fret))
    return Status::error(ErrorCode::InvalidInput, "powell: objective is not finite at the start point");

  Eigen::MatrixXd dirs = step.asDiagonal();  // columns are the direction set
  Eigen::VectorXd pt = p;
  Status status = Status::success();

  auto minimize_along = [&](const Eigen::VectorXd& dir, Eigen::VectorXd& point, double& value) {
    const Eigen::VectorXd origin = point;
    std::function<double(double)> g = [&](double t) -> double {
      if (evals >= max_evals) return std::numeric_limits<double>::infinity();
      ++evals;
      return sanitize(f(origin + t * dir));
    };
    // line_minimize counts its own calls; our lambda counts against the
    // global budget, so give it an unlimited local budget.
    int local = 0;
    double t = 0.0, ft = value;
    line_minimize(g, value, options.line_tolerance, t, ft, local, std::numeric_limits<int>::max(),
                  options.line_absolute_tolerance);
    if (ft < value) {
      point = origin + t * dir;
      value = ft;
    }
    return t;
  };

  for (int iter = 1;; ++iter) {
    const double fp = fret;
    int biggest = 0;
    double biggest_drop = 0.0;
    for (int i = 0; i < n; ++i) {
      const double before = fret;
      minimize_along(dirs.col(i), p, fret);
      if (before - fret > biggest_drop) { biggest_drop = before - fret; biggest = i; }
    }
    out.iterations = iter;
    out.value_per_iteration.push_back(fret);
    if (2.0 * (fp - fret) <= options.tolerance * (std::fabs(fp) + std::fabs(fret)) + 1e-25) {
      out.converged = evals < max_evals;
      break;
    }
    if (iter >= options.max_iterations || evals >= max_evals) break;
    if (!report(progress, "powell", std::min(1.0, double(evals) / max_evals))) {
      status = Status::error(ErrorCode::Cancelled, "powell: cancelled");
      break;
    }
    // Extrapolate along the average direction of this sweep and decide
    // whether it should replace the direction of largest decrease (NR 10.5).
    const Eigen::VectorXd extrapolated = 2.0 * p - pt;
    const Eigen::VectorXd average_dir = p - pt;
    pt = p;
    const double fe = eval(extrapolated);
    if (fe < fp) {
      const double t = 2.0 * (fp - 2.0 * fret + fe) * (fp - fret - biggest_drop) * (fp - fret - biggest_drop) -
                       biggest_drop * (fp - fe) * (fp - fe);
      if (t < 0.0 && average_dir.squaredNorm() > 0.0) {
        minimize_along(average_dir, p, fret);
        dirs.col(biggest) = dirs.col(n - 1);
        dirs.col(n - 1) = average_dir;
      }
    }
  }
  out.x = p;
  out.value = fret;
  out.evaluations = evals;
  return status;
}

}  // namespace lk
