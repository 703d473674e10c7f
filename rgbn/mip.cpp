#include "rgbn/mip.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>

#include "core/error.h"
#include "rgbn/parallel.h"

namespace proctex::rgbn {

MipMethod parse_mip_method(const std::string& name) {
  if (name == "naive") return MipMethod::Naive;
  if (name == "toksvig") return MipMethod::Toksvig;
  if (name == "vmf") return MipMethod::Vmf;
  if (name == "sh") return MipMethod::Sh;
  throw UsageError("unknown MIP method '" + name + "'", "use naive, toksvig, vmf or sh");
}

std::string mip_method_name(MipMethod m) {
  switch (m) {
    case MipMethod::Naive: return "naive";
    case MipMethod::Toksvig: return "toksvig";
    case MipMethod::Vmf: return "vmf";
    case MipMethod::Sh: return "sh";
  }
  return "?";
}

namespace {

inline double dot(const Vec3& a, const Vec3& b) { return double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2]; }

// log of the vMF normaliser C(kappa) = kappa / (4 pi sinh kappa).
inline double log_c(double k) {
  if (k < 1e-6) return -std::log(4 * M_PI);
  return std::log(k) - std::log(2 * M_PI) - k - std::log1p(-std::exp(-2 * k));
}

// Real spherical harmonics up to order L at unit direction d, (L+1)^2 values, index l(l+1)+m.
void sh_eval(int L, const Vec3& d, std::vector<double>& out) {
  out.assign(size_t(L + 1) * (L + 1), 0.0);
  const double z = std::clamp(double(d[2]), -1.0, 1.0);
  const double phi = std::atan2(double(d[1]), double(d[0]));
  const double sx = std::sqrt(std::max(0.0, 1 - z * z));
  // Associated Legendre P_l^m(z) by the standard recurrences.
  std::vector<double> P(size_t(L + 1) * (L + 1), 0.0);
  auto at = [&](int l, int m) -> double& { return P[size_t(l) * (L + 1) + m]; };
  at(0, 0) = 1;
  for (int m = 1; m <= L; ++m) at(m, m) = -(2 * m - 1) * sx * at(m - 1, m - 1);
  for (int m = 0; m < L; ++m) at(m + 1, m) = (2 * m + 1) * z * at(m, m);
  for (int m = 0; m <= L; ++m)
    for (int l = m + 2; l <= L; ++l) at(l, m) = ((2 * l - 1) * z * at(l - 1, m) - (l + m - 1) * at(l - 2, m)) / (l - m);
  for (int l = 0; l <= L; ++l)
    for (int m = -l; m <= l; ++m) {
      const int am = std::abs(m);
      double f = 1;  // (l-|m|)! / (l+|m|)!
      for (int k = l - am + 1; k <= l + am; ++k) f /= k;
      const double K = std::sqrt((2 * l + 1) / (4 * M_PI) * f);
      double v;
      if (m == 0) v = K * at(l, 0);
      else if (m > 0) v = std::sqrt(2.0) * K * std::cos(m * phi) * at(l, am);
      else v = std::sqrt(2.0) * K * std::sin(am * phi) * at(l, am);
      out[size_t(l * (l + 1) + m)] = v;
    }
}

// Funk-Hecke factors 2 pi int_{-1}^{1} max(0,t)^s P_l(t) dt, cached per (L, s).
const std::vector<double>& lobe_factors(int L, float s) {
  static std::mutex mutex;
  static std::map<std::pair<int, float>, std::vector<double>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto it = cache.find({L, s});
  if (it != cache.end()) return it->second;
  std::vector<double> f(L + 1, 0.0);
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const double t = (i + 0.5) / n;
    const double k = std::pow(t, double(s)) / n;
    double p0 = 1, p1 = t;  // Legendre P_l(t) by recurrence
    for (int l = 0; l <= L; ++l) {
      const double pl = l == 0 ? p0 : (l == 1 ? p1 : 0);
      double v = pl;
      if (l >= 2) {
        v = ((2 * l - 1) * t * p1 - (l - 1) * p0) / l;
        p0 = p1, p1 = v;
      }
      f[l] += 2 * M_PI * k * v;
    }
  }
  return cache[{L, s}] = f;
}

