#include "rgbn/acquire.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"
#include "rgbn/parallel.h"

namespace proctex::rgbn {

namespace {

void check_inputs(const std::vector<Image>& photos, const std::vector<Vec3>& lights, size_t needed, const char* what) {
  if (photos.size() != lights.size())
    throw UsageError(std::to_string(photos.size()) + " photos but " + std::to_string(lights.size()) + " light directions",
                     "give one light direction per photo");
  if (photos.size() < needed)
    throw UsageError(std::string(what) + " needs at least " + std::to_string(needed) + " photos under different lights, got " +
                         std::to_string(photos.size()),
                     "add photos lit from other directions");
  for (size_t i = 1; i < photos.size(); ++i)
    if (photos[i].width != photos[0].width || photos[i].height != photos[0].height)
      throw Error("photo " + std::to_string(i + 1) + " is " + std::to_string(photos[i].width) + "x" +
                      std::to_string(photos[i].height) + " but photo 1 is " + std::to_string(photos[0].width) + "x" +
                      std::to_string(photos[0].height),
                  "all photos must be taken from the same viewpoint at the same size");
  for (const auto& l : lights) {
    const float n = std::sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
    if (!std::isfinite(n) || std::abs(n - 1.0f) > 1e-3f)
      throw UsageError("light directions must be finite unit vectors", "give azimuth,elevation or a normalised x,y,z");
  }
}

double condition_number(const Eigen::MatrixXd& m) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(m);
  const auto& s = svd.singularValues();
  return s(s.size() - 1) > 0 ? s(0) / s(s.size() - 1) : INFINITY;
}

}  // namespace

Rgbn photometric_stereo(const std::vector<Image>& photos, const std::vector<Vec3>& lights, const StereoOptions& o,
                        StereoReport* report) {
  check_inputs(photos, lights, 3, "photometric stereo");
  const int m = int(lights.size());
  Eigen::MatrixXd L(m, 3);
  for (int i = 0; i < m; ++i) L.row(i) << lights[i][0], lights[i][1], lights[i][2];
  const double cond = condition_number(L);
  if (!(cond < 1e3))
    throw Error("the light directions are (nearly) coplanar: condition number " + std::to_string(cond),
                "photometric stereo needs three lights that do not lie in one plane through the origin");
  const Eigen::Matrix3d LtL = L.transpose() * L;
  const Eigen::MatrixXd pinv = LtL.inverse() * L.transpose();
  const int w = photos[0].width, h = photos[0].height;
  Rgbn out(w, h);
  std::vector<double> resid_rows(h, 0.0), dropped_rows(h, 0.0), count_rows(h, 0.0);
  std::vector<std::vector<float>> grey(m);
  for (int i = 0; i < m; ++i) grey[i] = luminance(photos[i]);
  detail::parallel_rows(h, [&](int y0, int y1) {
    std::vector<double> I(m);
    std::vector<char> use(m);
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t p = size_t(y) * w + x;
        double top = 0;
        for (int i = 0; i < m; ++i) top = std::max(top, I[i] = grey[i][p]);
        Eigen::Vector3d g;
        std::fill(use.begin(), use.end(), 1);
        auto fit = [&]() -> bool {
          Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
          Eigen::Vector3d b = Eigen::Vector3d::Zero();
          int k = 0;
          for (int i = 0; i < m; ++i) {
            if (!use[i]) continue;
            const Eigen::Vector3d l = L.row(i).transpose();
            A += l * l.transpose();
            b += l * I[i];
            ++k;
          }
          if (k < 3) return false;
          // Nearly coplanar remaining lights: det(A) tiny against trace(A)^3.
          const double tr = A.trace();
          if (A.determinant() < 1e-6 * tr * tr * tr) return false;
          g = A.ldlt().solve(b);
          return true;
        };
        if (!o.robust) {
          Eigen::VectorXd Iv = Eigen::Map<Eigen::VectorXd>(I.data(), m);
          g = pinv * Iv;
        } else {
          for (int i = 0; i < m; ++i) use[i] = I[i] > o.shadow * top;
          if (!fit()) {
            std::fill(use.begin(), use.end(), 1);
            fit();
          } else {
            // Drop highlights one at a time while the fit stays determined.
            for (int round = 0; round < m; ++round) {
              const double a = g.norm();
              int worst = -1;
              double worst_r = o.specular * a;
              for (int i = 0; i < m; ++i) {
                if (!use[i]) continue;
                const double r = I[i] - L.row(i).dot(g);
                if (r > worst_r) worst_r = r, worst = i;
              }
              if (worst < 0) break;
              use[worst] = 0;
              if (!fit()) {
                use[worst] = 1;
                fit();
                break;
              }
            }
          }
        }
        const double a = g.norm();
        Eigen::Vector3d n = a > 1e-12 ? Eigen::Vector3d(g / a) : Eigen::Vector3d(0, 0, 1);
        float* on = out.n(x, y);
        on[0] = float(n(0)), on[1] = float(n(1)), on[2] = float(n(2));
        // Per-channel albedo k_c = sum I_c <l,n> / sum <l,n>^2 over the used samples.
        double den = 0;
        double num[3] = {0, 0, 0};
        for (int i = 0; i < m; ++i) {
          if (o.robust && !use[i]) {
            dropped_rows[y] += 1;
            continue;
          }
          const double d = L.row(i).dot(n);
          den += d * d;
          for (int c = 0; c < 3; ++c) num[c] += photos[i].pixels[3 * p + c] * d;
          const double r = I[i] - a * d;
          resid_rows[y] += r * r;
          count_rows[y] += 1;
        }
        for (int c = 0; c < 3; ++c) out.a(x, y)[c] = den > 0 ? float(std::max(0.0, num[c] / den)) : 0.0f;
      }
  });
  if (report) {
    double r = 0, d = 0, c = 0;
    for (int y = 0; y < h; ++y) r += resid_rows[y], d += dropped_rows[y], c += count_rows[y];
    report->mean_residual = c > 0 ? std::sqrt(r / c) : 0.0;
    report->samples_dropped = d / (double(w) * h * m);
    report->condition = cond;
  }
  return out;
}

