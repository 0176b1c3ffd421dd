#include "tpkit/match/multi_image_lsm.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "tpkit/core/error.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/match/lsm_refine.hpp"
#include "tpkit/match/radiometric_highpass.hpp"
#include "tpkit/rpc/rpc_ground.hpp"

namespace tpkit {

const char* to_string(MultiLsmViewStatus s) {
  switch (s) {
    case MultiLsmViewStatus::Ok: return "ok";
    case MultiLsmViewStatus::Template: return "template";
    case MultiLsmViewStatus::OutOfImage: return "out of image";
    case MultiLsmViewStatus::Diverged: return "diverged";
    case MultiLsmViewStatus::NotConverged: return "not converged";
    case MultiLsmViewStatus::Drifted: return "drifted";
    case MultiLsmViewStatus::LowCorrelation: return "low correlation";
    case MultiLsmViewStatus::Imprecise: return "imprecise";
    case MultiLsmViewStatus::Geometry: return "geometry";
  }
  return "?";
}

namespace {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

// The pixel p' of the plain model whose biased projection is p: p' + b(p') = p (the bias is small and
// smooth: a fixed-point iteration).
Vec2 unbias(const ImageBias& b, const Vec2& p) {
  Vec2 u = p;
  for (int i = 0; i < 4; ++i) u = p - b.offset(u);
  return u;
}

Vec3 ray_point(const MultiLsmImage& im, const Vec2& p, double h) {
  const Vec2 u = unbias(im.bias, p);
  const Vec2 ll = im.model->localize(u.x(), u.y(), h);
  return {ll.x(), ll.y(), h};
}

Vec2 observe(const MultiLsmImage& im, const Vec3& g) { return im.bias.apply(im.model->project(g)); }

// View k's first-order map from the template's pixels and the height (header: q_k0, M_k, e_k).
struct ViewGeometry {
  Vec2 q0;
  Eigen::Matrix2d M;
  Vec2 e;  // pixels per metre
};

ViewGeometry linearise(const MultiLsmImage& t, const Vec2& pt, double h0, const MultiLsmImage& k) {
  auto q = [&](double u, double v, double h) { return observe(k, ray_point(t, pt + Vec2(u, v), h)); };
  ViewGeometry g;
  g.q0 = q(0, 0, h0);
  g.M.col(0) = (q(1, 0, h0) - q(-1, 0, h0)) / 2;
  g.M.col(1) = (q(0, 1, h0) - q(0, -1, h0)) / 2;
  g.e = (q(0, 0, h0 + 1) - q(0, 0, h0 - 1)) / 2;
  return g;
}

struct TemplatePixel {
  double u, v, w, T;
};

// The template block (header), grey levels normalised; false when fewer than 80 % of its pixels are
// valid or it is flat.
bool make_template(const Raster& r, const Vec2& p, const MultiLsmOptions& o, std::vector<TemplatePixel>& px) {
  px.clear();
  const long cx = std::lround(p.x()), cy = std::lround(p.y());
  const int hw = o.window / 2;
  const double rmax2 = o.support > 0 ? std::pow(o.support * o.taper, 2) : std::numeric_limits<double>::infinity();
  long expected = 0;
  for (int j = -hw; j <= hw; ++j)
    for (int i = -hw; i <= hw; ++i) {
      if (i * i + j * j > rmax2) continue;
      ++expected;
      const long x = cx + i, y = cy + j;
      if (x < r.x0 || y < r.y0 || x >= r.x0 + r.width || y >= r.y0 + r.height) continue;
      const float val = r.at(x - r.x0, y - r.y0);
      if (std::isnan(val)) continue;
      const double u = static_cast<double>(x) - p.x(), v = static_cast<double>(y) - p.y();
      const double w = o.taper > 0 ? std::exp(-(u * u + v * v) / (2 * o.taper * o.taper)) : 1.0;
      px.push_back({u, v, w, val});
    }
  if (px.size() < 0.8 * expected || px.size() < 9) return false;
  double sw = 0, s = 0, s2 = 0;
  for (const auto& q : px) sw += q.w, s += q.w * q.T;
  const double mean = s / sw;
  for (const auto& q : px) s2 += q.w * (q.T - mean) * (q.T - mean);
  const double sd = std::sqrt(s2 / sw);
  if (!(sd > 1e-6 * std::max(1.0, std::fabs(mean)))) return false;
  for (auto& q : px) q.T = (q.T - mean) / sd;
  return true;
}

// tan of the view angle off nadir at the ground point of pixel p at height h: the horizontal displacement
// (metres) of the ground point that keeps its pixel when raised by 1 m.
double tan_off_nadir(const MultiLsmImage& im, const Vec2& p, double h) {
  const Vec3 g = ray_point(im, p, h);
  Eigen::Matrix<double, 2, 3> J;
  im.model->project(g, J);
  const double my = 111132.0, mx = my * std::cos(g.y() * M_PI / 180);
  Eigen::Matrix2d Jh;
  Jh.col(0) = J.col(0) / mx;
  Jh.col(1) = J.col(1) / my;
  const Vec2 d = -Jh.inverse() * J.col(2);
  return d.norm();
}

// Outcome of one solve over a set of views.
struct Solve {
  bool converged = false;
  int failed = -1;  // index into `active` of a view that made the solve fail (status in `why`)
  MultiLsmViewStatus why = MultiLsmViewStatus::NotConverged;
  std::vector<Vec2> q;       // final positions
  std::vector<double> sigma, corr;
  double h = 0;
  int iterations = 0;
};

class TrackSolver {
 public:
  TrackSolver(const std::vector<MultiLsmImage>& images, const std::vector<MultiLsmView>& views, int t, const MultiLsmOptions& o,
              const std::vector<TemplatePixel>& tpl)
      : im_(images), views_(views), t_(t), o_(o), tpl_(tpl), G_(o.curvature ? 6 : 3) {}