std::vector<Vec3> half_vectors() {
  std::vector<Vec3> hs;
  const int n = 64;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 0.5 + 0.5 * (i + 0.5) / n;  // elevation >= 30 degrees
    const double r = std::sqrt(1 - z * z), a = golden * i;
    hs.push_back({float(r * std::cos(a)), float(r * std::sin(a)), float(z)});
  }
  return hs;
}

}  // namespace

std::vector<VmfLobe> fit_vmf(const std::vector<Vec3>& ns, int J, int iterations) {
  const size_t N = ns.size();
  std::vector<VmfLobe> lobes;
  if (N == 0) return lobes;
  Vec3 m{0, 0, 0};
  for (const auto& n : ns)
    for (int c = 0; c < 3; ++c) m[c] += n[c];
  double ml = std::sqrt(dot(m, m));
  // Start from the sample closest to the mean direction (a data point, so that a footprint of a
  // few distinct normals is fitted by exactly those), then add the farthest samples.
  size_t first = 0;
  double best_dot = -2;
  for (size_t i = 0; i < N && ml > 1e-12; ++i)
    if (dot(ns[i], m) > best_dot) best_dot = dot(ns[i], m), first = i;
  std::vector<Vec3> mus = {ns[first]};
  // Farthest-point start: each new mean is the normal least like the existing ones.
  while (int(mus.size()) < J) {
    double worst = 2;
    size_t pick = 0;
    for (size_t i = 0; i < N; ++i) {
      double best = -2;
      for (const auto& u : mus) best = std::max(best, dot(ns[i], u));
      if (best < worst) worst = best, pick = i;
    }
    if (worst > 0.9999) break;
    mus.push_back(ns[pick]);
  }
  const int K = int(mus.size());
  lobes.resize(K);
  for (int j = 0; j < K; ++j) lobes[j] = {1.0f / K, mus[j], 200.0f};
  std::vector<double> g(N * K);
  for (int it = 0; it < iterations; ++it) {
    // E-step.
    for (size_t i = 0; i < N; ++i) {
      double mx = -1e300;
      for (int j = 0; j < K; ++j) {
        const double lp = std::log(std::max(double(lobes[j].alpha), 1e-300)) + log_c(lobes[j].kappa) +
                          lobes[j].kappa * dot(lobes[j].mu, ns[i]);
        g[i * K + j] = lp;
        mx = std::max(mx, lp);
      }
      double sum = 0;
      for (int j = 0; j < K; ++j) sum += g[i * K + j] = std::exp(g[i * K + j] - mx);
      for (int j = 0; j < K; ++j) g[i * K + j] /= sum;
    }
    // M-step.
    for (int j = 0; j < K; ++j) {
      double w = 0, r[3] = {0, 0, 0};
      for (size_t i = 0; i < N; ++i) {
        const double gi = g[i * K + j];
        w += gi;
        for (int c = 0; c < 3; ++c) r[c] += gi * ns[i][c];
      }
      lobes[j].alpha = float(w / double(N));
      if (w < 1e-9) continue;
      const double rl = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
      if (rl > 1e-12) lobes[j].mu = {float(r[0] / rl), float(r[1] / rl), float(r[2] / rl)};
      // kappa from the mean resultant length (Banerjee et al.); identical normals give a lobe so
      // sharp (1e9) that its Blinn-Phong convolution is the plain lobe to float precision.
      const double rb = std::min(rl / w, 1.0 - 1e-9);
      lobes[j].kappa = float(std::min(1e9, (3 * rb - rb * rb * rb) / (1 - rb * rb)));
    }
  }
  lobes.erase(std::remove_if(lobes.begin(), lobes.end(), [](const VmfLobe& l) { return l.alpha < 1e-6f; }), lobes.end());
  return lobes;
}