// --- PTM ---------------------------------------------------------------------------------------
namespace {
inline void basis(double u, double v, double* b) {
  b[0] = 1, b[1] = u, b[2] = v, b[3] = u * v, b[4] = u * u, b[5] = v * v;
}
}  // namespace

Ptm fit_ptm(const std::vector<Image>& photos, const std::vector<Vec3>& lights, PtmReport* report) {
  check_inputs(photos, lights, 6, "a PTM fit");
  const int m = int(lights.size());
  Eigen::MatrixXd B(m, 6);
  for (int i = 0; i < m; ++i) {
    double b[6];
    basis(lights[i][0], lights[i][1], b);
    for (int k = 0; k < 6; ++k) B(i, k) = b[k];
  }
  const double cond = condition_number(B);
  if (!(cond < 1e4))
    throw Error("the light directions do not determine a biquadratic PTM (condition number " + std::to_string(cond) + ")",
                "use at least 6 lights spread in azimuth and elevation, not on one line or circle");
  const Eigen::MatrixXd pinv = B.completeOrthogonalDecomposition().pseudoInverse();
  Ptm ptm;
  ptm.width = photos[0].width, ptm.height = photos[0].height;
  ptm.coeff.assign(size_t(ptm.width) * ptm.height * 18, 0.0f);
  double sq = 0;
  const size_t n = size_t(ptm.width) * ptm.height;
  Eigen::VectorXd I(m);
  for (size_t p = 0; p < n; ++p)
    for (int c = 0; c < 3; ++c) {
      for (int i = 0; i < m; ++i) I(i) = photos[i].pixels[3 * p + c];
      const Eigen::VectorXd a = pinv * I;
      for (int k = 0; k < 6; ++k) ptm.coeff[p * 18 + c * 6 + k] = float(a(k));
      sq += (B * a - I).squaredNorm();
    }
  if (report) {
    report->rms_residual = std::sqrt(sq / double(n * 3 * m));
    report->condition = cond;
  }
  return ptm;
}

Image render_ptm(const Ptm& ptm, const Vec3& l) {
  Image out(ptm.width, ptm.height);
  double b[6];
  basis(l[0], l[1], b);
  for (size_t p = 0; p < size_t(ptm.width) * ptm.height; ++p)
    for (int c = 0; c < 3; ++c) {
      const float* a = &ptm.coeff[p * 18 + c * 6];
      double v = 0;
      for (int k = 0; k < 6; ++k) v += a[k] * b[k];
      out.pixels[3 * p + c] = float(v);
    }
  return out;
}

Ptm blend(const Ptm& a, const Ptm& b, float t) {
  if (a.width != b.width || a.height != b.height) throw Error("cannot blend PTMs of different sizes", "give PTMs of the same size");
  Ptm o = a;
  for (size_t i = 0; i < o.coeff.size(); ++i) o.coeff[i] = (1 - t) * a.coeff[i] + t * b.coeff[i];
  return o;
}