  // Views `active` (indices into views_, not the template) from the height h0.
  Solve run(const std::vector<int>& active, double h0) {
    Solve out;
    const int m = static_cast<int>(active.size());
    const int P = G_ + 4 * m;
    const MultiLsmImage& T = im_[views_[t_].image];
    const Vec2 pt = views_[t_].xy;
    Eigen::VectorXd x = Eigen::VectorXd::Zero(P);
    std::vector<ViewGeometry> geo(m);
    double h = h0, eref = 0;
    bool radiometry_set = false;
    Eigen::MatrixXd N(P, P);
    Eigen::VectorXd b(P);
    double sigma0_2 = 0;
    std::vector<double> corr(m, 0);
    int total_it = 0, unsettled = -1;
    for (int lin = 0; lin < std::max(1, o_.relinearise); ++lin) {
      // the geometry at the current height; the surface's offset moves into h
      try {
        for (int j = 0; j < m; ++j) geo[j] = linearise(T, pt, h, im_[views_[active[j]].image]);
      } catch (const NumericalError&) {
        out.why = MultiLsmViewStatus::Geometry;
        return out;
      }
      if (lin == 0) {
        for (int j = 0; j < m; ++j) eref = std::max(eref, geo[j].e.norm());
        if (!(eref > 1e-9)) {  // no parallax between the views: the surface is not observed
          out.why = MultiLsmViewStatus::Geometry;
          return out;
        }
      }
      if (!radiometry_set) {
        init_radiometry(active, geo, eref, x);
        radiometry_set = true;
      }
      bool converged = false;
      for (int it = 0; it < o_.max_iterations; ++it, ++total_it) {
        double ssr = 0;
        long n = 0;
        int bad = -1;
        accumulate(active, geo, eref, x, it >= 2 ? sigma0_2 : -1, N, b, ssr, n, corr, bad);
        if (bad >= 0) {
          out.failed = bad;
          out.why = MultiLsmViewStatus::OutOfImage;
          return out;
        }
        sigma0_2 = ssr / std::max<long>(1, n - P);
        // prior of the shifts (header): lambda = sigma0^2 / model_sigma^2 per coordinate
        for (int j = 0; j < m; ++j)
          for (int c = 0; c < 2; ++c) {
            const double ms = model_sigma(active[j]);
            const double lambda = ms > 0 ? sigma0_2 / (ms * ms) : 1e12 * std::max(sigma0_2, 1e-12);
            const int i = G_ + 4 * j + 2 + c;
            N(i, i) += lambda;
            b(i) -= lambda * x(i);
          }
        normal_ = N;
        const Eigen::VectorXd d = N.ldlt().solve(b);
        if (!d.allFinite()) {
          out.why = MultiLsmViewStatus::Diverged;
          return out;
        }
        x += d;
        // the largest update of a view's position, and a view drifting away from its input
        double step = 0;
        int far = -1;
        double far_by = 0;
        for (int j = 0; j < m; ++j) {
          const Vec2 dq = geo[j].e / eref * d(0) + d.segment<2>(G_ + 4 * j + 2);
          if (dq.norm() > step) step = dq.norm(), unsettled = j;
          const double moved = (position(geo[j], eref, x, j) - views_[active[j]].xy).norm();
          if (moved > o_.max_shift + 1 && moved > far_by) far = j, far_by = moved;
        }
        if (far >= 0) {
          out.failed = far;
          out.why = MultiLsmViewStatus::Drifted;
          return out;
        }
        if (it >= 2 && step < o_.tolerance) {
          converged = true;
          ++total_it;
          break;
        }
      }
      if (!converged) {
        // with several views, the one whose position moved the most in the last iteration leaves
        out.why = MultiLsmViewStatus::NotConverged;
        out.failed = m > 1 ? unsettled : -1;
        return out;
      }
      // a surface offset of under 0.05 px of parallax leaves the linearisation as it was (its error is of
      // second order in the offset); a larger one moves into h and the geometry is linearised there again
      // (the shifts s_k carry over: the new q_k0 is the old one moved by e_k dh)
      if (std::fabs(x(0)) < 0.05 || lin + 1 >= std::max(1, o_.relinearise)) {
        out.converged = true;
        break;
      }
      h += x(0) / eref;
      x(0) = 0;
    }
    if (!out.converged) return out;
    h += x(0) / eref;
    // precision: sigma0^2 N^-1 (the last iteration's N, its model within the tolerance of the solution)
    const Eigen::MatrixXd C = sigma0_2 * normal_.inverse();
    out.q.resize(m);
    out.sigma.resize(m);
    out.corr = corr;
    for (int j = 0; j < m; ++j) {
      out.q[j] = position(geo[j], eref, x, j);
      Eigen::MatrixXd Jq = Eigen::MatrixXd::Zero(2, P);
      Jq.col(0) = geo[j].e / eref;
      Jq(0, G_ + 4 * j + 2) = 1;
      Jq(1, G_ + 4 * j + 3) = 1;
      const Eigen::Matrix2d Cq = Jq * C * Jq.transpose();
      out.sigma[j] = o_.sigma_scale * std::sqrt(std::max(0.0, Cq.trace() / 2));
    }
    out.h = h;
    out.iterations = total_it;
    return out;
  }

 private:
  double model_sigma(int view) const {
    if (o_.model_sigma >= 0) return o_.model_sigma;
    const double s = im_[views_[view].image].model_sigma;
    return std::isfinite(s) ? std::min(s, o_.model_sigma_max) : o_.model_sigma_max;
  }

  Vec2 position(const ViewGeometry& g, double eref, const Eigen::VectorXd& x, int j) const {
    return g.q0 + g.e / eref * x(0) + x.segment<2>(G_ + 4 * j + 2);
  }