MipLevel build_level(const Rgbn& fine, int f, const MipOptions& o, bool vmf, bool sh) {
  if (f < 1 || f > std::min(fine.width, fine.height))
    throw UsageError("footprint " + std::to_string(f) + " does not fit the " + std::to_string(fine.width) + "x" +
                         std::to_string(fine.height) + " normal map",
                     "use footprints between 1 and the image size");
  MipLevel L;
  L.footprint = f;
  L.width = fine.width / f, L.height = fine.height / f;
  L.sh_order = o.sh_order;
  const size_t n = size_t(L.width) * L.height;
  L.mean.resize(n);
  if (vmf) L.vmf.resize(n);
  if (sh) L.sh.resize(n);
  detail::parallel_rows(L.height, [&](int y0, int y1) {
    std::vector<Vec3> ns;
    std::vector<double> y;
    for (int cy = y0; cy < y1; ++cy)
      for (int cx = 0; cx < L.width; ++cx) {
        ns.clear();
        Vec3 m{0, 0, 0};
        for (int j = 0; j < f; ++j)
          for (int i = 0; i < f; ++i) {
            const float* p = fine.n(cx * f + i, cy * f + j);
            ns.push_back({p[0], p[1], p[2]});
            for (int c = 0; c < 3; ++c) m[c] += p[c] / float(f * f);
          }
        const size_t t = size_t(cy) * L.width + cx;
        L.mean[t] = m;
        if (vmf) L.vmf[t] = fit_vmf(ns, std::min<int>(o.lobes, int(ns.size())), o.iterations);
        if (sh) {
          std::vector<float> c(size_t(o.sh_order + 1) * (o.sh_order + 1), 0.0f);
          for (const auto& v : ns) {
            sh_eval(o.sh_order, v, y);
            for (size_t k = 0; k < c.size(); ++k) c[k] += float(y[k] / double(ns.size()));
          }
          L.sh[t] = std::move(c);
        }
      }
  }, 4);
  return L;
}

float mip_specular(const MipLevel& L, size_t t, MipMethod method, const Vec3& h, float s) {
  switch (method) {
    case MipMethod::Naive:
    case MipMethod::Toksvig: {
      const Vec3& m = L.mean[t];
      const double len = std::sqrt(dot(m, m));
      if (len < 1e-12) return 0.0f;
      const double c = std::max(0.0, dot(m, h) / len);
      if (method == MipMethod::Naive) return float(std::pow(c, double(s)));
      const double ft = len / (len + s * (1 - std::min(len, 1.0)));
      return float(ft * std::pow(c, ft * s));
    }
    case MipMethod::Vmf: {
      double v = 0;
      for (const auto& l : L.vmf[t]) {
        const double k = double(l.kappa) / (double(l.kappa) + s);
        v += l.alpha * k * std::pow(std::max(0.0, dot(l.mu, h)), k * s);
      }
      return float(v);
    }
    case MipMethod::Sh: {
      const auto& f = lobe_factors(L.sh_order, s);
      thread_local std::vector<double> y;
      sh_eval(L.sh_order, h, y);
      double v = 0;
      for (int l = 0; l <= L.sh_order; ++l)
        for (int m = -l; m <= l; ++m) v += f[l] * L.sh[t][size_t(l * (l + 1) + m)] * y[size_t(l * (l + 1) + m)];
      return float(v);
    }
  }
  return 0.0f;
}

float truth_specular(const Rgbn& fine, int f, int cx, int cy, const Vec3& h, float s) {
  double v = 0;
  for (int j = 0; j < f; ++j)
    for (int i = 0; i < f; ++i) {
      const float* p = fine.n(cx * f + i, cy * f + j);
      v += std::pow(std::max(0.0, double(p[0]) * h[0] + double(p[1]) * h[1] + double(p[2]) * h[2]), double(s));
    }
  return float(v / double(f * f));
}