std::array<float, 6> legendre(const float* a) {
  const float s3 = std::sqrt(3.0f), s45 = std::sqrt(45.0f);
  return {2 * a[0] + (2.0f / 3.0f) * (a[4] + a[5]), (2 / s3) * a[1], (2 / s3) * a[2], (2.0f / 3.0f) * a[3],
          (4 / s45) * a[4], (4 / s45) * a[5]};
}

Ptm synthesize_ptm(const Ptm& ex, int w, int h, int patch, uint64_t seed) {
  check_dimensions(w, h);
  if (patch < 4 || patch > std::min(ex.width, ex.height))
    throw UsageError("patch size must be in [4, min(example width, height)]", "e.g. --patch 32");
  const int ov = std::max(1, patch / 6), step = patch - ov;
  // Legendre coefficients of the example (18 per pixel).
  std::vector<float> eb(size_t(ex.width) * ex.height * 18);
  for (size_t p = 0; p < size_t(ex.width) * ex.height; ++p)
    for (int c = 0; c < 3; ++c) {
      const auto b = legendre(&ex.coeff[p * 18 + c * 6]);
      std::copy(b.begin(), b.end(), &eb[p * 18 + c * 6]);
    }
  Ptm out;
  out.width = w, out.height = h;
  out.coeff.assign(size_t(w) * h * 18, 0.0f);
  std::vector<float> ob(out.coeff.size(), 0.0f);
  std::vector<char> filled(size_t(w) * h, 0);
  std::mt19937_64 rng(seed);
  const int cx = ex.width - patch + 1, cy = ex.height - patch + 1;
  const int candidates = 256;
  for (int oy = 0; oy < h; oy += step)
    for (int ox = 0; ox < w; ox += step) {
      // Score random candidate source positions by the overlap distance in the Legendre basis.
      std::vector<std::pair<double, std::pair<int, int>>> scored;
      for (int k = 0; k < candidates; ++k) {
        const int sx = int(rng() % uint64_t(cx)), sy = int(rng() % uint64_t(cy));
        double d = 0;
        for (int y = 0; y < patch && oy + y < h; ++y)
          for (int x = 0; x < patch && ox + x < w; ++x) {
            const size_t o = size_t(oy + y) * w + ox + x;
            if (!filled[o]) continue;
            const float* a = &ob[o * 18];
            const float* b = &eb[(size_t(sy + y) * ex.width + sx + x) * 18];
            for (int i = 0; i < 18; ++i) d += double(a[i] - b[i]) * (a[i] - b[i]);
          }
        scored.push_back({d, {sx, sy}});
      }
      std::sort(scored.begin(), scored.end());
      // Pick among the near-best (within 10% of the best) for variety.
      size_t n = 1;
      while (n < scored.size() && scored[n].first <= scored[0].first * 1.1 + 1e-12) ++n;
      const auto [sx, sy] = scored[rng() % n].second;
      for (int y = 0; y < patch && oy + y < h; ++y)
        for (int x = 0; x < patch && ox + x < w; ++x) {
          const size_t o = size_t(oy + y) * w + ox + x;
          const size_t s = size_t(sy + y) * ex.width + sx + x;
          float t = 1.0f;  // weight of the new patch: ramps across the overlap
          if (filled[o]) {
            const float tx = ox > 0 && x < ov ? float(x + 1) / (ov + 1) : 1.0f;
            const float ty = oy > 0 && y < ov ? float(y + 1) / (ov + 1) : 1.0f;
            t = std::min(tx, ty);
          }
          for (int i = 0; i < 18; ++i) {
            out.coeff[o * 18 + i] = (1 - t) * out.coeff[o * 18 + i] + t * ex.coeff[s * 18 + i];
            ob[o * 18 + i] = (1 - t) * ob[o * 18 + i] + t * eb[s * 18 + i];
          }
          filled[o] = 1;
        }
    }
  return out;
}

namespace {
std::vector<std::string> ptm_channels() {
  std::vector<std::string> names;
  for (const char* c : {"R", "G", "B"})
    for (int k = 0; k < 6; ++k) names.push_back(std::string(c) + ".a" + std::to_string(k));
  return names;
}
}  // namespace

void save_ptm(const Ptm& ptm, const std::filesystem::path& path) {
  detail::write_exr(path, ptm.width, ptm.height, ptm_channels(), ptm.coeff);
}

Ptm load_ptm(const std::filesystem::path& path) {
  Ptm p;
  p.coeff = detail::read_exr(path, ptm_channels(), p.width, p.height);
  return p;
}

}  // namespace proctex::rgbn