  // r1, r0 from the grey levels of each view's window at its start (unit deviation, zero mean like T)
  void init_radiometry(const std::vector<int>& active, const std::vector<ViewGeometry>& geo, double eref, Eigen::VectorXd& x) const {
    for (size_t j = 0; j < active.size(); ++j) {
      const Raster& r = *im_[views_[active[j]].image].raster;
      double sw = 0, s = 0, s2 = 0;
      for (const auto& p : tpl_) {
        const Vec2 q = geo[j].q0 + geo[j].M * Vec2(p.u, p.v) + geo[j].e / eref * x(0);
        double val;
        if (!bicubic(r, q.x(), q.y(), val)) continue;
        sw += p.w, s += p.w * val, s2 += p.w * val * val;
      }
      double r1 = 1, r0 = 0;
      if (sw > 0) {
        const double mean = s / sw, var = std::max(0.0, s2 / sw - mean * mean);
        r1 = var > 0 ? 1 / std::sqrt(var) : 1;
        r0 = -mean * r1;
      }
      x(G_ + 4 * j) = r0;
      x(G_ + 4 * j + 1) = r1;
    }
  }

  // Normal equations N d = b of the pixels' residuals T - (r0 + r1 I(q)) (Huber weights when sigma0_2 > 0).
  void accumulate(const std::vector<int>& active, const std::vector<ViewGeometry>& geo, double eref, const Eigen::VectorXd& x,
                  double sigma0_2, Eigen::MatrixXd& N, Eigen::VectorXd& b, double& ssr, long& n, std::vector<double>& corr,
                  int& bad) const {
    N.setZero();
    b.setZero();
    const double k = sigma0_2 > 0 ? 2 * std::sqrt(sigma0_2) : std::numeric_limits<double>::infinity();
    double basis[6];
    int idx[10];
    double J[10];
    for (size_t j = 0; j < active.size(); ++j) {
      const Raster& r = *im_[views_[active[j]].image].raster;
      const Vec2 eh = geo[j].e / eref;
      const int base = G_ + 4 * static_cast<int>(j);
      const double r0 = x(base), r1 = x(base + 1);
      const Vec2 s = x.segment<2>(base + 2);
      double sw = 0, st = 0, sv = 0, stt = 0, svv = 0, stv = 0;
      long used = 0;
      for (const auto& p : tpl_) {
        basis[0] = 1, basis[1] = p.u, basis[2] = p.v;
        if (G_ == 6) basis[3] = p.u * p.u / 2, basis[4] = p.u * p.v, basis[5] = p.v * p.v / 2;
        double hs = 0;
        for (int i = 0; i < G_; ++i) hs += basis[i] * x(i);
        const Vec2 q = geo[j].q0 + geo[j].M * Vec2(p.u, p.v) + eh * hs + s;
        double val, gx, gy;
        if (!bicubic(r, q.x(), q.y(), val, &gx, &gy)) continue;
        ++used;
        const double res = p.T - (r0 + r1 * val);
        double w = p.w;
        if (std::fabs(res) > k) w *= k / std::fabs(res);
        const double ge = r1 * (gx * eh.x() + gy * eh.y());
        int c = 0;
        for (int i = 0; i < G_; ++i) idx[c] = i, J[c++] = ge * basis[i];
        idx[c] = base, J[c++] = 1;
        idx[c] = base + 1, J[c++] = val;
        idx[c] = base + 2, J[c++] = r1 * gx;
        idx[c] = base + 3, J[c++] = r1 * gy;
        for (int a = 0; a < c; ++a) {
          b(idx[a]) += w * J[a] * res;
          for (int e = 0; e <= a; ++e) N(idx[a], idx[e]) += w * J[a] * J[e];
        }
        ssr += w * res * res;
        ++n;
        sw += p.w, st += p.w * p.T, sv += p.w * val, stt += p.w * p.T * p.T, svv += p.w * val * val, stv += p.w * p.T * val;
      }
      if (used < 0.8 * static_cast<double>(tpl_.size())) {
        bad = static_cast<int>(j);
        return;
      }
      const double ct = stt - st * st / sw, cv = svv - sv * sv / sw, ctv = stv - st * sv / sw;
      corr[j] = ct > 0 && cv > 0 ? ctv / std::sqrt(ct * cv) : 0;
    }
    // the lower triangle was filled
    N.triangularView<Eigen::StrictlyUpper>() = N.transpose().triangularView<Eigen::StrictlyUpper>();
  }

  const std::vector<MultiLsmImage>& im_;
  const std::vector<MultiLsmView>& views_;
  int t_;
  const MultiLsmOptions& o_;
  const std::vector<TemplatePixel>& tpl_;
  int G_;
  Eigen::MatrixXd normal_;
};

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  const size_t h = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + h, v.end());
  if (v.size() % 2) return v[h];
  const double hi = v[h];
  return (hi + *std::max_element(v.begin(), v.begin() + h)) / 2;
}

// The track's views in the images it lacks (MultiLsmOptions::extend): each image whose view of the
// track's ground point (res.llh) lies inside it by the window is tried with the template alone (a
// two-view solve started at the projection: it stands on its own evidence), and the views accepted
// there are solved together with the track's own. The joint solve replaces the track's when it keeps
// the template; otherwise the track stays as it was.
// The views a track of `t` has (its row r), in image order.
std::vector<MultiLsmView> track_views(const Tracks& t, size_t r) {
  std::vector<MultiLsmView> v;
  for (int k = 0; k < t.views(); ++k)
    if (t.seen(r, k)) {
      MultiLsmView mv;
      mv.image = k;
      mv.xy = t.point(r, k);
      v.push_back(mv);
    }
  return v;
}