double mip_error(const Rgbn& fine, const MipLevel& L, MipMethod method, float s) {
  static const std::vector<Vec3> hs = half_vectors();
  std::vector<double> num(L.height, 0.0), den(L.height, 0.0);
  detail::parallel_rows(L.height, [&](int y0, int y1) {
    for (int cy = y0; cy < y1; ++cy)
      for (int cx = 0; cx < L.width; ++cx) {
        const size_t t = size_t(cy) * L.width + cx;
        for (const auto& h : hs) {
          const double truth = truth_specular(fine, L.footprint, cx, cy, h, s);
          const double a = mip_specular(L, t, method, h, s);
          num[cy] += (a - truth) * (a - truth);
          den[cy] += truth * truth;
        }
      }
  }, 4);
  double n = 0, d = 0;
  for (int y = 0; y < L.height; ++y) n += num[y], d += den[y];
  return d > 0 ? std::sqrt(n / d) : 0.0;
}

Rgbn naive_level(const Rgbn& fine, int f) {
  const int w = fine.width / f, h = fine.height / f;
  Rgbn out(w, h);
  for (int cy = 0; cy < h; ++cy)
    for (int cx = 0; cx < w; ++cx) {
      double n[3] = {0, 0, 0}, a[3] = {0, 0, 0};
      for (int j = 0; j < f; ++j)
        for (int i = 0; i < f; ++i)
          for (int c = 0; c < 3; ++c) n[c] += fine.n(cx * f + i, cy * f + j)[c], a[c] += fine.a(cx * f + i, cy * f + j)[c];
      const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (int c = 0; c < 3; ++c) {
        out.n(cx, cy)[c] = l > 1e-12 ? float(n[c] / l) : (c == 2 ? 1.0f : 0.0f);
        out.a(cx, cy)[c] = float(a[c] / (f * f));
      }
    }
  return out;
}

void save_level(const MipLevel& L, MipMethod method, const std::filesystem::path& path) {
  std::vector<std::string> names;
  std::vector<float> data;
  const size_t n = size_t(L.width) * L.height;
  if (method == MipMethod::Naive || method == MipMethod::Toksvig) {
    names = {"N.X", "N.Y", "N.Z"};
    for (size_t t = 0; t < n; ++t) {
      const Vec3& m = L.mean[t];
      const double len = std::sqrt(dot(m, m));
      const double k = method == MipMethod::Naive && len > 1e-12 ? 1.0 / len : 1.0;
      for (int c = 0; c < 3; ++c) data.push_back(float(m[c] * k));
    }
  } else if (method == MipMethod::Vmf) {
    size_t J = 0;
    for (const auto& v : L.vmf) J = std::max(J, v.size());
    for (size_t j = 0; j < J; ++j)
      for (const char* c : {"A", "X", "Y", "Z", "K"}) names.push_back("lobe" + std::to_string(j) + "." + c);
    for (size_t t = 0; t < n; ++t)
      for (size_t j = 0; j < J; ++j) {
        VmfLobe l = j < L.vmf[t].size() ? L.vmf[t][j] : VmfLobe{};
        data.insert(data.end(), {l.alpha, l.mu[0], l.mu[1], l.mu[2], l.kappa});
      }
  } else {
    const size_t K = size_t(L.sh_order + 1) * (L.sh_order + 1);
    for (size_t k = 0; k < K; ++k) names.push_back("sh." + std::to_string(k));
    for (size_t t = 0; t < n; ++t) data.insert(data.end(), L.sh[t].begin(), L.sh[t].end());
  }
  detail::write_exr(path, L.width, L.height, names, data);
}

}  // namespace proctex::rgbn