MultiLsmResult extend_track(const std::vector<MultiLsmImage>& images, const std::vector<MultiLsmView>& input, const MultiLsmResult& res,
                            const MultiLsmOptions& o) {
  const int K = static_cast<int>(images.size());
  std::vector<char> has(static_cast<size_t>(K), 0);
  std::vector<MultiLsmView> kept;
  int t = -1;
  for (const auto& v : res.views) {
    has[static_cast<size_t>(v.image)] = 1;
    if (v.status != MultiLsmViewStatus::Ok && v.status != MultiLsmViewStatus::Template) continue;
    if (v.status == MultiLsmViewStatus::Template) t = static_cast<int>(kept.size());
    kept.push_back(v);
  }
  Vec3 llh = res.llh;
  if (!res.ok) {
    // the track's own views failed together: its template alone, at the intersection of its input views
    if (res.template_view < 0 || res.views[static_cast<size_t>(res.template_view)].status == MultiLsmViewStatus::Geometry) return res;
    std::vector<RpcObservation> obs;
    for (const auto& v : input) obs.push_back({images[static_cast<size_t>(v.image)].model, &images[static_cast<size_t>(v.image)].bias, v.xy});
    const RpcIntersection X = intersect_rpc(obs);
    if (!X.ok) return res;
    kept.clear();
    MultiLsmView tv = input[static_cast<size_t>(res.template_view)];
    tv.status = MultiLsmViewStatus::Template;
    kept.push_back(tv);
    t = 0;
    llh = X.llh;
  }
  if (t < 0 || !llh.allFinite()) return res;
  const MultiLsmView tpl = kept[static_cast<size_t>(t)];
  const double margin = o.window / 2 + 3;
  const size_t own = kept.size();
  for (int k = 0; k < K; ++k) {
    if (has[static_cast<size_t>(k)]) continue;
    const Raster& r = *images[static_cast<size_t>(k)].raster;
    Vec2 q;
    try {
      q = observe(images[static_cast<size_t>(k)], llh);
    } catch (const NumericalError&) {
      continue;
    }
    if (!(q.x() >= r.x0 + margin && q.y() >= r.y0 + margin && q.x() <= r.x0 + r.width - 1 - margin && q.y() <= r.y0 + r.height - 1 - margin)) continue;
    MultiLsmView c;
    c.image = k;
    c.xy = q;
    const MultiLsmResult pair = refine_track_views(images, {tpl, c}, o, 0);
    if (pair.ok && pair.views[1].status == MultiLsmViewStatus::Ok) {
      c.xy = pair.views[1].xy;
      kept.push_back(c);
    }
  }
  if (kept.size() == own || kept.size() < 2) return res;
  MultiLsmResult joint = refine_track_views(images, kept, o, t);
  if (!joint.ok) return res;
  // the track's own views that failed stay in the result, with their reasons (refine_tracks counts them)
  for (const auto& v : res.views)
    if (std::none_of(joint.views.begin(), joint.views.end(), [&](const MultiLsmView& w) { return w.image == v.image; })) joint.views.push_back(v);
  return joint;
}
}  // namespace

int choose_template(const std::vector<MultiLsmImage>& images, const std::vector<MultiLsmView>& views, const MultiLsmOptions& o,
                    std::vector<double>* scores) {
  std::vector<double> sc(views.size(), 0);
  for (size_t k = 0; k < views.size(); ++k) {
    const MultiLsmImage& im = images[views[k].image];
    const Raster& r = *im.raster;
    std::vector<TemplatePixel> px;
    if (!make_template(r, views[k].xy, o, px)) continue;
    // mean squared gradient of the normalised grey levels (central differences on the pixel grid)
    double sw = 0, sg = 0;
    for (const auto& p : px) {
      const long x = std::lround(views[k].xy.x() + p.u) - r.x0, y = std::lround(views[k].xy.y() + p.v) - r.y0;
      if (x < 1 || y < 1 || x + 1 >= r.width || y + 1 >= r.height) continue;
      const double gx = (r.at(x + 1, y) - r.at(x - 1, y)) / 2, gy = (r.at(x, y + 1) - r.at(x, y - 1)) / 2;
      if (!std::isfinite(gx) || !std::isfinite(gy)) continue;
      sw += p.w, sg += p.w * (gx * gx + gy * gy);
    }
    if (sw <= 0) continue;
    // px's T is normalised; the gradient above is of raw grey levels: divide by the window's variance
    double s = 0, s2 = 0, w = 0;
    for (const auto& p : px) {
      const long x = std::lround(views[k].xy.x() + p.u) - r.x0, y = std::lround(views[k].xy.y() + p.v) - r.y0;
      const double val = r.at(x, y);
      w += p.w, s += p.w * val, s2 += p.w * val * val;
    }
    const double var = s2 / w - (s / w) * (s / w);
    if (!(var > 0)) continue;
    double tan2 = 0;
    try {
      const double t = tan_off_nadir(im, views[k].xy, im.model->height_off);
      tan2 = t * t;
    } catch (const NumericalError&) {
      continue;
    }
    sc[k] = sg / sw / var / (1 + tan2);
  }
  if (scores) *scores = sc;
  return static_cast<int>(std::max_element(sc.begin(), sc.end()) - sc.begin());
}

MultiLsmResult refine_track_views(const std::vector<MultiLsmImage>& images, std::vector<MultiLsmView> views, const MultiLsmOptions& o,
                                  int template_view) {
  MultiLsmResult res;
  const int K = static_cast<int>(views.size());
  for (auto& v : views) v.status = MultiLsmViewStatus::NotConverged;
  res.views = views;
  if (K < 2) return res;
  std::vector<double> scores;
  const int t = template_view >= 0 ? template_view : choose_template(images, views, o, &scores);
  res.template_view = t;
  std::vector<TemplatePixel> tpl;
  if ((template_view < 0 && !(scores[t] > 0)) || !make_template(*images[views[t].image].raster, views[t].xy, o, tpl)) {
    for (auto& v : res.views) v.status = MultiLsmViewStatus::Geometry;
    return res;
  }
  res.views[t].status = MultiLsmViewStatus::Template;
  // starting height: the intersection of all views, then the median of each view's height along its
  // epipolar direction from the template (robust to one wrong view among three or more)
  double h0 = NAN;
  {
    std::vector<RpcObservation> obs;
    for (const auto& v : views) obs.push_back({images[v.image].model, &images[v.image].bias, v.xy});
    const RpcIntersection X = intersect_rpc(obs);
    if (!X.ok) {
      for (int k = 0; k < K; ++k)
        if (k != t) res.views[k].status = MultiLsmViewStatus::Geometry;
      return res;
    }
    std::vector<double> hk;
    for (int k = 0; k < K; ++k) {
      if (k == t) continue;
      try {
        const ViewGeometry g = linearise(images[views[t].image], views[t].xy, X.llh.z(), images[views[k].image]);
        if (g.e.squaredNorm() > 0) hk.push_back(X.llh.z() + g.e.dot(views[k].xy - g.q0) / g.e.squaredNorm());
      } catch (const NumericalError&) {
      }
    }
    h0 = hk.empty() ? X.llh.z() : median(hk);
  }
  TrackSolver solver(images, views, t, o, tpl);
  std::vector<int> active;
  for (int k = 0; k < K; ++k)
    if (k != t) active.push_back(k);
  while (!active.empty()) {
    Solve s = solver.run(active, h0);
    res.iterations += s.iterations;
    if (!s.converged) {
      if (s.failed < 0) {
        // a failure of the whole solve (not converged, no geometry, singular): every remaining view
        for (int k : active) res.views[k].status = s.why;
        active.clear();
        break;
      }
      res.views[active[s.failed]].status = s.why;
      active.erase(active.begin() + s.failed);
      continue;
    }
    // acceptance: the worst failing view leaves, the others are solved again without it
    int worst = -1;
    double worst_score = 0;
    MultiLsmViewStatus why = MultiLsmViewStatus::Ok;
    for (size_t j = 0; j < active.size(); ++j) {
      const MultiLsmView& v = views[active[j]];
      const double moved = (s.q[j] - v.xy).norm();
      double score = 0;
      MultiLsmViewStatus w = MultiLsmViewStatus::Ok;
      if (moved > o.max_shift) score = 2 + moved / o.max_shift, w = MultiLsmViewStatus::Drifted;
      else if (s.corr[j] < o.min_corr) score = 1 + (o.min_corr - s.corr[j]), w = MultiLsmViewStatus::LowCorrelation;
      else if (!(s.sigma[j] <= o.max_sigma)) score = s.sigma[j] / o.max_sigma, w = MultiLsmViewStatus::Imprecise;
      if (score > worst_score) worst = static_cast<int>(j), worst_score = score, why = w;
    }
    if (worst >= 0) {
      res.views[active[worst]].status = why;
      active.erase(active.begin() + worst);
      continue;
    }
    double smin = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < active.size(); ++j) {
      MultiLsmView& v = res.views[active[j]];
      v.xy = s.q[j];
      v.sigma = s.sigma[j];
      v.corr = s.corr[j];
      v.status = MultiLsmViewStatus::Ok;
      smin = std::min(smin, v.sigma);
    }
    res.views[t].sigma = smin;
    res.views[t].corr = 1;
    try {
      res.llh = ray_point(images[views[t].image], views[t].xy, s.h);
    } catch (const NumericalError&) {
      res.llh = Vec3(NAN, NAN, s.h);
    }
    res.ok = true;
    break;
  }
  return res;
}

std::vector<ImageBias> estimate_track_biases(const Tracks& t, const std::vector<const RpcModel*>& models, BiasModel m, int reference,
                                             int rounds, std::vector<double>* residual_rms) {
  const int K = t.views();
  if (static_cast<int>(models.size()) != K) throw UsageError("estimate_track_biases: one model per image of the tracks");
  std::vector<ImageBias> bias(K);
  const std::array<bool, 6> used = bias_terms_used(m);
  std::vector<double> rms(K, NAN);
  for (int round = 0; round < rounds; ++round) {
    // offsets observed - projected, per image, at the tracks' current ground points
    std::vector<std::vector<Vec2>> at(K), off(K);
    for (size_t r = 0; r < t.size(); ++r) {
      std::vector<RpcObservation> obs;
      std::vector<int> img;
      for (int k = 0; k < K; ++k)
        if (t.seen(r, k)) obs.push_back({models[k], &bias[k], t.point(r, k)}), img.push_back(k);
      if (obs.size() < 2) continue;
      const RpcIntersection X = intersect_rpc(obs);
      if (!X.ok) continue;
      for (size_t i = 0; i < obs.size(); ++i) {
        const Vec2 p = models[img[i]]->project(X.llh);
        if (!p.allFinite()) continue;
        at[img[i]].push_back(p);
        off[img[i]].push_back(obs[i].xy - p);
      }
    }
    for (int k = 0; k < K; ++k) {
      if (k == reference && !at[k].empty()) {
        // the datum: no fit, the RMS of its offsets within 3 robust deviations
        std::vector<double> len;
        for (const auto& d : off[k]) len.push_back(d.norm());
        const double thr = std::max(0.05, 3 * 1.4826 * median(len));
        double s2 = 0;
        long nk = 0;
        for (double l : len)
          if (l <= thr) s2 += l * l, ++nk;
        rms[k] = nk ? std::sqrt(s2 / nk) : NAN;
      }
      if (k == reference || at[k].size() < 3) continue;
      const size_t n = at[k].size();
      // columns of the design: 1, x, y (centred and scaled for the conditioning), the terms the model uses
      Vec2 c = Vec2::Zero();
      for (const auto& p : at[k]) c += p;
      c /= static_cast<double>(n);
      const double sc = 1000;
      std::vector<bool> keep(n, true);
      Eigen::Vector3d ax = Eigen::Vector3d::Zero(), ay = Eigen::Vector3d::Zero();
      for (int pass = 0; pass < 3; ++pass) {
        Eigen::MatrixXd A(n, 3);
        Eigen::MatrixXd B(n, 2);
        A.setZero();
        B.setZero();
        for (size_t i = 0; i < n; ++i) {
          if (!keep[i]) continue;
          A(i, 0) = 1;
          A(i, 1) = (at[k][i].x() - c.x()) / sc;
          A(i, 2) = (at[k][i].y() - c.y()) / sc;
          B(i, 0) = off[k][i].x();
          B(i, 1) = off[k][i].y();
        }
        // terms the model leaves out: their columns zeroed (used[1] = a1 (x), used[2] = a2 (y))
        if (!used[1]) A.col(1).setZero();
        if (!used[2]) A.col(2).setZero();
        const Eigen::MatrixXd Z = A.completeOrthogonalDecomposition().solve(B);
        ax = Z.col(0), ay = Z.col(1);
        std::vector<double> len(n), kept_len;
        for (size_t i = 0; i < n; ++i) {
          const double dx = (at[k][i].x() - c.x()) / sc, dy = (at[k][i].y() - c.y()) / sc;
          const Vec2 f(ax(0) + ax(1) * dx + ax(2) * dy, ay(0) + ay(1) * dx + ay(2) * dy);
          len[i] = (off[k][i] - f).norm();
          if (keep[i]) kept_len.push_back(len[i]);
        }
        const double thr = std::max(0.05, 3 * 1.4826 * median(kept_len));
        double s2 = 0;
        long nk = 0;
        for (size_t i = 0; i < n; ++i) {
          keep[i] = len[i] <= thr;
          if (keep[i]) s2 += len[i] * len[i], ++nk;
        }
        rms[k] = nk ? std::sqrt(s2 / nk) : NAN;
      }
      // back to the bias of uncentred pixels: d = a0 + a1 (x - cx) / sc + a2 (y - cy) / sc
      ImageBias b;
      b.a = {ax(0) - ax(1) * c.x() / sc - ax(2) * c.y() / sc, ax(1) / sc, ax(2) / sc};
      b.b = {ay(0) - ay(1) * c.x() / sc - ay(2) * c.y() / sc, ay(1) / sc, ay(2) / sc};
      // the offsets are from the plain projection: each round fits the whole bias (at better ground points)
      bias[k] = b;
    }
  }
  if (residual_rms) *residual_rms = rms;
  return bias;
}

Tracks refine_tracks(const Tracks& t, const std::vector<MultiLsmImage>& images, const MultiLsmOptions& o, int threads, MultiLsmStats* stats) {
  const int K = t.views();
  if (static_cast<int>(images.size()) != K) throw UsageError("refine_tracks: one image per column pair of the tracks");
  std::vector<MultiLsmResult> res(t.size());
  std::vector<char> at_fallback(t.size(), 0);
  MultiLsmOptions of = o;  // the fallback size
  of.window = o.fallback_window, of.taper = o.fallback_taper, of.fallback_window = 0;
  // views accepted in a result (0 when the track failed), and of them the track's own
  auto accepted = [](const MultiLsmResult& x, const std::vector<MultiLsmView>* own) {
    int n = 0;
    for (const auto& w : x.views)
      if (x.ok && (w.status == MultiLsmViewStatus::Ok || w.status == MultiLsmViewStatus::Template))
        n += !own || std::any_of(own->begin(), own->end(), [&](const MultiLsmView& u) { return u.image == w.image; });
    return n;
  };
  parallel_for(t.size(), threads, [&](size_t r) {
    const std::vector<MultiLsmView> v = track_views(t, r);
    int tv = -1;
    for (size_t i = 0; i < v.size(); ++i)
      if (v[i].image == o.template_image) tv = static_cast<int>(i);
    auto solve = [&](const MultiLsmOptions& oo) {
      MultiLsmResult x = refine_track_views(images, v, oo, tv);
      return oo.extend ? extend_track(images, v, x, oo) : x;
    };
    res[r] = solve(o);
    if (o.fallback_window > 0 && accepted(res[r], &v) < static_cast<int>(v.size())) {
      MultiLsmResult b = solve(of);
      if (accepted(b, nullptr) > accepted(res[r], nullptr)) res[r] = std::move(b), at_fallback[r] = 1;
    }
  });
  MultiLsmStats st;
  st.template_count.assign(K, 0);
  Tracks out;
  out.source = t.source;
  out.images = t.images;
  out.meta = t.meta;
  // sigma columns replaced, `template` added (or replaced); the other extra columns kept
  std::vector<int> keep_cols;
  for (size_t c = 0; c < t.extra.names.size(); ++c) {
    const std::string& nm = t.extra.names[c];
    bool sigma_col = nm == "template";
    for (int k = 0; k < K; ++k) sigma_col = sigma_col || nm == "sigma" + std::to_string(k + 1);
    if (!sigma_col) keep_cols.push_back(static_cast<int>(c)), out.extra.names.push_back(nm);
  }
  const int first_new = static_cast<int>(out.extra.names.size());
  for (int k = 0; k < K; ++k) out.extra.names.push_back("sigma" + std::to_string(k + 1));
  out.extra.names.push_back("template");
  std::vector<size_t> rows;
  for (size_t r = 0; r < t.size(); ++r) {
    ++st.tracks;
    int ok = 0;
    long added = 0;
    for (const auto& v : res[r].views) {
      ++st.views;
      if (v.status == MultiLsmViewStatus::Ok || v.status == MultiLsmViewStatus::Template) {
        if (res[r].ok) ++ok, added += !t.seen(r, v.image);
      } else {
        ++st.views_dropped;
        ++st.by_status[static_cast<int>(v.status)];
      }
    }
    if (res[r].ok && ok >= 2) {
      rows.push_back(r);
      st.views_refined += ok - 1;
      st.views_added += added;
      st.tracks_at_fallback += at_fallback[r];
      ++st.template_count[res[r].views[res[r].template_view].image];
    } else {
      ++st.tracks_dropped;
      // a dropped track's accepted views count as dropped too
      for (const auto& v : res[r].views)
        if (v.status == MultiLsmViewStatus::Ok || v.status == MultiLsmViewStatus::Template) ++st.views_dropped;
    }
  }
  st.tracks_written = static_cast<long>(rows.size());
  const Eigen::Index n = static_cast<Eigen::Index>(rows.size());
  out.xy = Eigen::MatrixXd::Constant(n, 2 * K, NAN);
  out.extra.values = Eigen::MatrixXd::Constant(n, static_cast<Eigen::Index>(out.extra.names.size()), NAN);
  std::map<int, long> by_views;
  for (Eigen::Index i = 0; i < n; ++i) {
    const size_t r = rows[i];
    out.id.push_back(t.id[r]);
    if (!t.line.empty()) out.line.push_back(t.line[r]);
    for (size_t c = 0; c < keep_cols.size(); ++c) out.extra.values(i, static_cast<Eigen::Index>(c)) = t.extra.values(r, keep_cols[c]);
    int seen = 0;
    for (const auto& v : res[r].views) {
      if (v.status != MultiLsmViewStatus::Ok && v.status != MultiLsmViewStatus::Template) continue;
      out.xy(i, 2 * v.image) = v.xy.x();
      out.xy(i, 2 * v.image + 1) = v.xy.y();
      out.extra.values(i, first_new + v.image) = v.sigma;
      ++seen;
    }
    ++by_views[seen];
    out.extra.values(i, first_new + K) = res[r].views[res[r].template_view].image + 1;
  }
  for (auto& kv : out.meta)
    if (kv.first == "tracks_by_views") {
      std::ostringstream s;
      for (const auto& bv : by_views) s << (s.tellp() > 0 ? " " : "") << bv.first << ":" << bv.second;
      kv.second = s.str();
    }
  if (stats) *stats = st;
  return out;
}

namespace {
// A sample of tracks refined with the model sigma kHighpassModelSigma (across its epipolar direction a
// view then sits where its image puts it): per sampled track and accepted non-template view, the template
// and view images, the view's position and its epipolar direction (unit) from the template. Tracks spread
// evenly over the file.
struct SampledView {
  int tpl = 0, image = 0;
  Vec2 xy = Vec2::Zero(), q0 = Vec2::Zero(), e = Vec2::Zero();
};
std::vector<size_t> sample_rows(const Tracks& t, size_t samples) {
  std::vector<size_t> rows;
  const size_t n = t.size(), want = std::min(n, samples);
  for (size_t i = 0; i < want; ++i) rows.push_back(i * n / want);
  return rows;
}
std::vector<std::vector<SampledView>> refine_sample(const Tracks& t, const std::vector<MultiLsmImage>& im, const std::vector<size_t>& rows,
                                                    const MultiLsmOptions& o, int threads) {
  MultiLsmOptions so = o;
  so.extend = false;
  so.model_sigma = kHighpassModelSigma;  // loose: the views may leave the models across their epipolar lines
  std::vector<std::vector<SampledView>> out(rows.size());
  parallel_for(rows.size(), threads, [&](size_t i) {
    const MultiLsmResult res = refine_track_views(im, track_views(t, rows[i]), so, -1);
    if (!res.ok) return;
    const MultiLsmView& tv = res.views[static_cast<size_t>(res.template_view)];
    for (const auto& w : res.views) {
      if (w.status != MultiLsmViewStatus::Ok) continue;
      try {
        const ViewGeometry g = linearise(im[static_cast<size_t>(tv.image)], tv.xy, res.llh.z(), im[static_cast<size_t>(w.image)]);
        if (!(g.e.norm() > 0)) continue;
        out[i].push_back({tv.image, w.image, w.xy, g.q0, g.e.normalized()});
      } catch (const NumericalError&) {
      }
    }
  });
  return out;
}
// The spread of the sampled views across their epipolar directions about each image pair's median: what
// the models and biases still get wrong across the epipolar lines is mostly an offset per image pair,
// common to every candidate, and left out. NaN with fewer than 20 views in pairs of at least 5.
double across_spread(const std::vector<std::vector<SampledView>>& sample) {
  std::map<std::pair<int, int>, std::vector<double>> by_pair;
  for (const auto& a : sample)
    for (const SampledView& v : a) {
      const Vec2 d = v.xy - v.q0;
      by_pair[{v.tpl, v.image}].push_back(d.x() * v.e.y() - d.y() * v.e.x());
    }
  std::vector<double> all;
  for (auto& bp : by_pair) {
    if (bp.second.size() < 5) continue;
    const double m = median(bp.second);
    for (double d : bp.second) all.push_back(std::abs(d - m));
  }
  return all.size() < 20 ? std::numeric_limits<double>::quiet_NaN() : median(all);
}
// The views two runs over the same sampled tracks both accepted (same track, template and image), as
// two samples of the same shape: a's views and b's.
std::pair<std::vector<std::vector<SampledView>>, std::vector<std::vector<SampledView>>> common_views(
    const std::vector<std::vector<SampledView>>& a, const std::vector<std::vector<SampledView>>& b) {
  std::vector<std::vector<SampledView>> ca(a.size()), cb(a.size());
  for (size_t i = 0; i < a.size(); ++i)
    for (const SampledView& u : a[i])
      for (const SampledView& v : b[i])
        if (u.tpl == v.tpl && u.image == v.image) ca[i].push_back(u), cb[i].push_back(v);
  return {std::move(ca), std::move(cb)};
}
long count_views(const std::vector<std::vector<SampledView>>& s) {
  long n = 0;
  for (const auto& a : s) n += static_cast<long>(a.size());
  return n;
}
}  // namespace

HighpassChoice choose_track_highpass(const Tracks& t, const std::vector<MultiLsmImage>& images, const MultiLsmOptions& o, int threads,
                                     const std::vector<double>& candidates, size_t samples) {
  const int K = t.views();
  if (static_cast<int>(images.size()) != K) throw UsageError("choose_track_highpass: one image per column pair of the tracks");
  const std::vector<size_t> rows = sample_rows(t, samples);
  MultiLsmOptions ob = o;  // at the base size: the window's size is chosen after the high-pass, on its images
  if (o.fallback_window > 0) ob.window = o.fallback_window, ob.taper = o.fallback_taper;
  auto sample_at = [&](double sigma) {
    std::vector<Raster> filtered(static_cast<size_t>(K));
    std::vector<MultiLsmImage> im = images;
    for (int k = 0; k < K && sigma > 0; ++k) {  // unfiltered: the images as they are
      filtered[static_cast<size_t>(k)] = *images[static_cast<size_t>(k)].raster;
      highpass_raster(filtered[static_cast<size_t>(k)], sigma);
      im[static_cast<size_t>(k)].raster = &filtered[static_cast<size_t>(k)];
    }
    return refine_sample(t, im, rows, ob, threads);
  };
  // Each candidate against the best so far over the views both accepted (same track, template and
  // image): the spreads of two runs over the views each accepted differ by which views those are, and
  // on the synthetic block of docs/blocks.md that difference alone moved the choice across the gain
  // (0.173 -> 0.1645 px, none; a few tracks changed: 0.1741 -> 0.1651, 1 px, and the ground points 0.034
  // -> 0.077 m NMAD from the true terrain).
  HighpassChoice c;
  c.samples = static_cast<long>(rows.size());
  c.paired_gain = kTrackHighpassGain;
  std::vector<std::vector<SampledView>> best = sample_at(0.0);
  c.spread_none = c.spread = across_spread(best);
  for (double sg : candidates) {
    const std::vector<std::vector<SampledView>> cand = sample_at(sg);
    const auto [ca, cb] = common_views(best, cand);
    const double before = across_spread(ca), after = across_spread(cb);
    c.tried.push_back(sg);
    c.tried_spread.push_back(after);
    c.tried_reference.push_back(before);
    c.tried_common.push_back(count_views(ca));
    if (!(std::isfinite(before) && std::isfinite(after) && after < (1 - kTrackHighpassGain) * before)) break;
    c.sigma = sg;
    c.spread = across_spread(cand);
    best = cand;
  }
  return c;
}

WindowSizeChoice choose_track_size(const Tracks& t, const std::vector<MultiLsmImage>& images, const MultiLsmOptions& o, int threads,
                                   size_t samples) {
  if (static_cast<int>(images.size()) != t.views()) throw UsageError("choose_track_size: one image per column pair of the tracks");
  const std::vector<size_t> rows = sample_rows(t, samples);
  const WindowSize base{o.fallback_taper, o.fallback_window, false}, large{o.taper, o.window, false};
  MultiLsmOptions ob = o, ol = o;
  ob.taper = base.taper, ob.window = base.window;
  const std::vector<std::vector<SampledView>> sb = refine_sample(t, images, rows, ob, threads), sl = refine_sample(t, images, rows, ol, threads);
  WindowSizeChoice c;
  c.size = base;
  c.samples = static_cast<long>(rows.size());
  c.shapes = false;  // the surface model is the same at both sizes
  WindowSizeChoice::Tried tr;
  tr.size = large;
  // the views refined at both sizes against the same template: their differences along and across
  std::vector<double> along, across;
  const auto [cb, cl] = common_views(sb, sl);
  for (size_t i = 0; i < rows.size(); ++i)
    for (size_t j = 0; j < cb[i].size(); ++j) {
      const SampledView &a = cb[i][j], &b = cl[i][j];
      const Vec2 d = b.xy - a.xy;
      along.push_back(d.dot(a.e));
      across.push_back(d.x() * a.e.y() - d.y() * a.e.x());
    }
  tr.common = static_cast<long>(along.size());
  if (along.size() >= 20) {
    const double sa = robust_spread(along), sc = robust_spread(across);
    tr.ratio = sc > 0 ? sa / sc : std::numeric_limits<double>::quiet_NaN();
  }
  tr.spread_before = across_spread(cb);
  tr.spread = across_spread(cl);
  tr.kept = tr.ratio <= kWindowSizeMaxRatio && tr.spread <= (1 - kWindowSizeMinGain) * tr.spread_before;
  c.tried.push_back(tr);
  if (tr.kept) c.size = large;
  return c;
}

void use_track_size(const WindowSizeChoice& c, MultiLsmOptions& o) {
  if (c.size.window == o.window && c.size.taper == o.taper) return;
  o.window = c.size.window, o.taper = c.size.taper;
  o.fallback_window = 0;
}

std::string describe_track_highpass(const HighpassChoice& h, bool given) {
  return describe_highpass_choice(h, "every image", given, "sampled tracks", "spread of their views across the models' epipolar directions",
                                  "(not estimated: no tracks to sample)");
}

}  // namespace tpkit
